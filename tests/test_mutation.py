"""Mutation testing (testing/mutation.py, mutation_report.py, softplc test
--mutate): each mutant classified, the time budget and the per-mutant limit
honoured, the same results in one process or several, the report."""

import io
import re

import pytest
from rich.console import Console

from softplc_lite.testing.mutation import (INVALID, KILLED, NOT_COVERED, OUT_OF_TIME, SURVIVED, TIMED_OUT,
                                           MutationError, run_mutation)
from softplc_lite.testing.mutation_report import print_report
from tests.helpers.apps import make_app
from tests.helpers.cli import softplc_here

LADDER = (
    "XIC B3/0 OTE B3/1\n"  # checked by the scenarios
    "XIC B3/0 OTE B3/2\n"  # executed, its output checked by none
    "XIC B3/0 TON T4:0 0.01 32767 0\n"  # a preset one more does not validate
    "XIC B3/3 OTE B3/4\n"  # counted as not covered below
)
SCENARIOS = (
    'scenario "on":\n    set B3/0 = 1\n    scan 1\n    expect B3/1 == 1\n'
    'scenario "off":\n    scan 1\n    expect B3/1 == 0\n'
)
EXPECTED = [
    KILLED, KILLED, KILLED,  # rung 0: contact, OTE removed, rung deleted
    SURVIVED, SURVIVED, SURVIVED,  # rung 1
    SURVIVED, INVALID, SURVIVED, SURVIVED,  # rung 2: contact, preset +1, preset -1, rung deleted
    NOT_COVERED, NOT_COVERED, NOT_COVERED,  # rung 3
]


def _app(tmp_path, ladder=LADDER, scenarios=SCENARIOS):
    app = make_app(tmp_path / "app", ladder)
    (app / "tests").mkdir()
    (app / "tests" / "t.plctest").write_text(scenarios, encoding="utf-8")
    return app


def _not_rung_3(key):
    return key != (2, 3)


@pytest.mark.parametrize("jobs", [1, 2])
def test_each_mutant_is_killed_survives_is_invalid_or_not_covered(tmp_path, jobs):
    report = run_mutation(_app(tmp_path), jobs=jobs, covered=_not_rung_3)
    assert [o.status for o in report.outcomes] == EXPECTED
    assert report.jobs == jobs
    assert report.score == pytest.approx(100 * 3 / 9)
    invalid = report.outcomes[7].detail
    assert "main.lad:3:" in invalid and "32768" in invalid
    assert report.outcomes[0].detail.startswith("on: ")  # the scenario that killed it, and why


def test_serial_and_parallel_runs_agree_outcome_for_outcome(tmp_path):
    app = _app(tmp_path)
    serial = run_mutation(app, jobs=1)
    parallel = run_mutation(app, jobs=2)
    assert serial.outcomes == parallel.outcomes
    assert [m.description for m in serial.mutants] == [m.description for m in parallel.mutants]


@pytest.mark.parametrize("jobs", [1, 2])
def test_no_mutant_starts_once_the_budget_is_spent(tmp_path, jobs):
    report = run_mutation(_app(tmp_path), jobs=jobs, budget=0, covered=_not_rung_3)
    assert [o.status for o in report.outcomes] == [OUT_OF_TIME] * 10 + [NOT_COVERED] * 3
    assert report.score is None


def test_a_mutant_over_the_per_mutant_limit_is_timed_out(tmp_path):
    # a millionth of a second: less than loading the app takes
    report = run_mutation(_app(tmp_path), jobs=1, limit=1e-6, covered=_not_rung_3)
    assert [o.status for o in report.outcomes] == [TIMED_OUT] * 10 + [NOT_COVERED] * 3
    assert report.outcomes[0].detail == "over the per-mutant limit of 1e-06 s"


def test_scenarios_failing_on_the_original_program_stop_it(tmp_path):
    app = _app(tmp_path, scenarios='scenario "wrong":\n    scan 1\n    expect B3/1 == 1\n')
    with pytest.raises(MutationError, match=r"fail on the unmutated program(.|\n)*wrong: .*t.plctest:3: expected"):
        run_mutation(app, jobs=1)


