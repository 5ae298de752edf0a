"""Rungs drawn as an online ladder editor draws them: rails, contacts,
coils, boxes and branches, each operand with its current value, and power
flow in colour (power.py says what is energized).

A rung at 64 columns (I:0/0 forced, a timer timing)::

       Rung 0
        Run the timer while Start is held and B3/1 or not B3/2.
    | Start                                                        |
    | I:0/0    B3/1                          +-TON---------------+ |
    |--] [---+-] [--+------------------------|T4:0 base 0.01     |-|
    |  1 F   |  0   |                        |EN TT . PRE 5 ACC 3| |
    |        | B3/2 |                        +-------------------+ |
    |        +-]/[--+                                              |
    |           0                                                  |

* the header line: ``>`` when selected, ``*`` with a breakpoint, the rung
  number; then the rung comment (dim), reflowed to the width (blank lines
  separate paragraphs), and a red ``! ...`` line per address fault;
* a contact or coil has its symbol (if the program declares one; a bit of
  a named element is named after it, ``Reply/DN``) and its address above
  it, its bit value (and ``F`` when forced) below it;
* every other instruction is a box: the mnemonic in its top border, then
  its operands (``ADDR=value``, ``Symbol(ADDR)=value``, constants with the
  operand's name; compares, math and moves as formulas,
  ``N7:0=5 + 1 -> N7:1=6``), then, for a timer, counter or control
  element, its status bits (set ones by name, clear ones ``.``) and words
  (``EN DN . . LEN 255 POS 2``), live from the table;
* branches are legs stacked between ``+`` connectors; output instructions
  (the rung's tail of outputs) sit against the right rail;
* a rung wider than the space wraps between elements: the wire ends with
  ``>>`` at the right and the next row starts with ``>>``; a branch too wide
  for a row wraps inside its legs the same way, and a box's contents wrap
  inside the box. Nothing is cut off;
* a branch nested deeper than MAX_DEPTH levels, or left too few columns
  for its legs (MIN_LEG), is one ``BST`` box saying what it holds
  (``2 legs, 12 levels, 13 instructions``), with its power;
* colour: energized wires, true instructions and energized outputs bold
  green, faults bold red, ``F`` yellow. Plain text shows values, not power.

Layout works on blocks: lines of (text, style) runs, all one width, with
the row the rung wire runs through (``wire``), composed side by side
(series) and stacked (branches, wrapped rows). Laying out a rung takes
time linear in its size (times the nesting depth drawn, at most
MAX_DEPTH), and a long rung is laid out only as far as it is drawn (see
``_Layout`` in layout.py; the pieces are drawn by cells.py).
"""

from __future__ import annotations

import copy
import io
import itertools
from collections.abc import Callable, Iterable, Mapping

from rich.console import Console, ConsoleOptions, RenderResult
from rich.segment import Segment
from rich.style import Style
from rich.text import Text

from ..datatable import DataTable
from ..ladder.ast import (
    ProgramFile,
    Rung,
)
from ..ladder.instructions import BUILTIN, InstructionSet
from .power import Power, rung_power
from .cells import (  # the styles are part of this module's interface (tests, the screen)
    BREAKPOINT, COMMENT, COMMENT_INDENT, ENERGIZED, FAULT, FORCED, HEADER, SELECTED, Line, _Context,
    _SymbolNames, _runs,
)

__all__ = ["BREAKPOINT", "COMMENT", "ENERGIZED", "FAULT", "FORCED", "HEADER", "SELECTED", "ProgramFileView",
           "RungView"]
from .layout import _Layout



# -- renderables ------------------------------------------------------------------------------


def _segments(line: Line) -> Iterable[Segment]:
    for text, style in _runs(line):
        if text:
            yield Segment(text, style)


def _paragraphs(comment: str) -> list[str]:
    """The comment's paragraphs (blank lines separate them), each line
    break inside one a space: the view wraps to its own width."""
    paragraphs, current = [], []
    for line in comment.split("\n"):
        if line.strip():
            current.append(line.strip())
        elif current:
            paragraphs.append(" ".join(current))
            current = []
    if current:
        paragraphs.append(" ".join(current))
    return paragraphs


