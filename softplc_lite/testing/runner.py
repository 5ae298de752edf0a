"""Runs scenario files against an app: each scenario on a fresh ``PLC``
(fresh data table, simulated clock, the app's modules as configured), after
the file's setup, scan by scan. A failed expectation ends its scenario and
says what was expected, the actual value, the scan number and the time,
and draws the rungs that write the failing address as they were then
(drawing.py)."""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console, ConsoleOptions, RenderResult
from rich.segment import Segment
from rich.text import Text

from ..errors import LocatedError
from ..ladder.ast import Program
from .coverage import Coverage
from .drawing import RungsAt, writers_at
from .plc import PLC
from .scenario import DeviceCounter, Scenario, ScenarioErrors, ScenarioFile, Step, load_scenarios
from .scenario_devices import counter_errors, open_plc
from .values import value_errors

SCENARIO_GLOB = "tests/*.plctest"


@dataclass
class Failure:
    expectation: str
    actual: object
    scan: int
    time_ms: int
    path: str
    line: int
    address: str
    rungs: RungsAt | None = None  # the rungs that write the address, as they were at the failure
    trend: object | None = None  # a trends.chart.TrendChart of the address up to the failure (failure_trend.py)

    def report(self) -> str:
        return (f"{self.path}:{self.line}: expected {self.expectation}, got {self.actual!r} "
                f"(scan {self.scan}, {self.time_ms / 1000:g} s)")

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        yield Text(self.report(), style="red")  # one line on a soft-wrapping console
        if self.rungs is not None:  # indented under the report, not padded to the width
            for line in console.render_lines(self.rungs, options.update(width=max(options.max_width - 2, 20)),
                                             pad=False):
                yield Segment("  ")
                yield from line
                yield Segment.line()
        if self.trend is not None:
            x = self.trend.x
            yield Text(f"  {self.address} from scan {x.first_scan} to the failure:", style="dim")
            for line in console.render_lines(self.trend, options.update(width=max(options.max_width - 2, 20)),
                                             pad=False):
                yield Segment("  ")
                yield from _rstripped(line)  # the chart fills its width: no spaces at a line's end in a log
                yield Segment.line()

    def text(self, width: int = 80) -> str:
        """The report (one line) and its rungs (``width`` columns wide) as plain text."""
        out = io.StringIO()
        Console(file=out, width=width, color_system=None, highlight=False, soft_wrap=True).print(self)
        return out.getvalue().rstrip("\n")


def _rstripped(segments: list[Segment]) -> list[Segment]:
    out = list(segments)
    while out and not out[-1].text.rstrip():
        out.pop()
    if out:
        out[-1] = Segment(out[-1].text.rstrip(), out[-1].style, out[-1].control)
    return out


@dataclass
class Result:
    path: str
    name: str
    failure: Failure | None = None
    fault: str | None = None  # the major fault the PLC ended in, if any (mutation testing kills on it)

    @property
    def passed(self) -> bool:
        return self.failure is None


EXPORT_SCENARIO_GLOB = "STEM.tests/*.plctest"  # beside a Studio 5000 export (docs/logix.md)
_EXPORT_SUFFIXES = (".l5x", ".l5k")


def scenario_glob(app: str | Path) -> str:
    """Where an app's scenario files are, as the messages say it: APP/tests/
    for an app directory; beside an export, a directory named after it
    (``tank_line.tests/`` for ``tank_line.L5X``: a choice, the export being
    Studio's file, one project's L5X and L5K share their tests)."""
    path = Path(app)
    if path.suffix.lower() in _EXPORT_SUFFIXES:
        return f"{path.stem}.tests/*.plctest"
    return SCENARIO_GLOB


def scenario_files(app: str | Path) -> list[Path]:
    base = Path(app)
    if base.suffix.lower() in _EXPORT_SUFFIXES and not base.is_dir():
        return sorted(base.parent.glob(scenario_glob(base)))
    return sorted(base.glob(SCENARIO_GLOB)) if base.is_dir() else []


def check_names(file: ScenarioFile, plc: PLC) -> None:
    """Every address or symbol a step names exists, and its value is of a
    kind the address holds (values.py): all problems at once, in file order."""
    errors = []
    for step in file.all_steps():
        if step.kind in ("scan", "run") or isinstance(step.args[0], DeviceCounter):
            continue
        name = step.args[0]
        try:
            plc.address(name)
        except Exception as e:  # AddressError / SymbolError: the reason is the message
            reason = getattr(e, "reason", None) or str(e)
            errors.append(LocatedError(f"expected an address or a symbol of the program: {name}: {reason}",
                                       file.path, step.line, step.column_of(0)))
    errors += value_errors(file, plc) + counter_errors(file, plc)
    if errors:
        raise ScenarioErrors(sorted(errors, key=lambda e: (e.line, e.column)))


def _seconds(number, unit) -> float:
    return number / 1000 if unit == "ms" else number


_SCANNING = ("scan", "run", "wait_until")
_EDGES = ("expect_rising", "expect_falling")


