"""Bits and registers to and from their Modbus byte form: the hot path of a
data-moving master (every read and write goes through here).

"Modbus Application Protocol Specification V1.1b3": registers are 16-bit
big-endian (section 4.2, data encoding); coils and discrete inputs are
packed 8 a byte, the first in the lowest bit of the first byte, the unused
high bits of the last byte zero (sections 6.1, 6.2, 6.11).

Whole buffers at a time: ``array`` with ``byteswap`` for registers, one
big-int conversion or one table lookup per byte for bits, no per-bit
Python loop.

>>> pack_bits([True, False, False, True, False, False, True, False, False, True]).hex(" ")
'49 02'
>>> unpack_bits(bytes.fromhex("49 02"), 10)
[True, False, False, True, False, False, True, False, False, True]
>>> registers_to_bytes([1, 0xBEEF, -1]).hex(" ")
'00 01 be ef ff ff'
>>> bytes_to_registers(bytes.fromhex("00 01 BE EF"))
array('H', [1, 48879])
"""

from __future__ import annotations

import sys
from array import array
from collections.abc import Iterable
from itertools import chain

__all__ = ["pack_bits", "unpack_bits", "registers_to_bytes", "bytes_to_registers"]

_LITTLE_ENDIAN_HOST = sys.byteorder == "little"
_BIT_DIGITS = bytes.maketrans(b"\x00\x01", b"01")  # 0/1 bytes -> b"0"/b"1"
_BYTE_BITS: tuple[tuple[bool, ...], ...] = tuple(
    tuple(bool(byte >> i & 1) for i in range(8)) for byte in range(256))  # lowest bit first


def pack_bits(bits: Iterable[object]) -> bytes:
    """``bits`` (anything truthy is on) 8 a byte, the first in the lowest bit
    of the first byte; the unused high bits of the last byte are 0.

    >>> pack_bits([True] * 9).hex(" ")
    'ff 01'
    >>> pack_bits([])
    b''
    """
    flags = bytes(map(bool, bits))  # one 0/1 byte per bit
    if not flags:
        return b""
    # Reversed, as binary digits, the flags are the number whose bit i is bits[i].
    number = int(flags[::-1].translate(_BIT_DIGITS), 2)
    return number.to_bytes((len(flags) + 7) // 8, "little")


def unpack_bits(data: bytes, count: int) -> list[bool]:
    """The first ``count`` bits of ``data`` (lowest bit of the first byte
    first); ValueError when ``data`` holds fewer than ``count`` bits.

    >>> unpack_bits(b"\\x05", 4)
    [True, False, True, False]
    """
    if not 0 <= count <= 8 * len(data):
        raise ValueError(f"cannot unpack {count} bits from {len(data)} bytes")
    bits = list(chain.from_iterable(map(_BYTE_BITS.__getitem__, data[:(count + 7) // 8])))
    del bits[count:]
    return bits


def registers_to_bytes(values: Iterable[int]) -> bytes:
    """16-bit registers, big-endian. Values may be unsigned (0..65535) or
    signed (-32768..32767): the low 16 bits are sent. ValueError outside
    -32768..65535, TypeError for a value that is not an int.

    >>> registers_to_bytes([0x1234, -2]).hex(" ")
    '12 34 ff fe'
    """
    if not isinstance(values, (list, tuple, array, range)):
        values = list(values)
    try:
        words = array("H", values)
    except OverflowError:  # signed values (or out of range: checked below)
        if values and (min(values) < -0x8000 or max(values) > 0xFFFF):
            raise ValueError(f"register values must be -32768..65535, "
                             f"got {min(values)}..{max(values)}") from None
        words = array("H", [value & 0xFFFF for value in values])
    if _LITTLE_ENDIAN_HOST:
        words.byteswap()
    return words.tobytes()


def bytes_to_registers(data: bytes) -> array:
    """Big-endian 16-bit registers as ``array('H')`` (unsigned); ValueError
    for an odd number of bytes.

    >>> list(bytes_to_registers(b"\\xff\\xfe\\x00\\x07"))
    [65534, 7]
    """
    if len(data) % 2:
        raise ValueError(f"registers need an even number of bytes, not {len(data)}")
    words = array("H")
    words.frombytes(data)
    if _LITTLE_ENDIAN_HOST:
        words.byteswap()
    return words
