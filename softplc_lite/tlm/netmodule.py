"""What every network server module (MODBTCPS, ENIPS) does the same way
around its ``netserver.ServerHandle``: the scan's hooks, the watch view's
servers panel, the port a caller waits for, and the end. A server module
builds its handle in ``attach`` and sets ``self.server``."""

from __future__ import annotations

from ..netserver import Protocol, ServerHandle, ServerStatus, Settings, StatusWords
from ..netserver.handle import START_TIMEOUT_S
from .api import TLM


def settings_of(config) -> Settings:
    """The layer's settings from a server module's configuration (the
    fields tlm/netconfig.py checks)."""
    return Settings(host=config.host, port=config.port, allow=config.allow, max_connections=config.max_connections,
                    max_requests_per_second=config.max_requests_per_second,
                    idle_timeout_ms=config.idle_timeout_ms, debug=config.debug)


def _of_server(name: str, default=None) -> property:
    """An attribute of the server handle; ``default`` before the engine attaches it."""
    return property(lambda self: getattr(self.server, name) if self.server is not None else default,
                    doc=f"The server's ``{name}`` (netserver.ServerHandle).")


class NetServerModule(TLM):
    """A module's ``config`` has the listening fields (tlm/netconfig.py) and
    ``status``; its ``attach`` builds its protocol and calls ``serve``."""

    server: ServerHandle | None = None
    config = None

    def reference_config(self, table) -> None:
        """Create the words the configuration names before the first scan."""
        for address in self.config_references():
            table.reference(address)

    def serve(self, table, protocol: Protocol, where: str, status_words: StatusWords) -> None:
        """Hold the server of ``protocol`` over ``table`` (started by the
        first scan); ``where`` names what to check when it cannot listen."""
        self.server = ServerHandle(protocol, settings_of(self.config), self.log, where, status_words)
        self.server.attach(table, self.config.status)

    image = _of_server("image")
    process = _of_server("process")
    port = _of_server("port")
    failed = _of_server("failed")
    started = _of_server("started", False)
    rate = _of_server("rate", 0)

    def wait_until_listening(self, timeout: float = START_TIMEOUT_S) -> int | None:
        """For a caller beside the scan (a test, an example, a benchmark),
        scanning or not: the port, once the server listens; None if it
        failed, ended, or did not listen in time."""
        return self.server.wait_until_listening(timeout) if self.server is not None else None

    @property
    def listening(self) -> str:
        return self.server.listening

    # -- each scan ---------------------------------------------------------------------------
    def on_input(self, engine) -> None:
        self.server.on_input(engine)

    def on_output(self, engine, outputs_enabled: bool) -> None:
        self.server.on_output(engine, outputs_enabled)

    def server_status(self) -> ServerStatus | None:
        """The server as the watch view shows it."""
        if self.server is None:  # not attached to an engine
            return None
        return self.server.server_status()

    def network_servers(self) -> list:
        status = self.server_status()
        return [status] if status is not None else []

    # -- the end -----------------------------------------------------------------------------
    def close(self) -> None:
        if self.server is not None:
            self.server.close()
