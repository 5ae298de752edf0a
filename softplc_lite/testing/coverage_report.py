"""Reporters of a Coverage (testing/coverage.py): the figures per program
file, and the terminal summary ``softplc test --coverage`` prints.

The figures (docs/testing.md "Coverage"): a rung counts once for having run
("Rungs") and twice for its outcomes, true and false ("Rung T/F"); a leg
once, powered; a condition twice, seen true and seen false; an output twice,
on and off. "Total" is everything covered over everything there is, a rung
as a line and every outcome as a branch, as coverage.py's total counts
statements and branches together; ``--fail-under`` compares it exactly (not
the rounded figure shown).

A file made from Structured Text counts its statements instead of rungs
(a statement once, its first rung ran: "Statements") and the arms of its
IFs, CASEs and loops instead of rung outcomes, legs, conditions and
outputs (an arm once, taken: "Branches"; testing/coverage_st.py).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from rich import box
from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

from . import coverage_st
from .coverage import Coverage, FileInfo
from .coverage_outcomes import rung_outcomes


@dataclass
class Figures:
    """Covered and total counts of one program file (or of all of them)."""

    rungs: int = 0
    rungs_run: int = 0
    outcomes: int = 0  # rung true/false: 2 a rung
    outcomes_seen: int = 0
    legs: int = 0
    legs_powered: int = 0
    conditions: int = 0  # 2 a condition instruction: true and false
    conditions_seen: int = 0
    outputs: int = 0  # 2 an output instruction: on and off
    outputs_seen: int = 0
    statements: int = 0  # Structured Text: 1 a statement, run
    statements_run: int = 0
    arms: int = 0  # Structured Text: 1 an arm of an IF, CASE or loop, taken
    arms_taken: int = 0

    def add(self, other: "Figures") -> None:
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))

    @property
    def branches(self) -> int:
        """Every outcome (rung true/false, legs, conditions, outputs; the arms
        of Structured Text): a report's branches."""
        return self.outcomes + self.legs + self.conditions + self.outputs + self.arms

    @property
    def branches_seen(self) -> int:
        return self.outcomes_seen + self.legs_powered + self.conditions_seen + self.outputs_seen + self.arms_taken

    @property
    def lines(self) -> int:
        """What a report counts as lines: rungs, and Structured Text's statements."""
        return self.rungs + self.statements

    @property
    def lines_run(self) -> int:
        return self.rungs_run + self.statements_run

    @property
    def covered(self) -> int:
        return self.lines_run + self.branches_seen

    @property
    def total(self) -> int:
        return self.lines + self.branches

    @property
    def percent(self) -> float:
        return 100.0 if self.total == 0 else 100.0 * self.covered / self.total

    def below(self, percent: float) -> bool:
        """Exact: ``covered / total < percent / 100`` (no rounding)."""
        return self.covered * 100 < percent * self.total


# Figures' (total, covered) fields for each kind of outcome: the rung's own
# (true, false), then by the kind of element it is about.
_FIELDS = {None: ("outcomes", "outcomes_seen"), "branch": ("legs", "legs_powered"),
           "condition": ("conditions", "conditions_seen"), "output": ("outputs", "outputs_seen")}


def file_figures(cov: Coverage, info: FileInfo) -> Figures:
    """The figures of one program file, from the outcomes coverage_outcomes
    lists (the ones that can happen), so every report counts the same."""
    fig = Figures()
    if info.listing is not None:
        for s in coverage_st.statements(cov, info):
            fig.statements += 1
            fig.statements_run += s.covered
        for a in coverage_st.arms(cov, info):
            fig.arms += 1
            fig.arms_taken += a.covered
        return fig
    for rung in info.rungs:
        fig.rungs += 1
        fig.rungs_run += cov.executed(rung.key)
        for outcome in rung_outcomes(cov, rung):
            total, seen = _FIELDS[None if outcome.element is None else outcome.element.kind]
            setattr(fig, total, getattr(fig, total) + 1)
            setattr(fig, seen, getattr(fig, seen) + outcome.covered)
    return fig