def _clipped(text: str, limit: int) -> str:
    """The start of ``text`` (about ``limit`` characters, cut between words):
    wrapped, it gives the same first lines as the whole text as long as
    ``limit`` is two lines more than they hold."""
    if len(text) <= limit:
        return text
    cut = text.rfind(" ", 0, limit)
    return text[:cut if cut > 0 else limit]


def _wrapped(console: Console, text: str, width: int, indent: int, style: Style) -> Iterable[list[Segment]]:
    """``text`` wrapped to ``width``, indented: one list of segments a line."""
    for line in Text(text, style=style).wrap(console, max(10, width - indent)):
        line.rstrip()
        yield [Segment(" " * indent), *line.render(console)]


class RungView:
    """One rung, drawn with the data table's current values.

    ``number`` is the rung's number in its file (shown in the header);
    ``power`` a precomputed :func:`power.rung_power` (computed at each
    render when None); ``symbols`` the program's symbols (name ->
    SymbolDecl, Address or address text); ``selected`` marks the rung
    ``>``, ``breakpoint`` ``*``; ``forced`` the forced addresses (canonical
    text, e.g. ``{"I:0/0"}``), marked ``F``; ``tli_status`` shows the
    CONTROL status line of plug-in module instructions (COMSCAN...);
    ``instructions`` the app's instruction set (``app.instructions``), for
    module instructions' operand names; ``max_lines``: draw only the top
    of the rung, that many lines (a long rung is then laid out only as far
    as it is drawn); ``comments``: "full", "first line" (of the comment,
    ``...`` marking the rest) or "hidden"."""

    def __init__(self, rung: Rung, number: int, table: DataTable, power: Power | None = None,
                 symbols: Mapping[str, object] | None = None, selected: bool = False, breakpoint: bool = False,
                 forced=frozenset(), tli_status: bool = True, instructions: InstructionSet | None = None,
                 max_lines: int | None = None, comments: str = "full") -> None:
        self.rung = rung
        self.number = number
        self.table = table
        self.power = power
        self.names = symbols if hasattr(symbols, "replaces_address") else _SymbolNames(symbols)
        self.selected = selected
        self.breakpoint = breakpoint
        self.forced = forced
        self.tli_status = tli_status
        self.instructions = instructions or BUILTIN
        self.max_lines = max_lines
        self.comments = comments

    def _first_comment_line(self, console: Console, width: int) -> list[Segment] | None:
        """The comment's first line, cut to one screen line; `` ...`` when
        there is more of it."""
        lines = [line.strip() for line in (self.rung.comment or "").split("\n") if line.strip()]
        if not lines:
            return None
        text = Text(lines[0] + (" ..." if len(lines) > 1 else ""), style=COMMENT, no_wrap=True, overflow="ellipsis")
        text.truncate(max(10, width - COMMENT_INDENT), overflow="ellipsis")
        return [Segment(" " * COMMENT_INDENT), *text.render(console)]

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        lines = self._lines(console, max(options.max_width, 20))
        if self.max_lines is not None:
            lines = itertools.islice(lines, max(self.max_lines, 0))
        for line in lines:
            yield from line
            yield Segment.line()

    def _lines(self, console: Console, width: int) -> Iterable[list[Segment]]:
        power = self.power if self.power is not None else rung_power(self.rung, self.table)
        ctx = _Context(self.table, power, self.names, self.forced, self.instructions, self.tli_status)
        yield [Segment(">" if self.selected else " ", SELECTED if self.selected else None),
               Segment("*" if self.breakpoint else " ", BREAKPOINT),
               Segment(f" Rung {self.number}", SELECTED if self.selected else HEADER)]
        used = 1
        if self.comments == "first line":
            first = self._first_comment_line(console, width)
            if first is not None and (self.max_lines is None or used < self.max_lines):
                yield first
                used += 1
        full = self.rung.comment if self.comments == "full" else None
        for paragraph in _paragraphs(full or ""):
            if self.max_lines is not None:  # wrap no more of a long comment than is drawn
                if used >= self.max_lines:
                    return
                paragraph = _clipped(paragraph, (self.max_lines - used + 2) * width)
            for line in _wrapped(console, paragraph, width, COMMENT_INDENT, COMMENT):
                yield line
                used += 1
        for fault in dict.fromkeys(power.faults()):
            for line in _wrapped(console, f"! {fault}", width, COMMENT_INDENT, FAULT):
                yield line
                used += 1
        if self.max_lines is not None and used >= self.max_lines:
            return
        rest = None if self.max_lines is None else self.max_lines - used
        for line in _Layout(ctx, self.rung.elements).rung(width, rest).lines:
            yield list(_segments(line))


