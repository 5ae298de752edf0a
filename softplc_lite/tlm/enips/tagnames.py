"""The CIP tags the data table serves as (docs/enips.md, "CIP tags"): every
data file as an array tag named by its file, every program symbol as a tag
of its type, and what a symbolic request path names among them.

A path resolves to a ``Target``: a run of storage items of one file (items
as ``TableAccess`` counts them) read and written as units of one CIP data
type. The mapping follows Rockwell's "Map PLC/SLC messages", which gives a
Logix array for each PLC-5/SLC file (``N7`` an integer array, ``F8`` a REAL
array), kept at the PLC-5 file's own width: a word file is INT, not DINT,
so every value keeps the range the ladder gives it.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from ...cip import epath
from ...cip.status import PATH_DESTINATION_UNKNOWN, PATH_SEGMENT_ERROR
from ...datatable import AddressError, parse_address
from ...datatable.filetypes import FILE_TYPES as FILE_SPECS
from .access import FileInfo, TableAccess

# CIP elementary data type codes (CIP Vol. 1 appendix C; the codes pylogix
# and pycomm3 decode).
BOOL, SINT, INT, DINT, LINT, REAL = 0xC1, 0xC2, 0xC3, 0xC4, 0xC5, 0xCA
STRUCT = 0xA0
# Logix's STRING structure handle, the one pylogix (``StringID``) and
# pycomm3 recognise a STRING reply by; a STRING is DINT LEN + SINT[82] DATA,
# 88 bytes with its padding.
STRING_HANDLE = 0x0FCE
STRING_BYTES = 88
STRING_CHARS = 82

UNIT_BYTES = {BOOL: 1, SINT: 1, INT: 2, DINT: 4, LINT: 8, REAL: 4, STRUCT: STRING_BYTES}
UNIT_FORMATS = {BOOL: "B", SINT: "b", INT: "h", DINT: "i", LINT: "q", REAL: "f"}  # struct codes of the elementary units
ST_ITEMS = 83  # storage items of an ST element: .LEN, then 82 characters

# The CIP type of one item of each file type.
FILE_TYPES = {letter: INT for letter in "OISBTCRNDA"}
FILE_TYPES.update({"F": REAL, "L": DINT, "ST": STRUCT, "SI": SINT, "LI": LINT})
# T, C and R elements are 3 words: served as INT[elements, 3].
_ROWS = {"T": 3, "C": 3, "R": 3}


class PathError(Exception):
    """A request path that names nothing served: ``status`` is the CIP
    general status to answer with (0x04 a segment the path cannot have, 0x05
    a tag, member or element that does not exist)."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason


@dataclass(frozen=True)
class Target:
    """What a path names: ``units`` values of CIP type ``ctype`` from item
    ``item`` of file ``file`` on (one item a unit; 83 for a STRING), or one
    bit ``bit`` of that item (``ctype`` BOOL)."""

    file: str
    kind: str  # the file's type letters
    item: int
    ctype: int
    units: int  # how many units the tag has from ``item`` to its end
    bit: int | None = None
    member_len: bool = False  # ST element's .LEN, a DINT

    @property
    def items_per_unit(self) -> int:
        return _items_per_unit(self.ctype)

    @property
    def type_bytes(self) -> bytes:
        """The type field a reply (and a matching write) carries."""
        if self.ctype == STRUCT:
            return struct.pack("<BBH", STRUCT, 2, STRING_HANDLE)
        return struct.pack("<H", self.ctype)


@dataclass(frozen=True)
class Tag:
    """One served tag: a file (``dims`` its array dimensions) or a symbol."""

    name: str
    file: FileInfo
    item: int  # first item
    ctype: int
    dims: tuple[int, ...]  # () for a scalar
    bit: int | None = None

    def symbol_type(self) -> int:
        """Attribute 2 of the Symbol object: the type code, the number of
        dimensions in bits 13-14, bit 15 and the template instance for a
        structure (the layout pylogix's Tag.parse and pycomm3 decode). Bits
        8-10 (a BOOL's bit position) stay 0: pylogix takes them into the
        type code it names the type by."""
        code = (0x8000 | STRING_HANDLE) if self.ctype == STRUCT else self.ctype
        return code | (len(self.dims) << 13)


