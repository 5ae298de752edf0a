"""The shipped apps' scenario files catch at least 90% of the mutants of the
rungs they execute (docs/testing.md, "Mutation testing"): a scenario file
weakened, or a rung added without a scenario, fails here.

Four apps are left to the figures in docs/testing.md (and modbus_slave to
`benchmarks/bench_mutation.py`), for their time alone: every hmi_server,
bottling and scada_ua mutant starts its app's server process (MODBTCPS, ENIPS:
about 1.3 s each; OPCUAS about 2 s, asyncua building its address space), and
modbus_slave has over 700 mutants (about 45 s on two cores)."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.testing.mutation import KILLED, NOT_COVERED, OUT_OF_TIME, SURVIVED, TIMED_OUT, run_mutation

from helpers.shipped_apps import shipped_app_names

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"
SLOW = {"hmi_server", "bottling", "scada_ua", "modbus_slave"}
APPS = sorted(p.name for p in PROGRAMS.iterdir() if (p / "tests").is_dir() and p.name not in SLOW)


def test_every_shipped_app_but_the_slow_ones_is_judged_here():
    # programs/logix holds Studio 5000 exports, apps of one file: not mutated (docs/logix.md)
    assert set(shipped_app_names()) == set(APPS) | SLOW


@pytest.mark.parametrize("app", APPS)
def test_the_scenarios_kill_90_percent_of_the_covered_mutants(app):
    report = run_mutation(PROGRAMS / app, jobs=1)  # one job: the suite's workers are the parallelism
    assert report.count(KILLED) + report.count(SURVIVED) >= 10, "too few mutants judged to mean anything"
    assert report.count(NOT_COVERED) == 0, [m.description for m, _ in report.with_status(NOT_COVERED)]
    assert report.count(OUT_OF_TIME) == report.count(TIMED_OUT) == 0
    survivors = [m.description for m, _ in report.with_status(SURVIVED)]
    assert report.score >= 90.0, survivors
