"""Data table storage for Logix types: bits 0..31 of L elements (a DINT's
bit access), SI files (8-bit SINT) and LI files (64-bit LINT): the address
forms, the table's typed access, and the ladder on both executors."""

from __future__ import annotations

import pytest

from softplc_lite.datatable import DataTable, ValueKind, ValueRangeError, item_bit_mask, jsonio, parse_address, snapshot
from softplc_lite.datatable.errors import AddressError, AddressRangeError, DataTableError
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


# -- SI and LI files -----------------------------------------------------------------------------

SI_MIN, SI_MAX = -128, 127
LI_MIN, LI_MAX = -(2**63), 2**63 - 1


@pytest.mark.parametrize("letter, typecode, lo, hi, top", [
    ("SI", "b", SI_MIN, SI_MAX, 7), ("LI", "q", LI_MIN, LI_MAX, 63)])
def test_si_and_li_files_hold_their_range_and_bits(letter, typecode, lo, hi, top):
    t = DataTable()
    f = t.create_file(letter, 12, 3)
    assert (f.data.typecode, f.name, t.file(f"{letter.lower()}12") is f) == (typecode, f"{letter}12", True)
    t.write(f"{letter}12:0", hi)
    t.write(f"{letter}12:1", lo)
    assert (t.read(f"{letter}12:0"), t.read(f"{letter}12:1")) == (hi, lo)
    for bad in (hi + 1, lo - 1, 2.0):
        with pytest.raises(ValueRangeError, match=f"{top + 1}-bit"):
            t.write(f"{letter}12:2", bad)
    assert t.read(f"{letter}12:2") == 0
    t.write(f"{letter}12:2/{top}", 1)
    assert t.read(f"{letter}12:2") == lo and t.read(f"{letter}12:2/{top}") == 1
    t.write(f"{letter}12:2/{top}", 0)
    t.write(f"{letter}12:2/0", 1)
    assert t.read(f"{letter}12:2") == 1
    with pytest.raises(AddressError, match=f"out of range 0..{top}"):
        parse_address(f"{letter}12:0/{top + 1}")
    a = parse_address(f"{letter.lower()}12:0/{top}")
    assert str(a) == f"{letter}12:0/{top}" and a.kind is ValueKind.BIT
    assert parse_address(f"{letter}12:1").kind is ValueKind.LONG
    with pytest.raises(DataTableError, match="no raw 16-bit words"):
        t.read_word(f"{letter}12:0")


def test_si_and_li_do_not_clash_with_s_and_l():
    t = DataTable()
    t.create_file("SI", 12, 1)
    t.create_file("LI", 13, 1)
    t.write("S:1/15", 1)
    t.write("L9:0", 5) if "L9" in t else t.create_file("L", 9, 1)
    assert str(parse_address("S:1/15")) == "S:1/15"
    with pytest.raises(DataTableError, match="file number 12 is already SI12"):
        t.create_file("N", 12, 1)
    with pytest.raises(AddressError, match="unknown file type 'SX'"):
        parse_address("SX12:0")


def test_snapshot_and_json_round_trip_si_and_li():
    t = DataTable()
    t.create_file("SI", 12, 3)
    t.create_file("LI", 13, 3)
    t.create_file("L", 9, 1)
    for address, value in (("SI12:0", SI_MIN), ("SI12:2", SI_MAX), ("LI13:0", LI_MIN), ("LI13:2", LI_MAX),
                           ("L9:0", -2**31)):
        t.write(address, value)
    back = snapshot.decode(snapshot.encode(t))
    assert back == t and back.file("SI12").data.typecode == "b"
    assert back.read("LI13:0") == LI_MIN and back.read("SI12:2") == SI_MAX
    text = jsonio.dumps(t)
    assert '"SI12":[-128,0,127]' in text.replace(" ", "")
    again = jsonio.table_from_json(text)
    assert again == t and again.read("LI13:2") == LI_MAX
    with pytest.raises(DataTableError, match=r"SI12\[0\].*8-bit"):
        jsonio.table_from_json('{"SI12": [128]}')


def test_a_snapshot_without_logix_files_is_the_same_bytes():
    """The format did not change: a table of PLC-5 files encodes as before
    (the type letters, padded to two bytes, then the items)."""
    t = DataTable()
    raw = snapshot.encode(t)
    assert b"N \x07\x00" in raw and snapshot.decode(raw) == t


