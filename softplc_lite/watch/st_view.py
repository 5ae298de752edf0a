"""A Structured Text routine in the watch view: its text, line by line,
each line with the live values of the tags its statements read or write
and a mark when it ran in the last scan (docs/watch.md, "Watching
Structured Text")::

      1 // Fill the tank; count the overflows
    ●  2 Level := Level + Rate;                     Level=42.5  Rate=2.5
    ●  3 IF Level > 80.0 THEN                       Level=42.5
       4     High := 1;                             High=0
       5     Overflows := Overflows + 1;            Overflows=0
       6 ELSE
    ●  7     High := 0;                             High=0
       8 END_IF;

* the gutter: ``>`` on the selected line, ``*`` on a line with a
  breakpoint, ``●`` (bold green) on a line a rung of which ran in the last
  scan (st_ran.py says how that is known); then the line's number;
* the line numbers are the routine's own, from 1, as Studio 5000's ST
  editor numbers its lines and its Verify names them (a choice: the
  export's ``Line Number`` counts from 0, and the lines of the .L5X file
  itself mean nothing in the editor);
* a line's values are the tags of the rungs made from it (ladder/ast.py
  ``Listing.rung_lines``), named as the ladder view names them (naming.py:
  the tag path in the routine's scope), each once, in the order the
  statement uses them; beside the text when they fit, else under it;
* a line too long for the width is folded, not cut.

:class:`StExcerpt` draws a few chosen lines the same way, for a report
(a failed test's, testing/drawing_st.py).

The rungs are the statements' own: the rung the translation puts first, to
clear ``[:=]`` destinations on the first scan, and a rung that is only a
label a JMP lands on (the end of an IF) belong to no line.
"""

from __future__ import annotations

from collections.abc import Iterable

from rich.cells import cell_len
from rich.console import Console, ConsoleOptions, RenderResult
from rich.segment import Segment
from rich.style import Style

from ..datatable import ValueKind
from ..ladder.ast import AddressRef, ProgramFile, address_refs, walk
from .cells import BREAKPOINT, COMMENT, ENERGIZED, FORCED, SELECTED, value_run

RAN = "●"
VALUE_GAP = 2  # spaces between the text and its values, and between two values
_STRUCTS = (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL)
_LINE_NUMBER = Style(dim=True)
_LANDINGS = {"LBL", "NOP"}  # a rung of only these is where a JMP lands, no statement's work


class StLines:
    """Which rungs of an ST file each line of its text holds: ``rungs[line]``
    (lines from 0; lines without a statement hold none), ``code`` the lines
    that hold some, in order."""

    def __init__(self, pfile: ProgramFile) -> None:
        listing = pfile.listing
        self.pfile = pfile
        self.count = len(listing.lines)
        first = min(listing.statements, default=len(pfile.rungs))
        self.rungs: dict[int, list[int]] = {}
        for rung in range(first, len(pfile.rungs)):
            if not all(getattr(ins, "mnemonic", None) in _LANDINGS for ins in walk(pfile.rungs[rung].elements)):
                self.rungs.setdefault(listing.rung_lines[rung], []).append(rung)
        self.code = sorted(self.rungs)

    def line_of(self, rung: int) -> int:
        lines = self.pfile.listing.rung_lines
        return lines[rung] if 0 <= rung < len(lines) else 0

    def normal(self, rung: int) -> int:
        """``rung``, or the first rung of the first line with a statement at
        or after its line (the last one before it when there is none)."""
        if rung in self.rungs.get(self.line_of(rung), ()):
            return rung
        return self.at_line(self.line_of(rung))

    def at_line(self, line: int) -> int:
        """The first rung of line ``line`` or of the next line holding one."""
        after = [k for k in self.code if k >= line]
        chosen = after[0] if after else (self.code[-1] if self.code else None)
        return self.rungs[chosen][0] if chosen is not None else 0

    def top_for(self, rung: int) -> int:
        """The first line to show ``rung``'s line at the top: the lines
        before it that hold no statement (its comment) come with it."""
        line = self.line_of(rung)
        before = [k for k in self.code if k < line]
        return before[-1] + 1 if before else 0

    def step(self, rung: int, delta: int) -> int:
        """The first rung of the line holding statements ``delta`` such lines
        from ``rung``'s line (↑/↓ move by lines, not by rungs)."""
        if not self.code:
            return rung
        line = self.line_of(self.normal(rung))
        k = self.code.index(line) if line in self.code else 0
        return self.rungs[self.code[max(0, min(len(self.code) - 1, k + delta))]][0]


