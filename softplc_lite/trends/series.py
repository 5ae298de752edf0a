"""What a trend follows: the addresses and symbols an engineer names, each
resolved once to where its value lives (docs/trends.md, "What can be
trended").

A series is a bit (``B3/4``, ``T4:0/DN``), a word (``N7:0``, ``T4:0.ACC``),
a long (``L10:0``, or an 8-bit ``SI`` or 64-bit ``LI`` integer: numbers like words) or a float (``F8:0``) at a direct address; a symbol
names its address and gives the series its label. A whole timer, counter
or control element, a string, and an indirect or indexed address are
refused with what to name instead (a choice: a trend is one number a scan,
at one place).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from ..datatable import DataTableError
from ..datatable.address import Address, ValueKind
from ..ladder.symbols import SymbolIndex, is_name, resolve_name

BIT, WORD, LONG, FLOAT = "bit", "word", "long", "float"
KIND_OF = {ValueKind.BIT: BIT, ValueKind.WORD: WORD, ValueKind.LONG: LONG, ValueKind.FLOAT: FLOAT}
MAX_SERIES = 20  # recorded at once (--trend); the watch view's panel draws fewer (watch.trendview)


class TrendError(ValueError):
    """Addresses that cannot be trended: every problem, one a line."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


@dataclass(frozen=True)
class Series:
    text: str  # as the engineer wrote it
    label: str  # the symbol's name, or the address
    address: Address
    kind: str  # BIT WORD LONG FLOAT
    file: str  # the data file's name
    index: int  # the item in the file's storage
    bit: int | None

    @property
    def is_bit(self) -> bool:
        return self.kind == BIT


def resolve_series(texts: list[str], table, symbols: dict | None = None, what: str = "--trend",
                   limit: int = MAX_SERIES) -> list[Series]:
    """The series ``texts`` name, in order, each once; TrendError listing
    every problem (``what`` says where each text came from)."""
    names = SymbolIndex(symbols)
    out: list[Series] = []
    problems: list[str] = []
    seen: set[tuple] = set()
    for text in texts:
        name = text.strip()
        try:
            address = resolve_name(name, names)
        except DataTableError as e:
            message = str(e)
            problems.append(f"{what} {message}" if message.startswith((name, repr(name))) else f"{what} {name}: {message}")
            continue
        label = name if is_name(name, names) else str(address)
        problem = _untrendable(address)
        if problem is not None:
            problems.append(f"{what} {text!r}: {problem}")
            continue
        try:
            loc = table.resolve(address)
        except DataTableError as e:
            problems.append(f"{what} {text!r}: {getattr(e, 'message', str(e))}")
            continue
        key = (loc.file.name, loc.index, loc.bit)
        if key in seen:
            continue
        seen.add(key)
        out.append(Series(text, label, address, KIND_OF[address.kind], loc.file.name, loc.index, loc.bit))
    if len(out) > limit:
        problems.append(f"{what}: {len(out)} addresses; at most {limit} are trended at once")
    if problems:
        raise TrendError(problems)
    return out


def _untrendable(address: Address) -> str | None:
    if not address.is_direct:
        return "a trend follows one place: name a direct address (no [..], no #)"
    kind = address.kind
    if kind in (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL):
        return f"a whole {kind.value} is three words: name one of them ({address}.ACC, {address}.PRE, {address}/DN)"
    if kind is ValueKind.STRING:
        return "a string is not a number a trend can draw; trend its .LEN, or a number the ladder derives from it"
    return None


class Sampler:
    """Reads the series' values from the live table, fast (every scan)."""

    def __init__(self, table, series: list[Series]) -> None:
        self.table = table
        self.series = series
        self.refresh()

    def refresh(self) -> None:
        """Take the files' arrays again (a file added or replaced meanwhile)."""
        self._places = [(self.table.file(s.file).data, s.index, s.bit) for s in self.series]

    def values(self) -> list:
        return [data[i] if bit is None else (data[i] >> bit) & 1 for data, i, bit in self._places]


class FrameReader:
    """Reads the series' values from a step-back history frame (the whole
    table's bytes after one scan, watch/history.py), without touching the
    live table: what the watch view's trend draws from."""

    _FORMATS = {"h": "=h", "f": "=f", "i": "=i", "l": "=i"}

    def __init__(self, series: list[Series], table) -> None:
        self.series = series
        self._codes = {s.file: table.file(s.file).data.typecode for s in series}
        self._layout: tuple = ()
        self._places: list = []

    def _plan(self, layout: tuple) -> None:
        offsets, at = {}, 0
        for name, size in layout:
            offsets[name] = at
            at += size
        places = []
        for s in self.series:
            code = self._codes[s.file]
            fmt = struct.Struct(self._FORMATS.get(code, "=" + code))
            base = offsets.get(s.file)
            places.append(None if base is None else (fmt, base + s.index * fmt.size, s.bit))
        self._layout, self._places = layout, places

    def values(self, frame) -> list:
        if frame.layout is not self._layout:
            self._plan(frame.layout)
        raw = frame.raw
        out = []
        for place in self._places:
            if place is None:
                out.append(None)
                continue
            fmt, at, bit = place
            value = fmt.unpack_from(raw, at)[0]
            out.append(value if bit is None else (value >> bit) & 1)
        return out


def float32_text(value: float) -> str:
    """The shortest decimal that reads back as the same float32 (2.5, not
    2.5000000001; 0.1, not 0.10000000149011612)."""
    if value != value or value in (float("inf"), float("-inf")):
        return repr(value)
    packed = struct.pack("<f", value)
    for digits in range(1, 10):
        text = f"{value:.{digits}g}"
        if struct.pack("<f", float(text)) == packed:
            return repr(float(text))  # 20.0, not 2e+01
    return repr(value)
