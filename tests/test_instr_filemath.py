"""File arithmetic and search: FAL and FSC in ALL,
INC and numeric modes, and AVE, STD, SRT (ladder/instr/filemath.py).

Every behaviour runs on both executors: ``drive`` runs the same steps on
the compiled and the reference executor, checks that the two data tables
are identical and returns the compiled engine. docs/instructions.md
("File arithmetic and search instructions") has the rules and their AB
sources.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from softplc_lite.datatable.jsonio import dumps
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.errors import ProgramErrors
from softplc_lite.ladder.fmt import format_program
from softplc_lite.ladder.parser import parse_program

EXECUTORS = ("compiled", "reference")


def _engine(text: str, executor: str) -> Engine:
    engine = Engine(load_text(text), executor=executor)
    engine.set_mode(Mode.RUN)
    return engine


def drive(text: str, *steps: tuple[dict, int], values: dict | None = None) -> list[Engine]:
    """Run ``steps`` ((values to write, scans), ...) on both executors after
    writing ``values``; the tables must agree after every step. Returns the
    engines (compiled first)."""
    engines = [_engine(text, ex) for ex in EXECUTORS]
    for e in engines:
        for a, v in (values or {}).items():
            e.table.write(a, v)
    for writes, scans in steps:
        for e in engines:
            for a, v in writes.items():
                e.table.write(a, v)
            e.run(scans)
        assert [str(e.fault) for e in engines][0] == str(engines[1].fault)
        assert dumps(engines[0].table) == dumps(engines[1].table)
    return engines


def read(e: Engine, *addresses: str):
    return tuple(e.table.read(a) for a in addresses)


def words(e: Engine, file: str, first: int, n: int) -> list:
    return [e.table.read(f"{file}:{k}") for k in range(first, first + n)]


def control(e: Engine, name: str = "R6:0") -> dict:
    r = e.table.read(name)
    return {k: v for k, v in r.items() if k in ("EN", "EU", "DN", "ER", "IN", "FD", "POS", "LEN") and v}


ON, OFF = {"B3/0": 1}, {"B3/0": 0}
FIVE = {f"N7:{k}": v for k, v in enumerate([1, 2, 3, 4, 5])}


# -- FAL -------------------------------------------------------------------------------------


def test_fal_all_mode_does_the_whole_file_on_the_transition_only():
    e, _ = drive('XIC B3/0 FAL R6:0 5 0 ALL #N7:10 "#N7:0 * 2"', (ON, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [2, 4, 6, 8, 10]
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 5, "POS": 5}
    assert e.table.read("S:24") == 4  # the last element's offset
    # held true: nothing more; a false rung resets DN and POS; the next transition runs again
    e, _ = drive('XIC B3/0 FAL R6:0 5 0 ALL #N7:10 "#N7:0 * 2"', (ON, 1), ({"N7:0": 100}, 3), values=FIVE)
    assert e.table.read("N7:10") == 2
    e, _ = drive('XIC B3/0 FAL R6:0 5 0 ALL #N7:10 "#N7:0 * 2"', (ON, 1), (OFF, 1), values=FIVE)
    assert control(e) == {"LEN": 5}
    e, _ = drive('XIC B3/0 FAL R6:0 5 0 ALL #N7:10 "#N7:0 * 2"', (ON, 1), (OFF, 1), ({"N7:0": 100, "B3/0": 1}, 1),
                 values=FIVE)
    assert e.table.read("N7:10") == 200


def test_fal_inc_mode_does_one_element_per_false_to_true_transition():
    text = 'XIC B3/0 FAL R6:0 3 0 INC #N7:10 "#N7:0 + 1"'
    values = {"N7:0": 10, "N7:1": 20, "N7:2": 30}
    e, _ = drive(text, (ON, 3), values=values)
    assert words(e, "N7", 10, 3) == [11, 0, 0]
    assert control(e) == {"EN": 1, "EU": 1, "LEN": 3, "POS": 1}
    e, _ = drive(text, (ON, 1), (OFF, 2), values=values)
    assert control(e) == {"EU": 1, "LEN": 3, "POS": 1}  # under way: a false rung keeps the position
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), (OFF, 1), (ON, 1), values=values)
    assert words(e, "N7", 10, 3) == [11, 21, 31]
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 3, "POS": 3}
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), (OFF, 1), (ON, 1), (OFF, 1), ({"N7:0": 5, "B3/0": 1}, 1),
                 values=values)
    assert e.table.read("N7:10") == 6 and control(e)["POS"] == 1  # a new pass from element 0


def test_fal_numeric_mode_does_n_elements_a_scan_whatever_the_rung_does():
    text = "XIC B3/0 FAL R6:0 5 0 2 #N7:10 #N7:0"
    e, _ = drive(text, (ON, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [1, 2, 0, 0, 0] and control(e) == {"EN": 1, "EU": 1, "LEN": 5, "POS": 2}
    e, _ = drive(text, (ON, 1), (OFF, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [1, 2, 3, 4, 0] and control(e) == {"EU": 1, "LEN": 5, "POS": 4}
    e, _ = drive(text, (ON, 1), (OFF, 2), values=FIVE)
    assert words(e, "N7", 10, 5) == [1, 2, 3, 4, 5] and control(e) == {"DN": 1, "LEN": 5, "POS": 5}
    e, _ = drive(text, (ON, 1), (OFF, 3), values=FIVE)
    assert control(e) == {"LEN": 5}  # the false rung after the end resets it
    # held true: two a scan, DN on the third scan
    e, _ = drive(text, (ON, 3), values=FIVE)
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 5, "POS": 5}


def test_fal_file_to_element_and_element_to_file():
    # no '#' on the destination: every element goes to the one word (a running sum)
    e, _ = drive('FAL R6:0 4 0 ALL N7:20 "N7:20 + #N7:0"', ({}, 1), values=FIVE)
    assert e.table.read("N7:20") == 1 + 2 + 3 + 4
    # no '#' in the expression: one word into every element of the file
    e, _ = drive("FAL R6:0 3 0 ALL #N7:10 N7:0", ({}, 1), values={"N7:0": 7})
    assert words(e, "N7", 10, 3) == [7, 7, 7]
    # a float file from a word file, converted by the store
    e, _ = drive('FAL R6:0 3 0 ALL #F8:0 "#N7:0 | 2"', ({}, 1), values={"N7:0": 1, "N7:1": 3, "N7:2": -5})
    assert words(e, "F8", 0, 3) == [1.0, 2.0, -3.0]  # integer division rounds as DIV does


def test_fal_overflow_sets_er_and_stops_at_that_element():
    text = 'XIC B3/0 FAL R6:0 4 0 ALL #N7:10 "#N7:0 * 1000"'
    values = {"N7:0": 1, "N7:1": 40, "N7:2": 2, "N7:3": 3}
    e, _ = drive(text, (ON, 2), values=values)
    assert words(e, "N7", 10, 4) == [1000, 32767, 0, 0]  # clamped, then stopped
    assert control(e) == {"EN": 1, "ER": 1, "LEN": 4, "POS": 1}
    assert e.table.read("S:0") & (1 << S.OVERFLOW)
    assert e.table.read(f"S:{S.PLC5_MINOR_FAULT_BITS}/{S.MINOR_OVERFLOW_BIT}") == 1
    e, _ = drive(text, (ON, 1), (OFF, 1), values=values)
    assert control(e) == {"LEN": 4}  # the false rung clears ER for the next pass
    # a division by zero in the expression is an overflow too
    e, _ = drive('FAL R6:0 2 0 ALL #N7:10 "10 | #N7:0"', ({}, 1), values={"N7:0": 0, "N7:1": 2})
    assert control(e)["ER"] == 1 and words(e, "N7", 10, 2) == [32767, 0]


def test_fal_indexed_address_past_the_end_of_its_file_is_a_major_fault():
    # a file chosen at run time: the table cannot be grown for it at load
    text = "DATA N9 3\nXIC B3/0 FAL R6:0 5 0 ALL #N[N7:0]:0 5"
    e, r = drive(text, (ON, 1), values={"N7:0": 9})
    assert e.fault.code == S.FAULT_INDIRECT_RANGE and r.fault.code == S.FAULT_INDIRECT_RANGE
    assert "S:24 = 3" in str(e.fault) and e.table.read("R6:0.POS") == 3
    assert words(e, "N9", 0, 3) == [5, 5, 5]


def test_fal_files_named_with_a_constant_length_are_grown_at_load():
    e, _ = drive('FAL R6:0 5 0 ALL #N7:10 "#N11:3 + 1"', ({}, 1))
    assert e.fault is None
    assert e.table.file("N7").size == 15 and e.table.file("N11").size == 8


def test_fal_a_position_written_outside_the_file_sets_er():
    e, _ = drive("XIC B3/0 FAL R6:0 5 0 1 #N7:10 #N7:0", (ON, 1), ({"R6:0.POS": 9}, 1), values=FIVE)
    assert control(e) == {"EN": 1, "ER": 1, "LEN": 5, "POS": 9}
    assert words(e, "N7", 10, 5) == [1, 0, 0, 0, 0]


def test_fal_length_and_position_operands_are_what_a_download_writes():
    # the first pass starts at the downloaded POS; the false rung after it resets POS to 0
    text = "XIC B3/0 FAL R6:0 5 2 ALL #N7:10 #N7:0"
    e, _ = drive(text, ({}, 1), values=FIVE)
    assert control(e) == {"LEN": 5, "POS": 2}
    e, _ = drive(text, (ON, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [0, 0, 3, 4, 5] and control(e)["DN"] == 1
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [1, 2, 3, 4, 5]
    # the instruction works from the control's LEN, which the program may change
    e, _ = drive("XIC B3/0 FAL R6:0 5 0 ALL #N7:10 #N7:0", ({"R6:0.LEN": 2, "B3/0": 1}, 1), values=FIVE)
    assert words(e, "N7", 10, 5) == [1, 2, 0, 0, 0] and control(e) == {"EN": 1, "DN": 1, "LEN": 2, "POS": 2}
    e, _ = drive("XIC B3/0 FAL R6:0 5 0 ALL #N7:10 #N7:0", ({"R6:0.LEN": -1, "B3/0": 1}, 1), values=FIVE)
    assert control(e)["ER"] == 1 and words(e, "N7", 10, 5) == [0] * 5
    # a LEN past the end of the files the load grew: major fault 20 at the first element outside
    e, r = drive("XIC B3/0 FAL R6:0 5 0 ALL #N7:10 #N7:0", ({"R6:0.LEN": 8, "B3/0": 1}, 1), values=FIVE)
    assert e.fault.code == r.fault.code == S.FAULT_INDIRECT_RANGE and e.table.read("R6:0.POS") == 5


def test_fal_and_fsc_rung_syntaxes_give_the_same_program_and_results():
    mnemonic = 'XIC B3/0 FAL R6:0 5 0 ALL #N7:10 "#N7:0 + 5"\nXIC B3/0 FSC R6:1 5 0 INC "#N7:0 >= 3"'
    neutral = "XIC(B3/0)FAL(R6:0,5,0,ALL,#N7:10,#N7:0+5);\nXIC(B3/0)FSC(R6:1,5,0,INC,#N7:0 >= 3);"
    assert parse_program(mnemonic).main.rungs == parse_program(neutral).main.rungs
    a, _ = drive(mnemonic, (ON, 1), values=FIVE)
    b, _ = drive(neutral, (ON, 1), values=FIVE)
    assert dumps(a.table) == dumps(b.table)
    assert words(a, "N7", 10, 5) == [6, 7, 8, 9, 10]


@pytest.mark.parametrize("style", ["mnemonic", "neutral"])
def test_fal_fsc_ave_std_srt_fmt_round_trip(style):
    text = ('XIC B3/0 FAL R6:0 10 0 ALL #N7:10 "#N7:0 + 5"\nFAL R6:1 4 0 inc N7:30 "N7:30 + #N7:0"\n'
            'FAL R6:2 8 0 3 #F8:0 #N7:0\nFSC R6:3 6 0 ALL "#N7:0 = N7:20"\nAVE #N7:0 N7:21 R6:4 5 0\n'
            "STD #F8:0 F8:20 R6:5 8 0\nSRT #N7:0 R6:6 5 0\n")
    program = parse_program(text)
    printed = format_program(program, style)
    assert parse_program(printed).main.rungs == program.main.rungs
    assert format_program(parse_program(printed), style) == printed
    assert "inc" in printed and "ALL" in printed  # the mode as written
    load_text(printed)  # and it validates


def test_fal_and_fsc_mode_errors_are_located_and_name_the_choices():
    for mode, shown in [("FOO", "FOO"), ("0", "the constant 0"), ("6", "the constant 6"), ("2.5", "the constant 2.5")]:
        with pytest.raises(ProgramErrors) as info:
            load_text(f"MOV 1 N7:0\nFAL R6:0 5 0 {mode} #N7:10 #N7:0")
        assert str(info.value) == (f"<program>:2:14: FAL operand 4 (mode) must be ALL, INC or a number of elements "
                                   f"per scan 1..5, not {shown}")
    # ALL is a word of the instruction, even when a symbol has that name
    load_text("SYMBOL All N7:0\nFSC R6:0 5 0 all \"#N7:1 = 2\"")
    with pytest.raises(ProgramErrors) as info:
        load_text('FSC R6:0 5 0 ALL "#N7:0 + 1"\nFAL R6:1 5 0 ALL #N7:10 "#N7:0 > 1"')
    assert "<program>:1:19: FSC needs a comparison" in str(info.value)
    assert "<program>:2:" in str(info.value)
    # an unquoted expression in mnemonic text splits into operands: the error says to quote it
    with pytest.raises(ProgramErrors) as info:
        load_text("FAL R6:0 10 0 ALL #N7:10 #N7:0+5")
    assert str(info.value) == ('<program>:1:1: FAL takes 6 operands (FAL control length position mode dest '
                               'expression), got 7 (in mnemonic text an expression with operators is quoted: '
                               '"N7:1 + 5")')


# -- FSC -------------------------------------------------------------------------------------


SEARCH = {f"N7:{k}": v for k, v in enumerate([5, 9, 3, 9, 1, 2])} | {"N7:20": 9}


def test_fsc_all_mode_stops_at_a_match_and_clearing_in_goes_on():
    text = 'XIC B3/0 FSC R6:0 6 0 ALL "#N7:0 = N7:20"'
    e, _ = drive(text, (ON, 2), values=SEARCH)
    assert control(e) == {"EN": 1, "EU": 1, "FD": 1, "IN": 1, "LEN": 6, "POS": 1}
    e, _ = drive(text, (ON, 1), ({"R6:0/IN": 0}, 1), values=SEARCH)
    assert control(e) == {"EN": 1, "EU": 1, "FD": 1, "IN": 1, "LEN": 6, "POS": 3}
    e, _ = drive(text, (ON, 1), ({"R6:0/IN": 0}, 1), ({"R6:0/IN": 0}, 1), values=SEARCH)
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 6, "POS": 6}
    e, _ = drive(text, (ON, 1), ({"R6:0/IN": 0}, 1), ({"R6:0/IN": 0}, 1), (OFF, 1), values=SEARCH)
    assert control(e) == {"LEN": 6}
    # a found element stays found (IN) across a false rung until the program clears IN
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), values=SEARCH)
    assert control(e) == {"EN": 1, "EU": 1, "FD": 1, "IN": 1, "LEN": 6, "POS": 1}


def test_fsc_inc_mode_compares_one_element_per_transition():
    text = 'XIC B3/0 FSC R6:0 3 0 INC "#N7:0 > 5"'
    values = {"N7:0": 1, "N7:1": 7, "N7:2": 2}
    e, _ = drive(text, (ON, 2), values=values)
    assert control(e) == {"EN": 1, "EU": 1, "LEN": 3, "POS": 1}
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), values=values)
    assert control(e) == {"EN": 1, "EU": 1, "FD": 1, "IN": 1, "LEN": 3, "POS": 1}
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), (OFF, 1), (ON, 1), values=values)
    assert control(e)["POS"] == 1 and control(e)["IN"] == 1  # inhibited: the transition does nothing
    e, _ = drive(text, (ON, 1), (OFF, 1), (ON, 1), ({"B3/0": 0, "R6:0/IN": 0}, 1), (ON, 1), values=values)
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 3, "POS": 3}


def test_fsc_numeric_mode_searches_n_elements_a_scan():
    text = 'XIC B3/0 FSC R6:0 6 0 2 "#N7:0 <> 0"'
    values = {"N7:4": 1}
    for scans, pos in [(1, 2), (2, 4)]:
        e, _ = drive(text, (ON, scans), values=values)
        assert control(e) == {"EN": 1, "EU": 1, "LEN": 6, "POS": pos}
    e, _ = drive(text, (ON, 1), (OFF, 2), values=values)  # goes on while the rung is false
    assert control(e) == {"EU": 1, "FD": 1, "IN": 1, "LEN": 6, "POS": 4}


def test_fsc_with_float_and_word_files_and_rung_out():
    e, _ = drive('FSC R6:0 3 0 ALL "#F8:0 > #N7:0" OTE B3/1', ({}, 1),
                 values={"F8:0": 0.5, "F8:1": 2.5, "F8:2": 9.0, "N7:0": 1, "N7:1": 2, "N7:2": 3})
    assert control(e)["POS"] == 1 and control(e)["FD"] == 1 and e.table.read("B3/1") == 1


# -- AVE, STD, SRT ---------------------------------------------------------------------------


def test_ave_word_file_rounds_the_average_into_the_destination():
    e, _ = drive("XIC B3/0 AVE #N7:0 N7:20 R6:0 4 0", (ON, 1), values={"N7:0": 1, "N7:1": 2, "N7:2": 3, "N7:3": 5})
    assert e.table.read("N7:20") == 3  # 11 / 4 = 2.75
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 4, "POS": 4}
    e, _ = drive("AVE #N7:0 N7:20 R6:0 2 0", ({}, 1), values={"N7:0": -1, "N7:1": -2})
    assert e.table.read("N7:20") == -2  # -1.5: half to even
    assert e.table.read("S:0") & (1 << S.SIGN)
    # the sum of words does not overflow: 32767 * 3 / 3
    e, _ = drive("AVE #N7:0 F8:0 R6:0 3 0", ({}, 1), values={"N7:0": 32767, "N7:1": 32767, "N7:2": 32766})
    assert e.table.read("F8:0") == pytest.approx(98300 / 3) and control(e)["DN"] == 1


def test_ave_float_file_and_transition_only():
    text = "XIC B3/0 AVE #F8:0 F8:10 R6:0 3 0"
    values = {"F8:0": 1.5, "F8:1": 2.5, "F8:2": 3.0}
    e, _ = drive(text, (ON, 1), ({"F8:0": 100.0}, 2), values=values)
    assert e.table.read("F8:10") == pytest.approx(7 / 3)  # not redone while the rung stays true
    e, _ = drive(text, (ON, 1), ({"F8:0": 100.0, "B3/0": 0}, 1), (ON, 1), values=values)
    assert e.table.read("F8:10") == pytest.approx(105.5 / 3)
    e, _ = drive(text, (ON, 1), (OFF, 1), values=values)
    assert control(e) == {"LEN": 3}


def test_ave_result_too_big_for_its_word_sets_er_and_overflow():
    e, _ = drive("AVE #F8:0 N7:0 R6:0 2 0", ({}, 1), values={"F8:0": 1e6, "F8:1": 1e6})
    assert e.table.read("N7:0") == 32767 and control(e) == {"EN": 1, "ER": 1, "LEN": 2, "POS": 2}
    assert e.table.read("S:0") & (1 << S.OVERFLOW)


def test_ave_file_past_its_end_is_a_major_fault():
    e, _ = drive("DATA N9 3\nAVE #N[N7:0]:0 N7:5 R6:0 5 0", ({}, 1), values={"N7:0": 9})
    assert e.fault.code == S.FAULT_BLOCK_RANGE
    e, _ = drive("XIC B3/0 AVE #N7:0 N7:5 R6:0 5 0", ({"R6:0.LEN": 7, "B3/0": 1}, 1))
    assert e.fault.code == S.FAULT_BLOCK_RANGE


def test_ave_std_srt_work_from_the_control_len():
    values = {"N7:0": 4, "N7:1": 2, "N7:2": 9}
    e, _ = drive("XIC B3/0 AVE #N7:0 N7:5 R6:0 3 0\nXIC B3/0 SRT #N7:0 R6:1 3 0",
                 ({"R6:0.LEN": 2, "R6:1.LEN": 2, "B3/0": 1}, 1), values=values)
    assert e.table.read("N7:5") == 3 and words(e, "N7", 0, 3) == [2, 4, 9]
    e, _ = drive("XIC B3/0 AVE #N7:0 N7:5 R6:0 3 0", ({"R6:0.LEN": 0, "B3/0": 1}, 1), values=values)
    assert control(e) == {"EN": 1, "ER": 1}


def test_std_is_the_sample_standard_deviation():
    data = [2, 4, 4, 4, 5, 5, 7, 9]
    values = {f"N7:{k}": v for k, v in enumerate(data)}
    want = math.sqrt(sum((v - 5) ** 2 for v in data) / 7)
    e, _ = drive("STD #N7:0 F8:0 R6:0 8 0\nSTD #N7:0 N7:20 R6:1 8 0", ({}, 1), values=values)
    assert e.table.read("F8:0") == pytest.approx(want, rel=1e-6) and e.table.read("N7:20") == 2
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 8, "POS": 8}
    e, _ = drive("STD #F8:0 F8:9 R6:0 3 0", ({}, 1), values={"F8:0": 1.0, "F8:1": 1.0, "F8:2": 1.0})
    assert e.table.read("F8:9") == 0.0 and e.table.read("S:0") & (1 << S.ZERO)


def test_std_of_one_element_sets_er_and_leaves_the_destination():
    e, _ = drive("STD #N7:0 N7:20 R6:0 1 0", ({}, 1), values={"N7:0": 5, "N7:20": 42})
    assert e.table.read("N7:20") == 42 and control(e)["ER"] == 1 and "DN" not in control(e)


def test_srt_sorts_the_file_ascending_in_place():
    e, _ = drive("DATA N7 6\nXIC B3/0 SRT #N7:0 R6:0 5 0", (ON, 1),
                 values={"N7:0": 5, "N7:1": -3, "N7:2": 9, "N7:3": 0, "N7:4": 2, "N7:5": -100})
    assert words(e, "N7", 0, 6) == [-3, 0, 2, 5, 9, -100]  # N7:5 is outside the length
    assert control(e) == {"EN": 1, "DN": 1, "LEN": 5, "POS": 5}
    e, _ = drive("SRT #F8:2 R6:0 3 0", ({}, 1), values={"F8:2": 2.5, "F8:3": -1.25, "F8:4": 0.5})
    assert words(e, "F8", 2, 3) == [-1.25, 0.5, 2.5]


# -- both executors on random data -------------------------------------------------------------


@st.composite
def file_programs(draw):
    length = draw(st.integers(1, 8))
    mode = draw(st.sampled_from(["ALL", "INC", *map(str, range(1, length + 1))]))
    op = draw(st.sampled_from(["+", "*", "-", "|", "AND"]))
    k = draw(st.integers(-200, 200))
    text = "\n".join([
        f'XIC B3/0 FAL R6:0 {length} 0 {mode} #N7:20 "#N7:0 {op} {k}"',
        f'XIC B3/1 FSC R6:1 {length} 0 {mode} "#N7:0 > {k}"',
        f"XIC B3/2 AVE #N7:0 N7:40 R6:2 {length} 0",
        f"XIC B3/2 STD #N7:0 F8:0 R6:3 {length} 0",
        f"XIC B3/3 SRT #N7:0 R6:4 {length} 0",
        "XIC R6:1/FD OTU R6:1/IN",
    ])
    data = draw(st.lists(st.integers(-32768, 32767), min_size=length, max_size=length))
    rungs = draw(st.lists(st.integers(0, 15), min_size=1, max_size=12))
    return text, data, rungs


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(file_programs())
def test_fal_fsc_ave_std_srt_executors_agree_on_random_data(case):
    text, data, rungs = case
    values = {f"N7:{k}": v for k, v in enumerate(data)}
    steps = [({f"B3/{b}": (bits >> b) & 1 for b in range(4)}, 1) for bits in rungs]
    e, r = drive(text, *steps, values=values)
    assert str(e.fault) == str(r.fault)