def file_tags(files: list[FileInfo]) -> list[Tag]:
    out = []
    for info in files:
        if info.kind not in FILE_TYPES:  # SL (long strings): no CIP type serves 5,000 characters (softplc choice)
            continue
        rows = _ROWS.get(info.kind)
        dims = (info.elements, rows) if rows else (info.elements,)
        out.append(Tag(info.name, info, 0, FILE_TYPES[info.kind], dims))
    return out


def symbol_addresses(symbols) -> dict[str, str]:
    """A program's symbols (``Program.symbols``: name -> declaration) as the
    picklable name -> address text the tag services are built with."""
    return {decl.name: str(decl.address) for decl in symbols.values()}


def symbol_tags(symbols: dict[str, str], access: TableAccess) -> tuple[list[Tag], list[str]]:
    """The program symbols as tags, and what was left out and why (an
    indirect or indexed address, a file not served, an element past its
    end)."""
    out, skipped = [], []
    for name in sorted(symbols, key=str.upper):
        text = symbols[name]
        try:
            a = parse_address(text)
        except AddressError as e:
            skipped.append(f"{name}: {e}")
            continue
        info = access.file_named(a.file_name()) if a.is_direct else None
        if info is None or a.element is None and a.bit is None or info.kind not in FILE_TYPES:
            skipped.append(f"{name}: {text} is not a direct address of a served file")
            continue
        per = info.items_per_element
        if a.element is None:  # B3/20: a bit across the file
            element, bit = divmod(a.bit, 16)
            item = element
        else:
            element, bit = a.element, a.bit
            item = element * per
        if element >= info.elements:
            skipped.append(f"{name}: {text} is past the end of {info.name}")
            continue
        if a.member is not None:
            offset = info_member_offset(info.kind, a.member)
            if info.kind == "ST":  # LEN a DINT (as a Logix STRING's), a character DATAk a word
                out.append(Tag(name, info, item + offset, DINT if a.member == "LEN" else INT, ()))
                continue
            item += offset
            per = 1
        if bit is not None:
            out.append(Tag(name, info, item, BOOL, (), bit))
        elif info.kind in _ROWS and a.member is None:
            out.append(Tag(name, info, item, INT, (3,)))
        else:
            out.append(Tag(name, info, item, FILE_TYPES[info.kind], ()))
    return out, skipped


def info_member_offset(kind: str, member: str) -> int:
    return FILE_SPECS[kind].members_by_name[member].offset


def _items_per_unit(ctype: int) -> int:
    return ST_ITEMS if ctype == STRUCT else 1


# -- request paths ---------------------------------------------------------

# The segments a tag path may have (CIP Vol. 1 C-1.4.2), by logical kind:
# what parse_path calls them, and the value widths served.
_TAG_SEGMENTS = {epath.ELEMENT: ("index", (1, 2, 4)), epath.CLASS: ("class", (1, 2)),
                 epath.INSTANCE: ("instance", (1, 2, 4))}


def parse_path(path: bytes) -> list[tuple[str, object]]:
    """The segments of a symbolic path: ("name", text) for an ANSI extended
    symbolic segment (0x91), ("index", n) for an element segment (0x28 8-bit,
    0x29 16-bit, 0x2A 32-bit), ("class", n) and ("instance", n) for logical
    segments (0x20/0x21, 0x24/0x25/0x26)."""
    try:
        found = epath.segments(path)
    except epath.PathError as e:
        raise PathError(PATH_SEGMENT_ERROR, str(e)) from None
    out: list[tuple[str, object]] = []
    for s in found:
        if s.kind == epath.SYMBOLIC:
            out.append(("name", s.value))
            continue
        name, widths = _TAG_SEGMENTS.get(s.kind, (None, ()))
        if s.width not in widths:
            raise PathError(PATH_SEGMENT_ERROR, f"segment 0x{s.code:02X} has no place in a tag path")
        out.append((name, s.value))
    return out


