"""EPATH segments (CIP Volume 1, Appendix C "Data Management"): logical
segments naming class, instance and attribute (8- and 16-bit, padded form),
and port segments (route paths, as Unconnected_Send and Forward_Open carry).
Paths are padded EPATHs: a 16-bit logical value has a pad byte before it."""

from __future__ import annotations

import struct


class PathError(ValueError):
    """A path this codec cannot read: a CIP path segment error (0x04)."""


CLASS, INSTANCE, ATTRIBUTE, CONNECTION_POINT = 0x20, 0x24, 0x30, 0x2C
SYMBOLIC = 0x91  # ANSI extended symbolic segment


def logical(path: bytes) -> tuple[int | None, int | None, int | None]:
    """(class, instance, attribute) of an all-logical path; None for a part
    absent. Raises PathError for a segment that is not logical or is cut short."""
    found: dict[int, int] = {}
    i = 0
    while i < len(path):
        segment = path[i]
        kind, size = segment & 0xFC, segment & 0x03
        if kind not in (CLASS, INSTANCE, ATTRIBUTE, CONNECTION_POINT) or size > 1:
            raise PathError(f"segment 0x{segment:02X} at byte {i} is no 8- or 16-bit logical segment")
        if size == 0:
            if i + 2 > len(path):
                raise PathError(f"segment 0x{segment:02X} at byte {i} is cut short")
            value, i = path[i + 1], i + 2
        else:
            if i + 4 > len(path):
                raise PathError(f"segment 0x{segment:02X} at byte {i} is cut short")
            value, i = struct.unpack_from("<H", path, i + 2)[0], i + 4
        found[INSTANCE if kind == CONNECTION_POINT else kind] = value
    return found.get(CLASS), found.get(INSTANCE), found.get(ATTRIBUTE)


def encode_logical(class_id: int, instance: int | None = None, attribute: int | None = None) -> bytes:
    out = b""
    for kind, value in ((CLASS, class_id), (INSTANCE, instance), (ATTRIBUTE, attribute)):
        if value is None:
            continue
        out += bytes((kind, value)) if value < 0x100 else bytes((kind | 1, 0)) + struct.pack("<H", value)
    return out


def ports(path: bytes) -> list[tuple[int, bytes]]:
    """The (port, link address) hops of a route path of port segments."""
    hops = []
    i = 0
    while i < len(path):
        segment = path[i]
        if segment & 0xE0 != 0:
            raise PathError(f"segment 0x{segment:02X} at byte {i} is no port segment")
        port = segment & 0x0F
        if port == 0x0F:
            raise PathError(f"extended port numbers (segment 0x{segment:02X} at byte {i}) are not served")
        if segment & 0x10:
            if i + 2 > len(path):
                raise PathError(f"port segment at byte {i} is cut short")
            size = path[i + 1]
            start = i + 2
            end = start + size
            i = end + (size & 1)
        else:
            start, end = i + 1, i + 2
            i = end
        if end > len(path):
            raise PathError(f"port segment at byte {start - 1} is cut short")
        hops.append((port, bytes(path[start:end])))
    return hops
