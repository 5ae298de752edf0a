"""Independent reference implementations for tests (not softplc code)."""

from __future__ import annotations


def crc16_modbus_ref(data: bytes, preload: int) -> int:
    """CRC-16 bit by bit (poly 0xA001 reflected), independent of checksum.py."""
    crc = preload
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def rtu_frame(hex_text: str) -> bytes:
    """The bytes of ``hex_text`` with their Modbus RTU CRC appended, low byte
    first, computed bit by bit (independent of softplc_lite's codec)."""
    data = bytes.fromhex(hex_text)
    crc = crc16_modbus_ref(data, 0xFFFF)
    return data + bytes([crc & 0xFF, crc >> 8])
