"""``softplc test APP``: its summary and its exit codes."""

import shutil
from pathlib import Path

from tests.helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent


def _app(tmp_path, scenario: str) -> Path:
    app = tmp_path / "motor"
    app.mkdir()
    shutil.copy(ROOT / "programs" / "motor" / "main.lad", app / "main.lad")
    (app / "tests").mkdir()
    (app / "tests" / "m.plctest").write_text(scenario, encoding="utf-8")
    return app


def test_all_passing_exits_0_with_one_line_a_scenario():
    r = softplc_here("test", "programs/motor")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:3] == [
        "PASS programs/motor/tests/motor.plctest: start seals in",
        "PASS programs/motor/tests/motor.plctest: stop drops the motor",
        "PASS programs/motor/tests/motor.plctest: overload trips and stop resets",
    ]
    assert all(line.startswith("PASS programs/motor/tests/motor.plctest: ") for line in lines[:-1])
    assert lines[-1] == f"{len(lines) - 1} passed, 0 failed"


def test_a_failing_scenario_exits_1_and_says_why(tmp_path):
    app = _app(tmp_path, 'scenario "ok":\n    scan 1\nscenario "bad":\n    run 1 s\n    expect Motor == 1\n')
    r = softplc_here("test", str(app))
    assert r.returncode == 1
    lines = r.stdout.splitlines()
    assert lines[0].startswith("PASS") and lines[1].startswith("FAIL") and lines[1].endswith(": bad")
    assert lines[2].strip() == f"{app}/tests/m.plctest:5: expected Motor == 1, got 0 (scan 100, 1 s)"
    assert lines[-1] == "1 passed, 1 failed"


def test_located_errors_exit_1(tmp_path):
    app = _app(tmp_path, 'scenario "x":\n    scan x\n    expect Nope == 1\n')
    r = softplc_here("test", str(app))
    assert r.returncode == 1
    assert r.stderr.startswith(f"{app}/tests/m.plctest:2:")


def test_no_scenario_files_exit_1_and_usage_exits_2(tmp_path):
    app = _app(tmp_path, "")
    (app / "tests" / "m.plctest").unlink()
    r = softplc_here("test", str(app))
    assert r.returncode == 1 and "no scenario files" in r.stderr
    assert softplc_here("test").returncode == 2
