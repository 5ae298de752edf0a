"""STRPRINT and STRSCAN in ladder programs, on both executors: when they
execute, the CONTROL bits and LEN/POS, and every error path (ER with DN,
or STRPRINT's minor fault) without an exception leaving the scan."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.cli import main
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Mode, run_text
from softplc_lite.ladder import status as S
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config

DATA = Path(__file__).parent / "data" / "comgenius"
STRINGS = """
[STRINGS]
1 "Rack no: %3o has %2d modules.\\r\\n"
2 "%d %k"
3 "%ld|%x|%s|%e"
4 "%s %f %d"
5 "%.90c"
6 "%d and %d"
"""


@pytest.fixture(params=["compiled", "reference"])
def run(request):
    def _run(text: str, scans: int = 1, values: dict | None = None, config: str = STRINGS):
        table = DataTable()
        for addr in values or {}:
            table.reference(addr)
        module = ComGenius(parse_config(config))
        return run_text(text, scans=scans, executor=request.param, table=table, values=values, modules=[module])
    return _run


def control(e, addr: str = "R6:0") -> tuple:
    r = e.table.read(addr)
    return r["EN"], r["DN"], r["ER"], r["EM"], r["LEN"], r["POS"]


def test_strprint_formats_the_manuals_example_1(run):
    e = run("DATA ST9 1\nSTRPRINT ST9:0 1 N7:0 N7:1", values={"N7:0": 5, "N7:1": 2})
    assert e.table.read("ST9:0") == "Rack no:   5 has  2 modules.\r\n"


def test_strprint_in_neutral_text_with_every_param_kind(run):
    e = run("DATA ST9 2 = \"txt\"\nDATA N10 2 = -1 1\nDATA F8 1 = 1.5\nSTRPRINT(ST9:1,3,N10:0,255,ST9:0,F8:0);")
    assert e.table.read("ST9:1") == "131071|ff|txt|1.500000e+00"


def test_strprint_runs_on_every_true_scan_and_not_on_false_ones(run):
    e = run("DATA ST9 1\nXIC B3/0 STRPRINT ST9:0 6 N7:0 S:100", scans=3, values={"B3/0": 1})
    # S:100 counts the scans done before this one: the third scan printed 2
    assert e.table.read("ST9:0") == "0 and 2"
    e.table.write("B3/0", 0)
    e.run(2)
    assert e.table.read("ST9:0") == "0 and 2"


def test_strprint_keeps_the_first_82_characters(run):
    e = run("DATA ST9 1\nDATA N10 45\nSTRPRINT ST9:0 5 N10:0", values={"N10:0": 0x4241})
    assert e.table.read("ST9:0") == "AB" + "\0" * 80


@pytest.mark.parametrize("program,code", [
    ("STRPRINT ST9:0 9 N7:0", S.MINOR_CODE_FORMAT_INDEX),  # no string 9
    ("STRPRINT ST9:0 N7:5 N7:0", S.MINOR_CODE_FORMAT_INDEX),  # index from a word: -3
    ("STRPRINT ST9:0 2 N7:0", S.MINOR_CODE_FORMAT),  # %k
    ("STRPRINT ST9:0 1 N7:0", S.MINOR_CODE_PARAM),  # too few Params
    ("STRPRINT ST9:0 1 N7:0 ST9:0", S.MINOR_CODE_PARAM),  # %d given a STRING
    ("STRPRINT ST9:0 3 N7:9 1 ST9:0 1.5", S.MINOR_CODE_PARAM),  # %ld from the last word of N7
])
def test_strprint_errors_leave_the_string_and_set_a_minor_fault(run, program, code):
    e = run(f'DATA ST9 1 = "before"\nDATA N7 10\n{program}', values={"N7:5": -3})
    assert e.table.read("ST9:0") == "before"
    assert e.table.read("S:17") & (1 << S.MINOR_MODULE_BIT)
    assert e.table.read("S:102") == code
    assert (e.table.read("S:103"), e.table.read("S:104")) == (2, 0)  # file and rung
    assert e.mode is Mode.RUN and e.fault is None


def test_strscan_reads_the_manuals_strings_7_and_8(run):
    e = run("DATA ST9 2 = \"A_STRing -3.14 -4555\"\nXIC B3/0 STRSCAN R6:0 ST9:0 4 ST9:1 F8:0 N7:0",
            values={"B3/0": 1})
    assert e.table.read("ST9:1") == "A_STRing"
    assert e.table.read("F8:0") == pytest.approx(-3.14, rel=1e-7)
    assert e.table.read("N7:0") == -4555
    assert control(e) == (1, 1, 0, 0, 20, 3)


def test_strscan_mismatch_sets_er_with_the_offset_and_fields_matched(run):
    e = run('DATA ST9 2 = "12 and x"\nSTRSCAN R6:0 ST9:0 6 N7:0 N7:1')
    assert control(e) == (1, 1, 1, 0, 7, 1)  # failed at "x", offset 7, after one %d
    assert e.table.read("N7:0") == 12  # Params are staging areas: written as they match


def test_strscan_starts_only_on_the_rung_transition(run):
    e = run('DATA ST9 1 = "5 and 6"\nXIC B3/0 STRSCAN R6:0 ST9:0 6 N7:0 N7:1', values={"B3/0": 1})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (5, 6)
    e.table.write("ST9:0", "7 and 8")
    e.run(3)  # still true: no new scan, DN stays
    assert (e.table.read("N7:0"), control(e)[:3]) == (5, (1, 1, 0))
    e.table.write("B3/0", 0)
    e.scan()
    assert control(e)[:4] == (0, 0, 0, 0)  # a false rung clears EN, DN and ER
    e.table.write("B3/0", 1)
    e.scan()
    assert (e.table.read("N7:0"), e.table.read("N7:1"), control(e)[:3]) == (7, 8, (1, 1, 0))


@pytest.mark.parametrize("program", [
    "STRSCAN R6:0 ST9:0 9 N7:0",  # no string 9
    "STRSCAN R6:0 ST9:0 2 N7:0",  # illegal format %k
    "STRSCAN R6:0 ST9:0 6 N7:0",  # too few Params
    "STRSCAN R6:0 ST9:0 6 F8:0 N7:0",  # %d given a float
])
def test_strscan_errors_set_er_with_dn(run, program):
    e = run(f'DATA ST9 1 = "5 and 6"\n{program}')
    assert control(e)[:3] == (1, 1, 1)
    assert e.mode is Mode.RUN


def test_strscan_with_an_indirect_source_faults_like_builtin_instructions(run):
    e = run('DATA ST9 1\nSTRSCAN R6:0 ST[N7:0]:0 6 N7:1 N7:2', values={"N7:0": 99})
    assert e.mode is Mode.FAULTED
    assert e.fault.code == S.FAULT_INDIRECT_FILE
    assert "STRSCAN R6:0 ST[N7:0]:0 6 N7:1 N7:2" in e.fault.instruction


def test_check_warns_about_what_it_can_see_before_running(tmp_path, capsys):
    (tmp_path / "MODULES.LST").write_text("COMGENIUS\n")
    (tmp_path / "COMGENIUS.LST").write_text(STRINGS)
    (tmp_path / "main.lad").write_text("DATA ST9 1\nSTRPRINT ST9:0 1 F8:0 N7:0\nSTRSCAN R6:0 ST9:0 6 N7:0\n"
                                       "STRSCAN R6:1 ST9:0 2 N7:0\nSTRPRINT ST9:0 7\nSTRPRINT ST9:0 N7:1 N7:0\n")
    assert main(["check", str(tmp_path)]) == 0
    err = capsys.readouterr().err.splitlines()
    where = str(tmp_path / "main.lad")
    assert err == [
        f"warning: {where}:2:18: STRPRINT: Param 1 is F8:0 (a float); %3o in format 1 needs an integer",
        f"warning: {where}:3:1: STRSCAN: format 6 '%d and %d' needs 2 Params, 1 given",
        f"warning: {where}:4:20: STRSCAN: format 2 '%d %k', at character 3: '%k' has no conversion character "
        "'k' (scan conversions: b d i o u x X c C e E f g G s S R n, %%, % and a space)",
        f"warning: {where}:5:16: STRPRINT: format 7 is not in the string table (strings 1..6); "
        "it will set a minor fault",
    ]


def test_check_rejects_operands_of_the_wrong_kind(tmp_path, capsys):
    (tmp_path / "MODULES.LST").write_text("COMGENIUS\n")
    (tmp_path / "COMGENIUS.LST").write_text(STRINGS)
    (tmp_path / "main.lad").write_text("STRSCAN N7:0 ST9:0 4 5\nSTRPRINT N7:0 -1\n")
    assert main(["check", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "main.lad:1:9: STRSCAN operand 1 (control) must be control element (R), not N7:0 (a word)" in err
    assert "main.lad:1:22: STRSCAN operand 4 (param1) must be word, float or STRING element, not the constant 5" in err
    assert "main.lad:2:10: STRPRINT operand 1 (string) must be string element (ST), not N7:0 (a word)" in err
    assert "main.lad:2:15: STRPRINT operand 2 (format) must be a format index (integer in 0..32000" in err


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_the_strings_example_program(executor):
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions, Runner

    app = load_app(Path(__file__).resolve().parent.parent / "programs" / "strings", use_cache=False)
    app.state_dir = None  # nothing written in the repository: no code cache, no snapshot
    r = Runner(app, RunOptions(fresh=True, executor=executor, sets=("NewReading=1",)))
    r.run(2)
    assert r.table.read("ST9:1") == "Ticket 0042: 1234.5 kg"
    assert (r.table.read("R6:0")["LEN"], r.table.read("R6:0")["POS"]) == (17, 2)
    r.table.write("B3/0", 0)
    r.table.write("ST9:0", "WT: heavy")
    r.run(1)
    r.table.write("B3/0", 1)
    r.run(2)
    assert r.table.read("R6:0")["ER"] == 1 and r.table.read("C5:0.ACC") == 1
    assert r.table.read("ST9:1") == "Ticket 0042: 1234.5 kg"  # not printed after a failed parse
