"""Logix's function-block instructions called from Structured Text (TONR,
TOFR, RTOR on an FBD_TIMER; CTUD on an FBD_COUNTER; OSRI, OSFI on an
FBD_ONESHOT): ladder/instr/logix_fbd.py's rules, logix/fbd.py's
translation, docs/logix.md "Function-block instructions in Structured
Text". Hand-written exports in tmp_path, run on both executors over
simulated 10 ms scans, their members read as tags, by the command line, in
the watch view's tag monitor and over EtherNet/IP."""

from __future__ import annotations

import pytest
from pycomm3 import LogixDriver

from helpers.cli import softplc
from helpers.enips_apps import tank_line
from helpers.logix_aoi import Aoi, Param, write_aoi_l5x
from helpers.logix_l5x import Prog, Task, export_runner, l5x_text, read_tag, write_l5x, write_tag
from helpers.modbtcps_apps import Running
from softplc_lite.app import AppError, load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.session import WatchOptions, WatchSession
from softplc_lite.watch.snapshot import render

EXECUTORS = ["compiled", "reference"]
TAGS = [("Tm", "FBD_TIMER"), ("Run", "BOOL"), ("Rst", "BOOL"), ("Pre", "DINT"), ("Cn", "FBD_COUNTER"),
        ("Up", "BOOL"), ("Down", "BOOL"), ("Rise", "FBD_ONESHOT"), ("Fall", "FBD_ONESHOT"), ("In", "BOOL"),
        ("Rises", "DINT"), ("Falls", "DINT"), ("Count", "DINT")]


def runner(tmp_path, executor, st: str, values=None, edit=None):
    text = l5x_text(TAGS, [Prog("MainProgram", {"Main": st})], [Task("T", ["MainProgram"])])
    path = tmp_path / "fbd.L5X"
    path.write_text(edit(text) if edit else text, encoding="utf-8")
    r = export_runner(path, executor)
    for tag, value in (values or {}).items():
        write_tag(r, tag, value)
    return r


def timer_st(kind: str) -> str:
    return f"Tm.PRE := Pre;\nTm.TimerEnable := Run;\nTm.Reset := Rst;\n{kind}(Tm);"


def timer(r) -> tuple:
    return tuple(read_tag(r, f"Tm.{m}") for m in ("ACC", "EN", "TT", "DN"))


def scans(r, n: int, probe=timer, **writes) -> list:
    """``writes`` (tag=value) first, then ``n`` scans, probed after each."""
    for tag, value in writes.items():
        write_tag(r, tag, value)
    out = []
    for _ in range(n):
        r.run(1)
        out.append(probe(r))
    return out


@pytest.mark.parametrize("executor", EXECUTORS)
def test_ltonr_times_while_timer_enable_is_set_and_reset_clears_it(tmp_path, executor):
    r = runner(tmp_path, executor, timer_st("TONR"), {"Pre": 50, "Run": 1})
    # The scan TimerEnable goes set adds nothing; then 10 ms a scan up to PRE, where ACC stays.
    assert scans(r, 7) == [(0, 1, 1, 0), (10, 1, 1, 0), (20, 1, 1, 0), (30, 1, 1, 0), (40, 1, 1, 0),
                           (50, 1, 0, 1), (50, 1, 0, 1)]
    assert read_tag(r, "Tm.EnableOut") == 1 and read_tag(r, "Tm.EnableIn") == 1
    assert scans(r, 2, Rst=1) == [(0, 0, 0, 0)] * 2  # Reset: no timing while it is set, TimerEnable or not
    assert scans(r, 2, Rst=0) == [(0, 1, 1, 0), (10, 1, 1, 0)]  # timing again once Reset is cleared
    assert scans(r, 1, Run=0) == [(0, 0, 0, 0)]  # TimerEnable cleared: EN, TT, DN and ACC cleared


