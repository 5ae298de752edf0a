"""The report of a mutation run: each surviving mutant with the change
(``XIC Start -> XIO Start``), where it is, and its rung drawn as the watch
view draws it (the mutated rung with the change marked, or the deleted
one; a Structured Text mutant's line of text, a caret under the change),
then the score and the counts of every outcome."""

from __future__ import annotations

import itertools

from rich.console import Console, ConsoleOptions, RenderResult
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.style import Style
from rich.table import Table
from rich.text import Text

from ..app import AppError
from ..watch.rungs import RungView
from .mutants import Mutant
from .mutation import (INVALID, KILLED, NOT_COVERED, OUT_OF_TIME, STATUSES, SURVIVED, TIMED_OUT, MutationError,
                       MutationReport, run_mutation)
from .plc import PLC
from .scenario import ScenarioErrors

MARKED = Style(reverse=True, bold=True)


# The most differing characters marked: an in-place change (a contact, a
# latch, a comparison, a constant) differs in a few; more means the layout
# moved (a leg removed) and marks would only scatter over the drawing. Where
# both drawings have wire or border there (a box grown by a character), the
# difference is the layout's, not the change's: not marked.
MARK_MAX = 12
_WIRES = frozenset(" -+|")


class ChangedRung:
    """A surviving mutant's rung drawn as the watch view draws it, the
    characters that differ from the original rung's drawing marked: in
    reverse video, and on a console without colour by a ``^`` line under
    each line that has them."""

    def __init__(self, view: RungView, original: RungView | None) -> None:
        self.view, self.original = view, original

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        lines = console.render_lines(self.view, options, pad=False)
        marks = self._marks(console, options, lines)
        for line, cols in zip(lines, marks):
            text = Text.assemble(*((seg.text, seg.style) for seg in line if not seg.control))
            for col in cols:
                text.stylize(MARKED, col, col + 1)
            yield text
            if cols and console.color_system is None:
                yield Text("".join("^" if k in cols else " " for k in range(max(cols) + 1)))

    def _marks(self, console: Console, options: ConsoleOptions, lines) -> list[set[int]]:
        none = [set() for _ in lines]
        if self.original is None:
            return none
        before = console.render_lines(self.original, options, pad=False)
        if len(before) != len(lines):
            return none
        marks = [{k for k, (a, b) in enumerate(itertools.zip_longest(_plain(x), _plain(y), fillvalue=" "))
                  if a != b and not (a in _WIRES and b in _WIRES)} for x, y in zip(lines, before)]
        return marks if 0 < sum(len(m) for m in marks) <= MARK_MAX else none


def _plain(line) -> str:
    return "".join(seg.text for seg in line if not seg.control)


def survivor_view(report: MutationReport, mutant: Mutant, original: dict | None = None) -> ChangedRung:
    """The rung a surviving mutant changed, drawn at a fresh load's values:
    the mutated rung with its change marked, or for a deleted rung the
    original one. ``original``: a dict this fills with the unmutated app's
    drawing state, to share between the survivors of one report."""
    number, index = mutant.key
    original = {} if original is None else original
    if "program" not in original:
        with PLC.load(report.app) as plc:
            original.update(program=plc.runner.app.program, table=plc.table,
                            instructions=plc.runner.app.instructions)
    program, table, instructions = original["program"], original["table"], original["instructions"]

    def view(rung, table):
        return RungView(rung, index, table, symbols=program.symbols, instructions=instructions, comments="hidden")

    before = view(program.files[number].rungs[index], table)
    if mutant.rung is None:
        return ChangedRung(before, None)
    # loaded, not only checked: loading puts a timer's or counter's preset in the table
    with PLC.load(report.app, program=mutant.apply(report.source)) as plc:
        return ChangedRung(view(plc.runner.app.program.files[number].rungs[index], plc.table), before)


def text_view(report: MutationReport, mutant: Mutant) -> Text:
    """A surviving mutant of Structured Text: the line of the text it is on,
    a caret under where the change is (the routine's listing, as the
    annotated export shows it)."""
    listing = report.source.files[mutant.key[0]].listing
    for pos, line in listing.lines:
        if pos.line == mutant.pos.line:
            column = max(mutant.pos.column - pos.column, 0)
            return Text(f"  {line.rstrip()}\n  {' ' * column}^")
    return Text("")


