"""The data table: each file type and member, PLC typing, raw words, blocks,
growth, indirect and indexed resolution."""

from __future__ import annotations

from array import array

import pytest
from hypothesis import given
from hypothesis import strategies as st

from softplc_lite.datatable import (
    AddressRangeError,
    BlockRangeError,
    DataTable,
    DataTableError,
    ValueRangeError,
)


@pytest.fixture
def table() -> DataTable:
    t = DataTable()
    for addr in ("N7:19", "B3:9", "T4:4", "C5:4", "R6:4", "F8:9", "ST9:4"):
        t.reference(addr)
    return t


def test_default_files():
    t = DataTable()
    names = [(f.name, f.size) for f in t.files()]
    assert names == [("O0", 32), ("I1", 32), ("S2", 128), ("B3", 1), ("T4", 1),
                     ("C5", 1), ("R6", 1), ("N7", 1), ("F8", 1)]


def test_storage_is_machine_word_arrays(table):
    assert isinstance(table.file("N7").data, array) and table.file("N7").data.typecode == "h"
    assert table.file("F8").data.typecode == "f"
    assert table.file("T4").data.typecode == "h"
    assert len(table.file("T4").data) == 3 * 5
    assert len(table.file("ST9").data) == 83 * 5


def test_files_grow_to_what_is_referenced():
    t = DataTable()
    t.reference("N7:99")
    assert t.file("N7").size == 100
    t.reference("N7:5")
    assert t.file("N7").size == 100  # never shrinks
    t.reference("ST12:3")
    assert t.file("ST12").size == 4
    t.reference("N[N7:2]:0")  # file chosen at run time: only N7:2 is needed now
    assert t.file("N7").size == 100


def test_an_address_past_the_end_is_an_error_not_a_grow():
    t = DataTable()
    with pytest.raises(AddressRangeError, match=r"N7:5: element 5 is past the end of N7 \(1 element\)"):
        t.read("N7:5")
    with pytest.raises(AddressRangeError, match="there is no data file N10"):
        t.read("N10:0")
    assert t.file("N7").size == 1 and "N10" not in t


def test_file_numbers_are_unique_across_types():
    t = DataTable()
    t.reference("ST9:0")
    with pytest.raises(DataTableError, match="file number 9 is already ST9; N9 cannot also exist"):
        t.reference("N9:0")


def test_file_lookup_by_name_and_number():
    t = DataTable()
    assert t.file("O").name == "O0" and t.file("o0").name == "O0"
    assert t.file(7).name == "N7"
    with pytest.raises(DataTableError, match="bad file name"):
        t.file("N7x")
    with pytest.raises(AddressRangeError):
        t.file("F7")  # file 7 is N, not F


# -- word files ------------------------------------------------------------------

@pytest.mark.parametrize("addr", ["N7:3", "B3:2", "O:1", "I:7", "S:24"])
def test_word_files_hold_signed_16_bit(table, addr):
    table.write(addr, -32768)
    assert table.read(addr) == -32768
    table.write(addr, 32767)
    assert table.read(addr) == 32767
    with pytest.raises(ValueRangeError, match=r"40000 does not fit .* 16-bit signed integer \(-32768..32767\)"):
        table.write(addr, 40000)
    with pytest.raises(ValueRangeError, match=r"holds a 16-bit signed integer \(-32768..32767\), got 1.5"):
        table.write(addr, 1.5)
    assert table.read(addr) == 32767  # refused writes change nothing


def test_raw_words_take_0_to_65535_and_read_back_signed(table):
    table.write_word("N7:1", 40000)
    assert table.read("N7:1") == 40000 - 65536
    assert table.read_word("N7:1") == -25536
    table.write_word("N7:1", 0xFFFF)
    assert table.read("N7:1") == -1
    for bad in (-1, 65536):
        with pytest.raises(ValueRangeError, match="raw word"):
            table.write_word("N7:1", bad)


