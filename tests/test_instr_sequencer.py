"""Sequencers (ladder/instr/sequencer.py): SQO, SQI, SQL and SLC's SQC
on both executors. docs/instructions.md cites the AB section of each rule."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from helpers.instr_helpers import EXECUTORS, pulse
from softplc_lite.datatable.jsonio import dumps
from softplc_lite.ladder import Engine, Mode, ProgramErrors, load_text, run_text

STEPS = {"N7:0": 0x0F0F, "N7:1": 0x0001, "N7:2": 0x0002, "N7:3": 0x0004, "N7:4": 0x0008}


def state(e: Engine, address: str = "R6:0") -> tuple[int, str]:
    r = e.table.read(address)
    return r["POS"], " ".join(b for b in ("EN", "DN", "ER") if r[b])


# -- SQO --------------------------------------------------------------------------------------

SQO = "XIC B3/0 SQO #N7:0 0x000F N7:20 R6:0 4 0"


def test_sqo_steps_from_the_startup_position_and_wraps_to_1(engine):
    e = engine(SQO, STEPS)
    seen = [(pulse(e).table.read("N7:20"), state(e)) for _ in range(6)]
    assert seen == [(1, (1, "")), (2, (2, "")), (4, (3, "")), (8, (4, "DN")), (1, (1, "")), (2, (2, ""))]


def test_sqo_true_held_steps_once_and_rewrites_the_destination_each_scan(engine):
    e = engine(SQO, STEPS)
    e.table.write("B3/0", 1)
    e.scan()
    e.table.write("N7:20", 0x00F0)  # something else writes the masked bits
    e.scan()
    assert e.table.read("N7:20") == 0x00F1 and state(e) == (1, "EN")


def test_sqo_mask_keeps_the_unmasked_destination_bits(engine):
    e = engine("XIC B3/0 SQO #N7:0 0x00F0 N7:20 R6:0 2 0", {"N7:1": 0x1234, "N7:20": -1})
    pulse(e)
    assert e.table.read("N7:20") == -1 & ~0x00F0 | 0x0030


def test_sqo_dn_stays_until_the_next_transition(engine):
    e = engine("XIC B3/0 SQO #N7:0 0x000F N7:20 R6:0 1 0", STEPS)
    pulse(e)
    assert state(e) == (1, "DN")
    e.scan()
    assert state(e) == (1, "DN")
    pulse(e)  # wraps to 1, the last step again
    assert state(e) == (1, "DN")


def test_sqo_mask_file_and_destination_file_step_with_the_position(engine):
    values = {"N7:1": 0x00FF, "N7:2": 0x00FF, "N7:31": 0x000F, "N7:32": 0x00F0}
    e = engine("XIC B3/0 SQO #N7:0 #N7:30 #N7:40 R6:0 2 0", values)
    pulse(e)
    pulse(e)
    assert [e.table.read(f"N7:{k}") for k in (40, 41, 42)] == [0, 0x000F, 0x00F0]


def test_sqo_bad_length_or_position_sets_er_and_does_nothing(engine):
    e = engine(SQO, STEPS)
    e.table.write("R6:0.POS", -1)  # as a program or a programming terminal may
    pulse(e)
    assert e.table.read("N7:20") == 0 and state(e) == (-1, "ER")
    e.table.write("R6:0", {"LEN": 0, "POS": 0})
    pulse(e)
    assert state(e) == (0, "ER")
    e.table.write("R6:0", {"LEN": 4, "POS": 3})
    pulse(e)
    assert state(e) == (4, "DN") and e.table.read("N7:20") == 8


def test_sqo_position_past_the_length_is_wrapped_by_the_next_step(engine):
    e = engine(SQO, STEPS)
    e.table.write("B3/0", 1)
    e.scan()
    e.table.write("R6:0.POS", 9)  # written while the rung stays true: nothing until the next step
    e.table.write("N7:20", 0)
    e.scan()
    assert state(e) == (9, "EN") and e.table.read("N7:20") == 0
    e.table.write("B3/0", 0)
    e.scan()
    pulse(e)  # the next false-to-true transition wraps it to 1
    assert state(e) == (1, "") and e.table.read("N7:20") == 1


def test_sqo_length_past_the_end_of_its_file_is_major_fault_202(engine):
    e = engine("MOV 2000 R6:0.LEN\n" + SQO, STEPS)
    pulse(e)
    assert e.fault.code == 202 and "SQO" in str(e.fault)


def test_sqo_grows_its_files_to_length_plus_1_words(engine):
    e = engine("XIC B3/0 SQO #N7:100 #N10:0 N7:0 R6:0 8 0")
    assert len(e.table.file("N7").data) >= 109 and len(e.table.file("N10").data) >= 9
    assert (e.table.read("R6:0")["LEN"], e.table.read("R6:0")["POS"]) == (8, 0)


# -- SQI --------------------------------------------------------------------------------------


def test_sqi_is_true_when_the_masked_source_matches_the_step_word(engine):
    e = engine("XIC B3/0 SQI #N7:0 0xFFF0 I:0.0 R6:0 4 2 OTE B3/5", {"N7:2": 0x1230})
    for source, out in ((0x1234, 1), (0x123F, 1), (0x1334, 0)):
        e.table.write("I:0.0", source)
        e.table.write("B3/0", 1)
        e.scan()
        assert e.table.read("B3/5") == out, hex(source)
    e.table.write("B3/0", 0)
    e.table.write("I:0.0", 0x1234)
    e.scan()
    assert e.table.read("B3/5") == 0 and state(e)[0] == 2  # SQI never steps


def test_sqi_paired_with_sqo_waits_for_each_step(engine):
    program = ("XIC B3/0 SQO #N7:0 0x00FF N7:20 R6:0 3 0\n"
               "SQI #N7:10 0x00FF N7:21 R6:0 3 0 OTE B3/5")
    e = engine(program, {"N7:1": 1, "N7:2": 2, "N7:3": 3, "N7:11": 10, "N7:12": 20, "N7:13": 30})
    pulse(e)
    e.table.write("N7:21", 10)
    e.scan()
    assert e.table.read("B3/5") == 1
    pulse(e)
    assert e.table.read("B3/5") == 0 and e.table.read("N7:20") == 2


def test_sqi_source_file_steps_and_bad_position_is_false_with_er(engine):
    e = engine("MOV N7:9 R6:0.POS\nSQI #N7:0 0x00FF #N7:10 R6:0 2 0 OTE B3/5",
               {"N7:2": 7, "N7:12": 7, "N7:9": 2})
    e.scan()
    assert e.table.read("B3/5") == 1
    e.table.write("N7:9", 3)
    e.scan()
    assert e.table.read("B3/5") == 0 and state(e) == (3, "ER")


# -- SQL --------------------------------------------------------------------------------------


def test_sql_loads_the_source_into_each_step_and_wraps(engine):
    e = engine("XIC B3/0 SQL #N7:0 N7:20 R6:0 3 0", {"N7:20": 0})
    for value in (11, 22, 33, 44):
        e.table.write("N7:20", value)
        pulse(e)
    assert [e.table.read(f"N7:{k}") for k in range(4)] == [0, 44, 22, 33]
    assert state(e) == (1, "")


def test_sql_true_held_keeps_loading_the_same_step(engine):
    e = engine("XIC B3/0 SQL #N7:0 N7:20 R6:0 3 0", {"N7:20": 5})
    e.table.write("B3/0", 1)
    e.scan()
    e.table.write("N7:20", 6)
    e.scan()
    assert (e.table.read("N7:1"), e.table.read("N7:2")) == (6, 0)
    assert state(e) == (1, "EN")


def test_sql_with_a_source_file_and_dn_at_the_last_step(engine):
    e = engine("XIC B3/0 SQL #N7:0 #N7:10 R6:0 2 0", {"N7:11": 5, "N7:12": 6})
    pulse(e)
    pulse(e)
    assert (e.table.read("N7:1"), e.table.read("N7:2"), state(e)) == (5, 6, (2, "DN"))


# -- SQC (SLC 500) ----------------------------------------------------------------------------


def test_sqc_steps_like_sqo_and_sets_fd_when_the_masked_source_matches(engine):
    e = engine("XIC B3/0 SQC #N7:0 0x00FF I:0.0 R6:0 2 0", {"N7:1": 0x0012, "N7:2": 0x0034, "I:0.0": 0x7712})
    e.table.write("B3/0", 1)
    e.scan()
    assert e.table.read("R6:0/FD") == 1 and state(e) == (1, "EN")
    e.table.write("I:0.0", 0x0013)  # assessed at every true evaluation, without stepping
    e.scan()
    assert e.table.read("R6:0/FD") == 0 and state(e) == (1, "EN")
    e.table.write("B3/0", 0)
    e.scan()
    e.table.write("I:0.0", 0x0034)
    pulse(e)
    assert e.table.read("R6:0/FD") == 1 and state(e) == (2, "DN")


def test_sqc_bad_position_sets_er_and_leaves_fd(engine):
    e = engine("XIC B3/0 SQC #N7:0 0x00FF I:0.0 R6:0 2 0")
    e.table.write("R6:0", {"POS": -1, "FD": 1})
    pulse(e)
    assert state(e) == (-1, "ER") and e.table.read("R6:0/FD") == 1


# -- syntax and validation ------------------------------------------------------------------


def test_sqo_sqi_sql_both_rung_syntaxes_agree():
    values = STEPS | {"B3/0": 1}
    mnemonic = run_text("XIC B3/0 SQO #N7:0 0x000F N7:20 R6:0 4 0\nSQL #N7:10 N7:0 R6:1 2 0"
                        "\nSQI #N7:0 0x000F N7:20 R6:0 4 0 OTE B3/5", values=values)
    neutral = run_text("XIC(B3/0)SQO(#N7:0,0x000F,N7:20,R6:0,4,0);\nSQL(#N7:10,N7:0,R6:1,2,0);"
                       "\nSQI(#N7:0,0x000F,N7:20,R6:0,4,0)OTE(B3/5);", values=values)
    assert dumps(mnemonic.table) == dumps(neutral.table)
    assert (mnemonic.table.read("N7:20"), mnemonic.table.read("B3/5")) == (1, 1)


@pytest.mark.parametrize("text,expected", [
    ("SQO #N7:0 0x0F N7:20 R6:0 0 0", "SQO operand 5 (length) must be in 1..1000"),
    ("SQO #N7:0 0x0F N7:20 R6:0 4 1001", "SQO operand 6 (position) must be in 0..1000"),
    ("SQO #N7:0 1.5 N7:20 R6:0 4 0", "SQO operand 2 (mask) must be integer or word address"),
    ("SQI #F8:0 0x0F N7:20 R6:0 4 0", "SQI operand 1 (file) must be word file address"),
    ("SQL #N7:0 N7:20 C5:0 4 0", "SQL operand 3 (control) must be control element (R)"),
    ("SQO #N7:0 0x0F N7:20 R6:0 4", "SQO takes 6 operands"),
])
def test_sqo_sqi_sql_bad_operands_are_located_errors(text, expected):
    with pytest.raises(ProgramErrors) as info:
        load_text(text)
    message = str(info.value)
    assert "<program>:1:" in message and expected in message, message


# -- both executors, random rung states -------------------------------------------------

PROGRAM = """XIC B3/0 SQO #N7:0 #N7:10 N7:30 R6:0 5 0
XIC B3/1 SQI #N7:0 0x00FF N7:31 R6:0 5 0 OTE B3/8
XIC B3/2 SQL #N7:20 N7:30 R6:1 3 1
XIO B3/3 SQO #N7:20 0xFFFF #N7:40 R6:2 3 0
XIC B3/3 SQC #N7:0 0x0F0F N7:31 R6:3 4 0
ADD N7:31 3 N7:31
"""


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 15), min_size=1, max_size=40))
def test_sqo_sqi_sql_sqc_executors_agree_on_random_rung_states(states):
    tables = []
    for executor in EXECUTORS:
        e = Engine(load_text(PROGRAM), executor=executor)
        for k in range(6):
            e.table.write(f"N7:{k}", 3 * k + 1)
            e.table.write(f"N7:{10 + k}", 0x0F0F if k % 2 else 0x00FF)
        e.set_mode(Mode.RUN)
        for word in states:
            e.table.write("B3:0", word)
            e.scan()
        assert e.fault is None
        tables.append(dumps(e.table))
    assert tables[0] == tables[1]


def test_sqi_on_the_control_of_its_sqo_is_no_check_warning():
    from softplc_lite.ladder.verify import verify

    shared = load_text("XIC B3/0 SQO #N7:0 0x0F N7:20 R6:0 3 0\nSQI #N7:10 0x0F I:0.0 R6:0 3 0 OTE B3/5")
    assert verify(shared) == []
    twice = load_text("XIC B3/0 SQO #N7:0 0x0F N7:20 R6:0 3 0\nXIC B3/1 SQO #N7:10 0x0F N7:21 R6:0 3 0")
    assert ["also used by SQO" in str(w) for w in verify(twice)] == [True]
