"""Mutation testing: run an app's scenario files against each mutant of its
program (mutants.py) and say which mutants they kill.

A mutant is killed when a scenario fails on it (or faults), survives when
every scenario passes, is invalid when it does not validate (counted apart:
not a test's merit), not covered when the scenarios never execute its rung
(reported, not run), timed out when one run of it takes longer than the
per-mutant limit, and not run when the total time budget ran out first.

Mutants run in worker processes (``jobs``, the CPU count by default), each
worker loading the scenario files and the original program once; results
are reported in the mutants' order whatever order they finished in.

Time is bounded three ways. The scenario's own steps bound simulated time
(``scan N``, ``run T`` and ``wait until ... within T`` all end), the
engine's watchdog ends a scan stuck in a backward jump, and a wall-clock
timer in the worker ends a mutant past the per-mutant limit or past the
total budget's end.
"""

from __future__ import annotations

import os
import signal
import tempfile
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..app import AppError, load_app
from ..ladder.ast import Program
from .coverage import Coverage
from ..watch.naming import LOGIX_OPERATORS, names_in_file, routines_of
from .mutants import AS_WRITTEN, Mutant, RungKey, Spelling, mutants
from .runner import run_scenario, scenario_files
from .scenario import ScenarioFile, load_scenarios

KILLED, SURVIVED, NOT_COVERED, INVALID, TIMED_OUT, OUT_OF_TIME = (
    "killed", "survived", "not covered", "invalid", "timed out", "not run (time)")
STATUSES = (KILLED, SURVIVED, NOT_COVERED, INVALID, TIMED_OUT, OUT_OF_TIME)

# Choices: the total budget a run of ``softplc test --mutate`` gets for its
# mutants, and the per-mutant limit, a multiple of the time the unmutated
# program takes to pass its scenarios (a mutant does the same steps), with a
# floor for the slowness of a loaded machine.
DEFAULT_BUDGET_S = 300.0
LIMIT_FACTOR = 20
MIN_LIMIT_S = 10.0


class MutationError(Exception):
    """Mutation testing cannot start: no scenario files, or the scenarios
    fail on the unmutated program."""


@dataclass(frozen=True)
class Outcome:
    index: int  # the mutant's
    status: str
    detail: str = ""  # killed: the failure; invalid: the first problem; timed out: the limit


@dataclass
class MutationReport:
    app: str
    mutants: list[Mutant]
    outcomes: list[Outcome]  # one a mutant, in the mutants' order
    jobs: int  # worker processes used (1: in this process)
    seconds: float  # the mutants' wall-clock time
    scenarios: int
    source: Program = field(repr=False, default=None)  # the original parsed program

    def count(self, status: str) -> int:
        return sum(1 for o in self.outcomes if o.status == status)

    @property
    def score(self) -> float | None:
        """killed / (killed + survived), in percent; None when neither."""
        killed, survived = self.count(KILLED), self.count(SURVIVED)
        return 100.0 * killed / (killed + survived) if killed + survived else None

    def with_status(self, status: str) -> list[tuple[Mutant, Outcome]]:
        return [(m, o) for m, o in zip(self.mutants, self.outcomes) if o.status == status]


# -- in a worker ---------------------------------------------------------------------


@dataclass
class _State:
    app: str
    files: list[ScenarioFile]
    source: Program
    timer: bool  # the per-mutant timer works here


_state: _State | None = None


class _Expired(BaseException):
    """The worker's timer: a BaseException, so no ``except Exception`` on
    the way (a scenario step, a module) takes it for a fault."""


def _init(app: str, paths: list[str], source: Program) -> None:
    """A worker's state (in a worker process: its timer installed for good).
    Ctrl-C is the parent's to handle: it stops giving out mutants."""
    global _state
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _state = _State(app, [load_scenarios(p) for p in paths], source, _install_timer() is not None)


def _run(mutant: Mutant, deadline: float, limit: float) -> Outcome:
    """One mutant against every scenario, the first failure killing it."""
    global _armed
    left = deadline - time.time()
    if left <= 0:
        return Outcome(mutant.index, OUT_OF_TIME)
    program = mutant.apply(_state.source)
    by_budget = left < limit
    try:
        try:
            _armed = _state.timer
            if _armed:
                signal.setitimer(signal.ITIMER_REAL, max(min(left, limit), 1e-6))
            return _verdict(mutant, program)
        finally:
            _armed = False
            if _state.timer:
                signal.setitimer(signal.ITIMER_REAL, 0)
    except _Expired:
        _armed = False
        if by_budget:
            return Outcome(mutant.index, OUT_OF_TIME)
        return Outcome(mutant.index, TIMED_OUT, f"over the per-mutant limit of {limit:g} s")


def _verdict(mutant: Mutant, program: Program) -> Outcome:
    # The mutant is checked and compiled at its first scenario's load, and
    # comes from the code cache for the others.
    with tempfile.TemporaryDirectory(prefix="softplc-mutant-") as cache:
        return _scenarios(mutant, program, (cache, f"mutant {mutant.index}"))


def _scenarios(mutant: Mutant, program: Program, code_cache: tuple[str, str]) -> Outcome:
    for file in _state.files:
        for scenario in file.scenarios:
            try:
                result = run_scenario(_state.app, file, scenario, program, code_cache=code_cache)
            except AppError as e:
                first = e.errors[0].report() if e.errors else str(e).splitlines()[0]
                return Outcome(mutant.index, INVALID, first)
            except Exception as e:  # a fault of the mutated program kills it as a failure does
                return Outcome(mutant.index, KILLED, f"{file.path}: {scenario.name}: {type(e).__name__}: {e}")
            if not result.passed:
                return Outcome(mutant.index, KILLED, f"{scenario.name}: {result.failure.report()}")
            if result.fault is not None:
                return Outcome(mutant.index, KILLED, f"{scenario.name}: major fault: {result.fault}")
    return Outcome(mutant.index, SURVIVED)


