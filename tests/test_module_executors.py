"""A plug-in module's instructions under the executor differential test.

Module instructions reach their operands through the access of the
executor that binds them (ladder/bound.py), as built-in bound instructions
do: the compiled path resolves a direct address once, the reference
interpreter at every use. A small module (a move through indirect
addresses, a CONTROL-element instruction, an expression-free copy) runs on
both executors from the same table with the same inputs, and the tables,
modes and fault records must be equal after every scan.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from softplc_lite.datatable import to_signed
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder.instructions import InstructionSet
from softplc_lite.ladder.specs import InstructionSpec, K, OperandSpec
from softplc_lite.tlm import TLM, ControlledInstruction


class Steps(ControlledInstruction):
    """STEPS control scans: done after ``scans`` true scans, POS counting."""

    def __init__(self, ctx):
        super().__init__(ctx.operands[0])
        self.scans = ctx.operands[1].constant
        self.left = 0

    def start(self, ctl):
        self.left = self.scans
        return self.step(ctl)

    def step(self, ctl):
        self.left -= 1
        ctl.pos = self.scans - self.left
        if self.left <= 0:
            ctl.finish(error=False)
            return True
        return False


class Mover(TLM):
    """MOVX source dest: dest = source + 1 on a true rung (through the
    operands' value() and location()); STEPS control scans (above)."""

    name = "MOVER"

    def instructions(self):
        return [
            InstructionSpec("MOVX", "move plus one", (OperandSpec("source", K.INT_SOURCE),
                            OperandSpec("dest", K.WORD)), True, module=self.name),
            InstructionSpec("STEPS", "done after N true scans", (OperandSpec("control", K.CONTROL),
                            OperandSpec("scans", K.PRESET)), True, module=self.name),
        ]

    def create(self, instr, ctx):
        if instr.mnemonic == "STEPS":
            return Steps(ctx)
        source, dest = ctx.operands

        def run(c):
            if c:
                d, i, _ = dest.location()
                d[i] = to_signed((source.value() + 1) & 0xFFFF)
            return c
        return run


PROGRAM = """\
DATA N9 3 = 0 1 2
DATA N10 5 = 7 8 9 10 11
DATA R6 3
XIC I:0/0 MOVX N10:[N9:0] N10:[N9:1]
XIC I:0/1 MOVX N10:4 N9:2
XIC I:0/2 MOVX 5 N10:[N9:2]
XIC I:0/3 ADD N9:0 1 N9:0
AND N9:0 3 N9:0
XIC I:0/4 ADD N9:1 1 N9:1
AND N9:1 3 N9:1
XIC I:0/5 STEPS R6:[N9:0] 2
XIC I:0/6 STEPS R6:1 3
XIC I:0/7 MOVX N10:[N9:1] N10:4
"""


def engines(text: str, words: list[int]):
    """Both executors over ``text`` with the module, I:0 from ``words``
    before each scan; yields (scan, compiled, reference) after each scan."""
    pair = []
    for executor in ("compiled", "reference"):
        module = Mover()
        program = load_text(text, instructions=InstructionSet(module.instructions()))
        engine = Engine(program, executor=executor, modules=[module])
        scan = iter(words)

        def hook(e, scan=scan):
            e.table.file(1).data[0] = to_signed(next(scan))

        engine.input_hooks.append(hook)
        engine.set_mode(Mode.RUN)
        pair.append(engine)
    compiled, reference = pair
    assert compiled.table == reference.table
    for k in range(len(words)):
        compiled.scan()
        reference.scan()
        yield k, compiled, reference


def fault_of(engine):
    f = engine.fault
    return None if f is None else (f.code, f.file, f.rung, f.instruction, f.message)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(words=st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=40))
def test_module_instructions_agree_on_both_executors(words):
    for k, compiled, reference in engines(PROGRAM, words):
        assert fault_of(compiled) == fault_of(reference), f"scan {k}"
        assert compiled.mode is reference.mode, f"scan {k}"
        assert compiled.table == reference.table, f"scan {k}"


def test_an_indirect_module_operand_out_of_range_faults_alike():
    text = "DATA N9 1 = 3\nDATA N10 2\nMOVX 1 N10:[N9:0]\n"
    faults = set()
    for _, compiled, reference in engines(text, [0]):
        assert compiled.mode is reference.mode is Mode.FAULTED
        assert fault_of(compiled) == fault_of(reference)
        faults.add(fault_of(compiled))
    (fault,) = faults
    assert "MOVX" in fault[3]


@pytest.mark.parametrize("executor, fixed", [("compiled", True), ("reference", False)])
def test_each_executor_binds_module_operands_through_its_own_access(executor, fixed):
    """The compiled path resolves a direct operand once, the reference
    interpreter at every use: two ways of finding operands, compared above."""
    seen = []

    class Spy(Mover):
        def create(self, instr, ctx):
            seen.extend(ctx.operands)
            return super().create(instr, ctx)

    module = Spy()
    program = load_text("MOVX N7:0 N7:1\n", instructions=InstructionSet(module.instructions()))
    engine = Engine(program, executor=executor, modules=[module])
    assert [op.fixed is not None for op in seen] == [fixed, fixed]
    engine.table.write("N7:0", 41)
    engine.set_mode(Mode.RUN)
    engine.scan()
    assert engine.table.read("N7:1") == 42