def resolve(tag: Tag, rest: list[tuple[str, object]]) -> Target:
    """The target of ``tag`` followed by ``rest`` (its indexes, then a member
    name or a bit number)."""
    info = tag.file
    indexes = []
    while rest and rest[0][0] == "index":
        indexes.append(rest.pop(0)[1])
    member = None
    if rest:
        kind, member = rest.pop(0)
        if kind != "name" or rest:
            raise PathError(PATH_SEGMENT_ERROR, "a tag path ends after one member name")
    if len(indexes) > len(tag.dims) or (indexes and len(indexes) != len(tag.dims) and len(tag.dims) > 1
                                        and len(indexes) != 1):
        raise PathError(PATH_SEGMENT_ERROR, f"{tag.name} has {len(tag.dims)} dimension(s), not {len(indexes)}")
    for k, value in enumerate(indexes):
        if value >= tag.dims[k]:
            raise PathError(PATH_DESTINATION_UNKNOWN, f"{tag.name}: index {value} is past its end ({tag.dims[k]})")
    ctype, per = tag.ctype, _items_per_unit(tag.ctype)
    if ctype == STRUCT:
        item = tag.item + (indexes[0] if indexes else 0) * per
    else:
        item = tag.item + sum(value * math.prod(tag.dims[k + 1:]) for k, value in enumerate(indexes))
    end = tag.item + math.prod(tag.dims) * per
    units = (end - item) // per
    target = Target(info.name, info.kind, item, ctype, units, tag.bit)
    if member is None:
        return target
    return _member(tag, target, indexes, member)


def _member(tag: Tag, target: Target, indexes: list, member: str) -> Target:
    spec = FILE_SPECS[target.kind]
    upper = member.upper()
    if member.isdigit():
        bit = int(member)
        if target.ctype != INT or target.bit is not None or bit > 15:
            raise PathError(PATH_SEGMENT_ERROR, f"{tag.name}: .{member} is not a bit of an INT")
        return Target(target.file, target.kind, target.item, BOOL, 1, bit)
    if target.kind == "ST" and upper == "LEN" and target.ctype == STRUCT:
        return Target(target.file, target.kind, target.item, DINT, 1, member_len=True)
    if target.kind in _ROWS and upper in spec.members_by_name and target.bit is None:
        # a member names a word (or a status bit) of one element: T4[0].ACC, Timer1.DN
        if tag.dims == (3,) and not indexes:
            element_start = tag.item
        elif len(tag.dims) == 2 and len(indexes) <= 1:
            element_start = tag.item + (indexes[0] if indexes else 0) * 3
        else:
            raise PathError(PATH_SEGMENT_ERROR, f"{tag.name}{list(indexes)} is a word; it has no .{member}")
        m = spec.members_by_name[upper]
        if hasattr(m, "offset"):
            return Target(target.file, target.kind, element_start + m.offset, INT, 1)
        return Target(target.file, target.kind, element_start + m.word, BOOL, 1, m.bit)
    raise PathError(PATH_SEGMENT_ERROR, f"{tag.name} has no member {member!r}")


class Catalogue:
    """The tags one request sees: files first (by number), then symbols (by
    name); instance ids 1.. in that order, as the Symbol object lists them."""

    def __init__(self, access: TableAccess, symbols: dict[str, str]) -> None:
        self.access = access
        files = file_tags(access.files())
        syms, self.skipped = symbol_tags(symbols, access)
        names = {t.name.upper() for t in files}
        self.tags = files + [t for t in syms if t.name.upper() not in names]
        self.by_name = {t.name.upper(): t for t in self.tags}

    def target(self, segments: list[tuple[str, object]]) -> Target:
        if not segments:
            raise PathError(PATH_SEGMENT_ERROR, "an empty tag path")
        kind, first = segments[0]
        if kind == "instance":
            if not 1 <= first <= len(self.tags):
                raise PathError(PATH_DESTINATION_UNKNOWN, f"no symbol instance {first}")
            tag = self.tags[first - 1]
        elif kind == "name":
            tag = self.by_name.get(str(first).upper())
            if tag is None:
                raise PathError(PATH_DESTINATION_UNKNOWN, f"no tag named {first!r}")
        else:
            raise PathError(PATH_SEGMENT_ERROR, "a tag path starts with a name or a symbol instance")
        return resolve(tag, list(segments[1:]))