def _plain(report) -> str:
    out = io.StringIO()
    print_report(report, Console(file=out, width=90, color_system=None, highlight=False, soft_wrap=True))
    return out.getvalue()


def test_the_report_draws_each_survivor_with_its_change_and_the_counts(tmp_path):
    app = _app(tmp_path)
    text = _plain(run_mutation(app, jobs=1, covered=_not_rung_3))
    lines = text.splitlines()
    head = lines.index(f"SURVIVED {app}/main.lad:2:1: rung 1: XIC B3/0 -> XIO B3/0 (contact)")
    # the mutated rung as the watch view draws it: the contact now ]/[ and its value
    assert lines[head + 1].strip() == "Rung 1"
    assert re.fullmatch(r"\|\s+B3/0\s+B3/2\s+\|", lines[head + 2])
    assert re.match(r"\|-+\]/\[-+.*\( \)-+\|", lines[head + 3]), lines[head + 3]
    assert lines[head + 4] == " " * lines[head + 3].index("/") + "^"  # the change marked under it
    assert f"SURVIVED {app}/main.lad:2:10: rung 1: OTE B3/2 removed (output)" in lines
    # a deleted rung is drawn as it was, nothing marked
    deleted = lines.index(f"SURVIVED {app}/main.lad:2:1: rung 1: rung deleted: XIC B3/0 OTE B3/2 (rung)")
    assert re.match(r"\|-+\] \[-+.*\( \)-+\|", lines[deleted + 3]), lines[deleted + 3]
    assert "^" not in "".join(lines[deleted:deleted + 5])
    # a preset one less: the digit marked under the box's line
    preset = lines.index(f"SURVIVED {app}/main.lad:3:10: rung 2: TON T4:0 0.01 32767 0 -> TON T4:0 0.01 32766 0 "
                         "(constant)")
    row = next(k for k in range(preset, preset + 6) if "PRE 32766" in lines[k])
    assert lines[row + 1] == " " * lines[row].index("32766") + "    ^"
    assert f"NOT COVERED rungs the scenarios never executed, their 3 mutants not run: {app}/main.lad:4 (rung 3)" \
        in lines
    assert lines[-1].startswith("mutation score 33.3% (3 killed of 9), 3 not covered, 1 invalid, 13 mutants, "
                                "2 scenarios, 1 job, ")


def test_softplc_test_mutate_reports_and_fails_under_a_score(tmp_path):
    app = _app(tmp_path, ladder="XIC B3/0 OTE B3/1\nXIC B3/0 OTE B3/2\n")
    r = softplc_here("test", str(app), "--mutate", "--jobs", "2")
    assert r.returncode == 0, r.stderr
    assert "2 passed, 0 failed" in r.stdout
    assert f"SURVIVED {app}/main.lad:2:1: rung 1: XIC B3/0 -> XIO B3/0 (contact)" in r.stdout
    assert re.search(r"^mutation score 50\.0% \(3 killed of 6\), 6 mutants, 2 scenarios, 2 jobs, ", r.stdout, re.M)
    r = softplc_here("test", str(app), "--mutate", "--jobs", "1", "--fail-under-mutation", "60")
    assert r.returncode == 2
    assert "mutation score 50.0% is under --fail-under-mutation 60%" in r.stdout
    r = softplc_here("test", str(app), "--mutate", "--jobs", "1", "--fail-under-mutation", "50")
    assert r.returncode == 0


def test_softplc_test_refuses_mutation_options_without_mutate_and_bad_values(tmp_path):
    app = _app(tmp_path)
    r = softplc_here("test", str(app), "--jobs", "2", "--fail-under-mutation", "90")
    assert r.returncode == 2
    assert r.stderr == "softplc test: --jobs, --fail-under-mutation apply to mutation testing: add --mutate\n"
    assert r.stdout == ""
    r = softplc_here("test", str(app), "--mutate", "--jobs", "0")
    assert r.returncode == 2 and "expected a whole number of 1 or more, got '0'" in r.stderr
    r = softplc_here("test", str(app), "--mutate", "--mutate-timeout", "-1")
    assert r.returncode == 2 and "expected a number of seconds above 0, got '-1'" in r.stderr


