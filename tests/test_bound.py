"""The bound-instruction door (ladder/bound.py, ladder/instr/): NOP and END,
and what every bound instruction gets from it on both executors."""

from __future__ import annotations

import pytest

from softplc_lite.datatable import DataTable
from softplc_lite.ladder import run_text
from softplc_lite.ladder.ast import AddressRef, Pos
from softplc_lite.ladder.bound import BoundAccess, ReferenceAccess, block
from softplc_lite.ladder.instr import BOUND
from softplc_lite.ladder.instructions import BUILTIN
from softplc_lite.ladder.parser import parse_expression
from softplc_lite.ladder.semantics import Machine, MajorFault
from softplc_lite.datatable import parse_address

EXECUTORS = ("compiled", "reference")


@pytest.mark.parametrize("executor", EXECUTORS)
def test_nop_passes_the_rung_condition_on(executor):
    for value in (0, 1):
        e = run_text("XIC B3/0 NOP OTE O:0/0\nXIC(B3/0)NOP()OTE(O:0/1);", values={"B3/0": value}, executor=executor)
        assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (value, value)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_end_is_a_no_op_marker(executor):
    e = run_text("MOV 1 N7:0\nEND\nMOV 2 N7:1", executor=executor)
    assert (e.table.read("N7:0"), e.table.read("N7:1"), e.mode.name) == (1, 2, "RUN")


def test_bound_instructions_are_in_the_instruction_table():
    assert BOUND, "no bound instruction groups"
    for mnemonic, bi in BOUND.items():
        assert BUILTIN.lookup(mnemonic) is bi.spec


@pytest.mark.parametrize("access_class", [BoundAccess, ReferenceAccess])
def test_access_follows_indirect_addresses_and_faults_like_built_ins(access_class):
    table = DataTable()
    table.reference("N7:9")
    m = Machine(table)
    access = access_class(table, m)
    get = access.value(AddressRef(parse_address("N7:[N7:0]")))
    table.write("N7:3", 42)
    table.write("N7:0", 3)
    assert get() == 42
    table.write("N7:0", 50)
    with pytest.raises(MajorFault) as info:
        get()
    assert info.value.code == 20
    # a direct address: the compiled access binds it once; both read current data
    direct = access.value(AddressRef(parse_address("N7:5")))
    table.write("N7:5", 7)
    assert direct() == 7


@pytest.mark.parametrize("access_class", [BoundAccess, ReferenceAccess])
def test_access_expression_reads_indexed_addresses_through_s24(access_class):
    table = DataTable()
    table.reference("N7:9")
    access = access_class(table, Machine(table))
    compute = access.expression(parse_expression("#N7:0 * 2 + 1", Pos("<test>", 1, 1)))
    for k in range(5):
        table.write(f"N7:{k}", 10 * k)
    table.write("S:24", 3)
    assert compute() == 61
    table.write("S:24", 4)
    assert compute() == 81


@pytest.mark.parametrize("access_class", [BoundAccess, ReferenceAccess])
def test_access_expression_reads_words_bits_floats_indirect_and_a_leaf_twice(access_class):
    table = DataTable()
    table.reference("N7:9")
    table.reference("F8:2")
    table.reference("B3/17")
    access = access_class(table, Machine(table))
    ref = AddressRef(parse_address("N7:[N7:0]"))
    node = parse_expression("N7:1 * B3/17 + F8:1 - N7:2 + (N7:3 AND 6)", Pos("<test>", 1, 1))
    twice = type(node)("+", ref, ref, Pos("<test>", 1, 1))  # one leaf object in two places, as CASE's test makes
    compute, doubled = access.expression(node), access.expression(twice)
    for address, value in (("N7:0", 5), ("N7:1", 7), ("B3/17", 1), ("F8:1", 0.5), ("N7:2", 10), ("N7:3", 13),
                           ("N7:5", 21)):
        table.write(address, value)
    assert compute() == 7 + 0.5 - 10 + 4
    assert doubled() == 42
    table.write("N7:0", 2)
    table.write("B3/17", 0)
    assert doubled() == 20 and compute() == 0 + 0.5 - 10 + 4


@pytest.mark.parametrize("access_class", [BoundAccess, ReferenceAccess])
def test_access_gives_an_indirect_bit_its_number_the_top_bit_too(access_class):
    table = DataTable()
    table.reference("N7:2")
    table.reference("B3:3")
    table.create_file("L", 9, 2)
    access = access_class(table, Machine(table))
    word_bit, long_bit = (access.location(AddressRef(parse_address(a))) for a in ("B3:[N7:0]/[N7:1]", "L9:[N7:0]/[N7:2]"))
    for element, bit, top in ((1, 15, 31), (0, 3, 30), (1, 0, 0)):
        for address, value in (("N7:0", element), ("N7:1", bit), ("N7:2", top)):
            table.write(address, value)
        assert word_bit()[1:] == (element, bit) and long_bit()[1:] == (element, top)
    table.write("N7:1", 16)
    with pytest.raises(MajorFault):
        word_bit()


def test_the_compiled_access_makes_an_expression_code_not_a_walk(monkeypatch):
    import softplc_lite.ladder.bound as bound_module

    walks = []
    monkeypatch.setattr(bound_module, "evaluate", lambda *a: walks.append(a) or 0)
    table = DataTable()
    compute = BoundAccess(table, Machine(table)).expression(parse_expression("N7:0 + B3/1 * 3", Pos("<test>", 1, 1)))
    table.write("N7:0", 4)
    table.write("B3/1", 1)
    assert compute() == 7 and walks == []


def test_block_faults_past_the_end_of_the_file():
    d = DataTable().file("N7").data
    block(d, 0, len(d), "#N7:0")
    with pytest.raises(MajorFault) as info:
        block(d, 1, len(d), "#N7:1")
    assert info.value.code == 202
