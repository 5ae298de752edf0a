"""Common packet format (CIP Volume 2, 2-6): the items SendRRData,
SendUnitData and ListIdentity carry: an item count, then items of type,
length, data."""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass

NULL_ADDRESS = 0x0000
LIST_IDENTITY = 0x000C
CONNECTED_ADDRESS = 0x00A1
CONNECTED_DATA = 0x00B1
UNCONNECTED_DATA = 0x00B2
LIST_SERVICES = 0x0100
SOCKADDR_O_T = 0x8000
SOCKADDR_T_O = 0x8001


class CpfError(ValueError):
    """Bytes that are no item list (an encapsulation incorrect-data refusal)."""


@dataclass(frozen=True)
class Item:
    type_id: int
    data: bytes = b""


def encode(items: list[Item]) -> bytes:
    out = struct.pack("<H", len(items))
    for item in items:
        out += struct.pack("<HH", item.type_id, len(item.data)) + item.data
    return out


def decode(raw: bytes) -> list[Item]:
    if len(raw) < 2:
        raise CpfError("no item count")
    count = struct.unpack_from("<H", raw)[0]
    items, i = [], 2
    for n in range(count):
        if i + 4 > len(raw):
            raise CpfError(f"item {n + 1} of {count}: header cut short")
        type_id, length = struct.unpack_from("<HH", raw, i)
        if i + 4 + length > len(raw):
            raise CpfError(f"item {n + 1} of {count}: {length} data bytes announced, fewer follow")
        items.append(Item(type_id, bytes(raw[i + 4:i + 4 + length])))
        i += 4 + length
    return items


def sockaddr(host: str, port: int) -> bytes:
    """A sockaddr info item's data: big-endian, as the specification says (2-6.3.3)."""
    return struct.pack(">hH4s8x", socket.AF_INET, port, socket.inet_aton(host))
