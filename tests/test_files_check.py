"""softplc check lists every problem of every config file, not the first:
MODULES.LST, COMGENIUS.LST (sim:// options included),
MODBMAST.XML sim:// devices, softplc.toml; each with file and line, and
"N problems found". Each runs the CLI in this process (helpers.cli): the
test reads only what it prints and returns."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from helpers.cli import ROOT, softplc_here


def check(app: Path) -> subprocess.CompletedProcess[str]:
    return softplc_here("check", str(app))


def test_every_problem_of_every_config_file(tmp_path):
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "loopback", app)
    lst = (app / "COMGENIUS.LST").read_text()
    lst = lst.replace("DEBUG=0", "DEBUG=0\nFOO=3").replace(
        "0, loop://, ISO-8859-1, 38400, 8, N, 1, 100",
        "0, sim://x?device=modbus&turnaround_ms=abc, ISO-8859-1, 38400, 8, N, 1, 100\n"
        "1, sim://y?device=nosuch, ISO-8859-1, 38400, 8, N, 1, 100\n"
        "2, loop://, ISO-8859-1, 38400, 9, N, 1, 100")
    (app / "COMGENIUS.LST").write_text(lst)
    (app / "softplc.toml").write_text("[scan]\nscan_ms = -1\nbogus = 2\n[math]\noverflow = \"x\"\n")
    result = check(app)
    assert result.returncode == 1
    lines = result.stderr.splitlines()
    lst_path, toml = app / "COMGENIUS.LST", app / "softplc.toml"
    assert lines == [
        f"{lst_path}:7: [DRIVER]: unknown setting 'FOO' (settings: DEBUG, PORT_ERRORS, RETRY_MS, COM1..COM99)",
        f"{lst_path}:11: COMGENIUS port 0: modbus device: turnaround_ms must be a number >= 0, not 'abc' "
        '(expected "sim://NAME[?device=KIND[&KEY=VALUE...]][&rate=unlimited]")',
        f"{lst_path}:12: COMGENIUS port 1: unknown device kind 'nosuch' (known: echo, modbus, modbus_master, scripted) "
        '(expected "sim://NAME[?device=KIND[&KEY=VALUE...]][&rate=unlimited]")',
        f"{lst_path}:13: [PORTS]: data bits 9 is out of range (5..8)",
        f"{toml}:2: [scan] scan_ms = -1; expected an integer from 0 to 32767",
        f"{toml}:3: [scan] has no setting 'bogus' (settings: scan_ms, watchdog_ms, jsr_depth)",
        f"{toml}:5: [math] overflow = 'x'; expected one of 'clamp', 'wrap'",
        "7 problems found",
    ]


def test_every_problem_of_modules_lst_and_the_settings_beside_it(tmp_path):
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "loopback", app)
    (app / "MODULES.LST").write_text("COMGENIUS\nFOO BAR\nNOSUCH\ncomgenius\n")
    (app / "softplc.toml").write_text("[scan]\nscan_ms = -1\n")
    result = check(app)
    assert result.returncode == 1
    lst = app / "MODULES.LST"
    assert result.stderr.splitlines() == [
        f"{lst}:2: expected one module name on the line, found 'FOO BAR'",
        f"{lst}:3: module NOSUCH is not installed (installed modules: COMGENIUS, ENIPS, MODBMAST, MODBTCPS, OPCUAS)",
        f"{lst}:4: module COMGENIUS is named twice (first on line 1)",
        f"{app / 'softplc.toml'}:2: [scan] scan_ms = -1; expected an integer from 0 to 32767",
        "4 problems found",
    ]


def test_a_bad_sim_device_in_modbmast_xml_is_located_beside_its_other_problems(tmp_path):
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "modbus_scada", app)
    xml = (app / "MODBMAST.XML").read_text()
    assert 'device="sim://' in xml
    start = xml.index('device="sim://') + len('device="')
    end = xml.index('"', start)
    xml = xml[:start] + "sim://plant?device=modbus&amp;turnaround_ms=abc" + xml[end:]
    xml = xml.replace("<ModbusSerial", '<ModbusSerial bogus="1"', 1)
    (app / "MODBMAST.XML").write_text(xml)
    result = check(app)
    assert result.returncode == 1
    line = xml[:start].count("\n") + 1
    assert f"MODBMAST.XML:{line}:" in result.stderr
    assert "MODBMAST port" in result.stderr and "turnaround_ms must be a number >= 0, not 'abc'" in result.stderr
    assert "bogus" in result.stderr and result.stderr.splitlines()[-1].endswith("problems found")
    assert int(result.stderr.splitlines()[-1].split()[0]) >= 2
