"""MODBMAST from the ladder and the command line: the MBR_ instructions in
both rung syntaxes, what bad operands do, PROGRAM -> PROGRAM reloading the
configuration, --port / --record / --replay, and the one-owner rule."""

from __future__ import annotations

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.ladder import status as S
from softplc_lite.ladder.engine import Mode
from softplc_lite.ports.modbus_slave import find_slave
from softplc_lite.tlm.modbmast.status import NO_REPLY

from helpers.cli import softplc_here
from helpers.modbmast_apps import Apps, link, modbmast, scans, serial_xml, status, write_app


@pytest.fixture
def apps(tmp_path):
    made = Apps(tmp_path)
    yield made
    made.close()


def three_slaves(name: str, timeout: int = 20) -> str:
    """Port 1 with slaves 1, 2 (on the line) and 3 (missing)."""
    slaves = "".join(f'<Slave id="{sid}" requestTimeout="{timeout}"><ReadMultipleRegisters><refNum>40001</refNum>'
                     f'<toBlock dest="N10:{10 * sid}" count="2" fmt="i2"/></ReadMultipleRegisters></Slave>'
                     for sid in (1, 2, 3))
    return serial_xml(f'<Port num="1" baudrate="38400" device="sim://{name}?device=modbus&amp;id=1,2">'
                      f'{slaves}</Port>')


MNEMONIC = """\
MBR_GETFAULTMAP 1 #B3:0 OTE B20/0
MBR_GETSTATUS #N9:0 1 1 3
XIC B20/1 MBR_CLEARSTATUS 1 3 1
"""
NEUTRAL = """\
MBR_GETFAULTMAP(1,#B3:0)OTE(B20/0);
MBR_GETSTATUS(#N9:0,1,1,3);
XIC(B20/1)MBR_CLEARSTATUS(1,3,1);
"""


@pytest.mark.parametrize("ladder", [MNEMONIC, NEUTRAL], ids=["mnemonic", "neutral"])
@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_the_three_instructions_as_the_manual_uses_them(apps, ladder, executor):
    r = apps(three_slaves(link()), ladder=ladder, executor=executor)
    scans(r, 20)
    t = r.table
    assert [t.read(f"B3/{k}") for k in range(5)] == [0, 0, 0, 1, 0]  # slave 3 not answering; bit 0 always 0
    assert [t.read_word(f"B3:{k}") for k in range(1, 17)] == [0] * 16
    assert t.read("B20/0") == 1  # the permissive is true while a slave has failed
    blocks = [[t.read(f"N9:{5 * k + w}") for w in range(5)] for k in range(3)]
    assert blocks[0][1:] == [0, 0, 0, 0] and blocks[0][0] >= 1  # slave 1: ~ms response time, no errors
    assert blocks[2][1] > 0 and blocks[2][3:] == [3, NO_REPLY]
    t.write("B20/1", 1)  # MBR_CLEARSTATUS 1 3 1
    r.engine.scan()
    assert status(r, 1, 3).words()[1:3] == (0, 0)
    t.write("B20/1", 0)
    find_slave(modbmast(r).drivers[0].port.url.split("//")[1].split("?")[0]).unit(1).online = False
    scans(r, 20)
    assert t.read("B3/1") == 1 and t.read("B3/3") == 1


def test_getstatus_of_ids_the_port_does_not_configure_gives_zeros(apps):
    r = apps(three_slaves(link()), ladder="FLL -1 #N9:0 20\nMBR_GETSTATUS #N9:0 1 2 3\n")
    scans(r, 5)
    words = [r.table.read(f"N9:{k}") for k in range(16)]
    assert words[5:10] != [0] * 5  # slave 3 has timed out
    assert words[10:15] == [0] * 5 and words[15] == -1  # slave 4 is not configured: zeros, and no more


@pytest.mark.parametrize("ladder,code", [
    ("MBR_GETSTATUS #N9:0 7 1 1\n", S.MINOR_CODE_PORT),
    ("MBR_CLEARSTATUS N7:0 1 1\n", S.MINOR_CODE_PORT),  # N7:0 holds 0: no port 0
    ("MBR_GETSTATUS #N9:0 1 247 2\n", S.MINOR_CODE_OPERAND),
    ("MBR_CLEARSTATUS 1 N7:1 0\n", S.MINOR_CODE_OPERAND),
])
def test_a_bad_port_or_slave_range_is_a_minor_fault(apps, ladder, code):
    r = apps(three_slaves(link()), ladder=ladder)
    scans(r, 2)
    s = r.engine.s
    assert s[S.MINOR_FAULT_BITS] & (1 << S.MINOR_MODULE_BIT) and s[S.MINOR_FAULT_CODE] == code
    assert r.engine.mode is Mode.RUN