def st_lines(pfile: ProgramFile | None, known: StLines | None = None) -> StLines | None:
    """The lines of ``pfile`` when it was made from Structured Text, else
    None; ``known`` is returned when it is that file's already."""
    if pfile is None or pfile.listing is None:
        return None
    return known if known is not None and known.pfile is pfile else StLines(pfile)


def goto_line(session, lines: StLines, text: str) -> None:
    """The ``g`` prompt in an ST routine: a line number (from 1)."""
    try:
        line = int(text.strip())
    except ValueError:
        session.message = f"go to line {text.strip()!r}: expected a line number, 1 to {lines.count}"
        return
    session.goto(lines.at_line(max(line, 1) - 1))
    shown = lines.line_of(session.selected) + 1
    session.message = "" if shown == line else f"go to line {line}: at line {shown}, the next line with a statement"


def hit_said(hit, program, naming) -> str:
    """A breakpoint's stop as the message line says it: a line of an ST
    routine by its routine and line number, anything else as Hit says it."""
    pfile = program.files.get(hit.file) if hit.file is not None else None
    if pfile is None or pfile.listing is None or not 0 <= hit.rung < len(pfile.listing.rung_lines):
        return str(hit)
    return f"break: {naming.where(hit.file)} line {pfile.listing.rung_lines[hit.rung] + 1} ran at scan {hit.scan}"


