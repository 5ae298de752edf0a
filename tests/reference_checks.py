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
