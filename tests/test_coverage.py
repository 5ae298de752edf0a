"""Ladder coverage (testing/coverage.py): each measure on small programs
whose answer is known by hand, merging over runs, and no instrumentation
at all when coverage is off."""

from __future__ import annotations

import gc

import pytest

from helpers.apps import make_app
from softplc_lite.ladder.interpreter import ReferenceFile
from softplc_lite.testing.coverage import Coverage, Recorder
from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import run_file

SEAL = "BST XIC B3/0 NXB XIC B3/2 BND XIC B3/3 OTE B3/1\n"


def _measure(tmp_path, ladder: str, sets=(), scans: int = 3, cov: Coverage | None = None) -> Coverage:
    cov = cov if cov is not None else Coverage()
    with PLC.load(make_app(tmp_path / "app", ladder), coverage=cov) as plc:
        for name, value in sets:
            plc.set(name, value)
        plc.scan(scans)
    return cov


def test_a_rung_only_ever_true_its_contact_only_seen_true_its_coil_never_off(tmp_path):
    cov = _measure(tmp_path, "XIC B3/0 OTE B3/1\n", sets=[("B3/0", 1)], scans=4)
    assert cov.executed((2, 0)) and cov.scans((2, 0)) == 4
    assert cov.rung_outcomes((2, 0)) == (True, False)
    assert cov.element_outcomes((2, 0, 0)) == (True, False)  # XIC: seen true, never false
    assert cov.element_outcomes((2, 0, 1)) == (True, False)  # OTE: on, never off
    assert cov.kinds == {(2, 0, 0): "condition", (2, 0, 1): "output"}


def test_a_leg_never_powered(tmp_path):
    cov = _measure(tmp_path, SEAL, sets=[("B3/0", 1), ("B3/3", 1)])
    # elements in pre-order: 0 the branch, 1 XIC B3/0 (leg 0), 2 XIC B3/2 (leg 1), 3 XIC B3/3, 4 OTE
    assert cov.leg_powered((2, 0, 0, 0)) and not cov.leg_powered((2, 0, 0, 1))
    assert cov.element_outcomes((2, 0, 2)) == (False, True)  # XIC B3/2: power reached it, always open
    assert cov.rung_outcomes((2, 0)) == (True, False)


def test_a_condition_counts_only_where_power_reaches_it(tmp_path):
    # B3/0 stays open: the XIC B3/2 after it is scanned but decides nothing, so it is seen neither way
    cov = _measure(tmp_path, "XIC B3/0 XIC B3/2 OTE B3/1\n", sets=[("B3/2", 1)])
    assert cov.element_outcomes((2, 0, 0)) == (False, True)
    assert cov.element_outcomes((2, 0, 1)) == (False, False)
    assert cov.element_outcomes((2, 0, 2)) == (False, True)  # OTE: never on, off
    assert cov.rung_outcomes((2, 0)) == (False, True)


def test_a_rung_skipped_by_a_jump_is_never_executed_and_a_jsr_file_is_measured(tmp_path):
    ladder = ("XIC B3/0 JMP 1\n"
              "OTE B3/4\n"
              "LBL 1 XIC B3/0 JSR 3\n"
              "\nFILE 3 Sub\nSBR\nXIC B3/2 OTE B3/5\nRET\n")
    cov = _measure(tmp_path, ladder, sets=[("B3/0", 1)], scans=2)
    assert cov.rung_outcomes((2, 0)) == (True, False)  # the JMP fired: power reached the rung's end
    assert not cov.executed((2, 1)) and cov.rung_outcomes((2, 1)) == (False, False)
    assert cov.element_outcomes((2, 1, 0)) == (False, False)  # its OTE neither on nor off
    assert [cov.executed((3, r)) for r in range(3)] == [True, True, True]
    assert cov.rung_outcomes((3, 1)) == (False, True)
    assert cov.files[3].name == "Sub" and [r.line for r in cov.files[3].rungs] == [6, 7, 8]
    # LBL and SBR test nothing: not counted
    assert (2, 2, 0) not in cov.kinds and (3, 0, 0) not in cov.kinds


def test_a_subroutine_never_called_is_never_executed(tmp_path):
    cov = _measure(tmp_path, "XIC B3/0 JSR 3\n\nFILE 3 Sub\nSBR\nOTE B3/5\nRET\n")
    assert cov.rung_outcomes((2, 0)) == (False, True)
    assert cov.element_outcomes((2, 0, 1)) == (False, True)  # the JSR: never on
    assert not any(cov.executed((3, r)) for r in range(3))


def test_runs_merge_into_one_coverage(tmp_path):
    cov = _measure(tmp_path / "1", "XIC B3/0 OTE B3/1\n", sets=[("B3/0", 1)])
    _measure(tmp_path / "2", "XIC B3/0 OTE B3/1\n", cov=cov)
    assert cov.rung_outcomes((2, 0)) == (True, True) and cov.scans((2, 0)) == 6
    assert cov.element_outcomes((2, 0, 0)) == (True, True)
    other = _measure(tmp_path / "3", "XIC B3/0 OTE B3/1\n", scans=5)
    cov.merge(other)
    assert cov.rungs[(2, 0)] == [3, 8]