def test_getfaultmap_of_an_unconfigured_port_is_false_with_a_minor_fault(apps):
    r = apps(three_slaves(link()), ladder="MBR_GETFAULTMAP 4 #B3:0 OTE B20/0\n")
    scans(r, 20)
    assert r.table.read("B20/0") == 0 and r.engine.s[S.MINOR_FAULT_CODE] == S.MINOR_CODE_PORT


def test_a_map_block_past_the_end_of_its_file_is_a_major_fault(apps):
    r = apps(three_slaves(link()), ladder="DATA N7 3 = 1 0 0\nMBR_GETFAULTMAP 1 #N7:[N7:0]\n")
    scans(r, 3)
    assert r.engine.mode is Mode.FAULTED and r.engine.fault.code == S.FAULT_BLOCK_RANGE
    assert "17 words from" in r.engine.fault.message


def test_a_direct_block_grows_its_file_as_cop_does(apps):
    r = apps(three_slaves(link()), ladder="MBR_GETFAULTMAP 1 #B30:0\nMBR_GETSTATUS #N40:0 1 1 4\n")
    assert r.table.file("B30").size == 17 and r.table.file("N40").size == 20


def test_check_warns_about_constant_operands_it_can_judge(tmp_path):
    d = write_app(tmp_path / "app", three_slaves(link()),
                  "MBR_GETFAULTMAP 5 #B3:0\nMBR_GETSTATUS #N9:0 1 240 10\nMBR_GETFAULTMAP 1 #N7:9990\n")
    app = load_app(d)
    text = "\n".join(app.warnings)
    assert "main.lad:1:17: MBR_GETFAULTMAP: port 5 is not configured in MODBMAST.XML (ports: 1)" in text
    assert "main.lad:2:23: MBR_GETSTATUS: slaves 240..249 are outside 1..247" in text
    assert "main.lad:3:19: MBR_GETFAULTMAP: 17 words from N7:9990 run past the largest file" in text


def test_operands_of_the_wrong_kind_are_errors(tmp_path):
    d = write_app(tmp_path / "app", three_slaves(link()), "MBR_GETFAULTMAP 1 #F8:0\nMBR_GETSTATUS #N9:0 1 1\n")
    with pytest.raises(AppError) as info:
        load_app(d)
    text = str(info.value)
    assert "main.lad:1:19: MBR_GETFAULTMAP operand 2 (map) must be word file address (#B3:0)" in text
    assert "main.lad:2:1: MBR_GETSTATUS takes 4 operands" in text


# -- PROGRAM -> PROGRAM: reload ----------------------------------------------------------------

def test_program_to_program_reloads_the_configuration(apps):
    name = link()
    r = apps(three_slaves(name), run=False)
    scans(r, 5)
    app_dir = r.app.path
    xml = (app_dir / "MODBMAST.XML").read_text().replace('dest="N10:20"', 'dest="N11:0"')
    (app_dir / "MODBMAST.XML").write_text(xml)
    r.engine.set_mode(Mode.PROGRAM)  # PROGRAM -> PROGRAM
    scans(r, 5)
    assert r.table.read("N11:1") != 0 and r.engine.mode is Mode.PROGRAM
    assert status(r, 1, 3).words()[1] > 0  # statuses start over with the new configuration, then count


def test_a_bad_file_at_reload_faults_the_plc_and_keeps_the_old_configuration(apps):
    r = apps(three_slaves(link()), run=False)
    scans(r, 2)
    (r.app.path / "MODBMAST.XML").write_text("<ModbusSerial><Port num='1'/></ModbusSerial>")
    r.engine.set_mode(Mode.PROGRAM)
    assert r.engine.mode is Mode.FAULTED and r.engine.fault.code == S.FAULT_MODULE_CONFIG
    assert "MODBMAST.XML:1:15: <Port> needs the attribute baudrate" in r.engine.fault.message
    before = r.table.read("N10:10")
    r.table.write("N10:10", 0)
    scans(r, 3)
    assert r.table.read("N10:10") == before  # the old scan list goes on
    r.engine.set_mode(Mode.PROGRAM)  # clear the fault
    assert r.engine.mode is Mode.PROGRAM


# -- the command line ---------------------------------------------------------------------------

COMGENIUS_LST = "[DRIVER]\nDEBUG=0\n[PORTS]\n1, {device}, ISO-8859-1, 38400, 8, N, 1, 50\n[STRINGS]\n\"x\"\n"


def test_port_overrides_name_the_module_when_both_have_the_port(tmp_path):
    d = write_app(tmp_path / "app", three_slaves("cli-a"), "MBR_GETSTATUS #N9:0 1 1 1\n",
                  modules="COMGENIUS\nMODBMAST\n", extra={"COMGENIUS.LST": COMGENIUS_LST.format(device="loop://")})
    args = ("run", str(d), "--fresh", "--scans", "20", "--print", "N10:11")
    both = softplc_here(*args, "--port", "1=sim://x?device=modbus&id=1")
    assert both.returncode == 1 and "COMGENIUS and MODBMAST both have a port 1; say which: " \
        "--port COMGENIUS:1=... or --port MODBMAST:1=..." in both.stderr
    ok = softplc_here(*args, "--port", "MODBMAST:1=sim://cli-b?device=modbus&id=1&values=index")
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.strip() == "N10:11 = 1"  # holding register 1 with values=index


