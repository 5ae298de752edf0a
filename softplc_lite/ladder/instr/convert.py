"""Conversions and word instructions: TOD, FRD (BCD), SWP (swap bytes),
DCD and ENC (decode 4 bits to 1 of 16 and back).

- TOD and FRD convert with CPT's TOD and FRD functions (``expr.FUNCTIONS``),
  one implementation for both. A value with no BCD form (TOD of a negative
  number or one above 9999, FRD of a nibble above 9) is NaN there, stored as
  overflow: S:0/1, the overflow minor fault, and 0 in the destination.
  TOD's sign bit always resets (1785-6.1 quick reference, "Conversion"),
  although a BCD pattern from 8000 up reads as a negative word.
- SWP swaps the bytes of ``length`` words from a word-file address (SLC
  5/03 and up, 1747-RM001 ch. 4).
- DCD turns on the bit the low 4 source bits number; ENC gives the number of
  the lowest bit on, with overflow (and no minor fault) when more than one
  is on (1747-RM001 ch. 5).

docs/instructions.md has each rule with its source.
"""

from __future__ import annotations

from ..bound import BoundInstruction, block, constant, file_references, unary_store
from ..expr import FUNCTIONS
from ..semantics import signed16
from ..specs import K, _spec
from .. import status as S

_TOD, _FRD = FUNCTIONS["TOD"], FUNCTIONS["FRD"]


def _reset_sign(m) -> None:
    m.s[S.ARITH_FLAGS] &= ~(1 << S.SIGN)


# TOD always resets S (the PLC-5 quick reference; docs/instructions.md).
_bind_tod = unary_store(_TOD, after=_reset_sign)
_bind_frd = unary_store(_FRD)


def _bind_swp(instr, access):
    op = instr.operands[0]
    get = access.location(op)
    length = instr.operands[1].value
    what = str(op.address)

    def run(c: bool) -> bool:
        if c:
            d, i, _ = get()
            block(d, i, length, what)
            for k in range(i, i + length):
                w = d[k] & 0xFFFF
                d[k] = signed16((w & 0xFF) << 8 | w >> 8)
        return c
    return run


def _swp_references(instr):
    return file_references(instr, 0, constant(instr, 1))


def _bind_dcd(instr, access):
    source = access.value(instr.operands[0])
    dest = access.location(instr.operands[1])

    def run(c: bool) -> bool:
        if c:
            d, i, _ = dest()
            d[i] = signed16(1 << (source() & 0xF))
        return c
    return run


def _bind_enc(instr, access):
    source = access.value(instr.operands[0])
    dest = access.location(instr.operands[1])
    m = access.machine

    def run(c: bool) -> bool:
        if c:
            d, i, _ = dest()
            w = source() & 0xFFFF
            lowest = (w & -w).bit_length() - 1 if w else 0
            d[i] = lowest
            # V: more than one bit on (the lowest one wins); no minor fault. C and S reset.
            m.flags(False, bool(w & (w - 1)), lowest == 0, False)
        return c
    return run


INSTRUCTIONS = [
    BoundInstruction(_spec("TOD", "convert to BCD", True, ("source", K.SOURCE), ("dest", K.WORD)), _bind_tod),
    BoundInstruction(_spec("FRD", "convert from BCD", True, ("source", K.INT_SOURCE), ("dest", K.DEST)), _bind_frd),
    BoundInstruction(_spec("SWP", "swap bytes", True, ("source", K.WORD_FILE), ("length", K.LENGTH)), _bind_swp,
                     _swp_references),
    BoundInstruction(_spec("DCD", "decode 4 to 1 of 16", True, ("source", K.INT_SOURCE), ("dest", K.WORD)), _bind_dcd),
    BoundInstruction(_spec("ENC", "encode 1 of 16 to 4", True, ("source", K.INT_SOURCE), ("dest", K.WORD)), _bind_enc),
]
