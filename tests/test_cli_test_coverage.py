"""``softplc test --coverage``: the summary read back, and ``--fail-under``'s
exit codes (docs/testing.md, Coverage)."""

import re
import shutil
from pathlib import Path

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
CONVEYOR = ROOT / "docs" / "examples" / "conveyor"


def _conveyor(tmp_path, extra: str = "") -> Path:
    app = tmp_path / "conveyor"
    shutil.copytree(CONVEYOR, app)
    if extra:
        with open(app / "tests" / "conveyor.plctest", "a", encoding="utf-8") as f:
            f.write(extra)
    return app


def _rows(stdout: str) -> dict[str, list[str]]:
    """The summary table's rows by file label: its cells split on runs of spaces."""
    lines = stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("File "))
    assert re.fullmatch(r"─+", lines[head + 1])
    return {cells[0]: cells[1:] for cells in (re.split(r"\s{2,}", line.strip()) for line in lines[head + 2:])}


def test_the_summary_counts_what_the_scenarios_did(tmp_path):
    r = softplc_here("test", str(_conveyor(tmp_path)), "--coverage")
    assert r.returncode == 0, r.stderr
    assert _rows(r.stdout) == {"2": ["main.lad", "2/2", "3/4", "1/2", "6/10", "3/4", "68%"]}


def test_covering_the_rest_reaches_100_percent(tmp_path):
    app = _conveyor(tmp_path, '\nscenario "manual and jam":\n    set Manual = 1\n    scan 1\n'
                              '    expect Conveyor == 1\n    set Jam = 1\n    scan 1\n    expect Conveyor == 0\n'
                              '    expect JamLamp == 1\n    set Jam = 0\n    set Manual = 0\n    set Enable = 0\n'
                              '    scan 1\n    expect Conveyor == 0\n')
    r = softplc_here("test", str(app), "--coverage")
    assert r.returncode == 0, r.stderr
    assert _rows(r.stdout)["2"] == ["main.lad", "2/2", "4/4", "2/2", "10/10", "4/4", "100%"]


def test_without_coverage_no_summary():
    r = softplc_here("test", str(CONVEYOR))
    assert r.returncode == 0 and "Rung T/F" not in r.stdout


def test_fail_under_exit_codes(tmp_path):
    app = _conveyor(tmp_path)  # 15 of 22 covered: 68.18%
    r = softplc_here("test", str(app), "--fail-under", "68")
    assert r.returncode == 0, r.stderr
    assert "Total" in r.stdout  # --fail-under alone measures and prints the summary
    r = softplc_here("test", str(app), "--fail-under", "68.5")
    assert r.returncode == 2
    assert r.stderr == "coverage 68.18% is below --fail-under 68.5%\n"
    failing = _conveyor(tmp_path / "f", '\nscenario "wrong":\n    scan 1\n    expect Conveyor == 1\n')
    assert softplc_here("test", str(failing), "--fail-under", "99").returncode == 1  # the failure first
    bad = softplc_here("test", str(app), "--fail-under", "lots")
    assert bad.returncode == 2 and "expected a percentage 0..100, got 'lots'" in bad.stderr
