"""The scenario runner and the Python API, on the shipped apps (only read:
the state directory is a temp dir)."""

from pathlib import Path

import pytest

from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import SCENARIO_GLOB, run_file
from softplc_lite.testing.scenario import ScenarioErrors

ROOT = Path(__file__).resolve().parent.parent
MOTOR = ROOT / "programs" / "motor"


def test_the_api_sets_scans_runs_and_reads_by_symbol_or_address():
    with PLC.load(MOTOR) as plc:
        plc.set("StopOk", 1)
        plc["Start"] = 1
        plc.scan(2)
        assert plc["Motor"] == 1 and plc["O:0/0"] == 1
        plc.set("Start", 0)
        plc.run(2.5)
        assert (plc.scan_number, plc.time_ms) == (252, 2520)
        assert plc["T4:0.ACC"] == 2
        plc.force("StopOk", 0)
        plc.set("StopOk", 1)
        plc.scan()
        assert plc["Motor"] == 0
        plc.unforce("StopOk")


def test_each_scenario_starts_fresh(tmp_path):
    f = tmp_path / "a.plctest"
    f.write_text('scenario "one":\n    set StopOk = 1\n    set Start = 1\n    scan 1\n    expect Motor == 1\n'
                 'scenario "two":\n    expect Motor == 0\n    expect C5:0.ACC == 0\n', encoding="utf-8")
    assert [r.passed for r in run_file(MOTOR, f)] == [True, True]


SHIPPED = sorted((ROOT / "programs").glob("*/" + SCENARIO_GLOB))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.parent.name}/{p.name}")
def test_the_shipped_scenarios_pass(path):
    """Every scenario file an app in programs/ ships passes: the apps' documented behaviour holds."""
    results = run_file(path.parent.parent, path)
    assert results and all(r.passed for r in results), [r.failure.report() for r in results if r.failure]


def test_the_shipped_apps_have_scenario_files():
    assert {"motor", "blinker", "modbus_slave", "modbus_master", "loopback", "strings", "modbus_scada",
            "hmi_server"} <= {p.parent.parent.name for p in SHIPPED}


def test_a_failure_says_expectation_actual_scan_and_time(tmp_path):
    f = tmp_path / "f.plctest"
    f.write_text('scenario "wrong":\n    run 1 s\n    expect Motor == 1\n', encoding="utf-8")
    [r] = run_file(MOTOR, f)
    assert r.failure.report() == f"{f}:3: expected Motor == 1, got 0 (scan 100, 1 s)"


@pytest.mark.parametrize("step, want", [
    ("expect C5:0.ACC within 0.5 of 1", "expected C5:0.ACC within 0.5 of 1, got 0"),
    ("expect C5:0.ACC between 1 and 2", "expected C5:0.ACC between 1 and 2, got 0"),
    ("expect rising Motor", "expected rising edge of Motor since the previous step, got 0"),
    ("expect falling Motor", "expected falling edge of Motor since the previous step, got 0"),
    ("wait until Motor == 1 within 50 ms", "expected Motor == 1 within 50 ms, got 0 (scan 6, 0.06 s)"),
    ("expect Motor != 0", "expected Motor != 0, got 0"),
])
def test_each_expectation_kind_fails_with_its_words(tmp_path, step, want):
    f = tmp_path / "f.plctest"
    f.write_text(f'scenario "s":\n    scan 1\n    {step}\n', encoding="utf-8")
    [r] = run_file(MOTOR, f)
    assert want in r.failure.report()


def test_unknown_names_are_located_all_at_once(tmp_path):
    f = tmp_path / "n.plctest"
    f.write_text('scenario "s":\n    set Nope = 1\n    scan 1\n    expect Q9:0 == 1\n', encoding="utf-8")
    with pytest.raises(ScenarioErrors) as e:
        run_file(MOTOR, f)
    assert [(x.line, x.column) for x in e.value.errors] == [(2, 9), (4, 12)]  # at the name
    assert "expected an address or a symbol of the program: Nope" in str(e.value)


def test_a_substituted_program_runs_with_the_rest_of_the_app(tmp_path):
    from softplc_lite.app import load_app
    from softplc_lite.ladder.ast import Program, ProgramFile
    source = load_app(MOTOR, state_dir=tmp_path, use_cache=False).source_program
    main = source.files[2]
    without_seal_in = Program({2: ProgramFile(2, main.name, main.rungs[1:], main.pos)}, source.data, source.symbols)
    with PLC.load(MOTOR, program=without_seal_in) as plc:
        plc.set("StopOk", 1)
        plc.set("Start", 1)
        plc.scan(2)
        assert plc["Motor"] == 0
    with PLC.load(MOTOR) as plc:  # the app's own files are untouched
        plc.set("StopOk", 1)
        plc.set("Start", 1)
        plc.scan(2)
        assert plc["Motor"] == 1
