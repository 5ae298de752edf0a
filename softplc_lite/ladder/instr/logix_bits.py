"""Logix's bit instructions, 32 bits wide where PLC-5's are 16 (a Logix
export's AND ... on DINTs, MEQ, MVM, BTD) and SWPB, bound objects run by both
executors.

Rules (1756-RM003, Logix 5000 Controllers General Instructions):

- BTD(Source, SourceBit, Dest, DestBit, Length): ``Length`` bits of Source
  from SourceBit copied into Dest from DestBit; the rest of Dest kept. A SINT
  or INT source is taken as a DINT, sign extended; bits that would go past
  the destination's width are not written ("Bit Field Distribute (BTD)":
  "the extra bits ... are lost"). SourceBit and DestBit 0 to 31, Length 1 to
  32 (checked by the translator). No status flags.
- AND, OR, XOR, NOT (and BAND, BOR, BXOR, BNOT): bit by bit, as wide as
  Dest (32 bits of a DINT), a constant taken as its 32-bit pattern
  (``16#FFFF_0000``); S:Z and S:N from the result ("Bitwise AND (AND)" ...;
  "Math status flags").
- MEQ(Source, Mask, Compare): true when Source and Compare agree in every
  bit Mask has set, over 32 bits ("Mask Equal To (MEQ)").
- MVM(Source, Mask, Dest): Dest's bits where Mask has a 1 become Source's,
  the others kept, as wide as Dest (32 bits of a DINT); S:Z and S:N as
  BAND sets them ("Masked Move (MVM)").
- SWPB(Source, OrderMode, Dest): the bytes of Source reordered: REVERSE
  (ABCD to DCBA), WORD (ABCD to CDAB), HIGH/LOW (ABCD to BADC); of an INT,
  every mode swaps its two bytes ("Swap Byte (SWPB)"). The result, read in
  the source's type, is stored as MOV stores it (the same type: the bytes as
  they are). No status flags.
"""

from __future__ import annotations

import struct

from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

REVERSE, WORD, HIGH_LOW = 0, 1, 2
MODES = {"REVERSE": REVERSE, "WORD": WORD, "HIGH/LOW": HIGH_LOW, "HIGHLOW": HIGH_LOW}
SPECS = [
    InstructionSpec("LBTD", "Logix bit field distribute", tuple(OperandSpec(n, K.ANY) for n in (
        "source", "source bit", "dest", "dest bit", "length")), True),
    InstructionSpec("LAND", "Logix bitwise AND", tuple(OperandSpec(n, K.ANY) for n in ("a", "b", "dest")), True),
    InstructionSpec("LOR", "Logix bitwise OR", tuple(OperandSpec(n, K.ANY) for n in ("a", "b", "dest")), True),
    InstructionSpec("LXOR", "Logix bitwise exclusive OR", tuple(OperandSpec(n, K.ANY) for n in ("a", "b", "dest")),
                    True),
    InstructionSpec("LNOT", "Logix bitwise NOT", tuple(OperandSpec(n, K.ANY) for n in ("source", "dest")), True),
    InstructionSpec("LMEQ", "Logix masked comparison for equal", tuple(OperandSpec(n, K.ANY) for n in (
        "source", "mask", "compare")), False),
    InstructionSpec("LMVM", "Logix masked move", tuple(OperandSpec(n, K.ANY) for n in ("source", "mask", "dest")),
                    True),
    InstructionSpec("LSWPB", "Logix swap byte", tuple(OperandSpec(n, K.ANY) for n in ("source", "mode", "dest")),
                    True),
]
LOGIX_NAMES = {"LBTD": "BTD", "LMVM": "MVM", "LSWPB": "SWPB", "LAND": "AND", "LOR": "OR", "LXOR": "XOR",
               "LNOT": "NOT", "LMEQ": "MEQ"}


def _distribute(instr, access):
    src, sbit, dest, dbit, length = instr.operands
    value, get = access.value(src), access.location(dest)
    sbit, dbit, length = sbit.value, dbit.value, length.value
    length = min(length, 32 - sbit)

    def run(c: bool) -> bool:
        if c:
            d, i, _ = get()
            width = 8 * d.itemsize
            n = min(length, width - dbit)
            if n > 0:
                v = value()
                field = (int(v) >> sbit) & ((1 << n) - 1)
                mask = ((1 << n) - 1) << dbit
                out = (d[i] & ~mask) | (field << dbit)
                out &= (1 << width) - 1
                d[i] = out - (1 << width) if out >> (width - 1) else out
        return c
    return run


def _swap(instr, access):
    src, mode, dest = instr.operands
    get_src, get_dest, mode = access.location(src), access.location(dest), mode.value
    machine = access.machine

    def run(c: bool) -> bool:
        if c:
            sd, si, _ = get_src()
            raw = sd[si:si + 1].tobytes()
            if len(raw) == 2 or mode == HIGH_LOW:
                raw = b"".join(raw[k:k + 2][::-1] for k in range(0, len(raw), 2))
            elif mode == REVERSE:
                raw = raw[::-1]
            else:
                raw = raw[2:] + raw[:2]
            (v,) = struct.unpack(sd.typecode, raw)
            d, i, _ = get_dest()
            if d.typecode == sd.typecode:
                d[i] = v
            else:
                machine.store(v, d, i)
        return c
    return run


_LOGIC = {"LAND": lambda a, b: a & b, "LOR": lambda a, b: a | b, "LXOR": lambda a, b: a ^ b}


def _logic(instr, access):
    ops = instr.operands
    if instr.mnemonic == "LNOT":
        a, b, fn = access.expression(ops[0]), (lambda: 0), (lambda x, _: ~x)
    else:
        a, b, fn = access.expression(ops[0]), access.expression(ops[1]), _LOGIC[instr.mnemonic]
    dest = access.location(ops[-1])
    logic = access.machine.logic

    def run(c: bool) -> bool:
        if c:
            d, i, _ = dest()
            logic(fn(int(a()), int(b())), d, i)
        return c
    return run


def _mask_equal(instr, access):
    source, mask, compare = (access.expression(op) for op in instr.operands)
    return lambda c: c and not (int(source()) ^ int(compare())) & int(mask()) & 0xFFFFFFFF


def _masked(instr, access):
    source, mask = access.expression(instr.operands[0]), access.expression(instr.operands[1])
    dest = access.location(instr.operands[2])
    logic = access.machine.logic

    def run(c: bool) -> bool:
        if c:
            d, i, _ = dest()
            m = int(mask())
            logic((d[i] & ~m) | (int(source()) & m), d, i)
        return c
    return run


_BINDS = {"LBTD": _distribute, "LAND": _logic, "LOR": _logic, "LXOR": _logic, "LNOT": _logic,
          "LMEQ": _mask_equal, "LMVM": _masked, "LSWPB": _swap}
INSTRUCTIONS = [BoundInstruction(spec, _BINDS[spec.mnemonic]) for spec in SPECS]
