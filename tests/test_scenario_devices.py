"""Simulated devices in scenario files: ``device PORT = KIND KEY=VALUE``
lines (parsed, attached on real sim:// ports of a fresh PLC each scenario)
and ``device PORT NAME`` values in expectations; every mistake located."""

from pathlib import Path

import pytest

from softplc_lite.testing.runner import run_file
from softplc_lite.testing.scenario import DeviceLine, ScenarioErrors, parse_scenarios

ROOT = Path(__file__).resolve().parent.parent
SLAVE = ROOT / "programs" / "modbus_slave"
LOOPBACK = ROOT / "programs" / "loopback"


def test_device_lines_and_counters_parse():
    f = parse_scenarios('device 0 = scripted match="?" reply="OK\\r\\n" delay_ms=5\n'
                        'device MODBMAST:1 = modbus id=1,2\n'
                        'scenario "s":\n    expect device 0 replies == 1\n'
                        '    wait until device MODBMAST:1 requests != 0 within 1 s\n')
    assert f.devices == [DeviceLine("0", "scripted", (("match", "?"), ("reply", "OK\r\n"), ("delay_ms", "5")), 1, 1),
                         DeviceLine("MODBMAST:1", "modbus", (("id", "1,2"),), 2, 1)]
    steps = f.scenarios[0].steps
    assert [s.args[0] for s in steps] == ["device 0 replies", "device MODBMAST:1 requests"]
    assert (steps[1].args[0].port, steps[1].args[0].attribute) == ("MODBMAST:1", "requests")


def test_misplaced_repeated_and_misspelt_device_lines_are_located(tmp_path):
    text = ('device 0 = echo\ndevice 0 = echo\ndevice 1 = echo delay_ms=1 delay_ms=2\ndevice = echo\n'
            'scenario "s":\n    scan 1\ndevice 2 = echo\n    set device 0 bad = 1\n')
    with pytest.raises(ScenarioErrors) as e:
        parse_scenarios(text, "f.plctest")
    assert [(x.line, x.message.split(":")[0]) for x in e.value.errors] == [
        (2, "expected one device a port"), (3, "expected each option once"), (4, "expected a step (set, force, unforce, scan, run, wait until, expect), a block header (setup"),
        (7, "expected device lines before setup"), (8, "expected a step (set, force, unforce, scan, run, wait until, expect), a block header (setup")]


def test_a_device_line_replaces_the_apps_device_and_its_score_is_expected(tmp_path):
    f = tmp_path / "fast.plctest"
    f.write_text('device 0 = modbus_master id=1 period_ms=10\n'
                 'scenario "fast master":\n    run 500 ms\n    expect device 0 bad == 0\n'
                 '    expect device 0 sent between 25 and 40\n    expect device 0 period_ns == 10000000\n'
                 'scenario "fails with its words":\n    run 100 ms\n    expect device 0 timeouts == 1\n',
                 encoding="utf-8")
    ok, failed = run_file(SLAVE, f)
    assert ok.passed, ok.failure.report()
    assert failed.failure.report() == f"{f}:9: expected device 0 timeouts == 1, got 0 (scan 100, 0.1 s)"


def test_a_master_polling_another_id_times_out(tmp_path):
    f = tmp_path / "other.plctest"
    f.write_text('device 0 = modbus_master id=7\nscenario "silence":\n'
                 '    wait until device 0 timeouts == 2 within 1 s\n    expect device 0 replies == 0\n'
                 '    expect Served.ACC == 0\n', encoding="utf-8")
    [r] = run_file(SLAVE, f)
    assert r.passed, r.failure.report()


def test_bad_devices_and_counters_are_located_all_at_once(tmp_path):
    f = tmp_path / "bad.plctest"
    f.write_text('device 0 = modbus_master speed=3\ndevice 3 = echo\n'
                 'scenario "s":\n    expect device 0 bogus == 0\n    expect device 2 bad == 0\n', encoding="utf-8")
    with pytest.raises(ScenarioErrors) as e:
        run_file(SLAVE, f)
    assert [(x.line, x.column) for x in e.value.errors] == [(1, 1), (2, 1)]
    assert "modbus_master device: unknown option 'speed'" in str(e.value)
    assert "expected a port of the app: the app has no port 3 (its ports: COMGENIUS:0)" in str(e.value)
    f.write_text('scenario "s":\n    expect device 0 bogus == 0\n    expect device 2 bad == 0\n', encoding="utf-8")
    with pytest.raises(ScenarioErrors) as e:
        run_file(SLAVE, f)
    assert [(x.line, x.column) for x in e.value.errors] == [(2, 5), (3, 5)]
    assert "expected a number of the modbus_master device's score: bogus (its numbers: bad, exceptions" in str(e.value)
    with pytest.raises(ScenarioErrors, match="no simulated device on it .loop://."):
        run_file(LOOPBACK, f)
