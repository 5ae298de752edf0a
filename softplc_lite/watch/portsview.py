"""Serial ports in the watch view (every module's: COMGENIUS, MODBMAST): per
port, its state, receive and transmit counts, what is waiting (COMGENIUS's
receive buffer), and the last frames in hex and ASCII."""

from __future__ import annotations

from rich.console import Console, ConsoleOptions, RenderResult
from rich.table import Table
from rich.text import Text

FRAMES = 4  # last frames shown per port
HEX_BYTES = 12  # bytes of a frame shown


def ports_of(engine) -> list:
    """The open ports (ports.SerialPort) of every module."""
    found = []
    for module in engine.modules:
        found += module.serial_ports()
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
            state = Text(f"{port.label} ", style="bold")
            state.append("up" if port.up else "down", style="green" if port.up else "red")
            counts = f"{port.rx_bytes}/{port.tx_bytes}, {getattr(port, 'waiting', 0)}"
            counts += " OV" if getattr(port, "overflow", False) else ""
            frames = Text()
            for t_ms, direction, data in list(port.history)[-FRAMES:]:
                if frames:
                    frames.append("\n")
                frames.append(f"{direction} ", style="cyan" if direction == "RX" else "magenta")
                frames.append(data[:HEX_BYTES].hex(" ").upper())
                frames.append(("…" if len(data) > HEX_BYTES else "") + f" {_ascii(data[:HEX_BYTES])}", style="dim")
            table.add_row(state, counts, frames or Text("-", style="dim"))
        yield table