@pytest.mark.parametrize("executor", EXECUTORS)
def test_lrtor_keeps_acc_and_dn_while_disabled_until_reset(tmp_path, executor):
    r = runner(tmp_path, executor, timer_st("RTOR"), {"Pre": 50, "Run": 1})
    assert scans(r, 3)[-1] == (20, 1, 1, 0)
    assert scans(r, 2, Run=0) == [(20, 0, 0, 0)] * 2  # retained
    assert scans(r, 5, Run=1)[-1] == (50, 1, 0, 1)  # the first scan back adds nothing, then on from 20
    assert scans(r, 1, Run=0) == [(50, 0, 0, 1)]  # DN kept too
    assert scans(r, 1, Rst=1) == [(0, 0, 0, 0)]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_ltofr_times_once_timer_enable_drops_and_reset_puts_acc_at_pre(tmp_path, executor):
    r = runner(tmp_path, executor, timer_st("TOFR"), {"Pre": 30, "Run": 1})
    assert scans(r, 1) == [(0, 1, 0, 1)]
    assert scans(r, 5, Run=0) == [(0, 0, 1, 1), (10, 0, 1, 1), (20, 0, 1, 1), (30, 0, 0, 0), (30, 0, 0, 0)]
    scans(r, 1, Run=1)
    assert scans(r, 1, Rst=1) == [(30, 0, 0, 0)]  # RM003: TOFR's Reset sets ACC = PRE


@pytest.mark.parametrize("executor", EXECUTORS)
def test_ltonr_with_a_negative_preset_sets_presetinv_and_instructfault_and_does_not_fault(tmp_path, executor):
    r = runner(tmp_path, executor, timer_st("TONR") + "\nCount := Count + 1;", {"Pre": -5, "Run": 1})
    scans(r, 3)
    assert (read_tag(r, "Tm.PresetInv"), read_tag(r, "Tm.InstructFault"), read_tag(r, "Tm.Status")) == (1, 1, 3)
    assert read_tag(r, "Tm.EnableOut") == 0 and timer(r) == (0, 0, 0, 0) and read_tag(r, "Count") == 3
    assert r.engine.fault is None
    scans(r, 2, Pre=100)
    assert (read_tag(r, "Tm.Status"), read_tag(r, "Tm.EnableOut"), read_tag(r, "Tm.ACC")) == (0, 1, 10)


def counter(r) -> tuple:
    return tuple(read_tag(r, f"Cn.{m}") for m in ("ACC", "CU", "CD", "DN", "OV", "UN"))


@pytest.mark.parametrize("executor", EXECUTORS)
def test_lctud_counts_edges_of_cuenable_and_cdenable(tmp_path, executor):
    st = "Cn.PRE := 2;\nCn.CUEnable := Up;\nCn.CDEnable := Down;\nCn.Reset := Rst;\nCTUD(Cn);"
    r = runner(tmp_path, executor, st)
    steps = [(1, 0), (1, 0), (0, 0), (1, 0), (1, 1), (0, 0), (0, 1)]  # (Up, Down) a scan
    seen = []
    for up, down in steps:
        seen.append(scans(r, 1, counter, Up=up, Down=down)[0])
    assert seen == [(1, 1, 0, 0, 0, 0), (1, 1, 0, 0, 0, 0), (1, 0, 0, 0, 0, 0), (2, 1, 0, 1, 0, 0),
                    (1, 1, 1, 0, 0, 0), (1, 0, 0, 0, 0, 0), (0, 0, 1, 0, 0, 0)]
    assert scans(r, 1, counter, Rst=1, Up=1, Down=0) == [(0, 0, 0, 0, 0, 0)]
    assert scans(r, 1, counter, Rst=0) == [(0, 1, 0, 0, 0, 0)]  # CUEnable held through Reset: no edge


