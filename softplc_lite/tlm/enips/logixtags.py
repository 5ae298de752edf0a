"""A Logix app's tags through the CIP tag services (docs/enips.md, "Logix
tags"): what a request path names among the export's tags (logixview.py),
structures read and written whole through their templates, and the tag
list the Symbol object browses, controller scope and each program's.

External Access is the export's (1756-PM004, "Data access control": Read
Only, external applications can read but not change the value; None, they
can neither read nor change it): a tag or member of access None is not
listed, and a request naming it, or a structure holding it, is refused with
CIP 0x0F privilege violation, the status a Logix controller gives a read of
a structure with a member of access None (pycomm3 issues 52 and 245); a
write to a Read Only tag or member is refused with the same 0x0F (libplctag
reports it as "not allowed" from a Logix controller, libplctag.NET issue
333). Everything else is as for the data table's tags (tags.py).
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass

from ...cip import status as st
from ...cip.status import PATH_DESTINATION_UNKNOWN, PATH_SEGMENT_ERROR, PRIVILEGE_VIOLATION
from .access import TableAccess
from .logixview import ATOMIC_CODES, ATOMIC_SIZES, STRING_SIZE, STRUCT_BIT, LogixTag, LogixView, Template
from .objects import REPLY, CipReply, CipRequest
from .tagnames import BOOL, ST_ITEMS, STRING_CHARS, STRING_HANDLE, STRUCT, PathError, Target

PROGRAM_PREFIX = "PROGRAM:"
PROGRAM_SYMBOL_TYPE = 0x1068  # a program's entry in the controller's list: a system symbol (bit 12), as Logix lists it
_LETTER_CODES = {"SI": 0xC2, "N": 0xC3, "L": 0xC4, "LI": 0xC5, "F": 0xCA, "B": 0xC1}
_RANK = {"rw": 0, "ro": 1, "none": 2}


def _weaker(a: str, b: str) -> str:
    return a if _RANK[a] >= _RANK[b] else b


@dataclass(frozen=True)
class Field:
    """An atomic or string leaf under a structure: ``per`` leaf items (or
    string elements, or bits of a B file) a structure element, byte
    ``offsets`` of each in it."""

    path: tuple[str, ...]
    kind: str  # "atomic", "bool" (a bit of a B file, a byte in the structure) or "string"
    code: int
    per: int
    offsets: tuple[int, ...]
    access: str


@dataclass(frozen=True)
class StructTarget:
    """``units`` structure elements of ``template`` from element ``flat``
    of the leaves under ``path`` of ``tag``."""

    tag: LogixTag
    template: Template
    path: tuple[str, ...]
    flat: int
    units: int
    access: str

    @property
    def type_bytes(self) -> bytes:
        return struct.pack("<BBH", STRUCT, 2, self.template.handle)


def fields(view: LogixView, template: Template) -> list[Field]:
    out: list[Field] = []
    for m in template.members:
        n = max(m.dim, 1)
        if m.kind in ("atomic", "bool"):
            out.append(Field((m.key,), m.kind, m.code, n, tuple(m.offset + j * m.size for j in range(n)), m.access))
        elif m.kind == "string":
            out.append(Field((m.key,), "string", m.code, n, tuple(m.offset + j * STRING_SIZE for j in range(n)),
                             m.access))
        elif m.kind == "struct":
            sub = view.templates[m.template]
            for f in fields(view, sub):
                offsets = tuple(m.offset + j * sub.size + o for j in range(n) for o in f.offsets)
                out.append(Field((m.key,) + f.path, f.kind, f.code, n * f.per, offsets, _weaker(f.access, m.access)))
    return out


class LogixCatalogue:
    """The tags one request sees: each scope's tags in the export's order,
    instance ids 1.. in that order (the controller's list then names each
    program as ``Program:Name``)."""

    def __init__(self, access: TableAccess, view: LogixView) -> None:
        self.access = access
        self.view = view
        self._fields: dict[int, list[Field]] = {}
        self.listed: dict[str | None, list] = {}
        for scope, tags in view.tags.items():
            self.listed[scope] = [t for t in tags if t.access != "none" and self._type_of(t) is not None]
        self.listed.setdefault(None, [])
        self.listed[None] = self.listed[None] + [f"Program:{p}" for p in view.programs]

    def fields_of(self, template: Template) -> list[Field]:
        if template.instance not in self._fields:
            self._fields[template.instance] = fields(self.view, template)
        return self._fields[template.instance]

    # -- the browse ---------------------------------------------------------------------------------
    def scope_of(self, program: str) -> str | None:
        """The scope a ``Program:Name`` segment names; PathError if none."""
        if not program.upper().startswith(PROGRAM_PREFIX):
            raise PathError(PATH_DESTINATION_UNKNOWN, f"{program!r} names no program")
        name = self.view.program(program[len(PROGRAM_PREFIX):])
        if name is None:
            raise PathError(PATH_DESTINATION_UNKNOWN, f"no program {program!r}")
        return name

    def entries(self, scope: str | None) -> list[tuple]:
        """Each listed symbol of ``scope``: (name, symbol type, element
        bytes, dims, external access code, base tag), as tags.py lists them.
        External access is what a client gets: Read Only (2) for a tag the
        export makes Read Only, and for one no ``<Writable>`` opens."""
        out = []
        for item in self.listed.get(scope, []):
            if isinstance(item, str):
                out.append((item, PROGRAM_SYMBOL_TYPE, 0, (), 0, True))
                continue
            symbol_type = self._type_of(item)
            out.append((item.name, symbol_type, self._size_of(symbol_type), self._dims_of(item),
                        0 if item.access == "rw" and self._writable(item) else 2, item.kind != "alias"))
        return out

    def _size_of(self, symbol_type: int) -> int:
        if symbol_type & STRUCT_BIT:
            instance = symbol_type & 0x0FFF
            return STRING_SIZE if instance == STRING_HANDLE else self.view.templates[instance].size
        return ATOMIC_SIZES.get(symbol_type & 0xFF, 0)

    def _writable(self, tag: LogixTag) -> bool:
        if tag.kind == "alias":
            try:
                target = self.resolve(_segments(tag.alias_of), tag.scope, True)
            except PathError:
                return False
            if isinstance(target, StructTarget):
                return target.access == "rw"
            t = target.target
            if t.bit is not None:
                return target.access == "rw" and self.access.writable_bits(t.file, t.item, ~(1 << t.bit), 1 << t.bit)
            return target.access == "rw" and self.access.writable(t.file, t.item, 1)
        for leaf in tag.leaves.values():
            if leaf.letter == "B":
                word, bit = divmod(leaf.first, 16)
                if self.access.writable_bits(leaf.file, word, ~(1 << bit), 1 << bit):
                    return True
            elif self.access.writable(leaf.file, leaf.first * (ST_ITEMS if leaf.letter == "ST" else 1), 1):
                return True
        return False

    def _type_of(self, tag: LogixTag) -> int | None:
        if tag.kind == "alias":
            try:
                target = self.resolve(_segments(tag.alias_of), tag.scope, for_alias=True)
            except PathError:
                return None
            if isinstance(target, StructTarget):
                return STRUCT_BIT | target.template.instance
            return _symbol_code(target)
        return tag.code | (len(tag.dims) << 13)

    def _dims_of(self, tag: LogixTag) -> tuple[int, ...]:
        return tag.dims if tag.kind != "alias" else ()

    # -- paths --------------------------------------------------------------------------------------
    def target(self, segments: list[tuple[str, object]], scope: str | None = None):
        if not segments:
            raise PathError(PATH_SEGMENT_ERROR, "an empty tag path")
        kind, first = segments[0]
        if kind == "name" and str(first).upper().startswith(PROGRAM_PREFIX):
            return self.target(segments[1:], self.scope_of(str(first)))
        return self.resolve(segments, scope)

    def by_instance(self, scope: str | None, instance: int) -> LogixTag:
        tags = self.listed.get(scope, [])
        if not 1 <= instance <= len(tags) or isinstance(tags[instance - 1], str):
            raise PathError(PATH_DESTINATION_UNKNOWN, f"no symbol instance {instance}")
        return tags[instance - 1]

    def resolve(self, segments: list[tuple[str, object]], scope: str | None, for_alias: bool = False):
        kind, first = segments[0]
        if kind == "instance":
            tag = self.by_instance(scope, first)
        elif kind == "name":
            tag = self.view.find(str(first), scope)
            if tag is None and scope is not None and for_alias:
                # an alias in a program sees the controller's tags too, as the program's rungs do;
                # a request's Program:Name.Tag names the program's own tags only
                tag = self.view.find(str(first), None)
            if tag is None:
                raise PathError(PATH_DESTINATION_UNKNOWN, f"no tag named {first!r}")
        else:
            raise PathError(PATH_SEGMENT_ERROR, "a tag path starts with a name or a symbol instance")
        if tag.access == "none":
            raise PathError(PRIVILEGE_VIOLATION, f"{tag.name}: External Access None")
        rest = list(segments[1:])
        if tag.kind == "alias":
            inner = self.resolve(_segments(tag.alias_of), tag.scope, True)
            if rest:
                raise PathError(PATH_SEGMENT_ERROR, f"{tag.name} is an alias: name what it stands for")
            return inner
        return _walk(self, tag, rest)


def _segments(text: str) -> list[tuple[str, object]]:
    """An alias's tag path as request segments: Batches.DN, Tanks[1].Level, Flags.8."""
    out: list[tuple[str, object]] = []
    for name, index in re.findall(r"([A-Za-z_][A-Za-z0-9_:]*|[0-9]+)|\[([^\]]*)\]", text or ""):
        if name:
            out.append(("name", name))
        else:
            out += [("index", int(i)) for i in index.split(",") if i.strip().isdigit()]
    return out


