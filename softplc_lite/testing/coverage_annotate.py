"""The annotated listing: each .lad file of the program as written, every
line behind a two-character gutter, and under a rung line one mark line for
each outcome that never happened, carets under the part of the rung it is
about (coverage.py's annotate, for ladder).

Gutter: ``> `` a rung with every outcome covered, ``! `` a rung with some
not, ``- `` a rung never scanned (nothing else is said of it), two spaces
any other line (comments, declarations, FILE headers). A mark line reads
``  ^^^^^^^ never true``: a condition never seen true (or ``never false``),
an output ``never on`` or ``never off``, a leg ``never powered`` (carets
under the whole leg), the rung ``rung never true`` or ``rung never false``
(one caret at its start).

A program file made from Structured Text is marked by its text's lines
instead (testing/coverage_st.py): the gutter of a line where statements
start or arms are tested says ``> `` all covered, ``! `` something not,
``- `` nothing there ran; a mark line ``^ never run`` under a statement
that never ran on a line where others did, ``^ never taken: ELSIF`` under
an arm never taken (``no arm (every test false)`` for an IF or CASE that
always took one; ``FOR body``, ``WHILE body``, ``REPEAT again`` for a
loop)."""

from __future__ import annotations

import os
import re
from pathlib import Path

from ..textfile import read_text
from . import coverage_st
from .coverage import Coverage, FileInfo, RungInfo
from .coverage_outcomes import rung_outcomes

BRANCH_WORDS = {"BST", "NXB", "BND", "SOR", "EOR"}


def _span(text: str, start: int, stop: int) -> tuple[int, int]:
    """Columns [start, end) of one instruction as written from ``start``
    (0-based) up to where the next element begins: the neutral form's
    ``MNEMONIC(...)``, or the mnemonic form's words before a branch word."""
    part = text[start:stop]
    if "(" in part:
        return start, start + part.rindex(")") + 1 if ")" in part else start + len(part.rstrip())
    words = []
    for m in re.finditer(r"\S+", part):
        if m.group().upper() in BRANCH_WORDS or m.group() in ("[", ",", "]", ";"):
            break
        words.append(m)
    return (start, start + words[-1].end()) if words else (start, start + 1)


def _marks(cov: Coverage, rung: RungInfo, lines: list[str]) -> dict[int, list[str]]:
    """Line number -> its mark lines (without the gutter)."""
    spans = {}  # element index -> (line, start, end), 0-based columns
    for el in rung.elements:
        text = lines[el.line - 1] if 0 < el.line <= len(lines) else ""
        later = [c - 1 for line, c in rung.starts if line == el.line and c > el.column]
        spans[el.index] = (el.line, *_span(text, el.column - 1, min(later) if later else len(text)))
    marks: dict[int, list[str]] = {}
    for o in rung_outcomes(cov, rung):
        if o.covered:
            continue
        if o.element is None:
            line, start, end = rung.line, rung.column - 1, rung.column
        elif o.leg is not None:
            members = [spans[i] for i in o.element.leg_ranges[o.leg] if i in spans]
            line, start, end = members[0] if members else spans[o.element.index]
            end = max([e for ln, _, e in members if ln == line] + [end])
        else:
            line, start, end = spans[o.element.index]
        marks.setdefault(line, []).append((start, " " * start + "^" * max(end - start, 1) + " " + o.missing))
    return {line: [text for _, text in sorted(ms, key=lambda m: m[0])] for line, ms in marks.items()}


def annotate_source(cov: Coverage, source: str) -> str:
    """The annotated listing of one .lad file."""
    lines = read_text(source).split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    rungs_at: dict[int, list[RungInfo]] = {}
    marks: dict[int, list[str]] = {}
    gutters: dict[int, str] = {}  # Structured Text lines
    for info in cov.files.values():
        if os.path.abspath(info.source) != os.path.abspath(source):
            continue
        if info.listing is not None:
            _text_marks(cov, info, gutters, marks)
            continue
        for rung in info.rungs:
            rungs_at.setdefault(rung.line, []).append(rung)
            if cov.executed(rung.key):
                for line, ms in _marks(cov, rung, lines).items():
                    marks.setdefault(line, []).extend(ms)
    out = []
    for number, text in enumerate(lines, 1):
        rungs = rungs_at.get(number, [])
        if number in gutters:
            gutter = gutters[number]
        elif not rungs:
            gutter = "  "
        elif not all(cov.executed(r.key) for r in rungs):
            gutter = "- "
        elif marks.get(number):
            gutter = "! "
        else:
            gutter = "> "
        out.append((gutter + text).rstrip())
        out += ["  " + m for m in marks.get(number, [])]
    return "\n".join(out) + "\n"


def _text_marks(cov: Coverage, info: FileInfo, gutters: dict[int, str], marks: dict[int, list[str]]) -> None:
    """The gutters and mark lines of a Structured Text file's lines."""
    found: dict[int, list[tuple[int, str]]] = {}  # line -> (column from 0, its mark)
    ran: dict[int, list[bool]] = {}  # line -> whether each statement and arm test there ran
    for s in coverage_st.statements(cov, info):
        ran.setdefault(s.line, []).append(s.covered)
        if not s.covered:
            found.setdefault(s.line, []).append((s.column, "never run"))
    for a in coverage_st.arms(cov, info):
        ran.setdefault(a.line, []).append(a.ran)
        if not a.covered:
            found.setdefault(a.line, []).append((a.column, a.missing))
    for line, flags in ran.items():
        if not any(flags):
            gutters[line] = "- "  # nothing there ran: nothing else is said of it
            continue
        ms = found.get(line, [])
        gutters[line] = "! " if ms else "> "
        for column, text in sorted(ms):
            marks.setdefault(line, []).append(" " * max(column - 1, 0) + "^ " + text)


def annotate(cov: Coverage, directory: str | Path) -> list[Path]:
    """Write ``DIRECTORY/NAME.lad.cover`` for each .lad file of the program;
    returns the paths written."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for source in sorted({os.path.abspath(info.source) for info in cov.files.values()}):
        if not os.path.isfile(source):  # a file the program made itself (a Logix app's continuous task)
            continue
        path = directory / (Path(source).name + ".cover")
        path.write_text(annotate_source(cov, source), encoding="utf-8")
        written.append(path)
    return written
