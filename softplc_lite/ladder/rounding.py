"""The one rule by which a float becomes an integer: every store of a float
into a word or a long (MOV, math and CPT destinations, JSR/SBR/RET
parameters, SCP, TOD, FRD, FLL, AVE/STD, PID outputs) and every float
operand of a bitwise operator goes through :func:`round_half_even`.

Allen-Bradley documents REAL to integer conversion as round to nearest, an
exact half to the even integer (Logix5000 Controllers General Instructions
Reference Manual, 1756-RM003, appendix A "Common Attributes", Data
Conversions, "REAL to an Integer": 2.5 -> 2, -2.5 -> -2, 1.5 -> 2), which is
IEEE 754's default rounding. DIV's quotient of two integers follows its own
rule (``Machine.divide``: half away from zero), as do SCL and DDV, which
compute with integers only.
"""

from __future__ import annotations

import struct

FLOAT32_MAX = 3.4028234663852886e38
_F32 = struct.Struct("<f")
_pack, _unpack = _F32.pack, _F32.unpack  # bound once: a store of a float into a word calls them


def round_half_even(v: float) -> int:
    """A finite float as the integer the PLC stores: the float32 the PLC
    computes with (the value an F element would hold; softplc computes in
    double precision, so a result such as 0.1 * 25, 2.5000000373 in double,
    is 2.5 in float32 and rounds to 2 as on the PLC), then to the nearest
    integer, an exact half to the even one. A value beyond the float32 range
    keeps its double value: it overflows any integer anyway, and the store
    clamps it or keeps its low bits as it does every out-of-range result.
    NaN and the infinities have no integer: callers decide what they store."""
    if -FLOAT32_MAX <= v <= FLOAT32_MAX:
        v = _unpack(_pack(v))[0]
    return round(v)
