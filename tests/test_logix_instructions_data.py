"""Logix's file, string and system instructions as bound objects
(ladder/instr/logix_data.py, logix_string.py, logix_system.py) on both
executors (the ``engine`` fixture runs each test on each), with the cases
1756-RM003 describes: COP/FLL lengths in destination elements stopping at
the array's end, COP's byte copy between types, the string instructions'
results and their minor faults, GSV/SSV of the clock, scan times and fault
bits. Exports that use them: tests/test_logix_instructions_export.py."""

from __future__ import annotations

import struct

import pytest

from softplc_lite.ladder import status as S

STRING_ERROR = 1 << S.MINOR_STRING_BIT


def string_error(e) -> bool:
    return bool(e.table.read(f"S:{S.MINOR_FAULT_BITS}") & STRING_ERROR)


# -- LCOP, LFLL ------------------------------------------------------------------------------

def test_lcop_copies_length_elements_and_stops_at_the_destination_end(engine):
    e = engine("DATA L10 5\nDATA L11 4\nLCOP L10:0 L11:1 N7:0 1 4 5", {"N7:0": 10})
    for k in range(5):
        e.table.write(f"L10:{k}", k + 1)
    e.scan()
    assert [e.table.read(f"L11:{k}") for k in range(4)] == [0, 1, 2, 3]  # 3 elements fit, no fault
    assert e.fault is None


def test_lcop_copies_what_the_source_holds_when_it_ends_first(engine):
    e = engine("DATA L10 2\nDATA L11 4\nLCOP L10:0 L11:0 4 1 4 2", {"L11:3": 9})
    e.table.write("L10:0", 5)
    e.table.write("L10:1", 6)
    e.scan()
    assert [e.table.read(f"L11:{k}") for k in range(4)] == [5, 6, 0, 9]


def test_lcop_between_types_copies_bytes(engine):
    # 1.5 as an IEEE REAL is 0x3FC00000; two INTs take its low then high half
    e = engine("DATA F10 1\nDATA N11 2\nLCOP F10:0 N11:0 2 1 2 1")
    e.table.write("F10:0", 1.5)
    e.scan()
    assert [e.table.read("N11:0"), e.table.read("N11:1")] == [0, 0x3FC0]


def test_lcop_of_sints_into_a_dint_is_little_endian(engine):
    e = engine("DATA SI10 4\nDATA L11 1\nLCOP SI10:0 L11:0 1 1 1 4")
    for k, v in enumerate((0x01, 0x02, 0x03, 0x04)):
        e.table.write(f"SI10:{k}", v)
    e.scan()
    assert e.table.read("L11:0") == 0x04030201


def test_lcop_of_structure_members_copies_items_per_element(engine):
    # a member DINT[3] of an array of structures: 3 items for each element
    e = engine("DATA L10 9\nDATA L11 9\nLCOP L10:3 L11:0 5 3 9 9")
    for k in range(9):
        e.table.write(f"L10:{k}", k)
    e.scan()
    assert [e.table.read(f"L11:{k}") for k in range(9)] == [3, 4, 5, 6, 7, 8, 0, 0, 0]


def test_lcop_of_strings_copies_whole_elements(engine):
    e = engine("DATA ST10 2\nLCOP ST10:0 ST10:1 1 1 2 2", {"ST10:0": "pump 3"})
    e.scan()
    assert e.table.read("ST10:1") == "pump 3"


def test_lcop_of_strings_into_a_smaller_string_type_cuts_them(engine):
    e = engine("DATA ST10 2\nLCOP ST9:0 ST10:0 5 1 2 2 3", {"ST9:0": "abcdef", "ST9:1": "xy"})
    e.scan()
    assert [e.table.read("ST10:0"), e.table.read("ST10:1")] == ["abc", "xy"]
    assert e.table.read("ST10:0.LEN") == 3


