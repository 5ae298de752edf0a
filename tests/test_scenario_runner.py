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


def test_every_shipped_app_has_scenario_files():
    """An app in programs/ documents what it does in scenario files the suite runs."""
    apps = {p.parent.name for p in (ROOT / "programs").glob("*/main.lad")}
    assert len(apps) >= 10
    assert apps - {p.parent.parent.name for p in SHIPPED} == set()


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


@pytest.mark.parametrize("steps, passed", [
    # seen between two scans of the step: a multi-scan step, or an edge one scan long
    ("set StopOk = 1\n    set Start = 1\n    scan 3\n    expect rising Motor", True),
    ("set StopOk = 1\n    set Start = 1\n    scan 1\n    expect Motor == 1\n    expect rising Motor", True),
    # an edge of an earlier scanning step is not one of the last
    ("set StopOk = 1\n    set Start = 1\n    scan 1\n    scan 1\n    expect rising Motor", False),
    ("set StopOk = 1\n    set Start = 1\n    run 1 s\n    wait until Motor == 1 within 1 s\n    expect rising Motor",
     False),
    # a value set between scans is no edge: the step starts from the value after the last scan
    ("scan 1\n    set Motor = 1\n    scan 1\n    expect falling Motor", False),
    # before any scan there is no edge
    ("set StopOk = 1\n    set Start = 1\n    expect rising Motor", False),
])
def test_an_edge_is_one_between_two_scans_of_the_last_scanning_step(tmp_path, steps, passed):
    f = tmp_path / "e.plctest"
    f.write_text(f'scenario "s":\n    {steps}\n', encoding="utf-8")
    [r] = run_file(MOTOR, f)
    assert r.passed is passed, r.failure and r.failure.report()


def test_a_long_run_sees_each_edge_of_a_blink_and_reads_stay_exact(tmp_path):
    f = tmp_path / "b.plctest"
    f.write_text('scenario "s":\n    run 1.55 s\n    expect rising Lamp\n    expect falling Lamp\n'
                 '    expect C5:0.ACC == 2\n    expect T4:0/DN == 1\n    expect Lamp == 1\n', encoding="utf-8")
    [r] = run_file(ROOT / "programs" / "blinker", f)
    assert r.passed, r.failure and r.failure.report()


@pytest.mark.parametrize("name, value", [
    ("Start", 1), ("Motor", 0), ("B3/15", 1), ("T4:0/DN", 1), ("N7:0", -32768), ("C5:1.PRE", 32767),
    ("C5:0.ACC", 999), ("F8:0", 2.5), ("C5:1.ACC", True),
])
def test_the_api_reads_and_writes_as_the_table_does(name, value):
    """A direct bit or word is read and set straight in its file's array: the same values as the table's."""
    with PLC.load(MOTOR) as plc:
        for _ in range(2):  # the second time through the bound array
            plc.set(name, value)
            assert plc[name] == plc.table.read(plc.address(name)) == value
            plc.scan()


@pytest.mark.parametrize("name, value", [("Start", 2), ("B3/15", -1), ("N7:0", 70000), ("N7:0", 1.5),
                                         ("N7:0", "x"), ("F8:0", "x")])
def test_the_api_refuses_what_the_table_refuses_with_its_words(name, value):
    with PLC.load(MOTOR) as plc:
        with pytest.raises(Exception) as direct:
            plc.table.write(plc.address(name), value)
        plc.set(name, 0)  # bound
        with pytest.raises(type(direct.value)) as through_api:
            plc.set(name, value)
        assert str(through_api.value) == str(direct.value)
