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


def _frame(direction: str, data: bytes, shown: int) -> Text:
    """``RX 01 03 02 …  ...``: a frame's first ``shown`` bytes in hex, then as ASCII."""
    text = Text(no_wrap=True, overflow="ellipsis")
    text.append(f"{direction} ", style="cyan" if direction == "RX" else "magenta")
    text.append(data[:shown].hex(" ").upper())
    text.append(("…" if len(data) > shown else "") + f" {_ascii(data[:shown])}", style="dim")
    return text


def frame_bytes(width: int) -> int:
    """How many bytes of a frame fit ``width`` cells on one line ("RX ",
    three cells a byte in hex, "…", a space, one cell a byte in ASCII):
    at most HEX_BYTES. A frame is never wrapped: a line of two bytes reads
    as nothing."""
    return max(1, min(HEX_BYTES, (width - 4) // 4))


class PortsView:
    """The ``ports`` panel. Where a table with the frames column at least
    TABLE_FRAME_BYTES wide fits, a table (port, counts, last frames); else
    (the 46-column side panel, 80 columns) each port on a line with its
    counts and its frames under it, one a line, as many bytes as fit."""

    def __init__(self, engine) -> None:
        self.engine = engine

    def __bool__(self) -> bool:
        return bool(ports_of(self.engine))

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        ports = ports_of(self.engine)
        width = options.max_width
        states = [_state(port) for port in ports]
        counts = [_counts(port) for port in ports]
        port_w = max([4] + [s.cell_len for s in states])
        counts_w = max([len(COUNTS_HEADING)] + [len(c) for c in counts])
        room = width - port_w - counts_w - 6  # two " │ " separators between three columns
        if frame_bytes(room) >= TABLE_FRAME_BYTES:
            yield self._table(ports, states, counts, frame_bytes(room))
            return
        yield Text("ports", style="italic")  # as a rich Table's title, like the servers panel's
        shown = frame_bytes(width - 2)
        for port, state, count in zip(ports, states, counts):
            line = Text(no_wrap=True, overflow="ellipsis")
            line.append_text(state)
            line.append("  rx/tx ", style="dim")
            line.append(count)
            yield line
            frames = list(port.history)[-FRAMES:]
            if not frames:
                yield Text("  -", style="dim")
            for _, direction, data in frames:
                yield Text("  ").append_text(_frame(direction, data, shown))

    def _table(self, ports, states, counts, shown: int) -> Table:
        table = Table(title="ports", title_justify="left", expand=True, show_edge=False, pad_edge=False)
        table.add_column("port", no_wrap=True)
        table.add_column(COUNTS_HEADING, no_wrap=True)
        table.add_column("last frames", no_wrap=True)
        for port, state, count in zip(ports, states, counts):
            frames = Text()
            for _, direction, data in list(port.history)[-FRAMES:]:
                if frames:
                    frames.append("\n")
                frames.append_text(_frame(direction, data, shown))
            table.add_row(state, count, frames or Text("-", style="dim"))
        return table


COUNTS_HEADING = "rx/tx bytes, waiting"
TABLE_FRAME_BYTES = 8  # the frames column of the table shows at least this many bytes, or the lines form is used


def _state(port) -> Text:
    state = Text(f"{port.label} ", style="bold")
    state.append("up" if port.up else "down", style="green" if port.up else "red")
    return state


def _counts(port) -> str:
    text = f"{port.rx_bytes}/{port.tx_bytes}, {getattr(port, 'waiting', 0)}"
    return text + (" OV" if getattr(port, "overflow", False) else "")
