"""Rungs of a program drawn as they were at one moment, for a report made
later: what a failed expectation shows (the rungs that write the failing
address), and what any other reporter of a test can show.

:func:`draw_rungs` is the glue: given a program, a data table and the rungs
to draw, it keeps a copy of the table's values (its bytes, as a retentive
snapshot holds them) and the rungs, and gives a :class:`RungsAt`. That is
data only (it pickles, and the live table may move on), and a rich
renderable that draws each rung with the watch view's ``RungView``: power
flow and live values as they were at that moment, the rung's comment, its
forced bits marked ``F``, to the console's width. :func:`writer_rungs` finds
the rungs that write an address or a symbol, from the program's
cross-reference (watch/xref.py). A file made from Structured Text is drawn
as its text instead: the lines those rungs were made from, with the heads
of the arms they sit in and their tags' values (drawing_st.py).

At most ``MAX_RUNGS`` rungs are drawn (a softplc_lite choice: four rungs of
a typical width fit one screen beside the failure's own line), and ``and K
more`` says how many were left out, with where they are; a line of
Structured Text counts as one rung, however many rungs it became.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from itertools import groupby

from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import DataTable
from ..datatable.snapshot import decode, encode
from ..ladder.ast import Program, ProgramFile, Rung
from ..ladder.instructions import InstructionSet
from ..watch.naming import names_in_file, routines_of
from ..watch.rungs import COMMENT, HEADER, RungView
from ..watch.xref import XrefIndex
from .drawing_st import excerpt, line_of, line_places

MAX_RUNGS = 4


@dataclass(frozen=True)
class RungsAt:
    """Rungs as they were at one moment. ``title`` names what they are
    drawn for (``Motor (O:0/0)``); ``rungs`` holds (program file, rung
    number, rung); ``table`` the data table's values then
    (``datatable.snapshot.encode``); ``more`` the places of the rungs not
    drawn; ``why_none`` what to say when there are no rungs."""

    title: str
    rungs: tuple[tuple[int, int, Rung], ...]
    table: bytes
    symbols: Mapping[str, object] | None = None
    forced: frozenset[str] = frozenset()
    instructions: InstructionSet | None = field(default=None, compare=False)
    more: tuple[tuple[int, int], ...] = ()
    why_none: str = ""
    routines: tuple[tuple[int, str], ...] = ()  # a Logix app's: its rungs drawn by tag path (watch/naming.py)
    texts: tuple[tuple[int, ProgramFile], ...] = ()  # the files made from Structured Text: drawn as lines

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        if not self.rungs:
            yield Text(self.why_none or f"no rung to draw for {self.title}", style=COMMENT)
            return
        table = decode(self.table)
        texts = dict(self.texts)
        for number, group in groupby(self.rungs, key=lambda place: place[0]):
            names, label = names_in_file(self.symbols, self.routines, number)
            pfile = texts.get(number)
            if pfile is not None:
                yield Text(f"{label}, lines that write {self.title}:", style=HEADER)
                yield excerpt(pfile, [k for _, k, _ in group], table, names, self.forced)
                continue
            yield Text(f"{label}, rungs that write {self.title}:", style=HEADER)
            for _, k, rung in group:
                yield RungView(rung, k, table, symbols=names, forced=self.forced, instructions=self.instructions)
        if self.more:
            where = ", ".join(f"{names_in_file(self.symbols, self.routines, f)[1]} line {line_of(texts[f], r) + 1}"
                              if f in texts else f"file {f} rung {r}" for f, r in self.more)
            yield Text(f"and {len(self.more)} more: {where}", style=COMMENT)


def writer_rungs(program: Program, name: str, instructions: InstructionSet | None = None
                 ) -> tuple[str, list[tuple[int, int]]]:
    """What ``name`` (an address or a symbol) names, as the cross-reference
    titles it (``Motor (O:0/0)``), and the (program file, rung) of every
    rung that writes it (or may: an indirect write into its file), in scan
    order, each once."""
    finding = XrefIndex(program, instructions).find(name)
    return finding.title, list(dict.fromkeys((u.file, u.rung) for u in finding.writers))


def draw_rungs(program: Program, table: DataTable, places: Iterable[tuple[int, int]], title: str = "",
               forced: Iterable[str] = (), instructions: InstructionSet | None = None,
               limit: int = MAX_RUNGS, why_none: str = "") -> RungsAt:
    """The rungs at ``places`` ((program file, rung number) pairs) of
    ``program``, to be drawn with ``table``'s values as they are now: at
    most ``limit`` of them, the rest listed as ``more``. ``forced``: the
    forced addresses (canonical text, ``I:0/0``)."""
    places = line_places(program.files, places)
    rungs = tuple((f, r, program.files[f].rungs[r]) for f, r in places[:max(limit, 0)])
    texts = tuple((f, program.files[f]) for f in dict.fromkeys(f for f, _ in places)
                  if program.files[f].listing is not None)
    if instructions is not None:  # its specs only: an app's set holds functions that do not pickle
        instructions = InstructionSet([s for s in instructions.all_specs() if s.module])
    return RungsAt(title, rungs, encode(table), program.symbols, frozenset(forced), instructions,
                   tuple(places[len(rungs):]), why_none, routines_of(program), texts)


def writers_at(program: Program, table: DataTable, name: str, forced: Iterable[str] = (),
               instructions: InstructionSet | None = None, limit: int = MAX_RUNGS) -> RungsAt:
    """The rungs that write ``name``, with ``table``'s values now; when no
    rung does, a drawing that says so."""
    title, places = writer_rungs(program, name, instructions)
    return draw_rungs(program, table, places, title, forced, instructions, limit,
                      why_none=f"no rung writes {title}: it is an input, or set by the test")
