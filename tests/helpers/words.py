"""16-bit words as the tests write their expectations.

A PLC word (an N element, a Modbus register as an N word reads it back)
holds -32768..32767; a register, a bit pattern or a wrapped result is
written 0..65535 or wider. ``signed`` is written here, not taken from
softplc_lite, so that a test's expected value does not come from the code
under test."""

from __future__ import annotations


def signed(value: int) -> int:
    """The low 16 bits of ``value`` as the signed word an N element holds
    (two's complement: 0xFFFF is -1, 40000 is -25536)."""
    value &= 0xFFFF
    return value - 0x10000 if value & 0x8000 else value