DEST_MATH = """DATA SI12 8 = 100 -100 {si_big}
DATA LI13 6
DATA L9 1
ADD SI12:0 SI12:0 SI12:3
SUB SI12:1 100 SI12:4
MUL SI12:2 2 SI12:5
MOV 300 SI12:6
CPT SI12:7 "SI12:0 + 27"
MOV 32767 LI13:0
MUL LI13:0 32767 LI13:1
MUL LI13:1 LI13:1 LI13:2
SUB 0 LI13:2 LI13:3
CPT LI13:4 "LI13:1 * 4"
MOV L9:0 LI13:5
"""


@pytest.mark.parametrize("overflow", ["clamp", "wrap"])
def test_math_into_si_and_li_on_both_executors(overflow):
    t = run_both(DEST_MATH.format(si_big=100), settings=Settings(overflow=overflow), values={"L9:0": -2**31})
    clamp = overflow == "clamp"
    si = [t.read(f"SI12:{k}") for k in range(3, 8)]
    assert si == ([127, -128, 127, 127, 127] if clamp else [-56, 56, -56, 44, 127])
    square = 32767 * 32767
    assert t.read("LI13:1") == square
    big = square * square  # 1.15e18: fits 64 bits
    assert (t.read("LI13:2"), t.read("LI13:3"), t.read("LI13:4")) == (big, -big, 4 * square)
    assert t.read("LI13:5") == -2**31
    assert t.read("S:10/14") == 1  # the SI overflows set the minor fault


@pytest.mark.parametrize("overflow", ["clamp", "wrap"])
def test_li_overflow_wraps_or_clamps_at_64_bits(overflow):
    text = "DATA LI13 4\nMOV 32767 LI13:0\nMUL LI13:0 LI13:0 LI13:0\nMUL LI13:0 LI13:0 LI13:1\n" \
           "MUL LI13:1 16 LI13:2\nADD LI13:2 LI13:2 LI13:3\n"
    t = run_both(text, settings=Settings(overflow=overflow))
    b = 32767 ** 4
    assert t.read("LI13:1") == b
    if overflow == "clamp":
        assert (t.read("LI13:2"), t.read("LI13:3")) == (LI_MAX, LI_MAX)
    else:
        wrap = lambda v: (v + 2**63) % 2**64 - 2**63  # noqa: E731
        assert (t.read("LI13:2"), t.read("LI13:3")) == (wrap(16 * b), wrap(2 * wrap(16 * b)))
    assert t.read("S:10/14") == 1  # the overflow minor fault


def test_bit_instructions_on_si_and_li_bits_on_both_executors():
    text = ("DATA SI12 3\nDATA LI13 2\nDATA N10 1 = 7\nXIC I:0/0 OTE SI12:0/7\nXIC I:0/0 OTL LI13:0/63\n"
            "XIC I:0/0 OTE SI12:1/[N10:0]\nXIC SI12:0/7 OTE LI13:1/31\nXIC LI13:0/63 OTE B3/0\n"
            "XIC I:0/0 ONS SI12:2/6 OTE B3/1\n")
    for inputs in (0, 1):
        t = run_both(text, 2, values={"I:0": inputs})
        assert t.read("SI12:0") == (-128 if inputs else 0)
        assert t.read("SI12:1") == (-128 if inputs else 0)
        assert t.read("LI13:0") == (LI_MIN if inputs else 0)
        assert t.read("LI13:1") == (2**31 if inputs else 0)
        assert t.read("B3/0") == inputs


def test_fll_and_cop_with_si_and_li_on_both_executors():
    text = ("DATA SI12 4\nDATA LI13 2\nDATA N10 2\nFLL 300 #SI12:0 2\nFLL -5 #LI13:0 2\n"
            "MOV 0x0102 N10:0\nCOP #N10:0 #SI12:2 2\n")
    t = run_both(text)
    assert [t.read(f"SI12:{k}") for k in range(4)] == [127, 127, 2, 1]  # a word's bytes, low first
    assert t.read("LI13:1") == -5


def test_check_says_what_does_not_fit_a_si_data_value():
    with pytest.raises(Exception, match="does not fit an 8-bit short integer"):
        run_text("DATA SI12 1 = 200\n")


