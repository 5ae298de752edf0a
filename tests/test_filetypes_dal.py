"""Data file types D (BCD), A (ASCII) and L (32-bit long): storage, DATA
initial values, JSON, snapshots, --print, the watch view, and what
instructions do with L elements, on both executors (docs/datatable.md)."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from softplc_lite.cli import main
from softplc_lite.datatable import DataTable, ValueRangeError, jsonio, parse_address, snapshot
from softplc_lite.datatable.address import ValueKind
from softplc_lite.datatable.display import format_read
from softplc_lite.datatable.errors import AddressError, DataTableError
from softplc_lite.ladder import load_text, run_text
from softplc_lite.ladder.ast import AddressRef
from softplc_lite.ladder.held_words import _is_word
from softplc_lite.ladder.errors import LadderError, ProgramErrors
from softplc_lite.ladder.semantics import Settings
from softplc_lite.watch.rungs import RungView

EXECUTORS = ("compiled", "reference")
LMAX, LMIN = 2**31 - 1, -(2**31)


def run_both(text: str, scans: int = 1, **kw):
    """Run on both executors; the two tables must be identical. Returns one."""
    tables = [run_text(text, scans, executor=ex, **kw).table for ex in EXECUTORS]
    assert tables[0] == tables[1], (jsonio.dumps(tables[0]), jsonio.dumps(tables[1]))
    return tables[0]


# -- storage -----------------------------------------------------------------------------------


def test_l_elements_are_32_bit_and_refuse_what_does_not_fit():
    t = DataTable()
    t.reference("L9:1")
    assert t.file("L9").data.itemsize == 4
    t.write("L9:0", LMAX)
    t.write("L9:1", LMIN)
    assert (t.read("L9:0"), t.read("L9:1")) == (LMAX, LMIN)
    with pytest.raises(ValueRangeError, match="32-bit"):
        t.write("L9:0", LMAX + 1)
    with pytest.raises(DataTableError, match="32-bit long"):
        t.read_word("L9:0")
    assert parse_address("L9:0").kind is ValueKind.LONG


def test_l_elements_take_bits_0_to_31_not_32():
    assert str(parse_address("L9:0/31")) == "L9:0/31"
    with pytest.raises(AddressError, match="bit number 32 out of range 0..31"):
        parse_address("L9:0/32")


def test_d_and_a_words_are_16_bit_words_that_also_take_their_text_forms():
    t = DataTable()
    for a in ("D10:1", "A11:1"):
        t.reference(a)
    t.write("D10:0", "1234")
    t.write("D10:1", 0x0099)
    t.write("A11:0", "AB")
    t.write("A11:1", "C")
    assert [t.read(a) for a in ("D10:0", "D10:1", "A11:0", "A11:1")] == [0x1234, 0x99, 0x4142, 0x4300]
    assert t.read("D10:0/4") == 1 and t.read("A11:0/14") == 1  # bits address like N
    for addr, bad in (("D10:0", "12a4"), ("D10:0", "12345"), ("A11:0", "ABC"), ("A11:0", "é\u0100")):
        with pytest.raises(ValueRangeError):
            t.write(addr, bad)


# -- DATA initial values -----------------------------------------------------------------------------


@pytest.mark.parametrize("executor", EXECUTORS)
def test_data_initial_values_for_l_d_and_a(executor):
    text = ('DATA L9 3 = 100000 -2147483648 2147483647\nDATA D10 2 = "1234" 0x99\nDATA A11 2 = "AB" "C"\n'
            "MOV L9:0 L9:2\n")
    t = run_text(text, 1, executor=executor).table
    assert [t.read(f"L9:{k}") for k in range(3)] == [100000, LMIN, 100000]
    assert (t.read("D10:0"), t.read("D10:1")) == (0x1234, 0x99)
    assert (t.read("A11:0"), t.read("A11:1")) == (0x4142, 0x4300)


@pytest.mark.parametrize("line, message", [
    ("DATA L9 1 = 2147483648", "does not fit a 32-bit long"),
    ('DATA D10 1 = "12a"', "four BCD digits"),
    ('DATA A11 1 = "ABC"', "two 8-bit characters"),
    ("DATA D10 1 = 70000", "16-bit"),
    ('DATA L9 1 = "x"', "32-bit long"),
])
def test_bad_data_values_for_l_d_and_a_are_located_errors(line, message):
    with pytest.raises(ProgramErrors) as e:
        load_text("XIC B3/0 OTE B3/1\n" + line + "\n")
    assert message in str(e.value)
    assert str(e.value).startswith("<program>:2:1:")


# -- JSON, snapshots, --print --------------------------------------------------------------------------


def test_json_exports_numbers_and_imports_text_forms():
    t = jsonio.table_from_json('{"L9": [2147483647, -5], "D10": ["1234", 4660], "A11": ["AB", 16706]}')
    doc = jsonio.export_table(t)
    assert doc["L9"] == [LMAX, -5] and doc["D10"] == [0x1234, 0x1234] and doc["A11"] == [0x4142, 0x4142]
    assert jsonio.table_from_json(jsonio.dumps(t)) == t
    with pytest.raises(DataTableError, match=r"L9\[0\].*32-bit"):
        jsonio.table_from_json('{"L9": [2147483648]}')
    with pytest.raises(DataTableError, match=r"D10\[0\].*BCD"):
        jsonio.table_from_json('{"D10": ["99999"]}')


def test_snapshot_round_trip_keeps_l_d_and_a(tmp_path):
    t = DataTable()
    t.reference("L9:2")
    t.reference("D10:0")
    t.reference("A11:0")
    t.write("L9:2", LMIN + 7)
    t.write("D10:0", "0042")
    t.write("A11:0", "OK")
    path = tmp_path / "s.snap"
    snapshot.save(t, path)
    back = snapshot.load(path)
    assert back == t and back.read("L9:2") == LMIN + 7 and back.file("L9").data.itemsize == 4


def test_print_shows_bcd_digits_and_ascii_characters(tmp_path, capsys):
    t = jsonio.table_from_json('{"L9": [-70000], "D10": ["1234", 171], "A11": ["AB"]}')
    assert format_read(t, parse_address("D10:0")) == "4660 (BCD 1234)"
    assert format_read(t, parse_address("D10:1")) == "171"  # 0x00AB is no BCD: the number alone
    assert format_read(t, parse_address("A11:0")) == '16706 (ASCII "AB")'
    path = tmp_path / "t.json"
    path.write_text(jsonio.dumps(t))
    assert main(["datatable", str(path), "--print", "D10:0", "--print", "A11:0", "--print", "L9:0"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "D10:0 = 4660 (BCD 1234)", 'A11:0 = 16706 (ASCII "AB")', "L9:0 = -70000"]


def test_watch_view_shows_d_as_four_digits_and_a_as_two_characters():
    program = load_text("MOV D10:0 A11:0\n")
    t = DataTable()
    t.reference("D10:0")
    t.reference("A11:0")
    t.write("D10:0", "0042")
    t.write("A11:0", "OK")
    console = Console(width=60, record=True, color_system=None, file=io.StringIO())
    console.print(RungView(program.main.rungs[0], 0, t, symbols={}))
    text = console.export_text()
    assert "0042" in text and '"OK"' in text


# -- instructions on L elements ----------------------------------------------------------------------


@pytest.mark.parametrize("overflow, expect", [("clamp", LMAX), ("wrap", LMIN)])
def test_l_math_overflows_at_32_bits_per_the_setting(overflow, expect):
    t = run_both("ADD L9:0 L9:1 L9:2\n", settings=Settings(overflow=overflow),
                 values={"L9:0": LMAX, "L9:1": 1})
    assert t.read("L9:2") == expect
    assert t.read("S:0/1") == 1  # V


def test_l_destination_holds_results_past_the_word_range_without_overflow():
    t = run_both("MUL N7:0 N7:1 L9:0\nADD N7:0 N7:0 L9:1\nSUB L9:2 N7:0 L9:3\nDIV L9:0 N7:0 L9:4\n",
                 values={"N7:0": 30000, "N7:1": 30000, "L9:2": -2_000_000_000})
    assert t.read("L9:0") == 900_000_000 and t.read("L9:1") == 60000
    assert t.read("L9:3") == -2_000_030_000 and t.read("L9:4") == 30000
    assert t.read("S:0/1") == 0


@pytest.mark.parametrize("overflow, expect", [("clamp", 32767), ("wrap", 70000 - 65536)])
def test_a_word_destination_receiving_a_long_overflows_as_today(overflow, expect):
    t = run_both("MOV L9:0 N7:0\n", settings=Settings(overflow=overflow), values={"L9:0": 70000})
    assert t.read("N7:0") == expect and t.read("S:0/1") == 1


def test_cpt_and_comparisons_take_longs():
    t = run_both('CPT L9:1 "L9:0 * 4 + 1"\nGRT L9:1 N7:0 OTE B3/0\nLIM 0 L9:0 100000 OTE B3/1\n',
                 values={"L9:0": 100000, "N7:0": 32767})
    assert t.read("L9:1") == 400001 and t.read("B3/0") == 1 and t.read("B3/1") == 1


def test_logical_instructions_on_longs_are_32_bit():
    t = run_both("AND L9:0 L9:1 L9:2\nOR L9:0 L9:1 L9:3\nXOR L9:0 L9:1 L9:4\nNOT L9:0 L9:5\n"
                 "AND L9:0 0xFF L9:6\nAND L9:0 L9:1 N7:0\n",
                 values={"L9:0": 0x12345678, "L9:1": -65536})
    assert t.read("L9:2") == 0x12340000 and t.read("L9:3") == -65536 + 0x5678
    assert t.read("L9:4") == (0x12345678 ^ -65536) and t.read("L9:5") == ~0x12345678
    assert t.read("L9:6") == 0x78
    assert t.read("N7:0") == 0  # a word destination keeps the low 16 bits (0x0000)
    assert t.read("S:0/3") == 0 and t.read("S:0/2") == 1  # flags of the last result: zero


def test_cop_between_longs_and_words_copies_memory_low_word_first():
    t = run_both("DATA N7 8\nCOP #N7:0 #L9:0 2\nCOP #L9:2 #N7:4 3\nCOP #L9:0 #L9:4 2\n",
                 values={"N7:0": 1, "N7:1": 2, "N7:2": -1, "N7:3": 0x7FFF, "L9:2": 0x12345678, "L9:3": -2,
                         "N7:7": 99})
    assert t.read("L9:0") == 0x00020001 and t.read("L9:1") == 0x7FFFFFFF
    assert [t.read(f"N7:{k}") for k in (4, 5, 6)] == [0x5678, 0x1234, -2]
    assert t.read("N7:7") == 99  # three words asked: the fourth is untouched
    assert (t.read("L9:4"), t.read("L9:5")) == (0x00020001, 0x7FFFFFFF)


@pytest.mark.parametrize("overflow, expect", [("clamp", LMAX), ("wrap", 2147483904 - 2**32)])
def test_fll_fills_longs_in_the_32_bit_range(overflow, expect):
    t = run_both("FLL 100000 #L9:0 2\nFLL F8:0 #L9:2 1\n", settings=Settings(overflow=overflow),
                 values={"F8:0": 2147483904.0})  # 2**31 + 256: a float32 exactly
    assert (t.read("L9:0"), t.read("L9:1")) == (100000, 100000)
    assert t.read("L9:2") == expect



def test_the_compilers_word_fast_paths_leave_longs_alone():
    program = load_text("ADD N7:0 N7:1 L9:0\nMOV L9:1 N7:2\n")
    ops = program.main.rungs[0].elements[0].operands
    assert _is_word(ops[0]) and not _is_word(ops[2])
    assert not _is_word(AddressRef(parse_address("L9:1"), ops[0].pos))
    t = run_both("ADD N7:0 N7:1 L9:0\nSUB N7:2 N7:1 L9:1\nMOV L9:2 N7:3\n",
                 values={"N7:0": 30000, "N7:1": 30000, "N7:2": -30000, "L9:2": 5})
    assert (t.read("L9:0"), t.read("L9:1"), t.read("N7:3")) == (60000, -60000, 5)


@pytest.mark.parametrize("text, message", [
    ("TON L9:0 1.0 10 0\n", "must be timer element"),
    ("AND L9:0 L9:1 F8:0\n", "must be word or long address"),
    ("MOV N7:[L9:0] N7:1\n", "must be a word address"),
    ("OTE L9:0/32\n", "out of range 0..31"),
])
def test_longs_where_they_do_not_belong_are_located_errors(text, message):
    with pytest.raises((ProgramErrors, LadderError)) as e:
        load_text(text)
    assert message in str(e.value) and "<program>:1:" in str(e.value)


def test_watch_break_condition_and_watch_list_take_longs():
    from softplc_lite.watch.breakpoints import Condition
    from softplc_lite.watch.watchlist import WatchItem

    t = DataTable()
    t.reference("L9:0")
    t.write("L9:0", 40001)
    assert Condition("L9:0 > 40000").value(t) is True
    item = WatchItem("L9:0")
    item.sample(t)
    assert item.value == 40001


def test_add_and_sub_into_a_long_carry_out_of_bit_31():
    t = run_both("ADD L9:0 L9:1 L9:2\nADD L9:3 L9:1 L9:4\n", values={"L9:0": -1, "L9:1": 1, "L9:3": 0xFFFF})
    assert t.read("L9:2") == 0 and t.read("L9:4") == 0x10000
    assert t.read("S:0/0") == 0  # 0xFFFF + 1 carries out of 16 bits, not out of 32
    t = run_both("ADD L9:0 L9:1 L9:2\n", values={"L9:0": -1, "L9:1": 1})
    assert t.read("S:0/0") == 1 and t.read("S:0/2") == 1
    t = run_both("SUB L9:0 L9:1 L9:2\n", values={"L9:0": 0x10000, "L9:1": 1})
    assert t.read("L9:2") == 0xFFFF and t.read("S:0/0") == 0  # no borrow at 32 bits


def test_display_section_shows_d_and_a_text_forms():
    from softplc_lite.run_output import parse_item

    t = jsonio.table_from_json('{"D10": ["0042"], "A11": ["OK"]}')
    assert parse_item("bcd", "D10:0", "softplc.toml").read(t) == "66 (BCD 0042)"
    assert parse_item("text", "A11:0", "softplc.toml").read(t) == '20299 (ASCII "OK")'


def test_logical_constants_stay_16_bit_and_sign_extend_against_a_long():
    t = run_both("AND L9:0 0xFFFF L9:1\nAND L9:0 0x7FFF L9:2\n", values={"L9:0": 0x12345678})
    assert t.read("L9:1") == 0x12345678  # 0xFFFF is the word -1: every bit set
    assert t.read("L9:2") == 0x5678
    with pytest.raises(ProgramErrors, match="16-bit"):
        load_text("AND L9:0 0x12345678 L9:1\n")
