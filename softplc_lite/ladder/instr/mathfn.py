"""Math functions as instructions: SIN COS TAN ASN ACS ATN LN LOG, XPY,
and SLC 500's DDV, SCL and SCP.

- The eight functions compute with the very functions CPT uses
  (``expr.FUNCTIONS``), so ``SIN F8:0 F8:1`` and ``CPT F8:1 "SIN(F8:0)"``
  cannot disagree. A source outside a function's domain (ASN of 2, LN of 0)
  gives NaN, which the store turns into overflow: S:0/1 and the overflow
  minor fault (1747-RM001 ch. 4, "sets if an overflow is generated or an
  unsupported input is detected").
- XPY raises through ``Machine.power`` (CPT's ``**``); a negative base with
  a fractional exponent uses the base's absolute value and sets overflow
  (1747-RM001 ch. 4, XPY).
- DDV divides SLC's 32-bit math register, here S:107 (high) and S:106
  (low) (status.py, MATH_REGISTER_*), by the source.
- SCL (rate in ten-thousandths, offset) and SCP (two ranges) scale.

docs/instructions.md has each rule with its source.
"""

from __future__ import annotations

from ...datatable.table import WORD_MAX, WORD_MIN
from ..bound import BoundInstruction, unary_store
from ..expr import FUNCTIONS
from ..specs import K, _spec
from .. import status as S

_FUNCTIONS = (
    ("SIN", "sine"), ("COS", "cosine"), ("TAN", "tangent"),
    ("ASN", "arc sine"), ("ACS", "arc cosine"), ("ATN", "arc tangent"),
    ("LN", "natural log"), ("LOG", "log to the base 10"),
)


def set_overflow(m) -> None:
    """S:0/1 and the overflow minor fault, after a store that did not see
    the overflow itself (XPY's negative base)."""
    m.s[S.ARITH_FLAGS] |= 1 << S.OVERFLOW
    m.overflow_fault()


def _bind_xpy(instr, access):
    get_a = access.value(instr.operands[0])
    get_b = access.value(instr.operands[1])
    dest = access.location(instr.operands[2])
    m = access.machine

    def run(c: bool) -> bool:
        if c:
            d, i, _ = dest()
            a, b = get_a(), get_b()
            unsupported = a < 0 and not float(b).is_integer()
            m.store(m.power(abs(a) if unsupported else a, b), d, i)
            if unsupported:
                set_overflow(m)
        return c
    return run


def _round_half_away(num: int, den: int) -> int:
    """num / den to the nearest integer, halves away from zero (den > 0 or < 0)."""
    q = (abs(num) * 2 + abs(den)) // (2 * abs(den))
    return q if (num >= 0) == (den >= 0) else -q


def _bind_ddv(instr, access):
    source = access.value(instr.operands[0])
    dest = access.location(instr.operands[1])
    m = access.machine
    s = m.s

    def run(c: bool) -> bool:
        if not c:
            return c
        d, i, _ = dest()
        divisor = source()
        # The high word is signed: the register holds a signed 32-bit value.
        dividend = (s[S.MATH_REGISTER_HIGH] << 16) | (s[S.MATH_REGISTER_LOW] & 0xFFFF)
        if divisor == 0:
            m.div_zero(dividend)  # the divide_by_zero setting: minor fault, or major fault 201
            _ddv_overflow(m, d, i)
            return c
        quotient = _round_half_away(dividend, divisor)
        if not WORD_MIN <= quotient <= WORD_MAX:
            _ddv_overflow(m, d, i)  # the math register keeps the dividend (softplc choice)
            return c
        unrounded = abs(dividend) // abs(divisor) * (1 if (dividend >= 0) == (divisor >= 0) else -1)
        m.store(quotient, d, i)
        s[S.MATH_REGISTER_HIGH] = unrounded
        s[S.MATH_REGISTER_LOW] = dividend - unrounded * divisor
        return c
    return run


def _ddv_overflow(m, d, i) -> None:
    # 1747-RM001, DDV: "The value 32,767 is placed in the destination".
    d[i] = WORD_MAX
    m.flags(False, True, False, False)
    m.overflow_fault()


def _bind_scl(instr, access):
    get_source, get_rate, get_offset = (access.value(op) for op in instr.operands[:3])
    dest = access.location(instr.operands[3])
    m = access.machine

    def run(c: bool) -> bool:
        if not c:
            return c
        d, i, _ = dest()
        scaled = _round_half_away(get_source() * get_rate(), 10000)
        # Overflow is checked before and after the offset is added; either
        # way the destination gets the extreme of the result's sign.
        value = scaled + get_offset() if WORD_MIN <= scaled <= WORD_MAX else scaled
        if WORD_MIN <= value <= WORD_MAX:
            d[i] = value
            m.flags(False, False, value == 0, value < 0)
        else:
            d[i] = WORD_MAX if value > 0 else WORD_MIN
            m.flags(False, True, False, value < 0)
            m.overflow_fault()
        return c
    return run


def _bind_scp(instr, access):
    getters = [access.value(op) for op in instr.operands[:5]]
    dest = access.location(instr.operands[5])
    m = access.machine

    def run(c: bool) -> bool:
        if not c:
            return c
        d, i, _ = dest()
        x, in_min, in_max, out_min, out_max = (g() for g in getters)
        if in_max == in_min:
            # No slope: a division by zero (the divide_by_zero setting).
            m.store(m.div_zero(out_max - out_min), d, i)
            return c
        y = (x - in_min) * (out_max - out_min) / (in_max - in_min) + out_min
        m.store(float(y), d, i)
        return c
    return run


INSTRUCTIONS = [
    *[BoundInstruction(_spec(name, title, True, ("source", K.SOURCE), ("dest", K.DEST)), unary_store(FUNCTIONS[name]))
      for name, title in _FUNCTIONS],
    BoundInstruction(_spec("XPY", "x to the power of y", True, ("a", K.SOURCE), ("b", K.SOURCE),
                           ("dest", K.DEST)), _bind_xpy),
    BoundInstruction(_spec("DDV", "double divide", True, ("source", K.INT_SOURCE), ("dest", K.WORD)), _bind_ddv),
    BoundInstruction(_spec("SCL", "scale", True, ("source", K.INT_SOURCE), ("rate", K.INT_SOURCE),
                           ("offset", K.INT_SOURCE), ("dest", K.WORD)), _bind_scl),
    BoundInstruction(_spec("SCP", "scale with parameters", True, ("input", K.SOURCE), ("input_min", K.SOURCE),
                           ("input_max", K.SOURCE), ("scaled_min", K.SOURCE), ("scaled_max", K.SOURCE),
                           ("output", K.DEST)), _bind_scp),
]
