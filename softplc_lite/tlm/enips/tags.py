"""CIP tag services on the data table (docs/enips.md, "CIP tags"): Read Tag,
Write Tag, their fragmented forms, Read-Modify-Write Tag, and the Symbol
object's instance attribute list that Logix clients browse tags with.

``TagServices`` answers symbolic paths (class_id None: paths that start
with an ANSI extended symbolic segment); ``SymbolObject`` answers class
0x6B, the browse and tag services addressed by symbol instance. Both take
the program's symbols as picklable data (name -> address text), so the
server process builds them from the app's config.

Service codes and request layouts are the ones 1756-PM020 ("Logix5000 Data
Access") documents and pylogix and pycomm3 send; status codes as
docs/enips.md lists them.
"""

from __future__ import annotations

import struct

from ...cip import status as st
from .access import TableAccess
from .logixtags import LogixCatalogue, StructTarget, read_struct, write_struct
from .logixview import LogixView
from .objects import REPLY, CipObject, CipReply, CipRequest
from .tagnames import (DINT, INT, LINT, SINT, ST_ITEMS, STRING_BYTES, STRING_CHARS, STRUCT, UNIT_BYTES,
                       UNIT_FORMATS, Catalogue, PathError, Target, parse_path)

READ_TAG, WRITE_TAG, RMW_TAG = 0x4C, 0x4D, 0x4E
READ_FRAGMENTED, WRITE_FRAGMENTED = 0x52, 0x53
GET_INSTANCE_ATTRIBUTE_LIST = 0x55
SYMBOL_CLASS = 0x6B

# Extended status words of general status 0xFF (1756-PM020's Read/Write
# Tag error tables; pycomm3's status_info names them the same).
EXT_OFFSET_OUT_OF_RANGE = 0x2104
EXT_BEYOND_END = 0x2105
EXT_TYPE_MISMATCH = 0x2107

# Reply data a tag service puts in one answer: 480 bytes keeps a reply
# with its headers within the 504-byte unconnected message limit (a
# choice; a client with a larger connection still gets every byte, in
# more fragments).
REPLY_BYTES = 480
BASE_TAG_BIT = 1 << 26
# Bits of one item by the file type letters; a word (16) for the others.
ITEM_BITS = {"SI": 8, "L": 32, "LI": 64}
# A Read-Modify-Write's mask size (bytes) for each integer type, and its format.
MASK_SIZES = {SINT: (1, "B"), INT: (2, "H"), DINT: (4, "I"), LINT: (8, "Q")}
WRITES = (0x4D, 0x53, 0x4E)