def _symbol_code(target: Target) -> int:
    return target.ctype if target.ctype != STRUCT else (STRUCT_BIT | STRING_HANDLE)


def _walk(cat: LogixCatalogue, tag: LogixTag, rest: list):
    view = cat.view
    kind, code, template = tag.kind, tag.code, tag.template
    dims, path, flat, access = tag.dims, (), 0, tag.access
    rest_in_array = 1  # elements from the one named to the end of its array
    while rest:
        step, value = rest.pop(0)
        if step == "index":
            indexes = [value]
            while rest and rest[0][0] == "index":
                indexes.append(rest.pop(0)[1])
            if not dims or len(indexes) != len(dims):
                raise PathError(PATH_SEGMENT_ERROR,
                                f"{tag.name}: {len(indexes)} index(es) for {len(dims)} dimension(s)")
            k = 0
            for i, size in zip(indexes, dims):
                if i >= size:
                    raise PathError(PATH_DESTINATION_UNKNOWN, f"{tag.name}: index {i} is past its end ({size})")
                k = k * size + i
            flat = flat * math.prod(dims) + k
            rest_in_array = math.prod(dims) - k
            dims = ()
            continue
        if step != "name":
            raise PathError(PATH_SEGMENT_ERROR, "a tag path holds names and indexes")
        if dims:
            raise PathError(PATH_SEGMENT_ERROR, f"{tag.name} is an array: name an element first")
        name = str(value)
        if kind == "atomic" and name.isdigit():
            if rest:
                raise PathError(PATH_SEGMENT_ERROR, "nothing follows a bit number")
            return _bit_of(tag, path, flat, code, int(name), access)
        if kind != "struct":
            raise PathError(PATH_SEGMENT_ERROR, f"{tag.name} has no member {name!r}")
        t = view.templates[template]
        m = t.member(name)
        if m is None:
            raise PathError(PATH_SEGMENT_ERROR, f"{t.name} has no member {name!r}")
        access = _weaker(access, m.access)
        if access == "none":
            raise PathError(PRIVILEGE_VIOLATION, f"{t.name}.{m.name}: External Access None")
        if m.kind == "bit":
            if rest:
                raise PathError(PATH_SEGMENT_ERROR, f"{m.name} is a BOOL: nothing follows it")
            host = t.member(m.host)
            return _bit_of(tag, path + (host.key,), flat, host.code, m.bit, access)
        path += (m.key,)
        kind, code, template = m.kind, m.code, m.template
        dims = (m.dim,) if m.dim else ()
        rest_in_array = 1
    units = math.prod(dims) if dims else rest_in_array
    flat = flat * (math.prod(dims) if dims else 1)
    if kind == "struct":
        t = view.templates[template]
        if any(f.access == "none" for f in cat.fields_of(t)):
            raise PathError(PRIVILEGE_VIOLATION, f"{t.name} holds a member of External Access None")
        return StructTarget(tag, t, path, flat, units, access)
    leaf = tag.leaves[path]
    if kind == "string":
        return _Access(Target(leaf.file, "ST", (leaf.first + flat) * ST_ITEMS, STRUCT, units), access)
    if leaf.letter == "B":
        bit_at = leaf.first + flat
        return _Access(Target(leaf.file, "B", bit_at // 16, BOOL, 1, bit_at % 16), access)
    return _Access(Target(leaf.file, leaf.letter, leaf.first + flat, code, units), access)


def _bit_of(tag: LogixTag, path: tuple, flat: int, code: int, bit: int, access: str):
    if code not in (ATOMIC_CODES["SINT"], ATOMIC_CODES["INT"], ATOMIC_CODES["DINT"], ATOMIC_CODES["LINT"]):
        raise PathError(PATH_SEGMENT_ERROR, f"{tag.name}: .{bit} is not a bit of an integer")
    if bit >= ATOMIC_SIZES[code] * 8:
        raise PathError(PATH_SEGMENT_ERROR, f"{tag.name}: no bit {bit}")
    leaf = tag.leaves[path]
    return _Access(Target(leaf.file, leaf.letter, leaf.first + flat, BOOL, 1, bit), access)


class _Access:
    """An atomic or string Target and the External Access it is reached with."""

    __slots__ = ("target", "access")

    def __init__(self, target: Target, access: str) -> None:
        self.target, self.access = target, access

    @property
    def ctype(self) -> int:
        return self.target.ctype


# -- structures read and written whole ------------------------------------------------------------

_FORMATS = {0xC2: "b", 0xC3: "h", 0xC4: "i", 0xC5: "q", 0xCA: "f", 0xC1: "B"}


async def read_struct(request: CipRequest, access: TableAccess, target: StructTarget, cat: LogixCatalogue,
                      reply_bytes: int) -> CipReply:
    from .tags import EXT_BEYOND_END, EXT_OFFSET_OUT_OF_RANGE, READ_FRAGMENTED

    data = request.data
    count = struct.unpack_from("<H", data, 0)[0]
    offset = struct.unpack_from("<I", data, 2)[0] if request.service == READ_FRAGMENTED else 0
    if count == 0 or count > target.units:
        return CipReply.error(request, st.GENERAL_ERROR, EXT_BEYOND_END)
    total = count * target.template.size
    if offset >= total:
        return CipReply.error(request, st.GENERAL_ERROR, EXT_OFFSET_OUT_OF_RANGE)
    whole = await _struct_bytes(access, target, cat, count)
    room = max(4, (reply_bytes - 4) // 4 * 4)
    part = whole[offset:offset + room]
    status = st.SUCCESS if offset + len(part) == total else st.PARTIAL_TRANSFER
    return CipReply(request.service | REPLY, status, (), target.type_bytes + part)


def _spans(target: StructTarget, cat: LogixCatalogue, count: int):
    """Each field's storage: (field, file, first item, items); a "bool"
    field's first item is a bit number, and its items bits."""
    for f in cat.fields_of(target.template):
        leaf = target.tag.leaves[target.path + f.path]
        first = leaf.first + target.flat * f.per
        if f.kind == "string":
            yield f, leaf.file, first * ST_ITEMS, count * f.per * ST_ITEMS
        else:
            yield f, leaf.file, first, count * f.per


def _words(first_bit: int, bits: int) -> tuple[int, int]:
    """The B file words holding bits first_bit..first_bit+bits-1."""
    return first_bit // 16, (first_bit + bits - 1) // 16 - first_bit // 16 + 1


async def _struct_bytes(access: TableAccess, target: StructTarget, cat: LogixCatalogue, count: int) -> bytes:
    spans = list(_spans(target, cat, count))
    values = await access.read([(file, *_words(first, n)) if f.kind == "bool" else (file, first, n)
                                for f, file, first, n in spans])
    size = target.template.size
    out = bytearray(size * count)
    for (f, _, first, _), items in zip(spans, values):
        for r in range(count * f.per):
            e, q = divmod(r, f.per)
            at = e * size + f.offsets[q]
            if f.kind == "bool":
                bit = first % 16 + r
                out[at] = 1 if items[bit // 16] & (1 << bit % 16) else 0
            elif f.kind == "string":
                element = items[r * ST_ITEMS:(r + 1) * ST_ITEMS]
                chars = bytes(c if 0 <= c < 256 else 0x3F for c in element[1:])
                out[at:at + STRING_SIZE] = struct.pack("<i", element[0]) + chars + b"\x00\x00"
            else:
                struct.pack_into("<" + _FORMATS[f.code], out, at, items[r])
    return bytes(out)


async def write_struct(request: CipRequest, access: TableAccess, target: StructTarget,
                       cat: LogixCatalogue) -> CipReply:
    from .tags import EXT_BEYOND_END, EXT_TYPE_MISMATCH, WRITE_FRAGMENTED

    data = request.data
    if data[:4] != target.type_bytes:
        return CipReply.error(request, st.GENERAL_ERROR, EXT_TYPE_MISMATCH)
    count = struct.unpack_from("<H", data, 4)[0]
    at = 6
    if request.service == WRITE_FRAGMENTED:
        # the whole structure in one request: a fragment of one is refused
        if struct.unpack_from("<I", data, at)[0] != 0:
            return CipReply.error(request, st.GENERAL_ERROR, EXT_BEYOND_END)
        at += 4
    if count == 0 or count > target.units:
        return CipReply.error(request, st.GENERAL_ERROR, EXT_BEYOND_END)
    size = target.template.size
    payload = data[at:]
    if len(payload) < count * size:
        return CipReply.error(request, st.NOT_ENOUGH_DATA)
    if target.access != "rw" or any(f.access != "rw" for f in cat.fields_of(target.template)):
        return CipReply.error(request, st.PRIVILEGE_VIOLATION)
    writes: list[tuple] = []
    for f, file, first, n in _spans(target, cat, count):
        if f.kind == "bool":  # each bit masked into its word, the other BOOLs of the word left as they are
            for r in range(n):
                e, q = divmod(r, f.per)
                word, bit = divmod(first + r, 16)
                on = payload[e * size + f.offsets[q]] & 1
                masks = (0xFFFF & ~(1 << bit), (1 << bit) if on else 0)
                if not access.writable_bits(file, word, *masks):
                    return CipReply.error(request, st.PRIVILEGE_VIOLATION)
                writes.append((file, word, *masks))
            continue
        items: list = []
        for r in range(n if f.kind != "string" else n // ST_ITEMS):
            e, q = divmod(r, f.per)
            where = e * size + f.offsets[q]
            if f.kind == "string":
                length = struct.unpack_from("<i", payload, where)[0]
                if not 0 <= length <= STRING_CHARS:
                    return CipReply.error(request, st.INVALID_ATTRIBUTE_VALUE)
                items.append(length)
                items.extend(payload[where + 4:where + 4 + STRING_CHARS])
            else:
                items.append(struct.unpack_from("<" + _FORMATS[f.code], payload, where)[0])
        if not access.writable(file, first, len(items)):
            return CipReply.error(request, st.PRIVILEGE_VIOLATION)
        writes.append((file, first, items))
    if not await access.write_group(writes):
        return CipReply.error(request, st.PRIVILEGE_VIOLATION)
    return CipReply.ok(request)
