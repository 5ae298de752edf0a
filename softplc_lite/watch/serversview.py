"""Network servers in the watch view (MODBTCPS's Modbus TCP server, or any
module's ``network_servers()``, each a netserver.ServerStatus): per server,
where it listens and whether it is up, the clients connected, requests a
second, requests and writes served, and the refusals by kind (docs/watch.md,
"Network servers")."""

from __future__ import annotations

from rich.console import Console, ConsoleOptions, RenderResult
from rich.table import Table
from rich.text import Text

# From this width a server is one row of a table with a column per count;
# narrower (the 46-column side panel), the counts go on two lines under it.
TABLE_WIDTH = 72


def servers_of(engine) -> list[tuple[str, object]]:
    """(module name, server status) of every module's network servers."""
    found = []
    for module in engine.modules:
        found += [(module.name, server) for server in module.network_servers()]
    return found


def refusals_text(server) -> str:
    """``3 (not allowed 2, exception 02 1)``: the total, then each kind that
    is not zero; then the counts that are not refusals (``; scans skipped 4``)."""
    kinds = ", ".join(f"{kind} {n}" for kind, n in (server.refused or {}).items() if n)
    text = f"{server.refusals} ({kinds})" if kinds else str(server.refusals)
    noted = "; ".join(f"{name} {n}" for name, n in (getattr(server, "noted", None) or {}).items() if n)
    return f"{text}; {noted}" if noted else text


def _where(name: str, server) -> Text:
    """``MODBTCPS 127.0.0.1:502 up``, ``MODBTCPS down`` and why, in red, or
    where it will listen while it is not started yet."""
    text = Text()
    text.append(name, style="bold")
    text.append(" ")
    if server.up:
        text.append(f"{server.listening} ")
        text.append("up", style="green")
    elif getattr(server, "pending", False):  # not started yet, or starting: neither up nor failed
        text.append(server.listening, style="dim")
    else:
        text.append("down", style="bold red")
        text.append(f" {server.listening}", style="red")  # what the module says went wrong
    return text


class ServersView:
    """The ``servers`` panel: shown when any module serves a network."""

    def __init__(self, engine) -> None:
        self.engine = engine

    def __bool__(self) -> bool:
        return bool(servers_of(self.engine))

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        servers = servers_of(self.engine)
        if options.max_width >= TABLE_WIDTH:
            yield self._table(servers)
            return
        yield Text("servers", style="italic")  # as a rich Table's title, like the ports panel's
        for name, server in servers:
            yield _where(name, server)
            counts = Text("  ")
            for label, value in (("clients", server.clients), ("req/s", server.rate),
                                 ("requests", server.requests), ("writes", server.writes)):
                counts.append(f"{label} ", style="dim")
                counts.append(f"{value}  ")
            counts.rstrip()
            yield counts
            refusals = Text("  ")
            refusals.append("refusals ", style="dim")
            refusals.append(refusals_text(server), style="yellow" if server.refusals else "")
            yield refusals

    def _table(self, servers) -> Table:
        table = Table(title="servers", title_justify="left", expand=True, show_edge=False, pad_edge=False)
        table.add_column("server")
        for heading in ("clients", "req/s", "requests", "writes"):
            table.add_column(heading, justify="right", no_wrap=True)
        table.add_column("refusals")
        for name, server in servers:
            refusals = Text(refusals_text(server), style="yellow" if server.refusals else "")
            table.add_row(_where(name, server), str(server.clients), str(server.rate), str(server.requests),
                          str(server.writes), refusals)
        return table