def test_bits_of_a_word_including_bit_15(table):
    table.write("N7:0", 0)
    table.write("N7:0/15", 1)
    assert table.read("N7:0") == -32768
    table.write("N7:0/0", 1)
    assert table.read("N7:0") == -32767
    assert table.read("N7:0/15") == 1 and table.read("N7:0/1") == 0
    table.write("N7:0/15", 0)
    assert table.read("N7:0") == 1
    with pytest.raises(ValueRangeError, match="a bit"):
        table.write("N7:0/3", 2)


def test_b_file_bit_across_file_is_the_same_bit(table):
    table.write("B3/17", 1)
    assert table.read("B3:1/1") == 1
    assert table.read("B3:1") == 2


def test_io_octal_addressing(table):
    table.write("I:012/17", 1)  # word 10, bit 15
    assert table.read_word("I:12") == -32768
    assert table.file("I1").data[10] == -32768


# -- floats ----------------------------------------------------------------------

def test_float_is_float32(table):
    table.write("F8:2", 3.14)
    assert table.read("F8:2") == 3.140000104904175
    table.write("F8:2", 7)
    assert table.read("F8:2") == 7.0
    table.write("F8:2", float("inf"))
    assert table.read("F8:2") == float("inf")
    with pytest.raises(ValueRangeError, match="float32"):
        table.write("F8:2", 1e39)
    with pytest.raises(ValueRangeError, match="holds a float"):
        table.write("F8:2", "3")
    with pytest.raises(DataTableError, match="F files have no raw 16-bit words"):
        table.read_word("F8:2")


# -- timers, counters, controls --------------------------------------------------

@pytest.mark.parametrize("element,bits,words", [
    ("T4:1", {"EN": 15, "TT": 14, "DN": 13}, {"PRE": 1, "ACC": 2}),
    ("C5:1", {"CU": 15, "CD": 14, "DN": 13, "OV": 12, "UN": 11}, {"PRE": 1, "ACC": 2}),
    ("R6:1", {"EN": 15, "EU": 14, "DN": 13, "EM": 12, "ER": 11, "UL": 10, "IN": 9, "FD": 8},
     {"LEN": 1, "POS": 2}),
])
def test_structure_members_live_in_their_words(table, element, bits, words):
    f = table.file(element.split(":")[0])
    base = 3 * int(element.split(":")[1])
    for name, bit in bits.items():
        table.write_word(element, 0)
        table.write(f"{element}/{name}", 1)
        assert table.read(f"{element}.{name}") == 1
        assert f.data[base] & 0xFFFF == 1 << bit
        assert table.read(f"{element}/{bit}") == 1
    for name, offset in words.items():
        table.write(f"{element}.{name}", -1234 - offset)
        assert f.data[base + offset] == -1234 - offset
        assert table.read_word(f"{element}.{name}") == -1234 - offset
    value = table.read(element)
    assert set(value) == set(bits) | set(words)


def test_structure_write_of_some_members(table):
    table.write("T4:0", {"PRE": 100, "DN": 1})
    assert table.read("T4:0") == {"EN": 0, "TT": 0, "DN": 1, "PRE": 100, "ACC": 0}
    with pytest.raises(ValueRangeError, match="'LEN' is not a member of T4:0"):
        table.write("T4:0", {"ACC": 5, "LEN": 3})
    assert table.read("T4:0.ACC") == 0  # a bad member leaves the element untouched
    with pytest.raises(ValueRangeError, match="give its members as an object"):
        table.write("C5:0", 5)


# -- strings ---------------------------------------------------------------------

