"""The pytest plugin in a real pytest run of a copied app: one item a
scenario, named by it, and --junitxml read back."""

import shutil
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_pytest_collects_scenarios_and_writes_junit(tmp_path):
    app = tmp_path / "motor"
    shutil.copytree(ROOT / "programs" / "motor", app, ignore=shutil.ignore_patterns(".softplc"))
    (app / "tests" / "bad.plctest").write_text('scenario "never":\n    run 1 s\n    expect Motor == 1\n'
                                               'scenario "input":\n    expect Start == 1\n', encoding="utf-8")
    junit = tmp_path / "out.xml"
    # the plugin comes from its pytest11 entry point, as in any project that installed softplc_lite
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist", "-q", f"--basetemp={tmp_path / 'bt'}",
                        f"--junitxml={junit}", "--rootdir", str(tmp_path), str(app / "tests")],
                       cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=120, check=False)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "expected Motor == 1, got 0 (scan 100, 1 s)" in r.stdout
    # the rung that writes Motor, drawn as plain text under the failure, and said of an input
    drawn = ["program file 2, rungs that write Motor (O:0/0):", "Rung 0", "Seal-in: start", "--( )--|"]
    assert all(part in r.stdout for part in drawn) and "\x1b[" not in r.stdout
    assert "no rung writes Start (I:0/0): it is an input, or set by the test" in r.stdout
    cases = {c.get("name"): c.find("failure") for c in ET.parse(junit).iter("testcase")}
    assert "start seals in" in cases and {name for name, f in cases.items() if f is not None} == {"never", "input"}
    assert all(part in cases["never"].text for part in drawn)
    assert "no rung writes Start (I:0/0)" in cases["input"].text



def test_the_plc_fixture_in_a_projects_test_file(tmp_path):
    """A project's own test file uses the ``plc`` fixture (from the entry
    point, nothing imported for it): a PLC with a simulated device on its
    port, closed after each test (its sim:// link gone)."""
    app = tmp_path / "modbus_slave"
    shutil.copytree(ROOT / "programs" / "modbus_slave", app, ignore=shutil.ignore_patterns(".softplc", "tests"))
    tests = tmp_path / "tests"
    tests.mkdir()
    (tests / "test_slave.py").write_text(f'''
from softplc_lite.ports import simlink
from softplc_lite.ports.modbus_master import ModbusMaster

APP = {str(app)!r}


def test_the_slave_serves_a_fast_master(plc):
    slave = plc(APP, devices={{0: ModbusMaster(1, period_ms=10)}})
    slave.run(0.5)
    master = slave.device(0)
    assert master.bad == 0 and master.replies > 20
    assert slave["N10:0"] == master.model.registers[0]
    assert [n for n in simlink.link_names() if n.startswith("plc")]


def test_the_link_was_closed_with_the_plc():
    assert not [n for n in simlink.link_names() if n.startswith("plc")]


def test_a_wrong_expectation_fails(plc):
    slave = plc(APP)
    slave.run(0.1)
    assert slave.device(0).timeouts == 1
''', encoding="utf-8")
    junit = tmp_path / "out.xml"
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist", "-p", "no:randomly",
                        "-q", f"--basetemp={tmp_path / 'bt'}", f"--junitxml={junit}", "--rootdir", str(tmp_path),
                        str(tests)],
                       cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
                       timeout=120, check=False)
    assert r.returncode == 1, r.stdout + r.stderr
    cases = {c.get("name"): c.find("failure") is not None for c in ET.parse(junit).iter("testcase")}
    assert cases == {"test_the_slave_serves_a_fast_master": False, "test_the_link_was_closed_with_the_plc": False,
                     "test_a_wrong_expectation_fails": True}, r.stdout
    assert "assert 0 == 1" in r.stdout
