"""``pytest --plc-coverage``: the plugin measures the scenarios it runs and
prints each app's summary; --plc-coverage-xml and --plc-coverage-lcov write
one report of every app (a real pytest run of copied apps)."""

import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_pytest_plc_coverage(tmp_path):
    apps = []
    for name in ("conveyor", "conveyor2"):
        shutil.copytree(ROOT / "docs" / "examples" / "conveyor", tmp_path / name)
        apps.append(tmp_path / name)
    (apps[1] / "tests" / "conveyor.plctest").write_text(
        'scenario "idle":\n    scan 2\n    expect Conveyor == 0\n', encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist", "-q",
                        f"--basetemp={tmp_path / 'bt'}", "--rootdir", str(tmp_path), "--plc-coverage",
                        "--plc-coverage-xml", "c.xml", "--plc-coverage-lcov", "c.info",
                        str(apps[0] / "tests"), str(apps[1] / "tests")],
                       cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
                       timeout=120, check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout.splitlines()
    first = next(i for i, line in enumerate(out) if f"ladder coverage: {apps[0]}" in line)
    assert out[first + 3].split() == ["2", "main.lad", "2/2", "3/4", "1/2", "6/10", "3/4", "68%"]
    second = next(i for i, line in enumerate(out) if f"ladder coverage: {apps[1]}" in line)
    # idle, by hand: rung 1 false only (1/2), no leg powered (0/2), XIC Enable and XIC Manual seen
    # false, PartSensor and XIO Jam never reached by power (2/8), OTE off (1/2); rung 2 false (1/2),
    # XIC Jam false (1/2), OTE off (1/2): 2 + 2 + 0 + 3 + 2 = 9 of 22
    assert out[second + 3].split() == ["2", "main.lad", "2/2", "2/4", "0/2", "3/10", "2/4", "41%"]
    root = ET.parse(tmp_path / "c.xml").getroot()
    assert sorted(c.get("filename") for c in root.iter("class")) == ["conveyor/main.lad", "conveyor2/main.lad"]
    assert (tmp_path / "c.info").read_text().count("end_of_record") == 2
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "--plc-coverage", "-n", "2", "-q",
                        f"--basetemp={tmp_path / 'bt2'}", "--rootdir", str(tmp_path), str(apps[0] / "tests")],
                       cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
                       timeout=120, check=False)
    assert r.returncode == 0 and "not measured across pytest-xdist workers" in r.stdout, r.stdout + r.stderr
