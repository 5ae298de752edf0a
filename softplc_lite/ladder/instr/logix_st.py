"""The one instruction Structured Text needs beyond the ladder's: a BOOL
assigned the value of an expression, a bound object run by both executors.

logix/st_routine.py turns each ST statement into ladder rungs: a numeric
assignment is a CPT, a condition a CMP before a JMP, a call the
instruction's own rungs. A BOOL destination has no ladder form (CPT writes
words; OTE writes the rung's condition, and is the non-retentive
assignment's form), so ``LSTB(dest, expression)`` writes 1 to the bit when
the expression is not zero, 0 when it is (1756-PM007, "Assignments": a
BOOL gets the expression's truth). It passes the rung condition on; with
the condition false it writes nothing.
"""

from __future__ import annotations

from ...datatable import data_bit_mask
from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

SPECS = [InstructionSpec("LSTB", "Structured Text BOOL assignment",
                         (OperandSpec("dest", K.ANY), OperandSpec("expression", K.ANY)), True)]
LOGIX_NAMES = {"LSTB": ":="}


def _assign_bit(instr, access):
    dest, value = access.location(instr.operands[0]), access.expression(instr.operands[1])

    def run(c: bool) -> bool:
        if c:
            d, i, bit = dest()
            mask = data_bit_mask(d, bit)  # bit 15 of a signed word is its sign: the mask is negative
            if value():
                d[i] |= mask
            else:
                d[i] &= ~mask
        return c
    return run


INSTRUCTIONS = [BoundInstruction(SPECS[0], _assign_bit)]