def test_lcop_does_nothing_on_a_false_rung_or_a_zero_length(engine):
    e = engine("DATA L10 2\nDATA L11 2\nXIC B3/0 LCOP L10:0 L11:0 2 1 2 2\nLCOP L10:0 L11:1 0 1 2 2")
    e.table.write("L10:0", 4)
    e.scan()
    assert e.table.read("L11:0") == 0 and e.table.read("L11:1") == 0


def test_lfll_converts_the_source_and_stops_at_the_array_end(engine):
    e = engine("DATA L10 4\nDATA N11 3\nLFLL 2.5 L10:1 9 1 4\nLFLL 70000 N11:0 3 1 3")
    e.scan()
    assert [e.table.read(f"L10:{k}") for k in range(4)] == [0, 2, 2, 2]  # half to even; three fit
    # too big for an INT: as the overflow setting says (clamp here; an export runs with wrap: the low bits)
    assert [e.table.read(f"N11:{k}") for k in range(3)] == [32767] * 3


def test_lfll_of_zero_clears_strings(engine):
    e = engine("DATA ST10 2\nLFLL 0 ST10:0 2 1 2", {"ST10:0": "a", "ST10:1": "b"})
    e.scan()
    assert e.table.read("ST10:0") == "" and e.table.read("ST10:1") == ""


def test_lfll_of_a_string_fills_each_string(engine):
    e = engine("DATA ST10 3\nLFLL ST9:0 ST10:1 5 1 3", {"ST9:0": "ok"})
    e.scan()
    assert [e.table.read(f"ST10:{k}") for k in range(3)] == ["", "ok", "ok"]


# -- strings ---------------------------------------------------------------------------------

def test_lconcat_joins_and_truncates_to_the_capacity_with_the_string_error(engine):
    e = engine("LCONCAT ST9:0 ST9:1 ST9:2 82\nLCONCAT ST9:0 ST9:1 ST9:3 4",
               {"ST9:0": "ab", "ST9:1": "cde"})
    e.scan()
    assert e.table.read("ST9:2") == "abcde" and e.table.read("ST9:3") == "abcd" and string_error(e)


def test_lconcat_into_its_own_source(engine):
    e = engine("LCONCAT ST9:0 ST9:1 ST9:0 82", {"ST9:0": "x", "ST9:1": "y"})
    e.run(2)
    assert e.table.read("ST9:0") == "xyy" and not string_error(e)


@pytest.mark.parametrize("qty, start, out, error", [(3, 2, "BCD", False), (0, 1, "", False), (6, 1, "ABCDEF", False),
                                                    (2, 6, None, True), (1, 0, None, True), (1, 7, None, True)])
def test_lmid_takes_qty_characters_from_start(engine, qty, start, out, error):
    e = engine(f"LMID ST9:0 {qty} {start} ST9:1 82", {"ST9:0": "ABCDEF", "ST9:1": "old"})
    e.scan()
    assert e.table.read("ST9:1") == (out if out is not None else "old") and string_error(e) == error


@pytest.mark.parametrize("start, out", [(1, "xyABC"), (3, "ABxyC"), (4, "ABCxy"), (5, None), (0, None)])
def test_linsert_puts_b_before_start(engine, start, out):
    e = engine(f"LINSERT ST9:0 ST9:1 {start} ST9:2 82", {"ST9:0": "ABC", "ST9:1": "xy", "ST9:2": "old"})
    e.scan()
    assert e.table.read("ST9:2") == (out or "old") and string_error(e) == (out is None)


@pytest.mark.parametrize("qty, start, out", [(2, 2, "ADEF"), (1, 6, "ABCDE"), (3, 5, None), (1, 0, None)])
def test_ldelete_removes_qty_characters_from_start(engine, qty, start, out):
    e = engine(f"LDELETE ST9:0 {qty} {start} ST9:1 82", {"ST9:0": "ABCDEF", "ST9:1": "old"})
    e.scan()
    assert e.table.read("ST9:1") == (out or "old") and string_error(e) == (out is None)


