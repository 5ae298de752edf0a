"""The data-file monitor: one data table file as a grid (the watch view's
counterpart of RSLogix 5's data monitor).

Word files (N B I O S D A, and L) show rows of words, each row labelled with
its first element's address (``N7:0`` then ``N7:10``); the radix is decimal,
hex, binary or ASCII (two characters a word, the first in the high byte, as
an A word holds them: docs/datatable.md gives the sources; ``.`` for a byte
that does not print). A B file starts in binary, an A file in ASCII, a D file in hex (its BCD digits), the rest in decimal. F
files show floats to 7 significant digits whatever the radix; T, C and R
files one element a row (status bits, then PRE/ACC or LEN/POS in the
radix); ST files one string a row (its length, then the text quoted).
The grid starts at element ``first`` and shows the rows that fit.
See docs/watch.md, "Data-file monitor".
"""

from __future__ import annotations

import json

from rich.cells import cell_len
from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import DataTable, DataTableError
from ..datatable.display import format_float
from ..datatable.filetypes import Storage
from ..datatable.table import member_order, read_string

RADIXES = ("decimal", "hex", "binary", "ascii")
WORDS_PER_ROW = (10, 5, 2, 1)  # the most that fit; rows start at element numbers ending in 0 or 5
_DEFAULT_RADIX = {"B": "binary", "A": "ascii", "D": "hex"}


def default_radix(letter: str) -> str:
    return _DEFAULT_RADIX.get(letter, "decimal")


def next_radix(radix: str) -> str:
    return RADIXES[(RADIXES.index(radix) + 1) % len(RADIXES)]


def float_text(value: float) -> str:
    """A float as a person reads it, as everywhere in the view
    (datatable/display.py: 7 significant digits, a float32 holds about that
    many); the JSON and --dump forms keep every digit."""
    return format_float(value)


def word_in_radix(word: int, radix: str, bits: int = 16) -> str:
    """One signed word (or an L, SI or LI element, ``bits`` wide) in ``radix``."""
    raw = word & ((1 << bits) - 1)
    if radix == "hex":
        return format(raw, f"0{bits // 4}X")
    if radix == "binary":
        return format(raw, f"0{bits}b")
    if radix == "ascii":
        chars = []
        for shift in range(bits - 8, -1, -8):  # high byte first
            byte = raw >> shift & 0xFF
            chars.append(chr(byte) if 0x20 <= byte < 0x7F else ".")
        return "".join(chars)
    return str(word)