def test_string_elements_hold_82_ucs2_code_units(table):
    table.write("ST9:1", "hello")
    assert table.read("ST9:1") == "hello"
    assert table.read("ST9:1.LEN") == 5
    full = "".join(chr(0x20 + i) for i in range(82))
    table.write("ST9:1", full)
    assert table.read("ST9:1") == full
    odd = "\u0000\uffff\ud800\u00e9"  # any 16-bit code unit, lone surrogates included
    table.write("ST9:2", odd)
    assert table.read("ST9:2") == odd and table.read("ST9:2.LEN") == 4
    with pytest.raises(ValueRangeError, match="at most 82 characters"):
        table.write("ST9:1", "x" * 83)
    with pytest.raises(ValueRangeError, match=r"U\+1F600 does not fit ST9:1: ST characters are UCS-2"):
        table.write("ST9:1", "\U0001F600")
    assert table.read("ST9:1") == full


def test_string_len_member_and_raw_words(table):
    table.write("ST9:0", "abcdef")
    table.write("ST9:0.LEN", 3)
    assert table.read("ST9:0") == "abc"
    with pytest.raises(ValueRangeError, match="string length"):
        table.write("ST9:0.LEN", 83)
    block = table.block("ST9:0", 4)
    assert block.values() == [3, ord("a"), ord("b"), ord("c")]


# -- blocks ----------------------------------------------------------------------

def test_block_of_consecutive_words(table):
    for i in range(4):
        table.write(f"N7:{10 + i}", i - 2)
    block = table.block("N7:10", 4)
    assert len(block) == 4 and block.values() == [-2, -1, 0, 1]
    block[0] = 0xABCD
    assert table.read("N7:10") == 0xABCD - 0x10000
    assert block.unsigned(0) == 0xABCD
    block.set_signed(1, -5)
    assert table.read("N7:11") == -5
    with pytest.raises(IndexError):
        block[4]
    assert str(block) == "4 words from N7:10"


def test_long_integer_as_two_words_low_first(table):
    value = 123456789
    block = table.block("N7:0", 2)
    block[0] = value & 0xFFFF
    block[1] = value >> 16
    assert (table.read_word("N7:1") & 0xFFFF) << 16 | (table.read_word("N7:0") & 0xFFFF) == value


def test_block_across_structure_members(table):
    table.write("T4:0.ACC", 7)
    table.write("T4:1.PRE", 9)
    assert table.block("T4:0.ACC", 3).values() == [7, 0, 9]


def test_block_past_the_end_names_file_size_and_block(table):
    with pytest.raises(BlockRangeError) as info:
        table.block("N7:18", 5)
    msg = str(info.value)
    assert "a block of 5 words from N7:18 runs past the end of N7" in msg
    assert "N7 has 20 elements (20 words)" in msg and "words 18..22" in msg
    with pytest.raises(BlockRangeError, match="T4 has 5 elements \\(15 words\\)"):
        table.block("T4:4.PRE", 3)
    with pytest.raises(DataTableError, match="is a bit"):
        table.block("N7:0/1", 1)


def test_float_block(table):
    table.block("F8:0", 3)[2] = 2.5
    assert table.read("F8:2") == 2.5


# -- indirect and indexed ----------------------------------------------------------

def test_indirect_element_file_and_bit(table):
    table.reference("N10:4")
    table.write("N10:4", 77)
    table.write("N7:1", 4)
    table.write("N7:2", 10)
    table.write("N7:3", 9)
    assert table.read("N10:[N7:1]") == 77
    assert table.read("N[N7:2]:4") == 77
    assert table.read("N[N7:2]:[N7:1]") == 77
    assert table.read("N10:4/[N7:3]") == (77 >> 9) & 1
    table.write("B3:2/3", 1)
    table.write("N7:5", 35)
    assert table.read("B3/[N7:5]") == 1


