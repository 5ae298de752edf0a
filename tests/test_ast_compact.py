"""The compact syntax tree: slotted nodes that keep
their position as slots, tuples in the validated tree, pickling (a code
cache pickles the validated Program), and the value semantics the
dataclass nodes had."""

from __future__ import annotations

import copy
import pickle
from dataclasses import FrozenInstanceError

import pytest

from softplc_lite.datatable import parse_address
from softplc_lite.ladder import parse_program
from softplc_lite.ladder.ast import (
    AddressRef,
    BinOp,
    Branch,
    Call,
    Const,
    Instruction,
    Placeholder,
    Pos,
    Rung,
    SymbolRef,
    Text,
    UnaryOp,
    walk,
)
from softplc_lite.ladder.validate import validate

PROGRAM = """\
SYMBOL Start I:0/0
SYMBOL Count C5:0
// the first rung
XIC Start BST XIO B3/1 NXB XIC B3/2 BND OTE O:0/0
CTU Count 10 0
CPT N7:0 "N7:1 * 2 + SQR(F8:0) - -3"
FILE 3
MOV 0x7FFF N7:4
"""


def _nodes(program):
    """Every node of a program with a position, in a fixed order."""
    for number in sorted(program.files):
        for rung in program.files[number].rungs:
            yield rung
            stack = list(reversed(rung.elements))
            while stack:
                node = stack.pop()
                yield node
                if isinstance(node, Branch):
                    for leg in reversed(node.legs):
                        stack.extend(reversed(leg))
                elif isinstance(node, Instruction):
                    stack.extend(reversed(node.operands))
                elif isinstance(node, BinOp):
                    stack.extend((node.right, node.left))
                elif isinstance(node, UnaryOp):
                    stack.append(node.operand)
                elif isinstance(node, Call):
                    stack.append(node.arg)


def test_pickle_keeps_the_validated_program_and_its_positions():
    program = validate(parse_program(PROGRAM, "plant.lad"))
    again = pickle.loads(pickle.dumps(program))
    assert again == program
    before, after = list(_nodes(program)), list(_nodes(again))
    assert len(before) == len(after) > 20
    assert [type(n) for n in after] == [type(n) for n in before]
    assert [n.pos for n in after] == [n.pos for n in before]
    assert str(after[1].pos) == "plant.lad:4:1"
    hex_constant = next(n for n in after if isinstance(n, Const) and n.hex)
    assert hex_constant.value == 0x7FFF


def test_copies_keep_positions():
    program = validate(parse_program(PROGRAM, "plant.lad"))
    for clone in (copy.copy(program.main.rungs[0]), copy.deepcopy(program)):
        assert clone == (program.main.rungs[0] if isinstance(clone, Rung) else program)
    deep = copy.deepcopy(program)
    assert [n.pos for n in _nodes(deep)] == [n.pos for n in _nodes(program)]


def test_nodes_keep_no_dict_and_no_pos_object():
    ref = AddressRef(parse_address("N7:0"), Pos("a.lad", 3, 7))
    for node in (ref, Const(1), Instruction("XIC", [ref]), Branch([[], []]), Rung([]), SymbolRef("x"), Text("t")):
        assert not hasattr(node, "__dict__")
    assert ref.pos == Pos("a.lad", 3, 7) and str(ref.pos) == "a.lad:3:7"


def test_the_validated_tree_is_tuples_and_shares_mnemonics():
    program = validate(parse_program("XIC B3/0 BST XIC B3/1 NXB XIO B3/2 BND OTE B3/3\nXIC B3/4 OTE B3/5\n"))
    first, second = program.main.rungs
    assert type(first.elements) is tuple
    branch = first.elements[1]
    assert type(branch.legs) is tuple and all(type(leg) is tuple for leg in branch.legs)
    instructions = [i for rung in program.main.rungs for i in walk(rung.elements)]
    assert all(type(i.operands) is tuple for i in instructions)
    xics = [i for i in instructions if i.mnemonic == "XIC"]
    assert len(xics) == 3 and all(i.mnemonic is xics[0].mnemonic for i in xics)