@pytest.mark.parametrize("executor", EXECUTORS)
def test_lctud_wraps_past_the_dint_range_setting_ov_and_un(tmp_path, executor):
    st = "Cn.CUEnable := Up;\nCn.CDEnable := Down;\nCTUD(Cn);"
    r = runner(tmp_path, executor, st)
    write_tag(r, "Cn.ACC", 2 ** 31 - 1)
    assert scans(r, 1, counter, Up=1) == [(-(2 ** 31), 1, 0, 0, 1, 0)]
    write_tag(r, "Cn.ACC", -(2 ** 31))
    scans(r, 1, counter, Up=0, Down=0)
    assert scans(r, 1, counter, Down=1) == [(2 ** 31 - 1, 0, 1, 1, 1, 1)]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_losri_and_losfi_set_outputbit_for_one_run_per_edge(tmp_path, executor):
    st = ("Rise.InputBit := In;\nFall.InputBit := In;\nOSRI(Rise);\nOSFI(Fall);\n"
          "IF Rise.OutputBit THEN Rises := Rises + 1; END_IF;\nIF Fall.OutputBit THEN Falls := Falls + 1; END_IF;")
    r = runner(tmp_path, executor, st, {"In": 1})

    def probe(r):
        return read_tag(r, "Rise.OutputBit"), read_tag(r, "Fall.OutputBit")
    assert scans(r, 2, probe) == [(0, 0), (0, 0)]  # the first scan takes InputBit as it is: no edge
    assert scans(r, 2, probe, In=0) == [(0, 1), (0, 0)]
    assert scans(r, 2, probe, In=1) == [(1, 0), (0, 0)]
    assert (read_tag(r, "Rises"), read_tag(r, "Falls"), read_tag(r, "Rise.EnableOut")) == (1, 1, 1)


def test_a_decorated_value_is_read_by_member_name(tmp_path):
    data = ('<Tag Name="Tm" TagType="Base" DataType="FBD_TIMER" Constant="false" ExternalAccess="Read/Write">'
            '<Data Format="L5K"><![CDATA[[1,0,0,0,0,0,0,0,0,4,0,0]]]></Data>'
            '<Data Format="Decorated"><Structure DataType="FBD_TIMER">'
            '<DataValueMember Name="EnableIn" DataType="BOOL" Value="1"/>'
            '<DataValueMember Name="TimerEnable" DataType="BOOL" Value="1"/>'
            '<DataValueMember Name="PRE" DataType="DINT" Radix="Decimal" Value="1500"/>'
            '<DataValueMember Name="Status" DataType="DINT" Radix="Hex" Value="16#0000_0000"/>'
            '</Structure></Data></Tag>')

    def edit(text):
        return text.replace('<Tag Name="Tm" TagType="Base" DataType="FBD_TIMER" Constant="false" '
                            'ExternalAccess="Read/Write"/>', data)
    r = runner(tmp_path, "compiled", "TONR(Tm);", edit=edit)
    assert (read_tag(r, "Tm.PRE"), read_tag(r, "Tm.TimerEnable"), read_tag(r, "Tm.Reset")) == (1500, 1, 0)
    r.run(3)
    assert timer(r) == (20, 1, 1, 0)


def test_the_wrong_tag_type_and_a_call_in_a_ladder_rung_are_located_errors(tmp_path):
    st = "TONR(Cn);\nCTUD(Tm);\nOSRI(Run, In);"
    path = write_l5x(tmp_path / "bad.L5X", TAGS, [Prog("MainProgram", {"Main": ["TONR(Tm);"], "S": st})],
                     [Task("T", ["MainProgram"])])
    with pytest.raises(AppError) as e:
        load_app(path)
    text = str(e.value)
    assert "TONR operand 'Cn': expected an FBD_TIMER tag, found FBD_COUNTER" in text
    assert "CTUD operand 'Tm': expected an FBD_COUNTER tag, found FBD_TIMER" in text
    assert "OSRI takes 1 operand, found 2" in text
    assert "TONR is a function-block instruction: Logix has it in Structured Text and function block diagrams, " \
           "not in a ladder rung" in text
    located = [line for line in text.splitlines() if "bad.L5X:" in line]
    assert len(located) >= 4, text


def test_softplc_run_prints_fbd_timer_members(tmp_path):
    write_l5x(tmp_path / "fbd.L5X", TAGS, [Prog("MainProgram", {"Main": timer_st("TONR")})],
              [Task("T", ["MainProgram"])])
    p = softplc("run", "fbd.L5X", "--scans", "5", "--set", "Run=1", "--set", "Pre=1000", "--print", "Tm.ACC",
                "--print", "Tm.TT", cwd=tmp_path)
    assert p.returncode == 0, p
    assert [line.split(" = ")[1] for line in p.stdout.splitlines() if line.startswith("Tm.")] == ["40", "1"], p


