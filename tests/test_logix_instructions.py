"""The Logix instructions whose rules differ from PLC-5's (ladder/instr/logix.py),
on both executors (the ``engine`` fixture runs each test on each), with the
cases 1756-RM003 describes for each: timers in milliseconds with 32-bit PRE
and ACC, 32-bit counters that wrap and set OV/UN, RES, and DIV's truncation.
A TIMER is three L items here (CTL, PRE, ACC), as a Logix export's tags are
laid out (logix/tags.py)."""

from __future__ import annotations

import pytest

from softplc_lite.ladder import status as S

EN, TT, DN = -(2 ** 31), 1 << 30, 1 << 29
CU, CD, OV, UN = EN, 1 << 30, 1 << 28, 1 << 27
TIMER_RUNG = "DATA L9 3\nXIC B3/0 {m} L9:0 L9:1 L9:2\n"
SCAN_MS = 10  # the simulated clock's step (Settings.scan_ms)


def status(e, item: int = 0) -> set[str]:
    w = e.table.read(f"L9:{item}")
    return {name for name, bit in (("EN", EN), ("TT", TT), ("DN", DN)) if w & bit}


def test_lton_times_in_ms_to_a_32_bit_preset_and_resets_on_a_false_rung(engine):
    e = engine(TIMER_RUNG.format(m="LTON"), {"L9:1": 70_000, "B3/0": 1})
    e.scan()  # the scan the rung goes true: timing starts, nothing added yet
    assert status(e) == {"EN", "TT"} and e.table.read("L9:2") == 0
    for _ in range(7_000):
        e.scan()
    assert e.table.read("L9:2") == 70_000 and status(e) == {"EN", "DN"}  # held at PRE, past 16 bits
    e.scan()
    assert e.table.read("L9:2") == 70_000
    e.table.write("B3/0", 0)
    e.scan()
    assert status(e) == set() and e.table.read("L9:2") == 0


def test_ltof_counts_while_the_rung_is_false_and_clears_dn_at_the_preset(engine):
    e = engine(TIMER_RUNG.format(m="LTOF"), {"L9:1": 50, "B3/0": 1})
    e.scan()
    assert status(e) == {"EN", "DN"} and e.table.read("L9:2") == 0
    e.table.write("B3/0", 0)
    e.scan()
    assert status(e) == {"DN", "TT"} and e.table.read("L9:2") == 0
    for _ in range(4):
        e.scan()
    assert status(e) == {"DN", "TT"} and e.table.read("L9:2") == 40
    e.scan()
    assert status(e) == set() and e.table.read("L9:2") == 50


def test_lrto_keeps_acc_and_dn_on_a_false_rung_until_lres(engine):
    e = engine("DATA L9 3\nXIC B3/0 LRTO L9:0 L9:1 L9:2\nXIC B3/1 LRES L9:0 L9:2\n", {"L9:1": 30, "B3/0": 1})
    for _ in range(3):
        e.scan()
    assert e.table.read("L9:2") == 20
    e.table.write("B3/0", 0)
    e.scan()
    assert status(e) == set() and e.table.read("L9:2") == 20  # kept
    e.table.write("B3/0", 1)
    for _ in range(3):
        e.scan()
    assert status(e) == {"EN", "DN"} and e.table.read("L9:2") == 30
    e.table.write("B3/0", 0)
    e.scan()
    assert status(e) == {"DN"}
    e.table.write("B3/1", 1)
    e.scan()
    assert status(e) == set() and e.table.read("L9:2") == 0


def test_a_negative_preset_is_major_fault_34(engine):
    e = engine(TIMER_RUNG.format(m="LTON"), {"L9:1": -1, "B3/0": 1})
    e.scan()
    assert e.fault is not None and e.fault.code == 34 and "negative PRE" in e.fault.message


def test_lctu_counts_rising_edges_and_wraps_with_ov(engine):
    e = engine("DATA L9 3\nXIC B3/0 LCTU L9:0 L9:1 L9:2\n", {"L9:1": 2, "B3/0": 0})
    for expected in (1, 2):
        e.table.write("B3/0", 1)
        e.scan()
        e.scan()  # held true: one count an edge
        e.table.write("B3/0", 0)
        e.scan()
        assert e.table.read("L9:2") == expected
    assert e.table.read("L9:0") & DN and not e.table.read("L9:0") & CU
    e.table.write("L9:2", 2 ** 31 - 1)
    e.table.write("B3/0", 1)
    e.scan()
    assert e.table.read("L9:2") == -(2 ** 31) and e.table.read("L9:0") & OV and e.table.read("L9:0") & CU
    assert not e.table.read("L9:0") & DN  # ACC below PRE after the wrap


def test_lctd_counts_down_and_wraps_with_un(engine):
    e = engine("DATA L9 3\nXIC B3/0 LCTD L9:0 L9:1 L9:2\n", {"L9:2": -(2 ** 31), "B3/0": 1})
    e.scan()
    assert e.table.read("L9:2") == 2 ** 31 - 1 and e.table.read("L9:0") & UN and e.table.read("L9:0") & CD


def test_lres_clears_a_counters_acc_and_status(engine):
    e = engine("DATA L9 3\nXIC B3/0 LRES L9:0 L9:2\n",
               {"L9:0": CU | DN | OV, "L9:1": 5, "L9:2": 9, "B3/0": 1})
    e.scan()
    assert e.table.read("L9:0") == 0 and e.table.read("L9:2") == 0 and e.table.read("L9:1") == 5


@pytest.mark.parametrize("a, b, dest, expected", [
    ("L9:0", "L9:1", "L9:2", 3),     # 7 / 2 with DINTs: truncated (RM003 "Divide")
    ("L9:3", "L9:1", "L9:2", -3),    # -7 / 2: toward zero
    ("F8:0", "L9:1", "L9:2", 4),     # 7.0 / 2 = 3.5 into a DINT: rounded, half to even
    ("L9:0", "L9:1", "F8:1", 3.5),   # into a REAL: the quotient
])
def test_ldiv_truncates_integers_and_rounds_reals(engine, a, b, dest, expected):
    e = engine(f"DATA L9 4\nDATA F8 2\nLDIV {a} {b} {dest}\n", {"L9:0": 7, "L9:1": 2, "L9:3": -7, "F8:0": 7.0})
    e.scan()
    assert e.table.read(dest) == expected


def test_ldiv_by_zero_is_a_minor_fault_and_the_scan_goes_on(engine):
    e = engine("DATA L9 3\nLDIV L9:0 L9:1 L9:2\nADD L9:0 1 L9:0\n", {"L9:0": 7})
    e.scan()
    assert e.fault is None and e.table.read("L9:0") == 8
    assert e.table.read(f"S:{S.MINOR_FAULT_BITS}") >> S.MINOR_DIV_ZERO_BIT & 1


def test_lidx_sums_the_strided_terms_and_faults_outside_a_dimension(engine):
    e = engine("DATA L9 3\nLIDX L9:0 1 L9:1 3 4 L9:2 4 1\n", {"L9:1": 2, "L9:2": 3})
    e.scan()
    assert e.table.read("L9:0") == 1 + 2 * 4 + 3
    e.table.write("L9:2", 4)
    e.scan()
    assert e.fault is not None and e.fault.code == 20


def test_lflt_faults_on_a_true_rung_only(engine):
    e = engine("XIC B3/0 LFLT 31\n", {"B3/0": 0})
    e.scan()
    assert e.fault is None
    e.table.write("B3/0", 1)
    e.scan()
    assert e.fault is not None and e.fault.code == 31
