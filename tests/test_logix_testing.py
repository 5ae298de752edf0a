"""``softplc test`` of a Studio 5000 export (docs/logix.md, "Testing a Logix
app"): scenario files beside the export in NAME.tests/, steps naming tag
paths, a failure drawn by tag path and routine, coverage and mutation."""

from __future__ import annotations

import re

import shutil
from pathlib import Path

from softplc_lite.testing.mutation import INVALID, KILLED, SURVIVED, run_mutation
from softplc_lite.testing.runner import scenario_files, scenario_glob

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
TANK_LINE = ROOT / "programs" / "logix" / "tank_line.L5X"


def _export(tmp_path: Path, scenario: str | None, suffix: str = ".L5X") -> Path:
    """A copy of the tank line in tmp_path, with one scenario file beside it (``scenario``)."""
    export = tmp_path / f"tank_line{suffix}"
    shutil.copy(TANK_LINE, export)
    if scenario is not None:
        (tmp_path / "tank_line.tests").mkdir()
        (tmp_path / "tank_line.tests" / "t.plctest").write_text(scenario, encoding="utf-8")
    return export


def test_scenario_files_are_beside_the_export(tmp_path):
    export = _export(tmp_path, 'scenario "x":\n    scan 1\n')
    assert scenario_glob(export) == "tank_line.tests/*.plctest"
    assert scenario_files(export) == [tmp_path / "tank_line.tests" / "t.plctest"]
    assert scenario_files(tmp_path / "other.L5K") == []
    assert scenario_glob(ROOT / "programs" / "motor") == "tests/*.plctest"


def test_the_tank_lines_scenarios_pass():
    r = softplc_here("test", "programs/logix/tank_line.L5X")
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    assert "PASS programs/logix/tank_line.tests/line.plctest: LineDone stops the line after 3 batches" in lines
    assert "PASS programs/logix/tank_line.tests/line.plctest: the mean level is the program's Overview" in lines
    assert lines[-1] == f"{len(lines) - 1} passed, 0 failed" and len(lines) - 1 >= 8


def test_tag_paths_in_set_force_and_expect(tmp_path):
    export = _export(tmp_path, 'scenario "by tag path":\n'
                               '    force Start = 1\n'
                               '    scan 1\n'
                               '    expect Running == 1\n'
                               '    set Tanks[0].Level = 10\n'
                               '    set Program:MainProgram.Settled = 0\n'
                               '    scan 1\n'
                               '    expect Tanks[0].Level == 10.5\n'
                               '    set Batches.ACC = 2\n'
                               '    expect Batches.ACC == 2\n'
                               '    expect Flags.8 == 0\n'
                               '    unforce Start\n')
    r = softplc_here("test", str(export))
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1] == "1 passed, 0 failed"


def test_a_failure_is_drawn_by_tag_path_in_its_routine(tmp_path):
    export = _export(tmp_path, 'scenario "fills faster":\n    set Start = 1\n    run 300 ms\n'
                               '    expect Tanks[0].Level == 30\n')
    r = softplc_here("test", str(export))
    assert r.returncode == 1
    out = r.stdout
    assert f"{tmp_path}/tank_line.tests/t.plctest:4: expected Tanks[0].Level == 30, got 15.0 (scan 30, 0.3 s)" in out
    assert "routine MainProgram.FillTank, rungs that write Tanks[0].Level (F12:0):" in out
    assert "Tanks[Active].Level=15.0" in out and "FillRate=0.5" in out and "F12:[" not in out


def test_mistakes_are_located_and_a_missing_directory_is_named(tmp_path):
    export = _export(tmp_path, 'scenario "x":\n    expect Tanks[5].Level == 1\n    set Nope = 1\n')
    r = softplc_here("test", str(export))
    assert r.returncode == 1
    errors = r.stderr.splitlines()
    assert errors[0].startswith(f"{tmp_path}/tank_line.tests/t.plctest:2:") and "Tanks[5]" in errors[0]
    assert errors[1].startswith(f"{tmp_path}/tank_line.tests/t.plctest:3:") and "Nope" in errors[1]
    bare = tmp_path / "bare"
    bare.mkdir()
    lonely = _export(bare, None)
    r = softplc_here("test", str(lonely))
    assert r.returncode == 1 and "no scenario files (tank_line.tests/*.plctest)" in r.stderr


def test_coverage_of_the_tank_line():
    r = softplc_here("test", "programs/logix/tank_line.L5X", "--coverage")
    assert r.returncode == 0, r.stdout + r.stderr
    rows = {line.split()[1]: line for line in r.stdout.splitlines() if line[:2].strip().isdigit()}
    assert "MainProgram.MainRoutine" in rows and "MainProgram.FillTank" in rows
    assert rows["MainProgram.MainRoutine"].rstrip().endswith("100%")


def test_mutation_judges_the_exports_rungs(tmp_path):
    export = _export(tmp_path, (ROOT / "programs/logix/tank_line.tests/line.plctest").read_text(encoding="utf-8"))
    report = run_mutation(export, jobs=1)
    assert report.count(INVALID) == 0
    assert report.count(KILLED) >= 30 and report.count(SURVIVED) == 0
    # every mutant is killed by a failed expectation, never by an error of the runner
    assert all("Error:" not in o.detail for _, o in report.with_status(KILLED))
    # described as Studio 5000 shows the rungs: neutral text, tag paths, no data table address
    described = [m.description for m, _ in report.with_status(KILLED)]
    assert "XIC(Start) -> XIO(Start)" in described, described[:10]
    assert not any(re.search(r"\b[BNFTCRL]\d+[:/]\d", d) for d in described), described


def test_coverage_annotates_the_export_itself(tmp_path):
    export = _export(tmp_path, 'scenario "started":\n    set Start = 1\n    run 300 ms\n')
    out = tmp_path / "cover"
    r = softplc_here("test", str(export), "--coverage-annotate", str(out))
    assert r.returncode == 0, r.stdout + r.stderr
    assert [p.name for p in out.iterdir()] == ["tank_line.L5X.cover"]  # not the continuous task's <generated>
    lines = (out / "tank_line.L5X.cover").read_text(encoding="utf-8").splitlines()
    settle = next(k for k, line in enumerate(lines) if "TON(SettleTimer,?,?)" in line)
    assert lines[settle].startswith("! <![CDATA[XIC(Tanks[Active].Drain)")
    assert lines[settle + 1].strip() == "^ rung never true"  # 30 scans: tank 0 is not full yet