@pytest.mark.parametrize("search, start, result", [("CD", 1, 3), ("CD", 4, 6), ("ZZ", 1, 0), ("AB", 1, 1)])
def test_lfind_gives_the_1_based_position_or_0(engine, search, start, result):
    e = engine(f"LFIND ST9:0 ST9:1 {start} L10:0", {"ST9:0": "ABCDECD", "ST9:1": search})
    e.scan()
    assert e.table.read("L10:0") == result


def test_lfind_with_a_start_past_the_end_is_the_string_error(engine):
    e = engine("LFIND ST9:0 ST9:1 9 L10:0", {"ST9:0": "AB", "ST9:1": "A", "L10:0": 5})
    e.scan()
    assert e.table.read("L10:0") == 5 and string_error(e)


def test_lupper_and_llower_change_only_letters(engine):
    e = engine("LUPPER ST9:0 ST9:1 82\nLLOWER ST9:0 ST9:2 82", {"ST9:0": "Tank 3: ok/ß"})
    e.scan()
    assert e.table.read("ST9:1") == "TANK 3: OK/ß" and e.table.read("ST9:2") == "tank 3: ok/ß"


def test_ldtos_writes_the_dint_and_faults_past_the_capacity(engine):
    e = engine("LDTOS L10:0 ST9:0 82\nLDTOS L10:0 ST9:1 5", {"L10:0": -2_000_000_000})
    e.scan()
    assert e.table.read("ST9:0") == "-2000000000" and e.table.read("ST9:1") == "-2000" and string_error(e)


@pytest.mark.parametrize("value, text", [(3.14, "3.14"), (-2.0, "-2.0"), (1e20, "1.0e+20"), (0.1, "0.1"),
                                         (123456.7, "123456.7")])
def test_lrtos_writes_the_shortest_text_of_the_real(engine, value, text):
    e = engine("LRTOS F10:0 ST9:0 82", {"F10:0": value})
    e.scan()
    assert e.table.read("ST9:0") == text
    assert struct.pack("f", float(text)) == struct.pack("f", value)


@pytest.mark.parametrize("text, value", [("123", 123), ("  -45 kg", -45), ("Tank 12b", 12), ("none", 0),
                                         ("+7", 7), ("2147483647", 2147483647)])
def test_lstod_takes_the_first_number(engine, text, value):
    e = engine("LSTOD ST9:0 L10:0", {"ST9:0": text, "L10:0": 99})
    e.scan()
    assert e.table.read("L10:0") == value


def test_lstod_past_a_dint_is_stored_as_a_mov_stores_and_sets_s_v(engine):
    e = engine("LSTOD ST9:0 L10:0", {"ST9:0": "4294967297"})
    e.scan()
    # clamped under the engine's default overflow setting; an export runs with wrap (the low bits)
    assert e.table.read("L10:0") == 2147483647 and e.table.read("S:0/1") == 1


@pytest.mark.parametrize("text, value", [("3.5", 3.5), ("x=-1.25e2;", -125.0), (".5", 0.5), ("no", 0.0)])
def test_lstor_takes_the_first_real(engine, text, value):
    e = engine("LSTOR ST9:0 F10:0", {"ST9:0": text})
    e.scan()
    assert e.table.read("F10:0") == value


@pytest.mark.parametrize("a, b, results", [("AB", "AB", [1, 0, 0, 0, 1, 1]), ("A", "AB", [0, 1, 1, 0, 1, 0]),
                                           ("B", "AB", [0, 1, 0, 1, 0, 1]), ("a", "B", [0, 1, 0, 1, 0, 1])])
def test_lscmp_compares_by_character_codes(engine, a, b, results):
    rungs = "\n".join(f"LSCMP ST9:0 ST9:1 {k} OTE B3/{k}" for k in range(6))
    e = engine(rungs, {"ST9:0": a, "ST9:1": b})
    e.scan()
    assert [e.table.read(f"B3/{k}") for k in range(6)] == results