# The per-mutant timer: SIGALRM, handled in the main thread only (without
# it, in another thread, mutants run with no wall-clock limit). The handler
# raises only while a mutant runs: a signal that arrives as the timer is
# being disarmed is ignored.
_armed = False


def _expire(signum, frame):
    if _armed:
        raise _Expired()


def _install_timer() -> object | None:
    """Install the handler; the one it replaced, or None when there is no timer here."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGALRM, _expire)


# -- the run ---------------------------------------------------------------------------


def baseline(app: str | Path, files: list[ScenarioFile],
             coverage_factory: Callable[[], Coverage] | None = Coverage) -> tuple[float, Callable[[RungKey], bool]]:
    """Run the scenarios on the unmutated program: the seconds it took and
    which rungs they executed (testing/coverage.py; every rung when
    ``coverage_factory`` is None). MutationError when one fails."""
    cov = coverage_factory() if coverage_factory is not None else None
    failures = []
    start = time.perf_counter()
    for file in files:
        for scenario in file.scenarios:
            result = run_scenario(app, file, scenario, coverage=cov)
            if not result.passed:
                failures.append(f"{scenario.name}: {result.failure.report()}")
    seconds = time.perf_counter() - start
    if failures:
        raise MutationError("the scenarios fail on the unmutated program, so no mutant can be judged:\n  "
                            + "\n  ".join(failures))
    if cov is None:
        return seconds, lambda key: True
    return seconds, cov.executed


def spelling_of(program: Program) -> Callable[[int], Spelling | None]:
    """How mutant descriptions write each program file: a Logix app's by
    tag path in neutral text with Logix's instruction names, as Studio 5000
    and the watch view show its rungs; another app's as its files are
    written. A Logix app's file that is none of its routines (the rungs a
    task calls its programs with, made at load) gets no mutants (None):
    its author wrote nothing there (a choice, docs/testing.md)."""
    routines = dict(routines_of(program))
    if not routines:
        return lambda number: AS_WRITTEN

    def spelling(number: int) -> Spelling | None:
        if number not in routines:
            return None
        names, _ = names_in_file(program.symbols, tuple(routines.items()), number)
        return Spelling("neutral", names.name, LOGIX_OPERATORS, names.mnemonic)
    return spelling


def run_mutation(app: str | Path, *, jobs: int | None = None, budget: float = DEFAULT_BUDGET_S,
                 limit: float | None = None, covered: Callable[[RungKey], bool] | None = None,
                 coverage_factory: Callable[[], Coverage] | None = Coverage,
                 select: Callable[[Mutant], bool] | None = None,
                 progress: Callable[[int, int], None] | None = None) -> MutationReport:
    """Mutation-test ``app`` with its scenario files. ``covered`` says which
    rungs the scenarios execute (measured by the baseline run when None);
    ``limit``: the per-mutant limit in seconds (from the baseline when None);
    ``select``: the mutants to make (all when None; the others are left
    out of the report, e.g. a sample of a large program's); ``progress``:
    called with (mutants judged, mutants to run) as they are judged."""
    app = str(app)
    paths = [str(p) for p in scenario_files(app)]
    if not paths:
        raise MutationError(f"{app}: no scenario files to judge mutants with")
    files = [load_scenarios(p) for p in paths]  # ScenarioErrors: every mistake, located
    with tempfile.TemporaryDirectory(prefix="softplc-mutate-") as state:
        loaded = load_app(app, state_dir=state, use_cache=False)
    source = loaded.source_program
    seconds, measured = baseline(app, files, coverage_factory)
    covered = covered or measured
    if limit is None:
        limit = max(MIN_LIMIT_S, LIMIT_FACTOR * seconds)
    found = [m for m in mutants(source, loaded.instructions, spelling_of(loaded.program))
             if select is None or select(m)]
    outcomes: dict[int, Outcome] = {m.index: Outcome(m.index, NOT_COVERED) for m in found if not covered(m.key)}
    todo = [m for m in found if m.index not in outcomes]
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(todo) or 1))
    start = time.time()
    deadline = start + budget
    if jobs == 1:
        global _state
        saved = _state
        previous = _install_timer()
        _state = _State(app, files, source, previous is not None)
        try:
            for done, m in enumerate(todo, 1):
                outcomes[m.index] = _run(m, deadline, limit)
                if progress is not None:
                    progress(done, len(todo))
        finally:
            _state = saved
            if previous is not None:
                signal.signal(signal.SIGALRM, previous)
    else:
        pool = ProcessPoolExecutor(max_workers=jobs, initializer=_init, initargs=(app, paths, source))
        try:
            futures = [(m, pool.submit(_run, m, deadline, limit)) for m in todo]
            for done, (m, future) in enumerate(futures, 1):
                outcomes[m.index] = future.result()
                if progress is not None:
                    progress(done, len(todo))
        finally:  # on Ctrl-C too: no mutant is started after it, those running end within their limit
            pool.shutdown(wait=True, cancel_futures=True)
    return MutationReport(app, found, [outcomes[m.index] for m in found], jobs, time.time() - start,
                          sum(len(f.scenarios) for f in files), source)
