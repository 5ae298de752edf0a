"""LAIN and LAOUT: the entry and exit of a Logix Add-On Instruction call, bound
objects (ladder/bound.py), so both executors run the same code. The Logix
loader (logix/aoi.py) makes each call ``Name(instance, args...)`` of a rung
into, in series where the call stands:

    LAIN ein eout flags (arg member)...  XIC ein JSR logic-file  LAOUT ein eout flags (member arg)...

(with an EnableInFalse routine: ``[XIC ein JSR logic, XIO ein JSR eif]``).
``ein`` and ``eout`` are the instance's EnableIn and EnableOut bits; each pair
copies a value, converted as MOV converts (a BOOL as a bit). ``flags`` bit 0:
the AOI has an EnableInFalse routine.

Rules (1756-PM010, Logix 5000 Controllers Add-On Instructions, "EnableIn and
EnableOut parameters", "EnableInFalse routine"):

- LAIN: EnableIn takes the rung-in; EnableOut is set to it (the Logic may
  clear it). Input arguments are copied into the instance when EnableIn is
  true, or when the EnableInFalse routine runs (a softplc choice for the
  case without one: nothing is copied). Rung-out: true, so the routine legs
  after it test EnableIn themselves.
- LAOUT: with EnableIn false, EnableOut is cleared. Output members are copied
  to their arguments after a routine ran (the Logic, or the EnableInFalse
  routine). Rung-out: EnableOut (false when EnableIn is false), whatever its
  rung-in (the routine legs').
"""

from __future__ import annotations

from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

MAX_COPIES = 2 * 128  # argument/member pairs of one call (a softplc limit)
HAS_EIF = 1  # flags bit 0


def _spec(mnemonic: str, title: str) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, (OperandSpec("EnableIn", K.ANY), OperandSpec("EnableOut", K.ANY),
                                             OperandSpec("flags", K.ANY), OperandSpec("copy", K.ANY)),
                           False, optional=1, repeat=MAX_COPIES)


SPECS = [_spec("LAIN", "Logix Add-On Instruction entry"), _spec("LAOUT", "Logix Add-On Instruction exit")]


def _put_bit(d, i, bit, on) -> None:
    width = d.itemsize * 8
    w = d[i] & ((1 << width) - 1)
    w = (w | (1 << bit)) if on else (w & ~(1 << bit))
    if d.typecode.islower() or d.typecode == "b":  # signed items keep their sign bit as a sign
        w = w - (1 << width) if w >> (width - 1) else w
    d[i] = w


def _bit(loc):
    d, i, bit = loc()
    return (d[i] >> bit) & 1


def _copies(pairs, access):
    machine = access.machine
    bound = [(access.value(src), access.location(dest)) for src, dest in pairs]

    def copy() -> None:
        for get, dest in bound:
            v = get()
            d, i, bit = dest()
            if bit is not None:
                _put_bit(d, i, bit, v != 0)
            else:
                machine.store(v, d, i)
    return copy


def _bind(instr, access):
    ein_op, eout_op, flags_op, *rest = instr.operands
    ein, eout = access.location(ein_op), access.location(eout_op)
    eif = bool(flags_op.value & HAS_EIF)
    copy = _copies(list(zip(rest[0::2], rest[1::2])), access)

    def put(loc, on):
        d, i, bit = loc()
        _put_bit(d, i, bit, on)

    if instr.mnemonic == "LAIN":
        def enter(c: bool) -> bool:
            put(ein, c)
            put(eout, c)
            if c or eif:
                copy()
            return True
        return enter

    def leave(c: bool) -> bool:
        if _bit(ein):
            copy()
            return bool(_bit(eout))
        put(eout, False)
        if eif:
            copy()
        return False
    return leave


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