def _cell_width(radix: str, bits: int) -> int:
    return {"hex": bits // 4, "binary": bits, "ascii": bits // 8}.get(radix, _DECIMAL_WIDTH[bits])


_DECIMAL_WIDTH = {8: 4, 16: 6, 32: 11, 64: 20}  # the most negative value's digits and sign


def grid_for(table: DataTable, text: str) -> DataGrid:
    """The grid the ``d`` prompt asks for: a file (``N7``, ``ST9``, ``O``)
    or a file and the element to start at (``N7:20``). DataTableError
    saying what was expected otherwise."""
    name, colon, start = text.strip().partition(":")
    if colon and not start.isdigit():
        raise DataTableError(f"data file {text.strip()!r}: expected a file (N7, T4, ST9) or a file and an "
                             "element to start at (N7:20)")
    return DataGrid(table, name, int(start) if colon else 0)


class DataGrid:
    """One file of ``table`` (``name``: ``N7``, ``B3``, ``T4``, ``ST9``) from
    element ``first``, in ``radix`` (None: the file's default); ``height``
    lines at most (None: the console's)."""

    def __init__(self, table: DataTable, name: str, first: int = 0, radix: str | None = None,
                 height: int | None = None) -> None:
        self.file = table.file(name)  # DataTableError naming what was expected for a bad name
        ftype = self.file.ftype
        if radix is not None and radix not in RADIXES:
            raise ValueError(f"radix {radix!r}: expected one of {', '.join(RADIXES)}")
        self.radix = radix or default_radix(ftype.letter)
        self.first = max(0, min(first, max(0, self.file.size - 1)))
        self.height = height
        self.rows_drawn = 0  # data rows of the last drawing (a page, for paging)
        self.per_row = 1  # elements a row in the last drawing

    def _title(self) -> Text:
        f = self.file
        t = Text(no_wrap=True, overflow="ellipsis")
        t.append(f" {f.name} ", style="bold reverse")
        t.append(f" {f.ftype.title}, {f.size} element{'s' if f.size != 1 else ''}")
        if f.ftype.storage is Storage.FLOAT:
            t.append("  floats, 7 digits", style="dim")
        elif not f.ftype.is_string:
            t.append(f"  radix {self.radix}", style="cyan")
        return t

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = options.max_width
        height = self.height or options.height or console.height
        rows = max(1, height - 1)
        title = self._title()
        f = self.file
        if f.ftype.is_string:
            lines = self._strings(rows)
        elif f.ftype.is_structure:
            lines = self._structures(rows)
        else:
            lines = self._words(rows, width)
        if lines:
            last = self.first + self.rows_drawn * self.per_row - 1
            title.append(f"  {f.name}:{self.first}..{min(last, f.size - 1)}", style="dim")
        yield title
        for line in lines:
            line.no_wrap, line.overflow = True, "ellipsis"
            yield line

    def _label(self, element: int) -> str:
        return f"{self.file.name}:{element}"

    def _words(self, rows: int, width: int) -> list[Text]:
        f = self.file
        bits = f.ftype.item_bits  # 16 a word, 32 an L, 8 an SI, 64 an LI element
        is_float = f.ftype.storage is Storage.FLOAT
        cell = 13 if is_float else _cell_width(self.radix, bits)
        label = max(cell_len(self._label(f.size - 1)), 4) + 1
        per_row = next((n for n in WORDS_PER_ROW if label + n * (cell + 1) <= width), 1)
        self.per_row = per_row
        data = f.data
        lines = []
        for start in range(self.first, f.size, per_row):
            if len(lines) == rows:
                break
            line = Text(self._label(start).ljust(label), style="bold")
            for e in range(start, min(start + per_row, f.size)):
                value = data[e]
                shown = float_text(value) if is_float else word_in_radix(value, self.radix, bits)
                line.append(" " + shown.rjust(cell), style=None if value else "dim")
            lines.append(line)
        self.rows_drawn = len(lines)
        return lines

    def _structures(self, rows: int) -> list[Text]:
        f = self.file
        ftype = f.ftype
        per = ftype.words_per_element
        label = max(cell_len(self._label(f.size - 1)), 4) + 1
        cell = max(_cell_width(self.radix, 16), 3)
        lines = []
        self.per_row = 1
        for e in range(self.first, f.size):
            if len(lines) == rows:
                break
            start = e * per
            line = Text(self._label(e).ljust(label), style="bold")
            for name in member_order(ftype):
                m = ftype.members_by_name[name]
                if hasattr(m, "bit"):
                    on = f.data[start + m.word] >> m.bit & 1
                    line.append(f" {name} ", style="dim")
                    line.append(str(on), style="bold green" if on else None)
                else:
                    line.append(f"  {name} ", style="dim")
                    line.append(word_in_radix(f.data[start + m.offset], self.radix).rjust(cell))
            lines.append(line)
        self.rows_drawn = len(lines)
        return lines

    def _strings(self, rows: int) -> list[Text]:
        f = self.file
        per = f.ftype.words_per_element
        label = max(cell_len(self._label(f.size - 1)), 4) + 1
        lines = []
        self.per_row = 1
        for e in range(self.first, f.size):
            if len(lines) == rows:
                break
            text = read_string(f.data, e * per, f.ftype.chars)
            line = Text(self._label(e).ljust(label), style="bold")
            line.append(f" LEN {len(text):2d} ", style="dim")
            line.append(json.dumps(text))
            lines.append(line)
        self.rows_drawn = len(lines)
        return lines

    def page(self, pages: int) -> None:
        """Move ``pages`` pages down (negative: up), a page being the rows
        the last drawing showed."""
        step = max(1, self.rows_drawn) * self.per_row * pages
        self.first = max(0, min(self.first + step, max(0, self.file.size - 1)))
