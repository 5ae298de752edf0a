"""softplc check's RSLogix-style verify warnings (ladder/verify.py): each
located file:line:col, none of them an error (exit code 0)."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.validate import check
from softplc_lite.ladder.verify import verify

from helpers.cli import softplc_here
from helpers.shipped_apps import shipped_app_names, shipped_exports

ROOT = Path(__file__).resolve().parent.parent


def warnings(text: str, overflow: str = "clamp") -> list[str]:
    parsed = parse_program(text, "v.lad")
    resolved, errors = check(parsed)
    assert errors == []
    return [str(w) for w in verify(resolved, parsed=parsed, overflow=overflow)]


def test_ote_on_one_bit_twice_is_a_duplicate_destructive_bit_naming_both_places():
    assert warnings("XIC B3/0 OTE O:0/1\nXIC B3/1 OTE O:0/1\n") == [
        "v.lad:2:10: OTE O:0/1: duplicate destructive bit, also written by OTE at v.lad:1:10 "
        "(the last OTE in the scan decides)"]


def test_ote_with_otl_otu_or_on_another_bit_is_not_a_duplicate():
    assert warnings("XIC B3/0 OTE O:0/1\nXIC B3/1 OTL O:0/1\nXIC B3/2 OTU O:0/1\nXIC B3/3 OTE O:0/2\n") == []


def test_a_symbol_and_its_address_are_one_bit():
    found = warnings("SYMBOL Lamp O:0/1\nXIC B3/0 OTE Lamp\nXIC B3/1 OTE O:0/1\n")
    assert len(found) == 1 and found[0].startswith("v.lad:3:10: OTE O:0/1: duplicate destructive bit")


def test_ote_in_two_files_is_a_duplicate_too():
    found = warnings("JSR 3\nXIC B3/0 OTE B3/5\nFILE 3\nSBR\nXIC B3/1 OTE B3/5\nRET\n")
    assert found == ["v.lad:5:10: OTE B3/5: duplicate destructive bit, also written by OTE at v.lad:2:10 "
                     "(the last OTE in the scan decides)"]


@pytest.mark.parametrize("program, where, first", [
    ("XIC B3/0 TON T4:0 1.0 10 0\nXIC B3/1 TON T4:0 1.0 10 0\n", "v.lad:2:10: TON T4:0", "TON at v.lad:1:10"),
    ("XIC B3/0 TON T4:0 1.0 10 0\nXIC B3/1 RTO T4:0 1.0 10 0\n", "v.lad:2:10: RTO T4:0", "TON at v.lad:1:10"),
    ("XIC B3/0 CTU C5:1 10 0\nXIC B3/1 CTU C5:1 10 0\n", "v.lad:2:10: CTU C5:1", "CTU at v.lad:1:10"),
])
def test_one_timer_or_counter_used_by_two_instructions(program, where, first):
    found = warnings(program)
    assert len(found) == 1 and found[0].startswith(where) and first in found[0]


def test_ctu_with_ctd_res_and_examined_bits_are_not_uses():
    program = ("XIC B3/0 CTU C5:0 10 0\nXIC B3/1 CTD C5:0 10 0\nXIC C5:0/DN RES C5:0\n"
               "XIC B3/2 TON T4:0 1.0 5 0\nXIC T4:0/DN OTE B3/9\nXIC B3/9 RES T4:0\n")
    assert warnings(program) == []


def test_control_elements_of_bound_instructions_count_when_the_table_has_them():
    # Any instruction with a control (R) operand uses it: whichever the table has.
    from softplc_lite.ladder.instructions import BUILTIN
    from softplc_lite.ladder.specs import K

    users = sorted(s.mnemonic for s in BUILTIN.all_specs() if any(o.kind is K.CONTROL for o in s.operands))
    if "BSL" not in users:
        pytest.skip("no BSL in the instruction table")
    found = warnings("XIC B3/0 BSL #B3:1 R6:0 B3/2 16\nXIC B3/3 BSL #B3:4 R6:0 B3/5 16\n")
    assert len(found) == 1 and found[0].startswith("v.lad:2:10: BSL R6:0: R6:0 is also used by BSL at v.lad:1:10")


def test_a_rung_with_no_output_instruction():
    assert warnings("XIC B3/0 XIO B3/1\nXIC B3/0 OTE B3/2\n") == [
        "v.lad:1:1: rung has no output instruction: its conditions are evaluated and nothing is done with them"]


def test_sbr_and_lbl_alone_mark_a_place_and_need_no_output():
    assert warnings("JSR 3\nJMP 1\nLBL 1\nXIC B3/0 OTE B3/1\nFILE 3\nSBR\nXIC B3/0 OTE B3/2\nRET\n") == []


def test_a_symbol_never_used_is_a_warning_at_its_declaration():
    program = ("SYMBOL Spare B3/9\nSYMBOL Start B3/0\nSYMBOL Level N7:0\nSYMBOL Timer T4:0\n"
               "XIC start OTE B3/1\nCPT N7:1 \"Level * 2\"\nXIC Timer/DN OTE B3/2\n")
    assert warnings(program) == ["v.lad:1:8: symbol Spare (B3/9) is never used in the program"]


def test_a_decimal_constant_a_word_cannot_hold():
    assert warnings("MOV 40000 N7:0\n") == [
        "v.lad:1:5: MOV 40000 N7:0: 40000 cannot fit N7:0, it will be stored as 32767 with overflow "
        "(a decimal constant is its value; write 0x.... for a 16-bit pattern)"]
    assert "stored as -25536" in warnings("MOV 40000 N7:0\n", overflow="wrap")[0]
    assert warnings("MOV 0x9C40 N7:0\nMOV -32768 N7:1\nMOV 40000 F8:0\nMOV 32767 N7:2\n") == []


def test_check_prints_the_warnings_located_and_exits_0(tmp_path):
    app = tmp_path / "warned"
    app.mkdir()
    (app / "main.lad").write_text("SYMBOL Spare B3/9\nXIC B3/0 OTE O:0/1\nXIC B3/1 OTE O:0/1\nXIC B3/2\n")
    p = softplc_here("check", str(app))
    assert p.returncode == 0, p.stderr
    main = app / "main.lad"
    assert p.stderr.splitlines() == [
        f"warning: {main}:1:8: symbol Spare (B3/9) is never used in the program",
        f"warning: {main}:3:10: OTE O:0/1: duplicate destructive bit, also written by OTE at {main}:2:10 "
        "(the last OTE in the scan decides)",
        f"warning: {main}:4:1: rung has no output instruction: its conditions are evaluated and nothing is done "
        "with them"]
    assert p.stdout == "warned: ok (1 program file, 3 rungs, 3 warnings)\n"


@pytest.mark.parametrize("name", shipped_app_names() + [f"logix/{p.name}" for p in shipped_exports()])
def test_shipped_programs_have_no_warnings(name):
    p = softplc_here("check", str(ROOT / "programs" / name))
    assert p.returncode == 0 and "warning" not in p.stderr, p.stderr


def test_ffl_with_ffu_on_one_control_is_the_fifo_pair_not_a_warning():
    from softplc_lite.ladder.instructions import BUILTIN

    if BUILTIN.lookup("FFL") is None or BUILTIN.lookup("FFU") is None:
        pytest.skip("no FFL/FFU in the instruction table")
    pair = "XIC B3/0 FFL N7:0 #N7:10 R6:0 5 0\nXIC B3/1 FFU #N7:10 N7:1 R6:0 5 0\n"
    assert warnings(pair) == []
    found = warnings(pair + "XIC B3/2 FFL N7:2 #N7:10 R6:0 5 0\n")
    assert found == ["v.lad:3:10: FFL R6:0: R6:0 is also used by FFL at v.lad:1:10; two instructions driving one "
                     "element overwrite each other's status bits and values"]
    assert warnings("XIC B3/0 CTU C5:0 9 0\nXIC B3/1 CTD C5:0 9 0\nXIC B3/2 CTD C5:0 9 0\n") == [
        "v.lad:3:10: CTD C5:0: C5:0 is also used by CTD at v.lad:2:10; two instructions driving one "
        "element overwrite each other's status bits and values"]