def test_softplc_test_mutate_says_why_it_cannot_run(tmp_path):
    app = _app(tmp_path, scenarios='scenario "wrong":\n    scan 1\n    expect B3/1 == 1\n')
    r = softplc_here("test", str(app), "--mutate")
    assert r.returncode == 1  # the scenario fails first: no mutant is made
    assert "0 passed, 1 failed" in r.stdout and "mutation" not in r.stdout


def test_mutants_of_rungs_the_scenarios_never_execute_are_not_run(tmp_path):
    # the baseline run measures coverage: the JMP skips rung 2 on every scan
    app = _app(tmp_path, ladder="XIC B3/0 OTE B3/1\nJMP 1\nXIC B3/3 OTE B3/4\nLBL 1\n")
    report = run_mutation(app, jobs=1)
    assert [(m.key, o.status) for m, o in zip(report.mutants, report.outcomes)] == [
        ((2, 0), KILLED), ((2, 0), KILLED), ((2, 0), KILLED),
        ((2, 1), SURVIVED),  # the JMP deleted: rung 2 then runs, and no scenario looks at B3/4
        ((2, 2), NOT_COVERED), ((2, 2), NOT_COVERED), ((2, 2), NOT_COVERED),
        ((2, 3), INVALID),  # the label deleted: the JMP has nowhere to go
    ]


def test_a_mutant_that_loops_within_a_scan_is_killed_by_the_watchdog_fault(tmp_path):
    # XIC B3/2 -> XIO B3/2 jumps back to LBL 1 on every pass: the engine's
    # watchdog ends the scan with a major fault, which kills the mutant
    app = _app(tmp_path, ladder="LBL 1 XIC B3/0 OTE B3/1\nXIC B3/2 JMP 1\n")
    report = run_mutation(app, jobs=1, select=lambda m: m.description == "XIC B3/2 -> XIO B3/2")
    [outcome] = report.outcomes
    assert outcome.status == KILLED
    assert "major fault: watchdog" in outcome.detail


def test_a_mutant_is_checked_and_compiled_once_for_all_its_scenarios(tmp_path):
    from softplc_lite.app import load_app
    from softplc_lite.testing.mutants import mutants
    from softplc_lite.testing.plc import PLC

    app = _app(tmp_path)
    loaded = load_app(app, state_dir=tmp_path / "s", use_cache=False)
    first, second = mutants(loaded.source_program, loaded.instructions)[:2]  # rung 0: XIC -> XIO, OTE removed
    cache = tmp_path / "cache"
    cache.mkdir()

    def load(mutant):
        with PLC.load(app, program=mutant.apply(loaded.source_program), code_cache=(cache, f"m{mutant.index}")) as plc:
            plc.scan()
            return plc.runner.app.code is not None, plc["B3/1"]  # (from the cache, the mutant's output)

    assert load(first) == (False, 1)  # XIO B3/0 with B3/0 off
    assert load(first) == (True, 1)
    assert load(second) == (False, 0)  # another key: checked and compiled, not the first's code
    assert not list(app.glob(".softplc*"))  # the app is only read


@pytest.mark.parametrize("jobs", [1, 2])
def test_progress_is_told_each_mutant_judged(tmp_path, jobs):
    seen = []
    run_mutation(_app(tmp_path), jobs=jobs, covered=_not_rung_3,
                 progress=lambda done, total: seen.append((done, total)))
    assert seen == [(k, 10) for k in range(1, 11)]


def test_on_a_colour_console_the_change_is_in_reverse_video_without_marker_lines(tmp_path):
    report = run_mutation(_app(tmp_path), jobs=1, covered=_not_rung_3,
                          select=lambda m: m.description == "XIC B3/0 -> XIO B3/0" and m.key == (2, 1))
    out = io.StringIO()
    print_report(report, Console(file=out, width=90, color_system="standard", force_terminal=True, soft_wrap=True))
    text = out.getvalue()
    assert re.search(r"\x1b\[(\d+;)*7(;\d+)*m/\x1b\[0m", text)  # reverse video (7) on the contact's slash alone
    assert "^" not in text