def print_report(report: MutationReport, out: Console, survivors: bool = True) -> None:
    original: dict = {}
    if survivors:
        for mutant, outcome in report.with_status(SURVIVED):
            pfile = report.source.files[mutant.key[0]]
            if pfile.listing is not None:  # the routine by name, the change by its text's line
                out.print(f"[yellow]SURVIVED[/] {escape(str(mutant.pos))}: {escape(pfile.name or '')} "
                          f"[bold]{escape(mutant.description)}[/] ({mutant.operator})")
                out.print(text_view(report, mutant))
                continue
            file = f"file {mutant.key[0]} " if mutant.key[0] != 2 else ""
            out.print(f"[yellow]SURVIVED[/] {escape(str(mutant.pos))}: {file}rung {mutant.key[1]}: "
                      f"[bold]{escape(mutant.description)}[/] ({mutant.operator})")
            out.print(survivor_view(report, mutant, original))
    uncovered = list(dict.fromkeys(m.key for m, _ in report.with_status(NOT_COVERED)))
    if uncovered:
        out.print(f"[yellow]NOT COVERED[/] rungs the scenarios never executed, their "
                  f"{report.count(NOT_COVERED)} mutants not run: "
                  + ", ".join(escape(_rung_place(report, key)) for key in uncovered))
    for mutant, outcome in report.with_status(TIMED_OUT):
        out.print(f"[red]TIMED OUT[/] {escape(str(mutant.pos))}: {escape(mutant.description)}: "
                  f"{escape(outcome.detail)}")
    table = Table(title=f"mutation testing of {escape(report.app)}", show_header=True, title_justify="left")
    table.add_column("outcome")
    table.add_column("mutants", justify="right")
    styles = {KILLED: "green", SURVIVED: "yellow", TIMED_OUT: "red", OUT_OF_TIME: "red"}
    for status in STATUSES:
        n = report.count(status)
        if n or status in (KILLED, SURVIVED):
            style = styles.get(status, "")
            table.add_row(f"[{style}]{status}[/]" if style else status, str(n))
    out.print(table)
    out.print(score_line(report))


def _rung_place(report: MutationReport, key) -> str:
    number, index = key
    pfile = report.source.files[number]
    pos = pfile.rungs[index].pos
    if pfile.listing is not None:
        line = pfile.listing.rung_lines[index] + 1
        return f"{pos.source}:{pos.line} ({pfile.name} line {line})"
    return f"{pos.source}:{pos.line} (rung {index})" if number == 2 else \
        f"{pos.source}:{pos.line} (file {number} rung {index})"


def score_line(report: MutationReport) -> str:
    score = report.score
    shown = "n/a (no mutant run)" if score is None else f"{score:.1f}%"
    parts = [f"mutation score {shown} ({report.count(KILLED)} killed of "
             f"{report.count(KILLED) + report.count(SURVIVED)})"]
    for status in (NOT_COVERED, INVALID, TIMED_OUT, OUT_OF_TIME):
        if report.count(status):
            parts.append(f"{report.count(status)} {status}")
    parts.append(f"{len(report.mutants)} mutants, {report.scenarios} scenarios, {report.jobs} "
                 f"{'job' if report.jobs == 1 else 'jobs'}, {report.seconds:.1f} s")
    return ", ".join(parts)


OK, CANNOT_RUN, UNDER = "ok", "cannot run", "under"


def mutate_and_report(app: str, out: Console, err, jobs: int | None, budget: float,
                      fail_under: float | None) -> str:
    """``softplc test APP --mutate`` after the scenarios passed: run and
    report. OK; CANNOT_RUN (said on ``err``); UNDER, the score under
    ``fail_under`` (or no score to compare)."""
    try:
        if out.is_terminal:  # a long run shows it is alive; a log or a pipe gets the report only
            with Progress(TextColumn("mutants"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                          console=out, transient=True) as bar:
                task = bar.add_task("mutants", total=None)
                report = run_mutation(app, jobs=jobs, budget=budget,
                                      progress=lambda done, total: bar.update(task, completed=done, total=total))
        else:
            report = run_mutation(app, jobs=jobs, budget=budget)
    except (MutationError, ScenarioErrors, AppError) as e:
        print(str(e), file=err)
        return CANNOT_RUN
    print_report(report, out)
    if fail_under is not None and (report.score is None or report.score < fail_under):
        shown = "no score" if report.score is None else f"{report.score:.1f}%"
        out.print(f"[red]mutation score {shown} is under --fail-under-mutation {fail_under:g}%[/]")
        return UNDER
    return OK