def test_cli_sets_and_prints_si_and_li(tmp_path):
    from helpers.cli import softplc_here

    app = tmp_path / "app.lad"
    app.write_text("DATA SI12 2\nDATA LI13 2\nADD SI12:0 100 SI12:1\nMUL LI13:0 4 LI13:1\n"
                   "XIC SI12:0/7 OTE LI13:1/63\n")
    out = softplc_here("run", str(app), "--scans", "1", "--set", "SI12:0=-100", "--set", "LI13:0=1000000000000",
                       "--print", "SI12:1", "--print", "LI13:1", "--print", "SI12:0/7", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == ["SI12:1 = 0", f"LI13:1 = {4 * 10**12 - 2**63}", "SI12:0/7 = 1"]
    bad = softplc_here("run", str(app), "--scans", "1", "--set", "SI12:0=200", cwd=tmp_path)
    assert bad.returncode == 1 and "8-bit signed integer (-128..127)" in bad.stderr


def test_the_data_grid_shows_si_and_li_at_their_width():
    from rich.console import Console

    from softplc_lite.watch.datagrid import DataGrid

    t = DataTable()
    t.create_file("SI", 12, 2)
    t.create_file("LI", 13, 1)
    t.write("SI12:0", -1)
    t.write("LI13:0", LI_MIN)
    console = Console(width=100, record=True, color_system=None)
    for name, radix in (("SI12", "hex"), ("LI13", "decimal"), ("LI13", "hex")):
        console.print(DataGrid(t, name, radix=radix, height=4))
    text = console.export_text()
    assert "FF" in text and str(LI_MIN) in text and "8000000000000000" in text


def test_trends_record_si_and_li_items(tmp_path):
    from helpers.cli import softplc_here

    app = tmp_path / "app.lad"
    app.write_text("DATA SI12 1\nDATA LI13 1\nADD SI12:0 50 SI12:0\nMUL LI13:0 2 LI13:0\nADD LI13:0 1 LI13:0\n")
    out = softplc_here("run", str(app), "--scans", "3", "--trend", "SI12:0", "--trend", "LI13:0",
                       "--trend", "SI12:0/7", "--trend-file", str(tmp_path / "t.csv"), cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    rows = (tmp_path / "t.csv").read_text().splitlines()
    assert [r.split(",")[2:] for r in rows[1:]] == [["50", "1", "0"], ["100", "3", "0"], ["127", "7", "0"]]
    out = softplc_here("run", str(app), "--scans", "1", "--trend", "SI12:0", "--trend", "LI13:0",
                       "--trend-file", str(tmp_path / "t.vcd"), cwd=tmp_path)
    vcd = (tmp_path / "t.vcd").read_text()
    assert "$var integer 8 " in vcd and "$var integer 64 " in vcd


@pytest.mark.parametrize("executor", EXECUTORS)
def test_forces_hold_l_si_and_li_bits(executor):
    from softplc_lite.ladder import Engine, Mode, load_text
    from softplc_lite.watch.forces import Forces, parse_force

    text = ("DATA L9 1\nDATA SI12 1\nDATA LI13 1\nXIC L9:0/31 OTE B3/0\nXIO I:0/0 OTU L9:0/31\n"
            "XIO I:0/0 OTU SI12:0/7\nXIO I:0/0 OTU LI13:0/63\n")
    engine = Engine(load_text(text), executor=executor)
    forces = Forces(engine)
    for force in ("L9:0/31=1", "SI12:0/7=1", "LI13:0/63=1"):
        forces.set(parse_force(force))
    engine.set_mode(Mode.RUN)
    engine.run(2)
    t = engine.table
    assert (t.read("L9:0"), t.read("SI12:0"), t.read("LI13:0"), t.read("B3/0")) == (-2**31, -128, LI_MIN, 1)


def test_an_l_bit_as_a_bit_shifts_source_bit_on_both_executors():
    """BSL's source bit is read through the bound instructions' access."""
    text = ("DATA L9 1 = -2147483648\nDATA N10 1\nADD N10:0 1 N10:0\nXIC N10:0/0 BSL #B3:1 R6:0 L9:0/31 16\n"
            "XIC N10:0/0 BSR #B3:2 R6:1 SI12:0/7 16\nDATA SI12 1 = -128\n")
    t = run_both(text, 5)
    assert t.read("B3:1") == 0b111  # three rising edges, each shifting bit 31's 1 in
    assert t.read("B3:2") == -32768 + 16384 + 8192  # BSR shifts in at the top