@pytest.mark.timeout(120)
def test_fbd_timer_members_are_tags_over_ethernet_ip(tmp_path):
    (tmp_path / "src").mkdir()
    source = write_l5x(tmp_path / "src" / "fbd.L5X", TAGS, [Prog("MainProgram", {"Main": "Tm.TimerEnable := Run;\nTONR(Tm);"})],
                       [Task("T", ["MainProgram"])])
    plc = Running(tank_line(tmp_path / "app", body='  <Writable tag="Tm"/>\n  <Writable tag="Run"/>\n',
                            source=source), module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            assert driver.write("Tm.PRE", 10_000_000).error is None
            assert driver.write("Run", True).error is None
            plc.wait_for(lambda: driver.read("Tm.ACC").value > 0, "the TONR timing")
            whole = driver.read("Tm")
            assert whole.error is None and whole.type == "FBD_TIMER", whole
            assert whole.value["TimerEnable"] is True and whole.value["TT"] is True and "CTL" not in whole.value
            assert whole.value["PRE"] == 10_000_000 and whole.value["DN"] is False
            assert driver.read("Tm.TT").value is True
    finally:
        plc.stop()


def test_the_watch_tag_monitor_opens_an_fbd_timer_as_a_timer(tmp_path):
    path = write_l5x(tmp_path / "fbd.L5X", TAGS, [Prog("MainProgram", {"Main": timer_st("TONR")})],
                     [Task("T", ["MainProgram"])])
    s = WatchSession(load_app(path, tmp_path / "state"),
                     WatchOptions(run=RunOptions(fresh=True, sets=("Run=1", "Pre=1000")), online=False))
    try:
        for _ in range(4):
            s.scan()
        s.show_file("Tm")
        text = render(s, 100, 30).export_text()
        rows = {line.split()[0]: line.split()[1:] for line in text.splitlines() if line.strip().startswith("Tm.")}
        assert rows["Tm.ACC"] == ["DINT", "30"] and rows["Tm.TT"] == ["BOOL", "1"], text
        assert rows["Tm.TimerEnable"] == ["BOOL", "1"] and rows["Tm.PRE"] == ["DINT", "1000"]
        assert "Tm.CTL" not in rows  # hidden, as a TIMER's
    finally:
        s.quit()


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_add_on_instruction_in_st_times_with_a_local_fbd_timer_per_instance(tmp_path, executor):
    debounce = Aoi("Debounce", [Param("In", "BOOL", "Input"), Param("Out", "BOOL", "Output")],
                   {"Logic": ["NOP();"]}, [("Dly", "FBD_TIMER", None)])
    st = "Dly.PRE := 30;\nDly.TimerEnable := In;\nTONR(Dly);\nOut := Dly.DN;"
    lines = "".join(f'<Line Number="{k}"><![CDATA[{t}]]></Line>' for k, t in enumerate(st.split("\n")))
    path = write_aoi_l5x(tmp_path / "aoi.L5X", [debounce],
                         [("D1", "Debounce"), ("D2", "Debounce"), ("Sig", "BOOL"), ("Q1", "BOOL"), ("Q2", "BOOL")],
                         [Prog("P", {"Main": ["Debounce(D1,Sig,Q1);", "Debounce(D2,0,Q2);"]})], [Task("T", ["P"])])
    text = path.read_text(encoding="utf-8")
    rll = ('<Routine Name="Logic" Type="RLL">\n<RLLContent>\n<Rung Number="0" Type="N">\n<Text>\n'
           '<![CDATA[NOP();]]>\n</Text>\n</Rung>\n</RLLContent>')
    assert rll in text
    path.write_text(text.replace(rll, f'<Routine Name="Logic" Type="ST">\n<STContent>{lines}</STContent>'),
                    encoding="utf-8")
    r = export_runner(path, executor)
    write_tag(r, "Sig", 1)
    r.run(3)
    assert (read_tag(r, "Q1"), read_tag(r, "D1.Dly.ACC")) == (0, 20)
    r.run(1)
    assert (read_tag(r, "Q1"), read_tag(r, "D1.Dly.DN"), read_tag(r, "Q2"), read_tag(r, "D2.Dly.ACC")) == (1, 1, 0, 0)
