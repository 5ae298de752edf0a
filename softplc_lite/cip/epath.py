"""EPATH segments (CIP Volume 1, Appendix C "Data Management"): logical
segments naming class, instance, element, connection point and attribute
(8-, 16- and 32-bit, padded form), ANSI extended symbolic segments (tag
names), and port segments (route paths, as Unconnected_Send and Forward_Open
carry). Paths are padded EPATHs: a 16- or 32-bit logical value has a pad
byte before it, a symbolic name of odd length one after it.

``segments`` reads the logical and symbolic segments of a path; each user
(the Message Router's logical paths, the tag services' paths) says which of
them it serves."""

from __future__ import annotations

import struct
from typing import NamedTuple


class PathError(ValueError):
    """A path this codec cannot read: a CIP path segment error (0x04)."""


CLASS, INSTANCE, ELEMENT, CONNECTION_POINT, ATTRIBUTE = 0x20, 0x24, 0x28, 0x2C, 0x30
SYMBOLIC = 0x91  # ANSI extended symbolic segment
_WIDTHS = (1, 2, 4)  # a logical segment's format bits: 8-, 16-, 32-bit value


class Segment(NamedTuple):
    """One segment: ``kind`` the logical type (CLASS ... ATTRIBUTE) or
    SYMBOLIC; ``value`` its number, or the name; ``width`` a logical value's
    bytes (0 for a name); ``code`` the segment byte; ``at`` its offset."""

    kind: int
    value: int | str
    width: int
    code: int
    at: int


def segments(path: bytes) -> list[Segment]:
    """The logical and symbolic segments of ``path``, in order. PathError
    for another kind of segment, one cut short, or a name not in ASCII."""
    out: list[Segment] = []
    i = 0
    while i < len(path):
        code = path[i]
        if code == SYMBOLIC:
            if i + 2 > len(path) or i + 2 + path[i + 1] > len(path):
                raise PathError(f"symbolic segment at byte {i} is cut short")
            size = path[i + 1]
            try:
                name = bytes(path[i + 2:i + 2 + size]).decode("ascii")
            except UnicodeDecodeError:
                raise PathError(f"symbolic segment at byte {i} is not ASCII") from None
            out.append(Segment(SYMBOLIC, name, 0, code, i))
            i += 2 + size + (size & 1)
            continue
        kind, fmt = code & 0xFC, code & 0x03
        if kind not in (CLASS, INSTANCE, ELEMENT, CONNECTION_POINT, ATTRIBUTE) or fmt == 3:
            raise PathError(f"segment 0x{code:02X} at byte {i} is no logical or symbolic segment")
        width = _WIDTHS[fmt]
        start = i + 1 if width == 1 else i + 2  # a pad byte before a 16- or 32-bit value
        if start + width > len(path):
            raise PathError(f"segment 0x{code:02X} at byte {i} is cut short")
        out.append(Segment(kind, int.from_bytes(path[start:start + width], "little"), width, code, i))
        i = start + width
    return out


def logical(path: bytes) -> tuple[int | None, int | None, int | None]:
    """(class, instance, attribute) of an all-logical path (a connection
    point standing for the instance); None for a part absent. Raises
    PathError for a segment that is not an 8- or 16-bit one of those, or is cut short."""
    found: dict[int, int] = {}
    for s in segments(path):
        if s.kind not in (CLASS, INSTANCE, ATTRIBUTE, CONNECTION_POINT) or s.width > 2:
            raise PathError(f"segment 0x{s.code:02X} at byte {s.at} is no 8- or 16-bit logical segment")
        found[INSTANCE if s.kind == CONNECTION_POINT else s.kind] = s.value
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
