"""The report of a mutation run: each surviving mutant with the change
(``XIC Start -> XIO Start``), where it is, and its rung drawn as the watch
view draws it (the mutated rung, or the deleted one), then the score and
the counts of every outcome."""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..app import AppError
from ..watch.rungs import RungView
from .mutants import Mutant
from .mutation import (INVALID, KILLED, NOT_COVERED, OUT_OF_TIME, STATUSES, SURVIVED, TIMED_OUT, MutationError,
                       MutationReport, run_mutation)
from .plc import PLC
from .scenario import ScenarioErrors


def survivor_view(report: MutationReport, mutant: Mutant) -> RungView:
    """The rung a surviving mutant changed, drawn at a fresh load's values:
    the mutated rung, or for a deleted rung the original one."""
    number, index = mutant.key
    program = None if mutant.rung is None else mutant.apply(report.source)
    with PLC.load(report.app, program=program) as plc:
        app = plc.runner.app
        rung = app.program.files[number].rungs[index]
        return RungView(rung, index, plc.table, symbols=app.program.symbols, instructions=app.instructions,
                        comments="hidden")


def print_report(report: MutationReport, out: Console, survivors: bool = True) -> None:
    if survivors:
        for mutant, outcome in report.with_status(SURVIVED):
            file = f"file {mutant.key[0]} " if mutant.key[0] != 2 else ""
            out.print(f"[yellow]SURVIVED[/] {escape(str(mutant.pos))}: {file}rung {mutant.key[1]}: "
                      f"[bold]{escape(mutant.description)}[/] ({mutant.operator})")
            out.print(survivor_view(report, mutant))
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