def figures(cov: Coverage) -> tuple[dict[int, Figures], Figures]:
    """Per program file (by number) and the total of all of them."""
    per_file = {n: file_figures(cov, cov.files[n]) for n in sorted(cov.files)}
    total = Figures()
    for fig in per_file.values():
        total.add(fig)
    return per_file, total


def percent_text(covered: int, total: int) -> str:
    """Whole percent, as coverage.py shows them: 100% only when all is
    covered, 0% only when nothing is."""
    if total == 0 or covered == total:
        return "100%"
    if covered == 0:
        return "0%"
    return f"{min(max(round(100 * covered / total), 1), 99)}%"


def file_label(info: FileInfo) -> str:
    return f"{info.number} {info.name}" if info.name else str(info.number)


def summary_table(cov: Coverage) -> Table:
    """One row a program file; the Statements and Branches columns only when
    a file is Structured Text, each file's row filled in its own columns."""
    per_file, total = figures(cov)
    ladder = any(cov.files[n].listing is None for n in per_file)
    text = any(cov.files[n].listing is not None for n in per_file)
    table = Table(box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False, title=None)
    table.add_column("File")
    table.add_column("Source")
    columns = []
    if ladder or not text:
        columns += [("Rungs", "rungs_run", "rungs"), ("Rung T/F", "outcomes_seen", "outcomes"),
                    ("Legs", "legs_powered", "legs"), ("Conditions", "conditions_seen", "conditions"),
                    ("Outputs", "outputs_seen", "outputs")]
    if text:
        columns += [("Statements", "statements_run", "statements"), ("Branches", "arms_taken", "arms")]
    for name, _, _ in columns:
        table.add_column(name, justify="right")
    table.add_column("Total", justify="right")

    def row(label, source, fig: Figures, st: bool | None):
        cells = []
        for name, seen, of in columns:
            mine = st is None or (name in ("Statements", "Branches")) == st
            cells.append(f"{getattr(fig, seen)}/{getattr(fig, of)}" if mine else "")
        table.add_row(label, source, *cells, percent_text(fig.covered, fig.total))
    for number, fig in per_file.items():
        info = cov.files[number]
        row(file_label(info), Path(info.source).name, fig, info.listing is not None)
    if len(per_file) > 1:
        row("TOTAL", "", total, None)
    return table


def missing_lines(cov: Coverage) -> list[str]:
    """Under the table, for each Structured Text file with something not
    covered: its statements never run and its arms never taken, by the
    routine's own line numbers (as the mutants and the watch view number
    them), as coverage.py's report shows missing lines."""
    out = []
    for number in sorted(cov.files):
        info = cov.files[number]
        if info.listing is None:
            continue
        parts = []
        never = list(dict.fromkeys(coverage_st.routine_line(info, s.line)
                                   for s in coverage_st.statements(cov, info) if not s.covered))
        if never:
            parts.append(f"statements never run: {'line' if len(never) == 1 else 'lines'} "
                         + ", ".join(map(str, never)))
        missed = [a for a in coverage_st.arms(cov, info) if not a.covered]
        if missed:
            parts.append("arms never taken: " + ", ".join(
                f"{a.arm.label} (line {coverage_st.routine_line(info, a.line)})" for a in missed))
        if parts:
            out.append(f"{file_label(info)}: " + "; ".join(parts))
    return out


def print_summary(cov: Coverage, console: Console) -> None:
    """The table at its natural width, however narrow the terminal: a
    wrapped row of figures reads worse than a long line."""
    table = summary_table(cov)
    width = Measurement.get(console, console.options.update_width(10_000), table).maximum
    narrow = console.width
    console.width = max(width, narrow)
    try:
        console.print(table)
        for line in missing_lines(cov):
            console.print(line, highlight=False, markup=False, soft_wrap=True)
    finally:
        console.width = narrow
