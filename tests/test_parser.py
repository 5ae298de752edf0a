"""Parsing both rung syntaxes into one AST, program structure, and syntax
errors with file:line:col."""

from __future__ import annotations

import pytest

from softplc_lite.datatable import parse_address
from softplc_lite.ladder.ast import AddressRef, BinOp, Branch, Const, Instruction, SymbolRef
from softplc_lite.ladder.errors import LadderError
from softplc_lite.ladder.parser import parse_program


def rungs(text: str):
    return parse_program(text, "t.lad").main.rungs


def I(m, *ops):  # noqa: E743 - short builder for expected trees
    return Instruction(m, [AddressRef(parse_address(o)) if isinstance(o, str) else Const(o) for o in ops])


def test_mnemonic_and_neutral_give_the_same_tree():
    a = rungs("XIC B3/0 BST XIC N7:0/1 NXB XIO B3/2 BND OTE O:0/0\n")
    b = rungs("XIC(B3/0)[XIC(N7:0/1),XIO(B3/2)]OTE(O:0/0);\n")
    expected = [I("XIC", "B3/0"), Branch([[I("XIC", "N7:0/1")], [I("XIO", "B3/2")]]), I("OTE", "O:0/0")]
    assert a[0].elements == expected == b[0].elements


def test_nested_branches_and_parallel_outputs():
    text = "XIC B3/0 BST XIC B3/1 BST XIC B3/2 NXB XIO B3/3 BND NXB XIO B3/4 BND BST OTE O:0/0 NXB OTE O:0/1 BND\n"
    neutral = "XIC(B3/0)[XIC(B3/1)[XIC(B3/2),XIO(B3/3)],XIO(B3/4)][OTE(O:0/0),OTE(O:0/1)];\n"
    assert rungs(text)[0].elements == rungs(neutral)[0].elements
    outer = rungs(text)[0].elements[1]
    assert isinstance(outer.legs[0][1], Branch)


def test_sor_eor_and_neutral_rungs_span_lines():
    text = "SOR XIC B3/0\n   XIO B3/1 // not a rung comment\n OTE O:0/0 EOR\nXIC(B3/0)\n  XIO(B3/1)\n  OTE(O:0/0);\n"
    r = rungs(text)
    assert len(r) == 2 and r[0].elements == r[1].elements
    assert r[0].comment is None and r[1].pos.line == 4


def test_rung_comments_are_the_lines_directly_above():
    text = "// header, not attached\n\n// first\n// second\nXIC B3/0 OTE O:0/0\nXIC B3/1 OTE O:0/1 // trailing\n"
    r = rungs(text)
    assert r[0].comment == "first\nsecond"
    assert r[1].comment == "trailing"


def test_files_labels_data_and_symbols():
    text = """SYMBOL Start I:0/0
DATA N10 4 = 1 -2 0x10
DATA ST11 2 = "hello" "a \\"quoted\\" word"
XIC Start JSR 3
FILE 3 Pump
SBR
LBL 5 MOV 1 N7:0
RET
"""
    p = parse_program(text, "t.lad")
    assert sorted(p.files) == [2, 3] and p.files[3].name == "Pump"
    assert p.symbols["Start"].address == parse_address("I:0/0")
    assert p.data[0].values == [1, -2, 16]
    assert p.data[1].values == ["hello", 'a "quoted" word']
    assert p.main.rungs[0].elements[0] == Instruction("XIC", [SymbolRef("Start")])


def test_constants_and_expressions():
    r = rungs('MOV 0x7F N7:0\nMOV -1.5e2 F8:0\nCPT N7:0 "N7:1 + 2 * (N7:2 | 4) MOD 3"\nCPT(N7:0,N7:1+2*(N7:2|4) MOD 3);\n')
    assert r[0].elements[0].operands[0] == Const(127)
    assert r[1].elements[0].operands[0] == Const(-150.0)
    assert r[2].elements == r[3].elements
    expr = r[2].elements[0].operands[1]
    assert isinstance(expr, BinOp) and expr.op == "+"
    assert expr.right.op == "MOD" and expr.right.left.op == "*"


def test_positions_point_at_the_source():
    p = parse_program("\n\n  XIC B3/0 OTE O:0/0\n", "x.lad")
    ins = p.main.rungs[0].elements[1]
    assert (ins.pos.source, ins.pos.line, ins.pos.column) == ("x.lad", 3, 12)
    assert str(ins.operands[0].pos) == "x.lad:3:16"


ERRORS = [
    ("XIC(B3/0)OTE(B3/1)\n", "1:18", "a neutral-text rung must end with ';'"),
    ("XIC B3/0 NXB OTE B3/1\n", "1:10", "NXB without a BST"),
    ("BST XIC B3/0 OTE B3/1\n", "1:1", "BST without a matching BND"),
    ("XIK B3/0 OTE B3/1\n", "1:1", "unknown instruction 'XIK' (did you mean"),
    ("XIC N7:-1 OTE B3/1\n", "1:8", "cannot be negative"),
    ("XIC T4:0.FOO\n", "1:10", "'FOO' is not a member of a timer"),
    ("XIC B3/0 OTE(O:0/0);\n", "1:13", "unexpected '('"),
    ("SOR XIC B3/0\nOTE B3/1\n", "2:5", "SOR without EOR"),
    ('CPT N7:0 "N7:1 +"\n', "1:", "unexpected end of file"),
    ("FILE 1\n", "1:1", "program file number 1 out of range"),
    ("FILE 3\nFILE 3\n", "2:1", "program file 3 is defined twice"),
    ("XIC B3/0 $ OTE B3/1\n", "1:10", "unexpected character '$'"),
    ('CPT N7:0 "FOO(N7:1)"\n', "1:", "unknown function FOO()"),
]


@pytest.mark.parametrize("text,where,message", ERRORS)
def test_syntax_errors_point_at_the_problem(text, where, message):
    with pytest.raises(LadderError) as info:
        parse_program(text, "e.lad")
    assert str(info.value).startswith(f"e.lad:{where}")
    assert message in str(info.value)