def test_list_and_tuple_trees_compare_equal():
    a, b = AddressRef(parse_address("B3/0")), AddressRef(parse_address("B3/1"), Pos("x", 9, 9))
    assert Instruction("XIC", [a]) == Instruction("XIC", (a,))
    assert Branch([[Instruction("XIC", [a])], [Instruction("XIO", [b])]]) == \
        Branch(((Instruction("XIC", (a,)),), (Instruction("XIO", (b,)),)), Pos("y", 1, 1))
    assert Rung([Instruction("OTE", [b])], "c") == Rung((Instruction("OTE", (b,)),), "c")
    assert Rung([Instruction("OTE", [b])], "c") != Rung([Instruction("OTE", [b])], "d")
    assert Instruction("XIC", [a]) != Instruction("XIO", [a])
    parsed = parse_program("XIC B3/0 OTE B3/1\n")
    assert validate(parsed).main.rungs == parsed.main.rungs


def test_operands_are_values_and_immutable():
    a = AddressRef(parse_address("N7:0"), Pos("a", 1, 1))
    assert a == AddressRef(parse_address("N7:0"), Pos("b", 2, 2)) and hash(a) == hash(AddressRef(parse_address("N7:0")))
    assert Const(1) != Placeholder(1) and Const(1) == Const(1.0)
    assert BinOp("+", a, Const(1)) == BinOp("+", a, Const(1), Pos("z", 5, 5))
    assert len({Const(2), Const(2, Pos("q", 1, 1)), Const(3)}) == 2
    with pytest.raises(FrozenInstanceError):
        a.address = parse_address("N7:1")
    with pytest.raises(FrozenInstanceError):
        Const(1).pos = Pos("a", 1, 1)
    with pytest.raises(TypeError):
        hash(Instruction("XIC", [a]))
    assert repr(Const(5, hex=True)) == "Const(value=5)"
    assert repr(Instruction("XIC", [SymbolRef("Go")])) == "Instruction(mnemonic='XIC', operands=[SymbolRef(name='Go')])"


def test_instructions_branches_and_rungs_can_be_changed_in_place():
    instr = Instruction("XIC", [], Pos("a", 1, 1))
    instr.operands.append(SymbolRef("Go"))
    instr.pos = Pos("b", 2, 3)
    instr.mnemonic = "XIO"
    assert instr == Instruction("XIO", [SymbolRef("Go")]) and str(instr.pos) == "b:2:3"


def test_validate_shares_a_tree_already_in_validated_form():
    """A tree of tuples with nothing to resolve (as a parser building
    tuples would give) is kept, not copied; one with symbols is copied."""
    b0, b1 = AddressRef(parse_address("B3/0"), Pos("t", 1, 5)), AddressRef(parse_address("B3/1"), Pos("t", 1, 30))
    xic = Instruction("XIC", (b0,), Pos("t", 1, 1))
    branch = Branch(((xic,), (Instruction("XIO", (b1,), Pos("t", 1, 20)),)), Pos("t", 1, 10))
    ote = Instruction("OTE", (b1,), Pos("t", 1, 40))
    parsed = parse_program("XIC B3/0 OTE B3/1\n")
    parsed.main.rungs[:] = [Rung((branch, ote), None, Pos("t", 1, 1))]
    rung = validate(parsed).main.rungs[0]
    assert rung is parsed.main.rungs[0]
    with_symbol = parse_program("SYMBOL Go B3/7\nXIC Go OTE B3/1\n")
    validated = validate(with_symbol).main.rungs[0]
    assert validated is not with_symbol.main.rungs[0]
    assert validated.elements[0].operands == (AddressRef(parse_address("B3/7")),)
    assert str(validated.elements[0].operands[0].pos) == "<program>:2:5"
