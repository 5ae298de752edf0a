"""Did-you-mean for misspelt mnemonics and symbols (ladder/spelling.py): a
swap of two letters is one edit, an unknown name where an output stands
prefers output instructions, and an operand is never offered an instruction."""

from __future__ import annotations

import pytest

from softplc_lite.ladder.errors import LadderError
from softplc_lite.ladder.instructions import BUILTIN
from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.spelling import distance
from softplc_lite.ladder.validate import check


def problems(text: str) -> list[str]:
    try:
        parsed = parse_program(text, "d.lad")
    except LadderError as e:
        return [str(e)]
    return [str(p) for p in check(parsed)[1]]


@pytest.mark.parametrize("a, b, d", [
    ("XCI", "XIC", 1), ("XCI", "ACI", 1), ("XCI", "XIO", 2), ("Strat", "Start", 1), ("OTR", "OR", 1),
    ("abc", "ABC", 0), ("", "OTE", 3), ("CA", "ABC", 3),  # an optimal string alignment: no edit of a swapped pair
])
def test_distance_counts_a_transposition_as_one_edit(a, b, d):
    assert distance(a, b) == d == distance(b, a)


@pytest.mark.parametrize("text, message", [
    ("XCI B3/0 OTE O:0/0\n", "d.lad:1:1: unknown instruction 'XCI' (did you mean XIC?)"),
    ("XIC(B3/0)XCI(B3/1)OTE(O:0/0);\n", "d.lad:1:10: unknown instruction 'XCI' (did you mean XIC?)"),
    ("XIC B3/0 TNO T4:0 0.01 5 0\n", "d.lad:1:10: unknown instruction 'TNO' (did you mean TON?)"),
])
def test_a_transposed_mnemonic_is_one_edit_away(text, message):
    assert problems(text) == [message]


@pytest.mark.parametrize("text, message", [
    ("XIC B3/0 OTR O:0/0\n", "d.lad:1:10: unknown instruction 'OTR' (did you mean OTE?)"),
    ("XIC(B3/0)OTR(O:0/0);\n", "d.lad:1:10: unknown instruction 'OTR' (did you mean OTE?)"),
    # ONE is one edit from ONS (an input) and OTE (an output): where it stands decides
    ("XIC B3/0 ONE B3/1\n", "d.lad:1:10: unknown instruction 'ONE' (did you mean OTE?)"),
    ("XIC B3/0 ONE B3/1 OTE B3/2\n", "d.lad:1:10: unknown instruction 'ONE' (did you mean ONS?)"),
    ("XIC(B3/0)[ONE(B3/1),OTE(B3/3)];\n", "d.lad:1:11: unknown instruction 'ONE' (did you mean OTE?)"),
    ("XIC(B3/0)[ONE(B3/1),OTE(B3/3)]OTE(B3/4);\n", "d.lad:1:11: unknown instruction 'ONE' (did you mean ONS?)"),
])
def test_an_unknown_name_where_an_output_stands_prefers_outputs(text, message):
    assert problems(text) == [message]


def test_the_instruction_set_takes_the_role_as_a_preference_only():
    assert BUILTIN.suggest("ONE", output=True) == "OTE" and BUILTIN.suggest("ONE", output=False) == "ONS"
    assert BUILTIN.suggest("XCI", output=True) == "XIC"  # a swap of letters wins over the role
    assert BUILTIN.suggest("QQQQ") is None


@pytest.mark.parametrize("text, message", [
    ("XIC B3/0 TON T4:0 0.01 abc 0\n", "d.lad:1:24: unknown symbol 'abc': TON operand 3 (preset) takes an integer "
                                       "constant"),
    ("XIC(B3/0)TON(T4:0,0.01,abc,0);\n", "d.lad:1:24: unknown symbol 'abc': TON operand 3 (preset) takes an "
                                         "integer constant"),
    ("XIC B3/0 MOV abc N7:0\n", "d.lad:1:14: unknown symbol 'abc': MOV operand 1 (source) takes a number or "
                                "word/float address, and no SYMBOL line declares abc"),
    ("XIC(XCI)OTE(O:0/0);\n", "d.lad:1:5: unknown symbol 'XCI': XIC operand 1 (bit) takes a bit address, and no "
                              "SYMBOL line declares XCI"),
    ('CPT N7:0 "abc * 2"\n', "d.lad:1:11: unknown symbol 'abc': CPT operand 2 (expression) takes numbers, word and "
                             "float addresses and declared symbols"),
])
def test_an_operand_is_told_what_it_takes_never_offered_an_instruction(text, message):
    assert problems(text) == [message]


def test_a_declared_symbol_is_still_suggested_first_and_a_swap_finds_it():
    assert problems("SYMBOL Start B3/0\nXIC Strat OTE O:0/0\n") == ["d.lad:2:5: unknown symbol 'Strat' (did you mean "
                                                                    "Start?)"]
    assert problems("SYMBOL Pump B3/0\nXIC Pmup OTE O:0/0\n") == ["d.lad:2:5: unknown symbol 'Pmup' (did you mean "
                                                                  "Pump?)"]