class TagServices(CipObject):
    """The tag services for symbolic paths."""

    class_id = None

    def __init__(self, symbols: dict[str, str] | None = None, reply_bytes: int = REPLY_BYTES,
                 logix: LogixView | None = None) -> None:
        self.symbols = dict(symbols or {})
        self.reply_bytes = reply_bytes
        self.logix = logix  # a Logix app's tags: served in place of the files and symbols
        self._catalogue: tuple[tuple, Catalogue] | None = None  # (the files it was built on, it)

    def catalogue(self, access: TableAccess) -> Catalogue | LogixCatalogue:
        """The tags of ``access``'s table, built again only when its files
        change (a file grown, one added): not at every request."""
        files = tuple(access.files())
        if self._catalogue is None or self._catalogue[0] != files or self._catalogue[1].access is not access:
            made = LogixCatalogue(access, self.logix) if self.logix is not None else Catalogue(access, self.symbols)
            self._catalogue = (files, made)
        return self._catalogue[1]

    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        catalogue = self.catalogue(access)
        try:
            segments = parse_path(request.path)
            if ("class", SYMBOL_CLASS) in segments[1:2]:  # Program:Name, then the Symbol object: a program's symbols
                return await symbol_request(self, request, access, segments)
            target = catalogue.target(segments)
        except PathError as e:
            return CipReply.error(request, e.status)
        return await self.serve_target(request, access, target)

    async def serve_target(self, request: CipRequest, access: TableAccess, target) -> CipReply:
        handler = {READ_TAG: self._read, READ_FRAGMENTED: self._read, WRITE_TAG: self._write,
                   WRITE_FRAGMENTED: self._write, RMW_TAG: self._rmw}.get(request.service)
        if handler is None:
            return CipReply.error(request, st.SERVICE_NOT_SUPPORTED)
        try:
            if isinstance(target, StructTarget):  # a Logix structure, whole
                catalogue = self.catalogue(access)
                if request.service in (READ_TAG, READ_FRAGMENTED):
                    return await read_struct(request, access, target, catalogue, self.reply_bytes)
                if request.service == RMW_TAG:
                    return CipReply.error(request, st.GENERAL_ERROR, EXT_TYPE_MISMATCH)
                return await write_struct(request, access, target, catalogue)
            if not isinstance(target, Target):  # a Logix tag's value and its External Access
                if request.service in WRITES and target.access != "rw":
                    return CipReply.error(request, st.PRIVILEGE_VIOLATION)
                target = target.target
            return await handler(request, access, target)
        except (struct.error, IndexError):
            return CipReply.error(request, st.NOT_ENOUGH_DATA)

    # -- reads -------------------------------------------------------------
    async def _read(self, request: CipRequest, access: TableAccess, target: Target) -> CipReply:
        data = request.data
        count = struct.unpack_from("<H", data, 0)[0]
        offset = struct.unpack_from("<I", data, 2)[0] if request.service == READ_FRAGMENTED else 0
        if len(data) > (6 if request.service == READ_FRAGMENTED else 2):
            return CipReply.error(request, st.TOO_MUCH_DATA)
        if count == 0 or count > target.units:
            return CipReply.error(request, st.GENERAL_ERROR, EXT_BEYOND_END)
        unit = UNIT_BYTES[target.ctype]
        total = count * unit
        if offset % unit or offset > total or (offset == total and total):
            return CipReply.error(request, st.GENERAL_ERROR, EXT_OFFSET_OUT_OF_RANGE)
        room = max(unit, (self.reply_bytes - len(target.type_bytes)) // unit * unit)
        first_unit = offset // unit
        units = min(count - first_unit, room // unit)
        values = await _read_units(access, target, first_unit, units)
        status = st.SUCCESS if first_unit + units == count else st.PARTIAL_TRANSFER
        return CipReply(request.service | REPLY, status, (), target.type_bytes + values)

    # -- writes ------------------------------------------------------------
    async def _write(self, request: CipRequest, access: TableAccess, target: Target) -> CipReply:
        data = request.data
        type_len = 4 if data[0] == STRUCT else 2
        if data[:type_len] != target.type_bytes:
            return CipReply.error(request, st.GENERAL_ERROR, EXT_TYPE_MISMATCH)
        count = struct.unpack_from("<H", data, type_len)[0]
        at = type_len + 2
        offset = 0
        if request.service == WRITE_FRAGMENTED:
            offset = struct.unpack_from("<I", data, at)[0]
            at += 4
        payload = data[at:]
        unit = UNIT_BYTES[target.ctype]
        if count == 0 or count > target.units:
            return CipReply.error(request, st.GENERAL_ERROR, EXT_BEYOND_END)
        if offset % unit or offset >= count * unit:
            return CipReply.error(request, st.GENERAL_ERROR, EXT_OFFSET_OUT_OF_RANGE)
        if request.service == WRITE_TAG:
            # Bytes past the count's worth are ignored, as a Logix controller
            # does: pycomm3 1.2's single-tag write sends its request twice over.
            if len(payload) < count * unit:
                return CipReply.error(request, st.NOT_ENOUGH_DATA)
            payload = payload[:count * unit]
        if len(payload) % unit or not payload:
            return CipReply.error(request, st.NOT_ENOUGH_DATA)
        if offset + len(payload) > count * unit:
            return CipReply.error(request, st.TOO_MUCH_DATA)
        first = offset // unit
        units = len(payload) // unit
        if target.bit is not None:
            mask = 1 << target.bit
            full = (1 << ITEM_BITS.get(target.kind, 16)) - 1
            and_mask, or_mask = full & ~mask, mask if payload[0] else 0
            if not access.writable_bits(target.file, target.item, and_mask, or_mask):
                return CipReply.error(request, st.PRIVILEGE_VIOLATION)
            ok = await access.write_masked(target.file, target.item, and_mask, or_mask)
            return _done(request, ok)
        try:
            items = _decode_units(target, payload, units)
        except ValueError:
            return CipReply.error(request, st.INVALID_ATTRIBUTE_VALUE)
        start = target.item + first * target.items_per_unit
        if not access.writable(target.file, start, len(items)):
            return CipReply.error(request, st.PRIVILEGE_VIOLATION)
        return _done(request, await access.write(target.file, start, items))

    async def _rmw(self, request: CipRequest, access: TableAccess, target: Target) -> CipReply:
        data = request.data
        size = struct.unpack_from("<H", data, 0)[0]
        if len(data) < 2 + 2 * size:
            return CipReply.error(request, st.NOT_ENOUGH_DATA)
        width = MASK_SIZES.get(target.ctype) if target.bit is None else None
        if width is None or size != width[0]:
            # masks of the target's own integer width: the table's masked write is one item's
            return CipReply.error(request, st.GENERAL_ERROR, EXT_TYPE_MISMATCH)
        or_mask, and_mask = struct.unpack_from(f"<{width[1]}{width[1]}", data, 2)
        if not access.writable_bits(target.file, target.item, and_mask, or_mask):
            return CipReply.error(request, st.PRIVILEGE_VIOLATION)
        return _done(request, await access.write_masked(target.file, target.item, and_mask, or_mask))


def _done(request: CipRequest, ok: bool) -> CipReply:
    return CipReply.ok(request) if ok else CipReply.error(request, st.PRIVILEGE_VIOLATION)


async def _read_units(access: TableAccess, target: Target, first: int, units: int) -> bytes:
    per = target.items_per_unit
    start = target.item + first * per
    [items] = await access.read([(target.file, start, units * per)])
    if target.bit is not None:
        return bytes([1 if items[0] & (1 << target.bit) else 0])
    if target.member_len:
        return struct.pack("<i", items[0])
    if target.ctype == STRUCT:
        out = bytearray()
        for k in range(units):
            element = items[k * ST_ITEMS:(k + 1) * ST_ITEMS]
            chars = bytes(c if 0 <= c < 256 else 0x3F for c in element[1:])
            out += struct.pack("<i", element[0]) + chars + b"\x00\x00"
        return bytes(out)
    return struct.pack(f"<{units}{UNIT_FORMATS[target.ctype]}", *items)


def _decode_units(target: Target, payload: bytes, units: int) -> list:
    """The storage items a write's data stands for; ValueError for a value
    the item cannot hold (a STRING or .LEN longer than 82)."""
    if target.member_len:
        length = struct.unpack_from("<i", payload)[0]
        if not 0 <= length <= STRING_CHARS:
            raise ValueError(length)
        return [length]
    if target.ctype == STRUCT:
        items: list = []
        for k in range(units):
            chunk = payload[k * STRING_BYTES:(k + 1) * STRING_BYTES]
            length = struct.unpack_from("<i", chunk)[0]
            if not 0 <= length <= STRING_CHARS:
                raise ValueError(length)
            items.append(length)
            items.extend(chunk[4:4 + STRING_CHARS])
        return items
    return list(struct.unpack(f"<{units}{UNIT_FORMATS[target.ctype]}", payload))


class SymbolObject(CipObject):
    """Class 0x6B: Get_Instance_Attribute_List (the tag browse of pylogix's
    GetTagList and pycomm3's get_tag_list) and the tag services addressed
    by symbol instance (pycomm3 at revision 21 and later). A path that
    starts with ``Program:Name`` names that program's symbols (a Logix
    app's; the data table's tags have no program)."""

    class_id = SYMBOL_CLASS

    def __init__(self, symbols: dict[str, str] | None = None, reply_bytes: int = REPLY_BYTES,
                 logix: LogixView | None = None) -> None:
        self.tags = TagServices(symbols, reply_bytes, logix)
        self.reply_bytes = reply_bytes

    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        try:
            segments = parse_path(request.path)
        except PathError as e:
            return CipReply.error(request, e.status)
        return await symbol_request(self.tags, request, access, segments)


async def symbol_request(tags: TagServices, request: CipRequest, access: TableAccess, segments: list) -> CipReply:
    """A request to the Symbol object: the browse, or a tag service on a
    symbol instance; after ``Program:Name``, of that program's symbols."""
    catalogue = tags.catalogue(access)
    scope = None
    try:
        if segments and segments[0][0] == "name":
            if not isinstance(catalogue, LogixCatalogue):
                return CipReply.error(request, st.PATH_DESTINATION_UNKNOWN)
            scope = catalogue.scope_of(str(segments[0][1]))
            segments = segments[1:]
        segments = [s for s in segments if s[0] != "class"]
        if request.service == GET_INSTANCE_ATTRIBUTE_LIST:
            first = segments[0][1] if segments and segments[0][0] == "instance" else 0
            return _browse(request, _entries(catalogue, scope), first, tags.reply_bytes)
        if isinstance(catalogue, LogixCatalogue) and segments:
            target = catalogue.resolve(segments, scope)
        else:
            target = catalogue.target(segments)
    except PathError as e:
        return CipReply.error(request, e.status)
    return await tags.serve_target(request, access, target)


def _entries(catalogue, scope) -> list[tuple]:
    """Each listed symbol: (name, symbol type, element bytes, dims, external
    access code, base tag); its instance is its place in the list, from 1."""
    if isinstance(catalogue, LogixCatalogue):
        return catalogue.entries(scope)
    access = catalogue.access
    return [(t.name, t.symbol_type(), UNIT_BYTES[t.ctype], t.dims,
             0 if access.writable(t.file.name, t.item, 1) else 2, True) for t in catalogue.tags]


# Symbol object instance attributes a browse may ask (1756-PM020 "Symbol
# Object"; 3 and 5 are addresses a Logix controller has and this table has
# not: served as 0; 6, software control, has bit 26 set, which pycomm3 reads
# as "a base tag, not an alias").
def _attribute(entry: tuple, number: int) -> bytes | None:
    name, symbol_type, size, dims, external, base = entry
    if number == 1:
        text = name.encode("ascii")
        return struct.pack("<H", len(text)) + text
    if number == 2:
        return struct.pack("<H", symbol_type)
    if number in (3, 5):
        return struct.pack("<I", 0)
    if number == 6:
        return struct.pack("<I", BASE_TAG_BIT if base else 0)
    if number == 7:
        return struct.pack("<H", size)
    if number == 8:
        return struct.pack("<3I", *(list(dims) + [0] * (3 - len(dims))))
    if number == 10:  # external access: 0 read/write, 2 read only, 3 none (pycomm3's EXTERNAL_ACCESS)
        return bytes([external])
    return None


def _browse(request: CipRequest, entries: list[tuple], first: int, budget: int) -> CipReply:
    data = request.data
    try:
        count = struct.unpack_from("<H", data, 0)[0]
        numbers = struct.unpack_from(f"<{count}H", data, 2)
    except struct.error:
        return CipReply.error(request, st.NOT_ENOUGH_DATA)
    out = bytearray()
    status = st.SUCCESS
    for instance in range(max(first, 1), len(entries) + 1):
        entry = bytearray(struct.pack("<I", instance))
        for number in numbers:
            value = _attribute(entries[instance - 1], number)
            if value is None:
                return CipReply.error(request, st.ATTRIBUTE_NOT_SUPPORTED)
            entry += value
        if out and len(out) + len(entry) > budget:
            status = st.PARTIAL_TRANSFER
            break
        out += entry
    return CipReply(request.service | REPLY, status, (), bytes(out))
