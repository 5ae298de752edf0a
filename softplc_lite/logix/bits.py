"""BTD, SWPB and TRN of a Logix export translated into the instructions
with their rules (ladder/instr/logix_bits.py; TRN: the CPT function
ladder/expr.py's FUNCTIONS has): operands whose Logix form differs from the
ladder's (a bit number, a keyword, a single-operand function).
"""

from __future__ import annotations

from ..ladder.ast import Call, Const, Instruction
from ..ladder.instr.logix_bits import MODES
from . import operands
from .operands import Operands
from .tags import PathError


def translate(el, pos, rung, ctx):
    build = {"BTD": _btd, "SWPB": _swpb, "TRN": _trn}[el.mnemonic]
    return operands.translate(el, pos, rung, ctx, build)


def _integer_source(ops: Operands, k: int):
    value = ops.value(k)
    if isinstance(value, Const):
        if not isinstance(value.value, int):
            raise PathError("expected an integer (SINT, INT, DINT)")
        return value
    if value.address.type_letter not in ("SI", "N", "L") or value.address.bit is not None:
        raise PathError("expected an integer (SINT, INT, DINT)")
    return value


def _constant(ops: Operands, k: int, low: int, high: int, what: str) -> Const:
    value = ops.value(k)
    if not isinstance(value, Const) or not isinstance(value.value, int) or not low <= value.value <= high:
        raise PathError(f"expected the {what} as a number from {low} to {high}")
    return value


def _btd(ops: Operands) -> list[Instruction]:
    """BTD(Source, SourceBit, Dest, DestBit, Length)."""
    ops.count(5)
    source = _integer_source(ops, 0)
    sbit = _constant(ops, 1, 0, 31, "source bit")
    dest = ops.dest(2)
    if dest.address.type_letter not in ("SI", "N", "L"):
        raise PathError("expected an integer tag (SINT, INT, DINT)")
    dbit = _constant(ops, 3, 0, 31, "destination bit")
    length = _constant(ops, 4, 1, 32, "length")
    return [Instruction("LBTD", [source, sbit, dest, dbit, length], ops.pos)]


def _swpb(ops: Operands) -> list[Instruction]:
    """SWPB(Source, OrderMode, Dest)."""
    ops.count(3)
    r = ops.resolve(0)
    if r.address is None or r.address.bit is not None or r.address.type_letter not in ("N", "L", "F"):
        raise PathError("expected an INT, DINT or REAL tag")
    source = ops.value(0)
    ops.where(1)
    mode = MODES.get(ops.text(1).upper().replace(" ", ""))
    if mode is None:
        raise PathError("expected the order mode REVERSE, WORD or HIGH/LOW")
    dest = ops.dest(2)
    return [Instruction("LSWPB", [source, Const(mode, ops.pos), dest], ops.pos)]


def _trn(ops: Operands) -> list[Instruction]:
    """TRN(Source, Dest): CPT(Dest, TRN(Source)), the fraction cut off
    (1756-RM003, "Truncate (TRN)")."""
    ops.count(2)
    source = ops.value(0)
    return [Instruction("CPT", [ops.dest(1), Call("TRN", source, ops.pos)], ops.pos)]