class _Run:
    def __init__(self, plc: PLC, path: str) -> None:
        self.plc, self.path = plc, path
        self.edges: dict[str, list] = {}  # name -> its values after each scan of the last scanning step
        self.watched: tuple[str, ...] = ()  # the names the next scanning step records scan by scan

    def _record(self) -> None:
        plc, edges = self.plc, self.edges
        plc.engine.scan()
        for name in self.watched:
            edges[name].append(plc[name])

    def step(self, step: Step) -> Failure | None:
        if step.kind not in _SCANNING:
            return self._check(step)
        edges, plc = self.edges, self.plc
        if not edges:
            return self._scan(step, plc.engine.scan)
        for seen in edges.values():  # an edge is looked for in the last scanning step
            del seen[:-1]
        try:
            return self._scan(step, self._record if self.watched else plc.engine.scan)
        finally:
            # only the names an edge expectation after this step looks at were
            # recorded scan by scan (the cost of a long run); the others keep
            # their value after the last scan, as the next scanning step starts from
            for name in edges.keys() - set(self.watched):
                edges[name] = [plc[name]]

    def _scan(self, step: Step, scan) -> Failure | None:
        plc, k, a = self.plc, step.kind, step.args
        clock = plc.engine.clock
        if k == "scan":
            for _ in range(a[0]):
                scan()
        elif k == "run":
            end = clock.now_ms + round(_seconds(*a) * 1000)
            while clock.now_ms < end:
                scan()
        else:
            name, op, value, limit, unit = a
            end = clock.now_ms + round(_seconds(limit, unit) * 1000)
            while not _compare(plc[name], op, value):
                if clock.now_ms >= end:
                    return self._fail(step, f"{name} {op} {value!r} within {limit} {unit}", plc[name])
                scan()
        return None

    def _check(self, step: Step) -> Failure | None:
        plc, k, a = self.plc, step.kind, step.args
        if k == "expect_cmp":
            name, op, value = a
            actual = plc[name]
            if not _compare(actual, op, value):
                return self._fail(step, f"{name} {op} {value!r}", actual)
        elif k == "set":
            plc.set(a[0], a[1])
        elif k == "expect_within":
            name, tol, value = a
            if abs(plc[name] - value) > tol:
                return self._fail(step, f"{name} within {tol} of {value}", plc[name])
        elif k == "expect_between":
            name, lo, hi = a
            if not lo <= plc[name] <= hi:
                return self._fail(step, f"{name} between {lo} and {hi}", plc[name])
        elif k == "force":
            plc.force(a[0], a[1])
        elif k == "unforce":
            plc.unforce(a[0])
        else:
            name = a[0]
            seen = self.edges.get(name, [])
            want = (0, 1) if k == "expect_rising" else (1, 0)
            if not any((bool(x), bool(y)) == want for x, y in zip(seen, seen[1:])):
                return self._fail(step, f"{'rising' if want == (0, 1) else 'falling'} edge of {name} "
                                  "since the previous step", plc[name])
        return None

    def _fail(self, step: Step, expectation: str, actual) -> Failure:
        plc = self.plc
        rungs = None if isinstance(step.args[0], DeviceCounter) else \
            writers_at(plc.runner.app.program, plc.table, step.args[0], plc.forces.forces,
                       plc.runner.app.instructions)
        return Failure(expectation, actual, plc.scan_number, plc.time_ms, self.path, step.line, step.args[0],
                       rungs)


def _compare(actual, op, value) -> bool:
    return (actual == value) if op == "==" else (actual != value)


def run_scenario(app: str | Path, file: ScenarioFile, scenario: Scenario, program: Program | None = None,
                 coverage: Coverage | None = None, code_cache: tuple | None = None, trend: bool = False) -> Result:
    """``program``: a parsed program run in place of the app's (PLC.load);
    ``coverage``: a Coverage the scenario's scans record into;
    ``code_cache``: PLC.load's (DIRECTORY, KEY) for ``program``;
    ``trend``: a failure's report draws its address over the scans before
    it (failure_trend.py: the scenario runs again for it)."""
    with open_plc(app, file, program=program, coverage=coverage, code_cache=code_cache) as plc:
        check_names(file, plc)
        failure = run_steps(plc, file, scenario)
        result = Result(file.path, scenario.name, failure, _fault(plc))
    if failure is not None and trend:
        from .failure_trend import failure_trend  # it runs the steps this module holds

        failure.trend = failure_trend(app, file, scenario, failure, program, code_cache)
    return result


def _fault(plc: PLC) -> str | None:
    fault = plc.engine.fault
    return None if fault is None else fault.message


def run_steps(plc: PLC, file: ScenarioFile, scenario: Scenario) -> Failure | None:
    """The file's setup, then the scenario's steps, on ``plc`` as it is (its
    names checked): the first failure, or None."""
    run = _Run(plc, file.path)
    steps = file.setup + scenario.steps
    for step in steps:  # edges are watched from the start
        if step.kind in _EDGES:
            run.edges.setdefault(step.args[0], [plc[step.args[0]]])
    for step, watched in zip(steps, _edges_expected_after(steps)):
        run.watched = watched
        failure = run.step(step)
        if failure is not None:
            return failure
    return None


def _edges_expected_after(steps: list[Step]) -> list[tuple[str, ...]]:
    """For each step, the names whose edges are expected after it and
    before the next scanning step: what a scanning step records each scan."""
    out: list[tuple[str, ...]] = [()] * len(steps)
    names: list[str] = []
    for i in range(len(steps) - 1, -1, -1):
        if steps[i].kind in _EDGES:
            names.append(steps[i].args[0])
        elif steps[i].kind in _SCANNING:
            out[i], names = tuple(dict.fromkeys(names)), []
    return out


def run_file(app: str | Path, path: str | Path, program: Program | None = None,
             coverage: Coverage | None = None, trend: bool = False) -> list[Result]:
    file = load_scenarios(path)
    return [run_scenario(app, file, sc, program, coverage=coverage, trend=trend) for sc in file.scenarios]
