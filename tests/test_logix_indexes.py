"""Array subscripts and bit numbers a Logix rung computes at run time
(``Arr[i+1]``, ``Grid[r,c]``, ``Tanks[i].Hist[j]``, ``Word.[n]``): the
index is taken where the instruction is (LIDX before it, ladder/instr/
logix.py), each dimension checked on its own, and one out of its range
is major fault type 4 code 20 (1756-PM014), on both executors."""

from __future__ import annotations

import pytest

from softplc_lite.runner import Runner

from helpers.logix_l5x import Prog, Task, write_l5x, export_runner

TAGS = [("i", "DINT"), ("j", "DINT"), ("n", "DINT"), ("Arr", "DINT[5]"), ("Grid", "INT[2,3]"),
        ("Word", "DINT"), ("Bits", "BOOL[32]"), ("Out", "DINT"), ("Flag", "BOOL")]


def run(tmp_path, rungs: list[str], executor: str, values: dict, scans: int = 1) -> Runner:
    path = write_l5x(tmp_path / "idx.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])])
    r = export_runner(path, executor)
    names = r.app.program.symbols
    for tag, value in values.items():
        r.table.write(names.resolve_path(tag), value)
    r.run(scans)
    return r


def value(r: Runner, tag: str):
    return r.table.read(r.app.program.symbols.resolve_path(tag))


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_an_expression_index_and_two_dimensions_and_a_computed_bit(tmp_path, executor):
    r = run(tmp_path, ["MOV(Arr[i+1],Out)MOV(7,Grid[i,j])OTE(Word.[n])XIC(Bits[n*2])OTE(Flag);"], executor,
            {"i": 1, "j": 2, "n": 3, "Arr[2]": 42, "Bits[6]": 1})
    assert value(r, "Out") == 42
    assert value(r, "Grid[1,2]") == 7 and value(r, "Grid[0,2]") == 0
    assert value(r, "Word") == 8 and value(r, "Flag") == 1
    assert r.engine.fault is None
    r.close()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
@pytest.mark.parametrize("values, index", [({"i": 0, "j": 3}, 3), ({"i": 2, "j": 0}, 2), ({"i": -1, "j": 0}, -1)])
def test_a_subscript_outside_its_dimension_is_major_fault_20(tmp_path, executor, values, index):
    # Grid[0,3] is inside the array's six items, but outside its second dimension: Logix faults.
    r = run(tmp_path, ["MOV(7,Grid[i,j]);"], executor, values)
    assert r.engine.fault is not None and r.engine.fault.code == 20
    assert f"array subscript {index} outside" in r.engine.fault.message
    r.close()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_the_index_is_taken_on_a_false_rung_too(tmp_path, executor):
    # OTE on a false rung clears its bit: the bit the index names at that instruction.
    r = run(tmp_path, ["XIC(Flag)OTE(Bits[n]);"], executor, {"n": 5, "Bits[5]": 1, "Bits[0]": 1})
    assert value(r, "Bits[5]") == 0 and value(r, "Bits[0]") == 1
    r.close()