def test_two_modules_may_not_open_one_device(tmp_path):
    tty = tmp_path / "ttyX"
    tty.write_text("")
    xml = serial_xml(f'<Port num="2" baudrate="9600" device="{tty}"/>')
    d = write_app(tmp_path / "app", xml, "XIC B3/0 OTE B3/1\n", modules="COMGENIUS\nMODBMAST\n",
                  extra={"COMGENIUS.LST": COMGENIUS_LST.format(device=tty)})
    result = softplc_here("check", str(d))
    assert result.returncode == 1
    assert f"MODBMAST.XML:2: MODBMAST port 2 would open {tty}, which COMGENIUS port 1 opens (" in result.stderr
    assert "COMGENIUS.LST:4); a serial device has one owner" in result.stderr


def test_record_then_replay_gives_the_same_data_table(tmp_path):
    d = write_app(tmp_path / "app", three_slaves("rec"), MNEMONIC)
    trace = tmp_path / "run.trace"
    args = ("run", str(d), "--fresh", "--scans", "40", "--print", "N10:11", "--print", "N9:6")
    first = softplc_here(*args, "--record", str(trace))
    assert first.returncode == 0, first.stderr
    text = trace.read_text()
    assert "MODBMAST:1 TX 01 03 00 00 00 02 C4 0B" in text and "MODBMAST:1 RX 01 03 04" in text
    again = softplc_here(*args, "--replay", str(trace))
    assert again.returncode == 0, again.stderr
    assert again.stdout == first.stdout and "output matched" in again.stderr


def test_check_lists_the_config_files_problems_and_the_programs_together(tmp_path):
    xml = serial_xml('<Port num="40" baudrate="9600"><Slave id="0"/></Port>', 'debug="7"')
    d = write_app(tmp_path / "app", xml, "XIC B3/0 OTE B3/1\nMOV 1 N7:0 N7:1\n",
                  modules="COMGENIUS\nMODBMAST\n", extra={"COMGENIUS.LST": "[DRIVER]\nDEBUG=5\n"})
    result = softplc_here("check", str(d))
    lines = result.stderr.splitlines()
    assert result.returncode == 1 and lines[-1] == "5 problems found"
    assert lines[0].endswith("COMGENIUS.LST:2: [DRIVER]: DEBUG must be 0, 1 or 2, not '5'")
    assert lines[1].endswith("MODBMAST.XML:1:15: debug='7': expected an integer 0..2")
    assert lines[2].endswith("MODBMAST.XML:2:7: num='40': expected an integer 0..31")
    assert lines[3].endswith("MODBMAST.XML:2:39: id='0': expected an integer 1..247")
    assert "main.lad:2:1: MOV takes 2 operands" in lines[4]


def test_a_port_that_opens_late_is_retried_and_recorded(tmp_path):
    """portErrors="retry": a port whose device is missing at start leaves its
    slaves Not Present (-5); once the device exists it opens, its slaves
    answer, and --record has its traffic."""
    import os
    import time

    from softplc_lite.runner import RunOptions, Runner
    from softplc_lite.tlm.modbmast.status import NO_XMIT_ROOM
    from helpers.ptypair import PtyPair, require_socat

    require_socat()
    late = tmp_path / "late-tty"
    body = ('<Slave id="2" requestTimeout="50"><ReadMultipleRegisters><refNum>40001</refNum>'
            '<toBlock dest="N7:0" count="1" fmt="i2"/></ReadMultipleRegisters></Slave>')
    xml = serial_xml(f'<Port num="1" baudrate="38400" device="{late}">{body}</Port>', 'portErrors="retry" retryMs="10"')
    d = write_app(tmp_path / "app", xml)
    trace = tmp_path / "run.trace"
    runner = Runner(load_app(d), RunOptions(fresh=True, realtime=True, scan_ms=0, record=str(trace)))
    pair = None
    try:
        assert any("cannot open" in w for w in runner.engine.module_warnings)
        runner.engine.set_mode(Mode.RUN)
        runner.engine.scan()
        s = status(runner, 1, 2)
        assert not s.present and s.last_code == NO_XMIT_ROOM
        pair = PtyPair(tmp_path)
        os.symlink(pair.a, late)  # the device appears; nothing answers on it: NO REPLY now, not NO XMIT ROOM
        end = time.monotonic() + 10
        while s.last_code != -3 and time.monotonic() < end:
            runner.engine.scan()
        assert s.last_code == -3 and modbmast(runner).drivers[0].port.up
    finally:
        runner.engine.close()
        if pair is not None:
            pair.close()
    assert "MODBMAST:1 TX 02 03 00 00 00 01" in trace.read_text()
