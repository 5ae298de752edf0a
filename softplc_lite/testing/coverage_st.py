"""Coverage of a program file made from Structured Text (its ladder/ast.py
``Listing``: logix/st_routine.py): what the rungs the text became did,
read as statements and arms of the text (docs/testing.md, "Structured
Text").

- A statement is covered when its first rung ran (``listing.statements``).
- An arm of an IF, CASE or loop is covered as ``listing.arms`` says: taken
  when its test rung ran with the outcome ``taken_when`` (a test that did
  not jump: False), or, ``taken_when`` None (an ELSE), when its label rung
  ran at all.

The measurement is the rungs' own (testing/coverage.py counts every rung
of the file as it counts a ladder file's); this module only reads it, for
every reporter alike.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..ladder.ast import Arm
from .coverage import Coverage, FileInfo


@dataclass(frozen=True)
class Statement:
    rung: int  # its first rung
    line: int  # its line in the export
    column: int
    scans: int  # scans its first rung ran in

    @property
    def covered(self) -> bool:
        return self.scans > 0


@dataclass(frozen=True)
class ArmOutcome:
    index: int  # its place in the file's arms (the order of the text)
    arm: Arm
    line: int  # its line in the export
    column: int
    count: int  # scans it was taken in
    ran: bool  # its test rung ran at all (an ELSE: always, its count says whether it was taken)

    @property
    def covered(self) -> bool:
        return self.count > 0

    @property
    def missing(self) -> str:
        """What the annotated listing says of it when it was never taken."""
        return f"never taken: {self.arm.label}" + (" (every test false)" if self.arm.label == "no arm" else "")


def statements(cov: Coverage, info: FileInfo) -> list[Statement]:
    """The file's statements in rung order (a statement nested in an IF
    comes after the IF's test)."""
    listing = info.listing
    found = []
    for rung in sorted(set(listing.statements)):
        pos = _pos(info, rung)
        found.append(Statement(rung, pos[0], pos[1], cov.scans((info.number, rung))))
    return found


def arms(cov: Coverage, info: FileInfo) -> list[ArmOutcome]:
    found = []
    for k, arm in enumerate(info.listing.arms):
        t, f = cov.rungs.get((info.number, arm.rung), (0, 0))
        count = t + f if arm.taken_when is None else t if arm.taken_when else f
        if arm.taken_when is None:
            line, column = _else_pos(info, arm)
        else:
            line, column = _line_pos(info, arm.line)
            if arm.rung < len(info.rungs) and info.rungs[arm.rung].line == line:
                column = info.rungs[arm.rung].column
        # An ELSE has no test of its own: "not reached" is not told apart from "not taken".
        found.append(ArmOutcome(k, arm, line, column, count, t + f > 0 or arm.taken_when is None))
    return found


def lines(cov: Coverage, info: FileInfo) -> list[tuple[int, int, list[ArmOutcome]]]:
    """For the file formats (testing/coverage_formats.py): each line of the
    export where a statement starts or an arm is tested, in line order, with
    its hits (the scans of the first rung on it: the line's first statement
    or test) and its arms."""
    first: dict[int, int] = {}  # line -> its first rung
    for s in statements(cov, info):
        first[s.line] = min(first.get(s.line, s.rung), s.rung)
    by_line: dict[int, list[ArmOutcome]] = {}
    for a in arms(cov, info):
        by_line.setdefault(a.line, []).append(a)
        first[a.line] = min(first.get(a.line, a.arm.rung), a.arm.rung)
    return [(line, cov.scans((info.number, first[line])), by_line.get(line, [])) for line in sorted(first)]


def _pos(info: FileInfo, rung: int) -> tuple[int, int]:
    r = info.rungs[rung]
    return r.line, r.column


def routine_line(info: FileInfo, line: int) -> int:
    """The routine's own number (from 1, as Studio 5000's editor and the
    watch view number them) of the export's line ``line``."""
    for k, (pos, _) in enumerate(info.listing.lines):
        if pos.line == line:
            return k + 1
    return 0


def _else_pos(info: FileInfo, arm: Arm) -> tuple[int, int]:
    """Where an ELSE is: the word ELSE on the lines from the last test's
    (``arm.line``) to its body's first (its label rung's), the nearest to
    the body; the body's start when the text is not found there."""
    listing = info.listing
    body = listing.rung_lines[arm.rung] if arm.rung < len(listing.rung_lines) else arm.line
    for index in range(min(body, len(listing.lines) - 1), arm.line - 1, -1):
        pos, text = listing.lines[index]
        if index == body:  # the body's own line: ELSE before its first statement
            limit = info.rungs[arm.rung].column - pos.column if pos.line == info.rungs[arm.rung].line else len(text)
            text = text[:max(limit, 0)]
        found = list(_ELSE.finditer(_code(text)))
        if found:
            return pos.line, pos.column + found[-1].start()
    return _pos(info, arm.rung) if arm.rung < len(info.rungs) else _line_pos(info, arm.line)


_ELSE = re.compile(r"\bELSE\b", re.IGNORECASE)


def _code(text: str) -> str:
    """A line with its // comment and quoted strings blanked (same length)."""
    text = re.sub(r"'[^']*'|\"[^\"]*\"", lambda m: " " * len(m.group()), text)
    cut = text.find("//")
    return text if cut < 0 else text[:cut] + " " * (len(text) - cut)


def _line_pos(info: FileInfo, index: int) -> tuple[int, int]:
    """Export line and column where listing line ``index`` (from 0) begins."""
    listing = info.listing
    if not listing.lines:
        return 0, 0
    pos, text = listing.lines[min(max(index, 0), len(listing.lines) - 1)]
    return pos.line, pos.column + len(text) - len(text.lstrip())