class ProgramFileView:
    """Consecutive rungs of a program file from rung ``first``, as many as
    fit in ``height`` lines (all of them when None; a first rung taller than
    ``height`` is cut to it; the lines left under the last whole rung show
    the top of the next one). After rendering, ``drawn`` is how many rungs
    were drawn and ``last_drawn`` the number of the last one (None if none).

    ``selected`` is the selected rung's number; ``breakpoints`` holds rung
    numbers or (file, rung) pairs; the rest as for :class:`RungView`."""

    def __init__(self, pfile: ProgramFile, table: DataTable, symbols: Mapping[str, object] | None = None,
                 first: int = 0, selected: int | None = None, breakpoints=frozenset(), forced=frozenset(),
                 height: int | None = None, tli_status: bool = True,
                 instructions: InstructionSet | None = None,
                 power_of: Callable[[Rung, DataTable], Power] = rung_power, comments: str = "full") -> None:
        self.pfile = pfile
        self.table = table
        self.names = symbols if hasattr(symbols, "replaces_address") else _SymbolNames(symbols)
        self.first = first
        self.selected = selected
        self.breakpoints = breakpoints
        self.forced = forced
        self.height = height
        self.tli_status = tli_status
        self.instructions = instructions
        self.power_of = power_of
        self.comments = comments
        self.drawn = 0
        self.last_drawn: int | None = None

    def rung_view(self, number: int, max_lines: int | None = None) -> RungView:
        rung = self.pfile.rungs[number]
        marked = number in self.breakpoints or (self.pfile.number, number) in self.breakpoints
        return RungView(rung, number, self.table, power=self.power_of(rung, self.table), symbols=self.names,
                        selected=number == self.selected, breakpoint=marked, forced=self.forced,
                        tli_status=self.tli_status, instructions=self.instructions, max_lines=max_lines,
                        comments=self.comments)

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        self.drawn, self.last_drawn = 0, None
        height = self.height
        used = 0
        unbounded = options.update(height=None)
        if not self.pfile.rungs:
            yield Segment("   (no rungs)", COMMENT)
            yield Segment.line()
            return
        for number in range(max(0, self.first), len(self.pfile.rungs)):
            # one line more than is left: a rung that gets it does not fit
            room = None if height is None else height - used + 1
            lines = console.render_lines(self.rung_view(number, room), unbounded, pad=False)
            if height is not None and used + len(lines) > height:
                if self.drawn:
                    # fill the rest with the top of the next rung (not counted
                    # as drawn: scrolling brings it fully into view)
                    for line in lines[:height - used]:
                        yield from line
                        yield Segment.line()
                    break
                lines = lines[:height]
            for line in lines:
                yield from line
                yield Segment.line()
            used += len(lines)
            self.drawn += 1
            self.last_drawn = number
            if height is not None and used >= height:
                break

    def rungs_that_fit(self, width: int, height: int | None = None) -> int:
        """How many rungs from ``first`` a render at ``width`` and ``height``
        (default: this view's) would draw; this view is left as it was."""
        probe = copy.copy(self)
        if height is not None:
            probe.height = height
        Console(width=width, color_system=None, file=io.StringIO()).render_lines(probe, pad=False)
        return probe.drawn
