"""Load-time validation: every problem found, each with file:line:col."""

from __future__ import annotations

import pytest

from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.validate import check


def problems(text: str) -> list[str]:
    _, errors = check(parse_program(text, "v.lad"))
    return [str(e) for e in errors]


CASES = [
    ("XIC B3/0 XIX B3/1 OTE O:0/0\n", "v.lad:1:10: unknown instruction 'XIX' (did you mean XIC?)"),
    ("XIX(B3/0)OTE(O:0/0);\n", "v.lad:1:1: unknown instruction 'XIX'"),
    ("TON T4:0 0.5 100 0\n", "v.lad:1:10: TON operand 2 (base) must be the time base 1.0, 0.01 or 0.001"),
    ("TON(T4:0,1.0,100);\n", "v.lad:1:1: TON takes 4 operands (TON timer base preset accum), got 3"),
    ("XIC N7:0\n", "v.lad:1:5: XIC operand 1 (bit) must be bit address, not N7:0 (a word)"),
    ("ADD N7:0 B3/1 N7:2\n", "v.lad:1:10: ADD operand 2 (b) must be number or word/float address, not B3/1 (a bit)"),
    ("MOV N7:0 5\n", "v.lad:1:10: MOV operand 2 (dest) must be word or float address, not the constant 5"),
    ("CTU T4:0 10 0\n", "v.lad:1:5: CTU operand 1 (counter) must be counter element (C)"),
    ("JMP 5\n", "v.lad:1:5: JMP to label 5, which is not in program file 2"),
    ("JSR 9\n", "v.lad:1:5: JSR to program file 9, which does not exist (files: 2)"),
    ('CPT N7:0 "N7:1 + ST9:0"\n', "v.lad:1:18: ST9:0 is a string; expressions take words, floats and numbers"),
    ('CMP "N7:1 + 2"\n', "CMP needs a comparison"),
    ('CPT N7:0 "N7:1 > 2"\n', "CPT computes a value; comparisons belong in CMP"),
    ("XIC(Foo)OTE(O:0/1);\n", "v.lad:1:5: unknown symbol 'Foo'"),
    ("XIC B3/0 LBL 3\n", "v.lad:1:10: LBL must be the first instruction of its rung"),
    ("LBL 3 OTE B3/0\nLBL 3 OTE B3/1\n", "v.lad:2:1: label 3 is defined twice in file 2"),
    ("SYMBOL XIC B3/0\nXIC B3/0\n", "symbol XIC has the name of an instruction"),
    ("DATA N10 3 = 1 2 3 4\n", "DATA N10: 4 values for 3 elements"),
    ("DATA X10 3\n", "DATA X10: expected a data file name"),
    ('DATA N10 1 = "a"\n', "DATA N10: 'a' does not fit a 16-bit word"),
    ("MEQ N7:0 70000 N7:1\n", "70000 does not fit a 16-bit word"),
    ("FILE 3\nXIC B3/0\n", "the program has no main file 2"),
    ("COP #N7:0 #N7:10 0\n", "COP operand 3 (length) must be in 1..1000"),
    ("XIC(B3/0)[OTE(B3/1)];\n", "a branch needs at least two legs"),
    ("RES N7:0\n", "RES operand 1 (element) must be timer, counter or control element"),
]


@pytest.mark.parametrize("text,message", CASES)
def test_each_problem_is_reported(text, message):
    found = problems(text)
    assert any(message in p for p in found), found


def test_every_problem_is_listed_in_source_order():
    text = "XIC N7:0\nJMP 4\nTON T4:0 2.0 1 0\n"
    found = problems(text)
    assert [p.split(":")[1] for p in found] == ["1", "2", "3"]


def test_valid_program_has_no_problems_and_is_resolved():
    text = "SYMBOL Go B3/0\nXIC Go OTE O:0/0\nCOP #N7:0 #N7:10 5\nMOV 0xFFFF N7:1\n"
    resolved, errors = check(parse_program(text, "ok.lad"))
    assert errors == []
    xic = resolved.main.rungs[0].elements[0]
    assert str(xic.operands[0].address) == "B3/0"
    cop = resolved.main.rungs[1].elements[0]
    assert str(cop.operands[0].address) == "N7:0"  # '#' marks a file operand, not indexing
    assert resolved.main.rungs[2].elements[0].operands[0].value == -1  # hex is a bit pattern