def test_scenarios_of_a_file_merge(tmp_path):
    app = make_app(tmp_path / "app", SEAL)
    (app / "tests").mkdir()
    (app / "tests" / "s.plctest").write_text(
        'setup:\n    set B3/3 = 1\n'
        'scenario "first leg":\n    set B3/0 = 1\n    scan 1\n    expect B3/1 == 1\n'
        'scenario "second leg":\n    set B3/2 = 1\n    scan 1\n    expect B3/1 == 1\n', encoding="utf-8")
    cov = Coverage()
    assert all(r.passed for r in run_file(app, app / "tests" / "s.plctest", coverage=cov))
    assert cov.leg_powered((2, 0, 0, 0)) and cov.leg_powered((2, 0, 0, 1))
    assert cov.rungs[(2, 0)] == [2, 0]


def test_another_program_is_refused(tmp_path):
    cov = _measure(tmp_path / "1", "XIC B3/0 OTE B3/1\n")
    with pytest.raises(ValueError, match="another program"):
        _measure(tmp_path / "2", "XIC B3/0 XIC B3/2 OTE B3/1\n", cov=cov)


def test_a_recorded_run_computes_what_the_compiled_one_does(tmp_path):
    ladder = ("ADD N7:0 1 N7:0\nCMP \"N7:0 MOD 3 = 0\" JSR 3\nXIC B3/0 JMP 1\nADD N7:3 1 N7:3\n"
              "LBL 1 BST XIC S:1/15 NXB GRT N7:0 4 BND OTE B3/1\n\nFILE 3 Sub\nSBR\nADD N7:1 2 N7:1\nRET\n")
    app = make_app(tmp_path / "app", ladder)
    tables = []
    for cov in (None, Coverage()):
        with PLC.load(app, coverage=cov) as plc:
            plc.scan(5)
            plc.set("B3/0", 1)
            plc.scan(5)
            tables.append([plc[a] for a in ("N7:0", "N7:1", "N7:3", "B3/1")])
    assert tables[0] == tables[1] == [10, 6, 5, 1]


def test_coverage_off_runs_the_compiled_code_with_no_recorder(tmp_path):
    app = make_app(tmp_path / "app", SEAL)
    gc.collect()
    with PLC.load(app) as plc:
        plc.scan(3)
        assert plc.engine.executor == "compiled"
        assert not any(isinstance(f, ReferenceFile) for f, _ in plc.engine.files.values())
        assert not any(isinstance(o, (Recorder, Coverage)) for o in gc.get_objects())
    with PLC.load(app, coverage=Coverage()) as plc:
        assert all(isinstance(f, ReferenceFile) for f, _ in plc.engine.files.values())
        assert any(isinstance(o, Recorder) for o in gc.get_objects())


def test_outcomes_that_cannot_happen_are_not_counted(tmp_path):
    from softplc_lite.testing.coverage_report import figures

    # rung 0: nothing can end it false; rung 1: a leg with no condition, so the OTE is never off;
    # rung 2: a condition, so both outcomes count
    ladder = "MOV 5 N7:0\nBST XIC B3/0 NXB OTE B3/2 BND OTE B3/1\nXIC B3/0 OTE B3/3\n"
    cov = _measure(tmp_path / "a", ladder, sets=[("B3/0", 1)])
    info = cov.files[2]
    assert [r.false_possible for r in info.rungs] == [False, False, True]
    assert [(e.text, e.off_possible) for e in info.rungs[1].elements if e.kind == "output"] == [("OTE", False),
                                                                                                ("OTE", False)]
    fig = figures(cov)[0][2]
    assert (fig.outcomes_seen, fig.outcomes) == (3, 4)  # rung 2 never false
    assert (fig.outputs_seen, fig.outputs) == (4, 5)  # MOV on, the OTEs on; OTE B3/3 never off
    # an MCR zone in the file can turn any rung off: every outcome counts
    mcr = _measure(tmp_path / "b", "XIC B3/0 MCR\nMOV 5 N7:0\nMCR\n", sets=[("B3/0", 1)])
    assert all(r.false_possible for r in mcr.files[2].rungs)
    assert mcr.rung_outcomes((2, 1)) == (True, False)


def test_a_scan_that_faults_leaves_its_rung_uncounted(tmp_path):
    # the scan B3/0 turns on, file 3 calls itself until JSRs nest too deep (a major fault)
    ladder = "XIC B3/1 OTE B3/2\nXIC B3/0 JSR 3\nOTE B3/3\n\nFILE 3 Loop\nSBR\nJSR 3\nRET\n"
    app = make_app(tmp_path / "app", ladder)
    cov = Coverage()
    with PLC.load(app, coverage=cov) as plc:
        plc.scan(2)
        plc.set("B3/0", 1)
        plc.scan(1)
        assert plc.engine.fault is not None
    assert [cov.rungs[(2, r)] for r in range(3)] == [[0, 3], [0, 2], [2, 0]]
    assert cov.element_outcomes((2, 1, 0)) == (True, True)  # the XIC passed power into the JSR that faulted
    assert cov.executed((3, 0)) and not cov.executed((3, 1)) and not cov.executed((3, 2))


def test_merging_another_programs_measurement_is_refused(tmp_path):
    cov = _measure(tmp_path / "1", "XIC B3/0 OTE B3/1\n")
    with pytest.raises(ValueError, match="another program"):
        cov.merge(_measure(tmp_path / "2", "XIC B3/0 XIC B3/2 OTE B3/1\n"))
