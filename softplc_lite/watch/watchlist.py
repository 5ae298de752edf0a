"""The watch list: chosen addresses, their values, what changed, and a
small trend (sparkline) of each numeric value over the last scans."""

from __future__ import annotations

from collections import deque
from pathlib import Path

from rich.console import Console, ConsoleOptions, RenderResult
from rich.table import Table
from rich.text import Text

from ..datatable import DataTable, DataTableError, ValueKind
from ..datatable.display import format_value
from ..datatable.errors import AddressError
from ..errors import LocatedError
from ..ladder.symbols import resolve_name
from ..textfile import decode_text

BARS = "▁▂▃▄▅▆▇█"
TREND = 24  # samples kept per address
WATCH_MAX = 256  # addresses in the watch list, --watch and --watch-file together
WATCH_FILE_BYTES = 1 << 20  # the largest watch file read (1 MiB)


def sparkline(values: list[float]) -> str:
    if not values:
        return ""
    lo, hi = min(values), max(values)
    if hi == lo:
        return BARS[0] * len(values)
    scale = (len(BARS) - 1) / (hi - lo)
    return "".join(BARS[int((v - lo) * scale + 0.5)] for v in values)


class WatchItem:
    def __init__(self, text: str, symbols=None) -> None:
        self.text = text
        self.address = resolve_name(text, symbols)  # an address, or a symbol with its suffix (PollTimer/DN)
        self.trend: deque[float] = deque(maxlen=TREND)
        self.value: object = None
        self.changed = False
        self._table: DataTable | None = None
        self._ref: tuple | None = None  # (array, index, mask or None) of a direct bit, word or float

    def _bind(self, table: DataTable) -> None:
        """A direct bit, word or float address is read straight from its file's
        array, as compiled rungs read it (the arrays stay in place for the
        table's life); anything else through ``table.read`` every sample."""
        self._table, self._ref = table, None
        a = self.address
        try:
            if a.is_direct and a.kind is ValueKind.BIT:
                self._ref = table.bit_ref(a)
            elif a.is_direct and a.kind in (ValueKind.WORD, ValueKind.FLOAT, ValueKind.LONG):
                self._ref = (*table.word_ref(a), None)
        except DataTableError:
            pass  # past the end of its file (for now): read() says why

    def sample(self, table: DataTable, trend: bool = True) -> None:
        """Read the value; ``trend``: also add it to the trend (a scan ran;
        not when a scan from history is shown)."""
        if table is not self._table:
            self._bind(table)
        ref = self._ref
        if ref is not None:
            data, index, mask = ref
            value = data[index] if mask is None else (1 if data[index] & mask else 0)
        else:
            try:
                value = table.read(self.address)
            except Exception as e:  # an address past its file shows why, it does not stop the view
                value = f"? {e}"
        self.changed = self.value is not None and value != self.value
        self.value = value
        if trend and isinstance(value, (int, float)) and not isinstance(value, bool):
            self.trend.append(float(value))


class WatchList:
    """Addresses given with --watch (or a watch file), sampled every scan."""

    def __init__(self, addresses: list[str], symbols=None) -> None:
        if len(addresses) > WATCH_MAX:
            raise DataTableError(f"--watch: {len(addresses)} addresses; the watch list holds at most {WATCH_MAX}")
        self.items = [WatchItem(a, symbols) for a in addresses]

    def sample(self, table: DataTable, trend: bool = True) -> None:
        for item in self.items:
            item.sample(table, trend)

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        table = Table(title="watch", title_justify="left", expand=True, show_edge=False, pad_edge=False)
        table.add_column("address", no_wrap=True)
        table.add_column("value", no_wrap=True)
        table.add_column("trend", no_wrap=True)
        if not self.items:
            table.add_row(Text("(none: --watch ADDR)", style="dim"), "", "")
        for item in self.items:
            shown = format_value(item.value) if not isinstance(item.value, str) or not item.value.startswith("?") \
                else item.value
            table.add_row(item.text, Text(shown, style="bold yellow" if item.changed else ""),
                          Text(sparkline(list(item.trend)), style="cyan"))
        yield table


def read_watch_file(path: str | Path, symbols=None, room: int = WATCH_MAX) -> list[str]:
    """A watch file: one address (or symbol) a line; ``#`` starts a comment.

    Every problem is a LocatedError naming the file, line and column: bytes
    that are not UTF-8, an address that does not parse (nor names one of
    ``symbols``), more than ``room`` addresses, a file over
    WATCH_FILE_BYTES. OSError as the OS reports it."""
    with open(path, "rb") as f:
        raw = f.read(WATCH_FILE_BYTES + 1)
    if len(raw) > WATCH_FILE_BYTES:
        raise LocatedError(f"larger than {WATCH_FILE_BYTES // 1024} KiB: a watch file lists at most {WATCH_MAX} "
                           "addresses, one a line", str(path))
    text = decode_text(raw, str(path))
    out = []
    for number, line in enumerate(text.split("\n"), 1):
        content = line.split("#", 1)[0].rstrip("\r")
        item = content.strip()
        if not item:
            continue
        column = len(content) - len(content.lstrip()) + 1
        if len(out) >= room:
            raise LocatedError(f"one address too many: the watch list holds at most {WATCH_MAX} "
                               "(--watch and --watch-file together)", str(path), number, column)
        try:
            resolve_name(item, symbols)
        except AddressError as e:
            raise LocatedError(str(e), str(path), number, column + e.position) from None
        except DataTableError as e:
            raise LocatedError(str(e), str(path), number, column) from None
        out.append(item)
    return out
