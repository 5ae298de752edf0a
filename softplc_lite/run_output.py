"""What ``softplc run`` shows of an app while it runs and when it ends.

An app names the values that tell its story in the ``[display]`` section
of its ``softplc.toml``::

    [display]
    status = { polls = "C5:0.ACC", good = "C5:1.ACC" }   # a live status line
    summary = { "first registers" = "#N11:0 10" }          # printed at the end

A value is a data table address (or a program symbol), or ``#ADDR LEN``:
LEN consecutive elements from ADDR, the file-address form COP and FLL
take. ``status`` items are also printed in the summary, first.

The status line is a rich renderable (:class:`StatusLine`); ``softplc run``
redraws it a few times a second on standard error while standard error is
a terminal, independently of the scan rate: for an app with ``status``
items, and for every app while a run is unbounded (no ``--scans``), then
with the scan count, the scan rate and the simulated/real time ratio only.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Iterable

if TYPE_CHECKING:
    from rich.console import Console, ConsoleOptions, RenderResult
    from rich.text import Text

from .datatable import DataTable, DataTableError
from .datatable.address import Address
from .datatable.display import format_read, format_value
from .ladder.symbols import resolve_name

_BLOCK = re.compile(r"#\s*(\S+)\s+([0-9]{1,6})$")


@dataclass(frozen=True)
class Item:
    """One named value: an address, or ``count`` elements from it."""

    label: str
    address: Address
    count: int | None = None

    @property
    def text(self) -> str:
        return f"#{self.address} {self.count}" if self.count is not None else str(self.address)

    def read(self, table: DataTable) -> str:
        if self.count is None:
            return format_read(table, self.address)
        return " ".join(format_value(v) for v in _block(table, self.address, self.count))


def _block(table: DataTable, start: Address, count: int) -> Iterable[object]:
    # parse_item made sure the element is a number; with_element keeps octal
    # I/O numbers and SLC slot.word forms right (text arithmetic would not).
    for k in range(count):
        yield table.read(start.with_element(start.element + k))


def _split_item(text: str) -> tuple[str, int | None]:
    """A [display] value as (address or symbol, block length or None):
    ``#N11:0 10`` is ("N11:0", 10), ``FaultMap`` ("FaultMap", None)."""
    text = text.strip()
    m = _BLOCK.match(text)
    return (m.group(1), int(m.group(2))) if m else (text, None)


def parse_item(label: str, value: object, where: str, symbols=None) -> Item:
    if not isinstance(value, str):
        raise DataTableError(f"{where}: [display] {label} = {value!r}; expected an address such as \"N7:0\" "
                             "or a block such as \"#N11:0 10\"")
    name, count = _split_item(value)
    try:
        address = resolve_name(name, symbols)
    except DataTableError as e:
        raise DataTableError(f"{where}: [display] {label} = {value!r}: {e}") from None
    if count is not None:
        whole_word = isinstance(address.element, int) and address.member is None and address.bit is None
        if not 1 <= count <= 1000 or not whole_word or not address.is_direct:
            raise DataTableError(f"{where}: [display] {label} = {value!r}: a block is #FILE:ELEMENT LEN "
                                 "with LEN 1..1000, e.g. \"#N11:0 10\"")
        return Item(label, address, count)
    return Item(label, address)


@dataclass
class Display:
    status: list[Item] = field(default_factory=list)
    summary: list[Item] = field(default_factory=list)

    def __bool__(self) -> bool:
        return bool(self.status or self.summary)

    def summary_lines(self, table: DataTable) -> list[str]:
        return [f"{item.label} ({item.text}) = {item.read(table)}" for item in self.status + self.summary]


def display_names(section: object) -> set[str]:
    """The names a ``[display]`` table shows (``FaultMap``, ``#Levels 5``):
    a symbol shown there is used, for softplc check's unused-symbol warning."""
    names: set[str] = set()
    for value in (section or {}).values() if isinstance(section, dict) else ():
        for text in value.values() if isinstance(value, dict) else ():
            if isinstance(text, str):
                names.add(_split_item(text)[0])
    return names


def parse_display(section: object, where: str, symbols=None) -> Display:
    """The ``[display]`` table of softplc.toml."""
    if not isinstance(section, dict):
        raise DataTableError(f"{where}: [display] must be a table")
    display = Display()
    for key, value in section.items():
        if key not in ("status", "summary") or not isinstance(value, dict):
            raise DataTableError(f"{where}: [display] has {key} = {value!r}; expected status = {{...}} and/or "
                                 "summary = {...}, each name = \"ADDRESS\"")
        items = [parse_item(label, v, where, symbols) for label, v in value.items()]
        getattr(display, key).extend(items)
    return display


class StatusLine:
    """One line: the app, the scan count and time, the scan rate and how
    fast simulated time goes against the wall clock, then each status value.

    ``update`` is given the wall-clock seconds since the run started
    (``wall_s``); the rate and the ratio are those since the update before
    (the last tenth of a second or so in ``softplc run``), so they follow a
    change of speed. Without ``wall_s`` (or before two updates) they are
    left out."""

    def __init__(self, name: str, items: list[Item]) -> None:
        self.name = name
        self.items = items
        self.scans = 0
        self.now_ms = 0
        self.realtime = False
        self.values: list[str] = ["-"] * len(items)
        self.rate: float | None = None  # scans a second of wall-clock time
        self.ratio: float | None = None  # PLC seconds per wall-clock second
        self.clients: int | None = None  # clients of the app's network servers (MODBTCPS); None: it has none
        self._last: tuple[float, int, int] | None = None  # (wall_s, scans, now_ms) of the update before

    def update(self, table: DataTable, scans: int, now_ms: int, realtime: bool, wall_s: float | None = None) -> None:
        self.scans, self.now_ms, self.realtime = scans, now_ms, realtime
        self.values = [item.read(table) for item in self.items]
        if wall_s is None:
            return
        last = self._last
        if last is not None and wall_s > last[0]:
            span = wall_s - last[0]
            self.rate = (scans - last[1]) / span
            self.ratio = (now_ms - last[2]) / 1000 / span
        self._last = (wall_s, scans, now_ms)

    def text(self) -> Text:
        from rich.text import Text  # here: only a status line drawn in a terminal needs rich

        t = Text()
        t.append(self.name, style="bold")
        clock = "real" if self.realtime else "simulated"
        t.append(f"  scan {self.scans}  {self.now_ms / 1000:.2f} s {clock}", style="dim")
        if self.rate is not None and self.ratio is not None:
            t.append(f"  {self.rate:.0f} scans/s  x{self.ratio:.2f} real time", style="dim")
        if self.clients is not None:
            t.append(f"  {self.clients} client{'s' if self.clients != 1 else ''}", style="dim")
        for item, value in zip(self.items, self.values):
            t.append("  ")
            t.append(f"{item.label} ", style="cyan")
            t.append(value, style="bold")
        return t

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        yield self.text()
