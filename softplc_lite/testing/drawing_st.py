"""A failure's drawing of a Structured Text routine (docs/testing.md,
"Structured Text"): the lines of the text that write the failing address,
not the rungs the translation made of them (logix/st_routine.py), which an
ST user never wrote.

A writer rung stands for its line (ladder/ast.py ``Listing.rung_lines``),
each line once; the rungs before the routine's first statement (those that
clear ``[:=]`` destinations on the first scan) stand for none. Each line
comes with the heads of the IF, ELSIF, ELSE, CASE arm, FOR or WHILE it
sits in, so that the line reads with the condition it runs under: an arm's
extent is found from its rungs, from its test (the rung whose JMP skips the
arm) to the label that JMP lands on. A REPEAT's body has no head line (its
test is at its end) and the CASE line itself has no rung of its own when
its selector is a tag: the arm's line shows the selector's value instead.
The lines are drawn by the watch view's StExcerpt (watch/st_view.py): the
routine's line numbers, the live values of the tags on each line, ``>`` on
the lines that write the address.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from ..ladder.ast import ProgramFile, walk
from ..watch.st_view import StExcerpt, StLines

_ELSE = re.compile(r"\s*ELSE\b", re.IGNORECASE)


def line_places(files, places: Iterable[tuple[int, int]]) -> list[tuple[int, int]]:
    """``places`` ((program file, rung) pairs) with the rungs of an ST
    file's (``files[n].listing`` not None) one line kept once, as its first
    rung, and the rungs of no line left out; other files' as they are."""
    out, seen = [], set()
    lines: dict[int, StLines] = {}
    for number, rung in places:
        pfile = files.get(number)
        if pfile is None or pfile.listing is None:
            out.append((number, rung))
            continue
        st = lines.setdefault(number, StLines(pfile))
        line = st.line_of(rung)
        if rung not in st.rungs.get(line, ()) or (number, line) in seen:
            continue
        seen.add((number, line))
        out.append((number, rung))
    return out


def line_of(pfile: ProgramFile, rung: int) -> int:
    """The line (from 0) of an ST file's rung ``rung``."""
    return StLines(pfile).line_of(rung)


def heads(pfile: ProgramFile) -> list[tuple[int, int, int]]:
    """(first rung, past the last rung, head line) of each arm of the file
    whose extent its rungs show: an IF's, ELSIF's, CASE label's, FOR's and
    WHILE's body (after its test rung, up to its JMP's label), an ELSE's
    (from its label rung up to the label the arm before it jumps to)."""
    labels: dict[object, int] = {}
    jumps: dict[int, object] = {}
    for k, rung in enumerate(pfile.rungs):
        for ins in walk(rung.elements):
            name = getattr(ins, "mnemonic", None)
            if name in ("LBL", "JMP") and getattr(ins, "operands", ()):
                value = getattr(ins.operands[0], "value", None)
                if name == "LBL":
                    labels.setdefault(value, k)
                else:
                    jumps[k] = value
    listing = pfile.listing
    out = []
    for arm in listing.arms:
        if arm.taken_when is False:
            first, test = arm.rung + 1, arm.rung
            line = arm.line
        elif arm.taken_when is None:
            first, test = arm.rung, arm.rung - 1
            line = _else_line(pfile, arm)
        else:
            continue  # a REPEAT's test, or an IF's "no arm": no body of its own
        end = labels.get(jumps.get(test), -1)
        if end >= first:
            out.append((first, end, line))
    return out


def _else_line(pfile: ProgramFile, arm) -> int:
    """The line an ELSE starts: the nearest line at or before its body's
    first that begins with ELSE, after the last test's line; the body's
    first line when none does (a choice: ELSE written after another word on
    its line is not looked for)."""
    lines = pfile.listing.lines
    body = pfile.listing.rung_lines[arm.rung] if arm.rung < len(pfile.listing.rung_lines) else arm.line
    for index in range(min(body, len(lines) - 1), arm.line, -1):
        if _ELSE.match(lines[index][1]):
            return index
    return body


def excerpt(pfile: ProgramFile, rungs: Iterable[int], table, names, forced=frozenset()) -> StExcerpt:
    """The lines of ``rungs`` (writers of one address, in ``pfile``, made
    from ST) and the heads of the arms they sit in, drawn with ``table``'s
    values; the writers' lines marked ``>``."""
    st = StLines(pfile)
    writers = {st.line_of(k) for k in rungs}
    spans = heads(pfile)
    shown = set(writers)
    for k in rungs:
        shown.update(line for first, end, line in spans if first <= k < end)
    return StExcerpt(pfile, table, names, shown, writers, forced)