def test_lscmp_on_a_false_rung_is_false(engine):
    e = engine("XIC B3/9 LSCMP ST9:0 ST9:0 0 OTE B3/0", {"ST9:0": "x"})
    e.scan()
    assert e.table.read("B3/0") == 0


# -- LGSV, LSSV ------------------------------------------------------------------------------

def test_lgsv_wall_clock_runs_with_the_engine_clock_and_lssv_sets_it(engine):
    from softplc_lite.ladder.instr.logix_system import WALL_CURRENT, WALL_DATETIME

    e = engine(f"DATA L10 7\nDATA LI11 2\nLGSV {WALL_CURRENT} LI11:0\nXIC B3/0 LSSV {WALL_DATETIME} L10:0\n"
               f"LGSV {WALL_DATETIME} L10:0")
    e.scan()
    first = e.table.read("LI11:0")
    e.run(3)
    assert e.table.read("LI11:0") - first == 30_000  # three 10 ms scans, in microseconds
    for k, v in enumerate((2024, 2, 29, 23, 59, 59, 500_000)):
        e.table.write(f"L10:{k}", v)
    e.table.write("B3/0", 1)
    e.scan()
    assert [e.table.read(f"L10:{k}") for k in range(7)] == [2024, 2, 29, 23, 59, 59, 500_000]
    e.table.write("B3/0", 0)
    e.run(100)  # one second later: the next day
    assert [e.table.read(f"L10:{k}") for k in range(7)] == [2024, 3, 1, 0, 0, 0, 500_000]
    e.scan()
    assert e.table.read("LI11:0") == 1709251200_000_000 + 510_000  # 2024-03-01 00:00:00.51 UTC


def test_lgsv_current_value_into_a_dint_pair(engine):
    from softplc_lite.ladder.instr.logix_system import WALL_CURRENT

    e = engine(f"DATA L10 2\nDATA LI11 1\nXIC B3/0 LSSV {WALL_CURRENT} LI11:0\nLGSV {WALL_CURRENT} L10:0",
               {"LI11:0": 5 << 32 | 7, "B3/0": 1})
    e.scan()
    assert [e.table.read("L10:0"), e.table.read("L10:1")] == [7, 5]


def test_lgsv_scan_times_in_microseconds_and_lssv_restarts_the_maximum(engine):
    from softplc_lite.ladder.instr.logix_system import LAST_SCAN, MAX_SCAN, WATCHDOG

    e = engine(f"LGSV {LAST_SCAN} L10:0\nLGSV {MAX_SCAN} L10:1\nLGSV {WATCHDOG} L10:2\nXIC B3/0 LSSV {MAX_SCAN} L10:3")
    e.scan()  # simulated time: S:8 is the scan's 10 ms
    e.table.write("S:9", 500)  # a long scan earlier
    e.table.write("S:28", 250)
    e.scan()
    assert [e.table.read(f"L10:{k}") for k in range(3)] == [10_000, 500_000, 250]
    e.table.write("B3/0", 1)  # SSV MaxScanTime 0 restarts the maximum
    e.run(2)
    assert e.table.read("L10:1") == 10_000


def test_lgsv_and_lssv_of_the_minor_fault_bits(engine):
    from softplc_lite.ladder.instr.logix_system import MINOR_BITS

    e = engine(f"LCONCAT ST9:0 ST9:0 ST9:1 1\nLGSV {MINOR_BITS} L10:0\nXIC B3/0 LSSV {MINOR_BITS} L10:1\n"
               f"LGSV {MINOR_BITS} L10:2", {"ST9:0": "ab"})
    e.scan()
    assert e.table.read("L10:0") == 1 << 4
    e.table.write("B3/0", 1)
    e.scan()  # the LCONCAT faults again before the SSV clears it
    assert e.table.read("L10:2") == 0 and e.table.read(f"S:{S.MINOR_FAULT_BITS}") == 0