class StView:
    """The text of an ST file from line ``top`` as fits ``height`` rows,
    scrolled so the selected rung's line shows (``scrolled(top)`` is told
    the top it settled on). ``ran``: the rungs that ran in the last scan
    (None: not known, no marks); ``names``: the file's operand names
    (naming.py); ``breakpoints`` (file, rung) pairs; ``forced`` the forced
    addresses' text."""

    def __init__(self, pfile: ProgramFile, lines: StLines, table, names, ran: set[int] | None, selected: int,
                 top: int = 0, height: int | None = None, breakpoints=frozenset(), forced=frozenset(),
                 scrolled=None, marked: frozenset[int] | None = None) -> None:
        self.pfile = pfile
        self.lines = lines
        self.table = table
        self.names = names
        self.ran = ran
        self.selected = selected
        self.top = top
        self.height = height
        self.breakpoints = breakpoints
        self.forced = forced
        self.scrolled = scrolled
        self.marked = marked  # the lines the gutter marks ">" (None: the selected rung's)
        self.last_drawn = None  # the rungs panel's scrolling is this view's own (lines, not rungs)

    # -- one line's parts ---------------------------------------------------------------------
    def values(self, line: int) -> list[list[tuple[str, Style | None]]]:
        """``name=value`` of each tag the line's rungs use, each once."""
        out, seen = [], set()
        rungs = self.pfile.rungs
        for rung in self.lines.rungs.get(line, ()):
            for ins in walk(rungs[rung].elements):
                for op in getattr(ins, "operands", ()):
                    for ref in address_refs(op) if not isinstance(op, AddressRef) else (op,):
                        address = ref.address
                        name = self.names.name(address)
                        if not name or name in seen or address.kind in _STRUCTS or self.hidden(address):
                            continue  # a hidden tag of the translation (a CASE's selector) has no name
                        seen.add(name)
                        item = [(f"{name}=", None), self.value(address)]
                        if str(address) in self.forced:
                            item.append((" F", FORCED))
                        out.append(item)
        return out

    def hidden(self, address) -> bool:
        """A timer's or counter's control word (``T1.CTL``, its bits packed):
        the tag monitor leaves it out too; its members are shown by name."""
        operands = getattr(self.names, "operands", None)
        if operands is None:
            return False
        full = operands.name_of(address, self.names.scope)
        return bool(full) and full.upper().endswith(".CTL")

    def value(self, address) -> tuple[str, Style | None]:
        return value_run(self.table, address)

    def gutter(self, line: int, digits: int) -> list[tuple[str, Style | None]]:
        rungs = self.lines.rungs.get(line, ())
        number = self.pfile.number
        chosen = line in self.marked if self.marked is not None else line == self.lines.line_of(self.selected)
        marked = any((number, r) in self.breakpoints or r in self.breakpoints for r in rungs)
        ran = self.ran is not None and any(r in self.ran for r in rungs)
        return [(">" if chosen else " ", SELECTED if chosen else None), ("*" if marked else " ", BREAKPOINT),
                (RAN if ran else " ", ENERGIZED if ran else None), (" ", None),
                (f"{line + 1:>{digits}} ", SELECTED if chosen else _LINE_NUMBER)]

    def column(self, width: int, digits: int, among: Iterable[int] | None = None) -> int:
        """Where values beside the text start: past the longest line (of
        ``among``, or of all holding a statement), but no further than two
        thirds of the width."""
        longest = max((len(self.text(k)) for k in (self.lines.rungs if among is None else among)), default=0)
        return min(_indent(digits) + longest + VALUE_GAP, width * 2 // 3)

    def text(self, line: int) -> str:
        return self.pfile.listing.lines[line][1].rstrip().expandtabs(4)

    def rows(self, line: int, width: int, digits: int, column: int = 0) -> list[list[tuple[str, Style | None]]]:
        """The screen rows of one line of text: its text folded to the
        width, then its values beside the last row (from ``column`` when
        they fit there) or under it."""
        text = self.text(line)
        indent = _indent(digits)
        room = max(10, width - indent)
        style = COMMENT if text.lstrip().startswith(("//", "(*", "/*")) else None
        pieces = [text[k:k + room] for k in range(0, len(text), room)] or [""]
        rows = [self.gutter(line, digits) + [(pieces[0], style)]]
        rows += [[(" " * indent, None), (piece, style)] for piece in pieces[1:]]
        values = self.values(line)
        if not values:
            return rows
        last = rows[-1]
        used = _width(last)
        together = sum(_width(v) for v in values) + VALUE_GAP * len(values)
        if used + together <= width:
            if column - VALUE_GAP > used and column + together - VALUE_GAP <= width:
                last.append((" " * (column - VALUE_GAP - used), None))
            for item in values:
                last += [(" " * VALUE_GAP, None), *item]
            return rows
        row = [(" " * (indent + VALUE_GAP), None)]
        for item in values:  # under the text, as many a row as fit
            if _width(row) + VALUE_GAP + _width(item) > width and len(row) > 1:
                rows.append(row)
                row = [(" " * (indent + VALUE_GAP), None)]
            row += ([(" " * VALUE_GAP, None)] if len(row) > 1 else []) + item
        rows.append(row)
        return rows

    # -- the whole ---------------------------------------------------------------------------
    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = max(options.max_width, 20)
        count = self.lines.count
        if not count:
            yield Segment("   (no lines)", COMMENT)
            yield Segment.line()
            return
        digits = len(str(count))
        column = self.column(width, digits)
        height = self.height
        top = max(0, min(self.top, count - 1))
        chosen = self.lines.line_of(self.selected)
        if chosen < top:
            top = chosen
        if height is not None:  # the chosen line's rows all in view, scrolling down as little as needed
            while top < chosen and sum(len(self.rows(k, width, digits, column)) for k in range(top, chosen + 1)) > height:
                top += 1
        if self.scrolled is not None:
            self.scrolled(top)
        used = 0
        for line in range(top, count):
            for row in self.rows(line, width, digits, column):
                if height is not None and used >= height:
                    return
                yield from _segments(row)
                yield Segment.line()
                used += 1


class StExcerpt:
    """Some lines of an ST file, drawn as :class:`StView` draws them (the
    routine's line numbers, each line's values beside or under it), for a
    report that shows a few lines rather than a screen: ``lines`` (from 0)
    in order, ``marked`` those the gutter marks ``>``; ``table``, ``names``
    and ``forced`` as StView's."""

    def __init__(self, pfile: ProgramFile, table, names, lines: Iterable[int], marked: Iterable[int] = (),
                 forced=frozenset()) -> None:
        self.view = StView(pfile, StLines(pfile), table, names, None, -1, forced=forced, marked=frozenset(marked))
        self.shown = sorted(set(lines))

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = max(options.max_width, 20)
        digits = len(str(max(self.shown, default=0) + 1))
        column = self.view.column(width, digits, self.shown)
        for line in self.shown:
            for row in self.view.rows(line, width, digits, column):
                yield from _segments(row)
                yield Segment.line()


def _indent(digits: int) -> int:
    """The gutter's width: the marks, a space, the line number and a space."""
    return 4 + digits + 1


def _width(row: Iterable[tuple[str, Style | None]]) -> int:
    return sum(cell_len(text) for text, _ in row)


def _segments(row) -> Iterable[Segment]:
    for text, style in row:
        if text:
            yield Segment(text, style)
