"""Reporters of a Coverage (testing/coverage.py): the figures per program
file, and the terminal summary ``softplc test --coverage`` prints.

The figures (docs/testing.md "Coverage"): a rung counts once for having run
("Rungs") and twice for its outcomes, true and false ("Rung T/F"); a leg
once, powered; a condition twice, seen true and seen false; an output twice,
on and off. "Total" is everything covered over everything there is, a rung
as a line and every outcome as a branch, as coverage.py's total counts
statements and branches together; ``--fail-under`` compares it exactly (not
the rounded figure shown).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from rich import box
from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

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

    def add(self, other: "Figures") -> None:
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))

    @property
    def branches(self) -> int:
        """Every outcome (rung true/false, legs, conditions, outputs): a report's branches."""
        return self.outcomes + self.legs + self.conditions + self.outputs

    @property
    def branches_seen(self) -> int:
        return self.outcomes_seen + self.legs_powered + self.conditions_seen + self.outputs_seen

    @property
    def covered(self) -> int:
        return self.rungs_run + self.branches_seen

    @property
    def total(self) -> int:
        return self.rungs + self.branches

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
    per_file, total = figures(cov)
    table = Table(box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False, title=None)
    table.add_column("File")
    table.add_column("Source")
    for name in ("Rungs", "Rung T/F", "Legs", "Conditions", "Outputs", "Total"):
        table.add_column(name, justify="right")

    def row(label, source, fig: Figures, **kw):
        table.add_row(label, source, f"{fig.rungs_run}/{fig.rungs}", f"{fig.outcomes_seen}/{fig.outcomes}",
                      f"{fig.legs_powered}/{fig.legs}", f"{fig.conditions_seen}/{fig.conditions}",
                      f"{fig.outputs_seen}/{fig.outputs}", percent_text(fig.covered, fig.total), **kw)
    for number, fig in per_file.items():
        row(file_label(cov.files[number]), Path(cov.files[number].source).name, fig)
    if len(per_file) > 1:
        row("TOTAL", "", total)
    return table


def print_summary(cov: Coverage, console: Console) -> None:
    """The table at its natural width, however narrow the terminal: a
    wrapped row of figures reads worse than a long line."""
    table = summary_table(cov)
    width = Measurement.get(console, console.options.update_width(10_000), table).maximum
    narrow = console.width
    console.width = max(width, narrow)
    try:
        console.print(table)
    finally:
        console.width = narrow
