"""COMGENIUS ports in the watch view: per port, its state, receive and
transmit counts, characters waiting, and the last frames in hex and ASCII."""

from __future__ import annotations

from rich.console import Console, ConsoleOptions, RenderResult
from rich.table import Table
from rich.text import Text

FRAMES = 4  # last frames shown per port
HEX_BYTES = 12  # bytes of a frame shown


def ports_of(engine) -> list:
    """The Port objects of every module that has a PortSet (COMGENIUS)."""
    found = []
    for module in engine.modules:
        port_set = getattr(module, "ports", None)
        found += list(getattr(port_set, "ports", {}).values())
    return found


def _ascii(data: bytes) -> str:
    return "".join(chr(b) if 32 <= b < 127 else "." for b in data)


class PortsView:
    def __init__(self, engine) -> None:
        self.engine = engine

    def __bool__(self) -> bool:
        return bool(ports_of(self.engine))

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        table = Table(title="ports", title_justify="left", expand=True, show_edge=False, pad_edge=False)
        table.add_column("port", no_wrap=True)
        table.add_column("rx/tx bytes, waiting", no_wrap=True)
        table.add_column("last frames")
        for port in ports_of(self.engine):
            state = Text(f"{port.number} ", style="bold")
            state.append("up" if port.up else "down", style="green" if port.up else "red")
            counts = f"{port.rx_bytes}/{port.tx_bytes}, {len(port.rx)}" + (" OV" if port.overflow else "")
            frames = Text()
            for t_ms, direction, data in list(port.history)[-FRAMES:]:
                if frames:
                    frames.append("\n")
                frames.append(f"{direction} ", style="cyan" if direction == "RX" else "magenta")
                frames.append(data[:HEX_BYTES].hex(" ").upper())
                frames.append(("…" if len(data) > HEX_BYTES else "") + f" {_ascii(data[:HEX_BYTES])}", style="dim")
            table.add_row(state, counts, frames or Text("-", style="dim"))
        yield table
