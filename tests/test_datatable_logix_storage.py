"""Data table storage for Logix types: bits 0..31 of L elements (a DINT's
bit access), SI files (8-bit SINT) and LI files (64-bit LINT): the address
forms, the table's typed access, and the ladder on both executors."""

from __future__ import annotations

import pytest

from softplc_lite.datatable import DataTable, item_bit_mask, jsonio, parse_address, snapshot
from softplc_lite.datatable.errors import AddressError, AddressRangeError
from softplc_lite.ladder import run_text
from softplc_lite.ladder.semantics import Settings

EXECUTORS = ("compiled", "reference")


def run_both(text: str, scans: int = 1, **kw) -> DataTable:
    """Run on both executors; the two tables must be identical. Returns one."""
    tables = [run_text(text, scans, executor=ex, **kw).table for ex in EXECUTORS]
    assert tables[0] == tables[1], (jsonio.dumps(tables[0]), jsonio.dumps(tables[1]))
    return tables[0]


# -- masks ------------------------------------------------------------------------------------


@pytest.mark.parametrize("itemsize, bit, mask", [
    (2, 15, -32768), (2, 3, 8), (4, 31, -2**31), (4, 15, 32768), (1, 7, -128), (1, 6, 64),
    (8, 63, -2**63), (8, 31, 2**31),
])
def test_item_bit_mask_makes_the_top_bit_the_sign(itemsize, bit, mask):
    assert item_bit_mask(bit, itemsize) == mask


# -- L bits -------------------------------------------------------------------------------------


def test_l_bits_parse_print_and_read_write_through_the_table():
    t = DataTable()
    t.create_file("L", 9, 2)
    for bit, value in ((31, -2**31), (15, 32768), (0, 1)):
        t.write("L9:0", 0)
        t.write(f"L9:0/{bit}", 1)
        assert t.read("L9:0") == value
        assert t.read(f"L9:0/{bit}") == 1
        t.write(f"L9:0/{bit}", 0)
        assert t.read("L9:0") == 0
    t.write("L9:1", -1)
    assert [t.read(f"L9:1/{b}") for b in (0, 15, 16, 31)] == [1, 1, 1, 1]
    t.write("L9:1/31", 0)
    assert t.read("L9:1") == 2**31 - 1
    assert str(parse_address("L9:1/31")) == "L9:1/31"


def test_an_indirect_l_bit_checks_the_32_bit_range_at_run_time():
    t = DataTable()
    t.create_file("L", 9, 1)
    t.write("N7:0", 31)
    t.write("L9:0/[N7:0]", 1)
    assert t.read("L9:0") == -2**31
    t.write("N7:0", 32)
    with pytest.raises(AddressRangeError, match="outside 0..31"):
        t.read("L9:0/[N7:0]")


def test_a_member_word_keeps_16_bits():
    with pytest.raises(AddressError, match="out of range 0..15"):
        parse_address("T4:0.ACC/16")


L_BITS = """DATA L9 3
XIC I:0/0 OTE L9:0/31
XIC I:0/0 OTE L9:0/15
XIC L9:0/31 OTE B3/0
XIO L9:0/15 OTE B3/1
XIC I:0/0 OTL L9:1/31
XIO I:0/0 OTU L9:1/31
XIC I:0/1 OTL L9:1/30
XIC I:0/0 ONS L9:2/31 OTE B3/2
XIC I:0/0 OSR L9:2/16 L9:2/17
XIO I:0/0 OSF L9:2/18 L9:2/19
MOV L9:0 L9:2
"""


@pytest.mark.parametrize("inputs", [0, 1, 3])
def test_bit_instructions_on_l_bits_agree_on_both_executors(inputs):
    t = run_both(L_BITS, 2, values={"I:0": inputs})
    on = inputs & 1
    assert t.read("L9:0") == (-2**31 + 32768 if on else 0)
    assert (t.read("B3/0"), t.read("B3/1")) == (on, 1 - on)
    assert t.read("L9:1/31") == on
    assert t.read("L9:1/30") == (inputs >> 1) & 1


def test_l_bit_one_shots_over_scans_on_both_executors():
    """B3/5 is on in odd scans: ONS and OSR fire on each rise, OSF on each fall."""
    text = ("DATA L9 2\nADD N7:5 1 N7:5\nXIC N7:5/0 OTE B3/5\n"
            "XIC B3/5 ONS L9:0/31 ADD N7:0 1 N7:0\n"
            "XIC B3/5 OSR L9:0/30 L9:1/31\nXIC B3/5 OSF L9:0/29 L9:1/15\n"
            "XIC L9:1/31 ADD N7:1 1 N7:1\nXIC L9:1/15 ADD N7:2 1 N7:2\n")
    for scans in range(1, 6):
        t = run_both(text, scans)
        rises, falls = (scans + 1) // 2, scans // 2
        assert (t.read("N7:0"), t.read("N7:1"), t.read("N7:2")) == (rises, rises, falls)
        assert t.read("L9:0/31") == t.read("L9:0/30") == scans % 2


def test_indirect_l_bits_agree_on_both_executors():
    text = ("DATA L9 2\nDATA N10 2 = 0 31\nXIC I:0/0 OTE L9:[N10:0]/[N10:1]\nXIC L9:0/[N10:1] OTE B3/0\n"
            "XIC I:0/0 OTL L9:[N10:0]/15\n")
    t = run_both(text, 1, values={"I:0": 1})
    assert t.read("L9:0") == -2**31 + 32768 and t.read("B3/0") == 1


def test_an_indirect_l_bit_past_31_faults_the_same_on_both_executors():
    text = "DATA L9 1\nDATA N10 1 = 32\nXIC I:0/0 OTE L9:0/[N10:0]\n"
    faults = []
    for ex in EXECUTORS:
        e = run_text(text, 1, executor=ex, values={"I:0": 1})
        faults.append((e.fault.code, e.fault.message))
    assert faults[0] == faults[1] and "outside 0..31" in faults[0][1]


def test_a_symbol_of_an_l_element_takes_a_bit():
    text = "SYMBOL Flags L9:0\nDATA L9 1\nXIC I:0/0 OTE Flags/31\n"
    t = run_both(text, 1, values={"I:0": 1})
    assert t.read("L9:0") == -2**31
    with pytest.raises(Exception, match="past bit 31"):
        run_text("SYMBOL Flags L9:0\nDATA L9 1\nXIC I:0/0 OTE Flags/32\n")
