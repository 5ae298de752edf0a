"""The watch list: chosen addresses, their values, what changed, and a
small trend (sparkline) of each numeric value over the last scans."""

from __future__ import annotations

from collections import deque
from pathlib import Path

from rich.cells import cell_len, set_cell_size
from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import DataTable, DataTableError, ValueKind
from ..datatable.display import format_value
from ..datatable.errors import AddressError
from ..errors import LocatedError
from ..ladder.symbols import resolve_name
from ..textfile import WATCH_FILE, FileRefused, decode_text, read_bytes

BARS = "▁▂▃▄▅▆▇█"
TREND = 24  # samples kept per address
NAME_MIN = 8  # cells of a name kept however long a value (a read error's text) is
WATCH_MAX = 256  # addresses in the watch list, --watch and --watch-file together
WATCH_FILE_BYTES = WATCH_FILE.size  # the largest watch file read (1 MiB)


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
        # Columns sized here, not by rich's Table (which shrinks every column
        # alike): the values first, whole; then the names, shortened with an
        # ellipsis only when a value would not fit beside them; the trend
        # gets what is left.
        width = options.max_width
        yield Text("watch", style="bold")
        if not self.items:
            yield Text("(none: --watch ADDR)", style="dim")
            return
        rows = [(item.text, _shown(item.value), item) for item in self.items]
        names_w = max(cell_len(n) for n, _, _ in rows)
        value_w = min(max(cell_len(v) for _, v, _ in rows), max(width - min(names_w, NAME_MIN) - 1, 1))
        name_w = min(names_w, max(width - value_w - 1, 1))
        trend_w = min(TREND, width - name_w - value_w - 2)
        for name, value, item in rows:
            line = Text(no_wrap=True, overflow="ellipsis")
            line.append(_fit(name, name_w).ljust(name_w) + " ")
            line.append(_fit(value, value_w).rjust(value_w), style="bold yellow" if item.changed else "")
            if trend_w > 0:
                line.append(" " + sparkline(list(item.trend))[-trend_w:], style="cyan")
            yield line


def _shown(value) -> str:
    if isinstance(value, str) and value.startswith("?"):  # why it cannot be read
        return value
    return format_value(value)


def _fit(text: str, width: int) -> str:
    """``text``, or its start and an ellipsis in ``width`` cells."""
    if cell_len(text) <= width:
        return text
    return set_cell_size(text, max(width - 1, 0)) + "…"


def read_watch_file(path: str | Path, symbols=None, room: int = WATCH_MAX) -> list[str]:
    """A watch file: one address (or symbol) a line; ``#`` starts a comment.

    Every problem is a LocatedError naming the file, line and column: bytes
    that are not UTF-8, an address that does not parse (nor names one of
    ``symbols``), more than ``room`` addresses, a file over
    WATCH_FILE_BYTES. OSError as the OS reports it."""
    try:
        raw = read_bytes(path, WATCH_FILE)  # a regular file only: a FIFO or a device is refused, not waited on
    except FileRefused as e:
        if not e.too_large:
            raise
        raise LocatedError(f"larger than {WATCH_FILE_BYTES // 1024} KiB: a watch file lists at most {WATCH_MAX} "
                           "addresses, one a line", str(path)) from None
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
