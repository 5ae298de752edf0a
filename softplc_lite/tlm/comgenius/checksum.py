"""The two checks of the format engine: ``%S`` (sum) and ``%R`` (CRC-16).

Both run over 16-bit characters but use only the low 8 bits of each: the
characters stand for bytes on the wire (the manual's binary packets).

- Sum: the 16-bit sum of the bytes; ``#`` gives its two's complement; the
  ``h`` modifier keeps one byte. Sent and compared little endian.
- CRC-16: reflected polynomial 0xA001 (the Modbus CRC), preloaded with 0, or
  with 0xFFFF when the ``#`` flag is given (Modbus RTU needs ``%#R``). Sent
  and compared little endian.

The widely published Modbus request ``01 03 00 00 00 0A`` goes on the wire
followed by ``C5 CD``:

>>> little_endian(crc16("\\x01\\x03\\x00\\x00\\x00\\x0a", 0xFFFF)).encode("latin-1").hex(" ")
'c5 cd'
"""

from __future__ import annotations

from typing import Iterable

from ...modbus.crc import crc16 as modbus_crc16  # one CRC-16 table for the formats and every Modbus part


def low_bytes(chars: str) -> bytes:
    """The low 8 bits of each character, as bytes."""
    try:
        return chars.encode("latin-1")
    except UnicodeEncodeError:
        return bytes(ord(c) & 0xFF for c in chars)


def crc16(chars: str, preload: int = 0) -> int:
    """CRC-16 (poly 0xA001, reflected) of the low bytes of ``chars``."""
    return crc16_bytes(low_bytes(chars), preload)


# The last CRC of a long run of bytes: (data, preload, crc). A master polling
# the same registers checks the same reply again and again (a 255-byte Modbus
# reply is a 253-byte Python loop), so an equal input is not run again.
# Short inputs (a query) are cheap and kept out, so they do not evict it.
_last_crc: tuple[bytes, int, int] = (b"", -1, 0)
_MEMO_FROM = 32  # bytes


def crc16_bytes(data: bytes | Iterable[int], preload: int = 0) -> int:
    """The same over bytes: the Modbus codec's table-driven CRC, with this
    module's default preload of 0."""
    global _last_crc
    last = _last_crc
    if last[1] == preload and last[0] == data:
        return last[2]
    crc = modbus_crc16(data, preload)
    if type(data) is bytes and len(data) >= _MEMO_FROM:
        _last_crc = (data, preload, crc)
    return crc


def sum16(chars: str, negate: bool = False, one_byte: bool = False) -> int:
    """The sum of the low bytes of ``chars``: 16 bits, or 8 with ``one_byte``;
    its two's complement with ``negate``."""
    total = sum(low_bytes(chars))
    if negate:
        total = -total
    return total & (0xFF if one_byte else 0xFFFF)


def little_endian(value: int, size: int = 2) -> str:
    """``value`` as ``size`` characters, least significant byte first."""
    return "".join(chr((value >> (8 * k)) & 0xFF) for k in range(size))
