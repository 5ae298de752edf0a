"""The Modbus check sums: the RTU CRC-16 and the ASCII LRC.

Both follow "Modbus over Serial Line Specification and Implementation Guide
V1.02": the CRC of section 2.5.1.2 (RTU mode; the generation procedure is in
Appendix B, section 6.2.2) and the LRC of section 2.5.2.2 (ASCII mode;
Appendix B, section 6.2.1). Pure functions of bytes.

The CRC is the reflected polynomial 0xA001 (x^16 + x^15 + x^2 + 1), preloaded
with 0xFFFF, no final XOR; it is appended to an RTU frame low byte first.
It runs once per transaction, so it is table-driven: one table lookup per
byte, the 256-entry table built once at import.

>>> hex(crc16(bytes.fromhex("02 03 00 00 00 7D")))
'0xd885'
>>> crc16(bytes.fromhex("02 03 00 00 00 7D")).to_bytes(2, "little").hex(" ")
'85 d8'
>>> crc16(bytes.fromhex("01 03 00 00 00 0A")).to_bytes(2, "little").hex(" ")
'c5 cd'
>>> hex(lrc(bytes.fromhex("F7 03 13 89 00 0A")))
'0x60'
"""

from __future__ import annotations

__all__ = ["CRC16_POLYNOMIAL", "CRC16_PRELOAD", "crc16", "lrc"]

CRC16_POLYNOMIAL = 0xA001  # 0x8005 bit-reversed
CRC16_PRELOAD = 0xFFFF


def _crc16_table(polynomial: int) -> tuple[int, ...]:
    """The CRC of each byte value from a zero preload (the bitwise algorithm
    of the serial-line spec, Appendix B, run once per table entry)."""
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ polynomial if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_CRC16_TABLE = _crc16_table(CRC16_POLYNOMIAL)


def crc16(data: bytes, preload: int = CRC16_PRELOAD) -> int:
    """The Modbus CRC-16 of ``data`` (any bytes-like object or iterable of
    byte values), 0..0xFFFF; an RTU frame carries it low byte first.

    ``preload`` continues a CRC over more data: ``crc16(b, crc16(a))`` equals
    ``crc16(a + b)``.

    >>> hex(crc16(bytes.fromhex("02 03 00 00 00 7D")))
    '0xd885'
    >>> crc16(b"")
    65535
    >>> crc16(b"\\x03\\x00", crc16(b"\\x02")) == crc16(b"\\x02\\x03\\x00")
    True
    """
    crc = preload
    table = _CRC16_TABLE
    for byte in data:
        crc = (crc >> 8) ^ table[(crc ^ byte) & 0xFF]
    return crc


def lrc(data: bytes) -> int:
    """The Modbus ASCII LRC of ``data``: the two's complement of the 8-bit sum
    of the bytes (address, function code and data, before hex encoding), 0..255.

    >>> lrc(bytes.fromhex("F7 03 13 89 00 0A"))  # 0xF7+0x03+...+0x0A = 0x1A0
    96
    >>> lrc(b"")
    0
    """
    return -sum(data) & 0xFF
