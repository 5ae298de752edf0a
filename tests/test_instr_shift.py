"""Shift registers, FIFO and LIFO (ladder/instr/shift.py): BSL, BSR, FFL,
FFU, LFL, LFU, on both executors. docs/instructions.md cites the AB
section of each rule."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from helpers.instr_helpers import EXECUTORS
from softplc_lite.datatable.jsonio import dumps
from softplc_lite.ladder import Engine, Mode, ProgramErrors, load_text, run_text



def scan_with(e: Engine, **bits) -> Engine:
    """Write B3 bits (b0=1 -> B3/0 = 1), then scan once."""
    for name, value in bits.items():
        e.table.write(f"B3/{name[1:]}", value)
    e.scan()
    return e


def control(e: Engine, address: str = "R6:0") -> dict:
    return e.table.read(address)


def status(e: Engine, address: str = "R6:0") -> str:
    """The set status bits of a control, in word order: 'EN DN UL'."""
    r = e.table.read(address)
    return " ".join(b for b in ("EN", "EU", "DN", "EM", "ER", "UL") if r[b])


# -- BSL, BSR ---------------------------------------------------------------------------


def test_bsl_shifts_the_source_bit_in_and_the_last_bit_out_to_ul(engine):
    e = engine("XIC B3/0 BSL #B3:1 R6:0 I:0/0 5", {"I:0/0": 1, "B3:1": 0b10110})
    scan_with(e, b0=1)
    # bit 4 (the last of 5) goes to UL; the source bit enters bit 0
    assert e.table.read("B3:1") == 0b01101
    assert status(e) == "EN DN UL"


def test_bsl_shifts_once_per_false_to_true_transition(engine):
    e = engine("XIC B3/0 BSL #B3:1 R6:0 I:0/0 8", {"I:0/0": 1})
    seen = [(scan_with(e, b0=b).table.read("B3:1"), status(e)) for b in (1, 1, 1, 0, 1)]
    assert seen == [(1, "EN DN"), (1, "EN DN"), (1, "EN DN"), (1, ""), (3, "EN DN")]


def test_bsl_length_58_spans_four_words_and_leaves_the_rest_of_the_last(engine):
    # AB's example: #B3:1, length 58 -> bits 16..73; bits 74..79 of B3:4 are not part of it
    beyond = -1024  # 0xFC00: bits 10..15 of B3:4, past bit 57 (B3:4/9), the last of the array
    e = engine("XIC B3/0 BSL #B3:1 R6:53 B3/100 58", {"B3:1": -32768, "B3:4": beyond | 0x0100})
    scan_with(e, b0=1)
    assert e.table.read("B3:2") == 1  # bit 15 of B3:1 carried into bit 0 of B3:2
    assert e.table.read("B3:4") == beyond | 0x0200  # bit 56 moved to bit 57; bits 10..15 untouched
    assert e.table.read("R6:53/UL") == 0
    scan_with(e, b0=0)
    e.table.write("B3:4", 0x0200)  # bit 57 is the last bit of the array
    scan_with(e, b0=1)
    assert e.table.read("R6:53/UL") == 1 and e.table.read("B3:4") == 0


def test_bsr_shifts_the_source_bit_into_the_last_bit_and_bit_0_out(engine):
    e = engine("XIC B3/0 BSR #B3:2 R6:54 I:0/0 38", {"I:0/0": 1, "B3:2": 0b101})
    scan_with(e, b0=1)
    assert e.table.read("B3:2") == 0b10
    assert e.table.read("B3:4") == 1 << 5  # bit 37 = bit 5 of the third word
    assert status(e, "R6:54") == "EN DN UL"


def test_bsl_wraps_around_when_the_source_is_the_last_bit(engine):
    e = engine("XIC B3/0 BSL #B3:1 R6:0 B3:1/3 4", {"B3:1": 0b1000})
    got = [scan_with(scan_with(e, b0=1), b0=0).table.read("B3:1") for _ in range(5)]
    assert got == [0b0001, 0b0010, 0b0100, 0b1000, 0b0001]


def test_bsr_wraps_through_the_unload_bit(engine):
    e = engine("XIC B3/0 BSR #B3:1 R6:0 R6:0/UL 3", {"B3:1": 0b001})
    got = []
    for _ in range(4):
        scan_with(scan_with(e, b0=1), b0=0)
        got.append((e.table.read("B3:1"), e.table.read("R6:0/UL")))
    assert got == [(0b000, 1), (0b100, 0), (0b010, 0), (0b001, 0)]


def test_bsl_length_is_written_into_len_by_the_download_and_read_from_it(engine):
    e = engine("XIC B3/0 BSL #B3:1 R6:0 I:0/0 16\nMOV N7:0 R6:0.LEN", {"I:0/0": 1, "B3:1": 0x0001, "N7:0": 16})
    assert control(e)["LEN"] == 16
    e.table.write("N7:0", 1)  # the program shortens the array to one bit
    scan_with(e, b0=0)
    scan_with(e, b0=1)
    assert e.table.read("B3:1") == 0x0001 and e.table.read("R6:0/UL") == 1


def test_bsl_negative_length_sets_er_and_shifts_nothing(engine):
    e = engine("MOV -1 R6:0.LEN\nXIC B3/0 BSL #B3:1 R6:0 I:0/0 8", {"I:0/0": 1, "B3:1": 5})
    scan_with(e, b0=1)
    assert e.table.read("B3:1") == 5 and status(e) == "EN ER"
    scan_with(e, b0=0)
    assert status(e) == ""


def test_bsl_length_past_the_end_of_its_file_is_major_fault_202(engine):
    e = engine("MOV 1000 R6:0.LEN\nXIC B3/0 BSL #B3:1 R6:0 I:0/0 8")
    scan_with(e, b0=1)
    assert e.mode.name == "FAULTED" and e.fault.code == 202
    assert "BSL" in str(e.fault)


def test_bsl_grows_its_file_to_the_length(engine):
    e = engine("XIC B3/0 BSL #B3:10 R6:0 I:0/0 40")
    assert len(e.table.file("B3").data) >= 13  # B3:10..B3:12 hold 40 bits


def test_bsl_both_rung_syntaxes_agree():
    mnemonic = run_text("XIC B3/0 BSL #B3:1 R6:0 I:0/0 16", values={"B3/0": 1, "I:0/0": 1, "B3:1": 0x00F0})
    neutral = run_text("XIC(B3/0)BSL(#B3:1,R6:0,I:0/0,16);", values={"B3/0": 1, "I:0/0": 1, "B3:1": 0x00F0})
    assert dumps(mnemonic.table) == dumps(neutral.table)
    assert mnemonic.table.read("B3:1") == 0x01E1


@pytest.mark.parametrize("text,expected", [
    ("BSL #B3:1 R6:0 I:0/0 0", "BSL operand 4 (length) must be in 1..16000"),
    ("BSR #B3:1 R6:0 I:0/0 16001", "BSR operand 4 (length) must be in 1..16000"),
    ("BSL #B3:1 T4:0 I:0/0 8", "BSL operand 2 (control) must be control element (R)"),
    ("BSL #F8:0 R6:0 I:0/0 8", "BSL operand 1 (file) must be word file address"),
    ("BSL #B3:1 R6:0 N7:0 8", "BSL operand 3 (bit) must be bit address"),
    ("FFL N7:0 #N7:10 R6:0 4 -1", "FFL operand 5 (position) must be in 0..1000"),
    ("FFU #N7:10 N7:1 R6:0 N7:2 0", "FFU operand 4 (length) must be a constant"),
    ("LFL N7:0 #N7:10 R6:0 1001 0", "LFL operand 4 (length) must be in 1..1000"),
])
def test_bsl_bsr_ffl_ffu_lfl_bad_operands_are_located_errors(text, expected):
    with pytest.raises(ProgramErrors) as info:
        load_text(text)
    message = str(info.value)
    assert "<program>:1:" in message and expected in message, message


# -- FFL, FFU, LFL, LFU -------------------------------------------------------------------

FIFO = "XIC B3/0 FFL N7:10 #N7:12 R6:0 34 9\nXIC B3/1 FFU #N7:12 N7:11 R6:0 34 9"


def test_ffl_loads_at_the_position_and_ffu_unloads_position_0(engine):
    # AB's FFL-FFU example: 34 words from N7:12, position 9
    e = engine(FIFO, {f"N7:{12 + k}": 100 + k for k in range(9)} | {"N7:10": 7})
    scan_with(e, b0=1)
    assert e.table.read("N7:21") == 7 and control(e)["POS"] == 10
    assert e.table.read("S:24") == 9  # SLC: the position at entry
    scan_with(e, b1=1)
    assert e.table.read("N7:11") == 100  # first in, first out
    assert [e.table.read(f"N7:{k}") for k in (12, 13, 20, 21)] == [101, 102, 7, 0]
    assert control(e)["POS"] == 9 and e.table.read("S:24") == 9  # the position at exit
    assert status(e) == "EN EU"


def test_ffl_sets_dn_when_full_and_loads_no_more(engine):
    e = engine("XIC B3/0 FFL N7:0 #N7:10 R6:0 2 0", {"N7:0": 5})
    for value in (5, 6, 7):
        e.table.write("N7:0", value)
        scan_with(scan_with(e, b0=1), b0=0)
    assert [e.table.read(f"N7:{k}") for k in (10, 11)] == [5, 6]
    assert control(e)["POS"] == 2 and status(e) == "DN"


def test_ffu_sets_em_when_empty_and_unloads_no_more(engine):
    e = engine("XIC B3/0 FFL N7:0 #N7:10 R6:0 3 0\nXIC B3/1 FFU #N7:10 N7:1 R6:0 3 0", {"N7:0": 42, "N7:1": -1})
    scan_with(e, b0=1)
    got = []
    for _ in range(2):
        scan_with(scan_with(e, b1=1), b1=0)
        got.append((e.table.read("N7:1"), control(e)["POS"], status(e)))
    assert got == [(42, 0, "EN EM"), (42, 0, "EN EM")]


def test_ffl_and_ffu_on_one_control_each_use_their_own_enable_bit(engine):
    e = engine("XIC B3/0 FFL N7:0 #N7:10 R6:0 4 0\nXIC B3/1 FFU #N7:10 N7:1 R6:0 4 0", {"N7:0": 3})
    scan_with(e, b0=1, b1=1)  # both rungs go true in one scan: load, then unload
    assert (e.table.read("N7:1"), control(e)["POS"], status(e)) == (3, 0, "EN EU EM")
    scan_with(e, b0=1, b1=1)  # held true: neither acts again
    assert control(e)["POS"] == 0


def test_ffl_true_held_loads_once(engine):
    e = engine("XIC B3/0 FFL N7:0 #N7:10 R6:0 4 0", {"N7:0": 9})
    for _ in range(3):
        scan_with(e, b0=1)
    assert control(e)["POS"] == 1 and e.table.read("N7:11") == 0


def test_lfl_and_lfu_unload_last_in_first_out(engine):
    e = engine("XIC B3/0 LFL N7:0 #N7:10 R6:0 34 0\nXIC B3/1 LFU #N7:10 N7:1 R6:0 34 0")
    for value in (1, 2, 3):
        e.table.write("N7:0", value)
        scan_with(scan_with(e, b0=1), b0=0)
    out = []
    for _ in range(3):
        scan_with(scan_with(e, b1=1), b1=0)
        out.append(e.table.read("N7:1"))
    assert out == [3, 2, 1]
    assert control(e)["POS"] == 0 and status(e) == "EM"
    assert [e.table.read(f"N7:{k}") for k in range(10, 13)] == [0, 0, 0]


def test_lfu_unloads_position_minus_1_and_sets_s24_to_the_position_at_exit(engine):
    e = engine("XIC B3/1 LFU #N7:12 N7:11 R6:0 34 9", {f"N7:{12 + k}": 100 + k for k in range(9)})
    scan_with(e, b1=1)
    assert e.table.read("N7:11") == 108 and e.table.read("N7:20") == 0
    assert control(e)["POS"] == 8 and e.table.read("S:24") == 8


def test_ffl_position_past_the_length_sets_er(engine):
    e = engine("MOV 5 R6:0.POS\nXIC B3/0 FFL N7:0 #N7:10 R6:0 4 0", {"N7:0": 1})
    scan_with(e, b0=1)
    assert status(e) == "EN ER" and control(e)["POS"] == 5
    assert [e.table.read(f"N7:{k}") for k in range(10, 14)] == [0, 0, 0, 0]


def test_ffu_length_past_the_end_of_its_file_is_major_fault_202(engine):
    e = engine("MOV 500 R6:0.LEN\nMOV 1 R6:0.POS\nXIC B3/1 FFU #N7:10 N7:1 R6:0 4 0")
    scan_with(e, b1=1)
    assert e.fault.code == 202 and "FFU" in str(e.fault)


def test_ffl_grows_its_stack_file_and_the_download_writes_len_and_pos(engine):
    e = engine("XIC B3/0 FFL N7:0 #N7:12 R6:0 34 9")
    assert len(e.table.file("N7").data) >= 46
    assert (control(e)["LEN"], control(e)["POS"]) == (34, 9)


# -- both executors, random rung states -------------------------------------------------

PROGRAM = """XIC B3/0 BSL #B3:10 R6:0 B3/1 20
XIC B3/1 BSR #B3:12 R6:1 B3/0 7
XIC B3/2 FFL N7:0 #N7:10 R6:2 4 0
XIC B3/3 FFU #N7:10 N7:1 R6:2 4 0
XIC B3/2 XIO B3/3 LFL N7:0 #N7:20 R6:3 3 0
XIC B3/4 LFU #N7:20 N7:2 R6:3 3 0
ADD N7:0 1 N7:0
"""


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 31), min_size=1, max_size=40))
def test_bsl_bsr_ffl_ffu_lfl_lfu_executors_agree_on_random_rung_states(states):
    tables = []
    for executor in EXECUTORS:
        e = Engine(load_text(PROGRAM), executor=executor)
        e.set_mode(Mode.RUN)
        for word in states:
            e.table.write("B3:0", word)
            e.scan()
        assert e.fault is None
        tables.append(dumps(e.table))
    assert tables[0] == tables[1]
