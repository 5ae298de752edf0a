"""The tag monitor: a Logix app's tags by name, the watch view's data-file
grid for a Studio 5000 export (docs/logix.md, "Watching a Logix app").

``d`` with nothing, or ``tags``, lists every tag: the controller's, then
each program's (``Program:MainProgram.Settled``), one a row with its type
and its value; a structure or an array shows ``{...}`` or its size and is
opened by naming it (``d Tanks``: one row an element; ``d Tanks[1]``: one
row a member, hidden members left out as Logix's monitor leaves them out).
An alias is its own row, its value the target's, ``-> Batches.DN`` beside
it. Integers show in the grid's radix (R), REAL to 7 digits as everywhere
in the view, a STRING quoted. The rows are made at each drawing from the
live table, so values move while the view runs.
"""

from __future__ import annotations

import itertools
import json
import re

from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import DataTableError
from ..datatable.display import format_float
from ..logix.tags import PathError, TagDirectory
from .datagrid import word_in_radix
from .power import READ_FAILURES

ALL = ("", "tags", "*")
_FILE = re.compile(r"[A-Za-z]{1,2}[0-9]*(:[0-9]*)?")  # a data file the grid shows (N7, F12:0, O)
_BITS = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}


class TagGrid:
    """The tags (``path`` None) or one tag path's elements or members,
    from row ``first``, ``height`` lines at most (None: the console's)."""

    def __init__(self, directory: TagDirectory, table, path: str | None = None, radix: str = "decimal",
                 height: int | None = None) -> None:
        self.directory = directory
        self.table = table
        self.path = path
        self.radix = radix
        self.height = height
        self.first = 0
        self.rows_drawn = 0
        self.per_row = 1
        self.count = len(self.names())  # PathError for a path that names nothing

    @property
    def name(self) -> str:
        return self.path or "tags"

    def opened(self) -> str:
        return f"{self.name}: name a structure or an array to open it (d Tanks[1]), R radix, PgUp/PgDn, Esc closes"

    def radix_said(self) -> str:
        return f"{self.name}: radix {self.radix} (REAL values show in decimal)"

    def names(self) -> list[str]:
        """The tag paths of the rows, in order."""
        if self.path is None:
            out = []
            for scope, tags in self.directory.scopes.items():
                for d in tags.values():
                    out.append(f"Program:{d.scope}.{d.tag.name}" if scope else d.tag.name)
            return out
        r = self.directory.resolve(self.path)
        if r.dims:
            return [f"{self.path}[{','.join(map(str, ix))}]"
                    for ix in itertools.product(*(range(n) for n in r.dims))]
        members = [m for m in r.type.members if not m.hidden] if r.type is not None else []
        if not members:
            return [self.path]
        return [f"{self.path}.{m.name}" for m in members]

    def row(self, path: str) -> tuple[str, str]:
        """(type, value) of one row."""
        try:
            r = self.directory.resolve(path)
        except PathError as e:  # a tag of a type softplc_lite does not hold
            return "", f"? {e}"
        type_text = r.type.name if r.type is not None else "?"
        if r.dims:
            return f"{type_text}[{','.join(map(str, r.dims))}]", ""
        alias = self._alias(path)
        if r.address is None:
            return type_text, "{...}" + (f"  -> {alias}" if alias else "")
        try:
            value = self.table.read(r.address)
        except READ_FAILURES:
            return type_text, "?"
        if isinstance(value, bool):
            shown = str(int(value))
        elif isinstance(value, float):
            shown = format_float(value)
        elif isinstance(value, str):
            shown = json.dumps(value)
        elif r.address.bit is not None:
            shown = str(int(bool(value)))
        else:
            shown = word_in_radix(value, self.radix, _BITS.get(type_text, 32))
        return type_text, shown + (f"  -> {alias}" if alias else "")

    def _alias(self, path: str) -> str | None:
        if self.path is not None or path.startswith("Program:"):
            return None
        d = self.directory.find(path, None)
        return d.tag.alias_for if d is not None and d.tag.alias_for else None

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        height = self.height or options.height or console.height
        rows = max(1, height - 1)
        names = self.names()
        self.count = len(names)
        self.first = max(0, min(self.first, max(0, self.count - 1)))
        shown = names[self.first:self.first + rows]
        cells = [(n, *self.row(n)) for n in shown]
        title = Text(no_wrap=True, overflow="ellipsis")
        title.append(f" {self.name} ", style="bold reverse")
        title.append(f" {self.count} {'tag' if self.path is None else 'row'}{'s' if self.count != 1 else ''}")
        title.append(f"  radix {self.radix}", style="cyan")
        if shown:
            title.append(f"  {self.first + 1}..{self.first + len(shown)}", style="dim")
        yield title
        width = max((len(n) for n, _, _ in cells), default=4) + 2
        twidth = max((len(t) for _, t, _ in cells), default=4) + 2
        for n, t, v in cells:
            line = Text(no_wrap=True, overflow="ellipsis")
            line.append(n.ljust(width), style="bold")
            line.append(t.ljust(twidth), style="dim")
            line.append(v, style=None if v not in ("0", "0.0", "") else "dim")
            yield line
        self.rows_drawn = len(cells)

    def page(self, pages: int) -> None:
        step = max(1, self.rows_drawn) * pages
        self.first = max(0, min(self.first + step, max(0, self.count - 1)))


def tag_grid_for(directory: TagDirectory, table, text: str) -> TagGrid | None:
    """The tag monitor ``d TEXT`` asks for: every tag for nothing or
    ``tags``, a tag path's elements or members; None when TEXT is a data
    file's name and no tag's (N7, F12: shown as a file); DataTableError
    saying what was expected when it is neither."""
    text = text.strip()
    if text.lower() in ALL:
        return TagGrid(directory, table)
    try:
        return TagGrid(directory, table, text)
    except PathError as e:
        if _FILE.fullmatch(text):
            return None
        raise DataTableError(f"{text}: {e}; expected a tag (Tanks, Tanks[1], tags for every tag) or a data "
                             "file (N7, F12:0)") from None