def test_indirect_out_of_range_is_a_range_error(table):
    table.write("N7:1", 500)
    with pytest.raises(AddressRangeError, match=r"element 500 \(from N7:1\) is past the end of N7"):
        table.read("N7:[N7:1]")
    table.write("N7:2", 11)
    with pytest.raises(AddressRangeError, match=r"there is no data file N11 \(from N7:2 = 11\)"):
        table.read("N[N7:2]:0")
    table.write("N7:2", 9)  # file 9 is ST, not N
    with pytest.raises(AddressRangeError, match="there is no data file N9"):
        table.read("N[N7:2]:0")
    table.write("N7:3", 16)
    with pytest.raises(AddressRangeError, match="bit 16"):
        table.read("N7:0/[N7:3]")


def test_indexed_addresses_add_s24(table):
    table.write("N7:5", 55)
    table.write("S:24", 5)
    assert table.read("#N7:0") == 55
    table.write("T4:3.ACC", 33)
    table.write("S:24", 3)
    assert table.read("#T4:0.ACC") == 33  # offset counts elements
    table.write("S:24", -1)
    with pytest.raises(AddressRangeError, match="index register S:24 = -1"):
        table.read("#N7:0")


def test_word_and_bit_refs_for_compiled_code(table):
    data, i = table.word_ref("N7:4")
    data[i] = 12
    assert table.read("N7:4") == 12
    data, i, mask = table.bit_ref("B3/17")
    data[i] |= mask
    assert table.read("B3:1/1") == 1
    data, i, mask = table.bit_ref("N7:0/15")
    assert mask == -32768
    with pytest.raises(DataTableError, match="indirect or indexed"):
        table.word_ref("N7:[N7:0]")
    with pytest.raises(DataTableError, match="use bit_ref"):
        table.word_ref("N7:0/1")
    with pytest.raises(DataTableError, match="not a bit"):
        table.bit_ref("N7:0")
    with pytest.raises(DataTableError, match="whole timer element"):
        table.word_ref("T4:0")
    with pytest.raises(DataTableError, match="whole string element"):
        table.word_ref("ST9:0")


def test_arrays_survive_growth(table):
    data, i = table.word_ref("N7:0")
    table.reference("N7:5000")
    assert table.file("N7").data is data


@given(st.lists(st.integers(-32768, 32767), min_size=1, max_size=50), st.integers(0, 15))
def test_bit_writes_change_exactly_one_bit(words, bit):
    t = DataTable()
    t.reference(f"N7:{len(words) - 1}")
    for i, w in enumerate(words):
        t.write(f"N7:{i}", w)
    for i, w in enumerate(words):
        t.write(f"N7:{i}/{bit}", 1)
        assert t.read(f"N7:{i}") & 0xFFFF == (w & 0xFFFF) | (1 << bit)
        t.write(f"N7:{i}/{bit}", 0)
        assert t.read(f"N7:{i}") & 0xFFFF == (w & 0xFFFF) & ~(1 << bit)


def test_max_elements_per_file():
    t = DataTable()
    t.reference("N7:9999")
    assert t.file("N7").size == 10_000
    with pytest.raises(DataTableError, match="at most 10000"):
        t.file("N7").grow(10_001)


@pytest.mark.parametrize("text", [
    "", "A_STRing", "x" * 82, "y" * 100,        # empty, short, full, truncated to 82
    "\u0141\u0242\uffff", "\ud800lone",          # all 16 bits, a lone surrogate kept as a unit
    "a\U0001F600b",                              # above U+FFFF: its low 16 bits
])
def test_store_text_keeps_82_units_and_zeroes_the_rest(text):
    from softplc_lite.datatable.table import STRING_CHARS, read_string, store_text
    data = array("h", [-1] * (2 + STRING_CHARS))  # garbage before the store
    store_text(data, 1, text)
    units = [ord(c) & 0xFFFF for c in text[:STRING_CHARS]]
    assert data[1] == len(units)
    assert [w & 0xFFFF for w in data[2:2 + STRING_CHARS]] == units + [0] * (STRING_CHARS - len(units))
    assert data[0] == -1  # the word before is untouched
    assert read_string(data, 1) == "".join(map(chr, units))
