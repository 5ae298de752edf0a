"""A Logix app's tags as the EtherNet/IP server serves them (docs/enips.md,
"Logix tags"): built in the runtime's process from the export's tag
directory (logix/tags.py), picklable, so the server process resolves tag
paths, lays out structures and lists the tags without the directory.

Each tag keeps its export name, scope, dimensions and External Access; each
atomic leaf the data table file and first item the directory gave it. Each
structure type (a user-defined type, TIMER, COUNTER, CONTROL, FBD_TIMER ...) becomes a CIP
template: its members with their byte offsets in the structure as a client
sees it. The byte layout is a softplc_lite choice that follows the rules a
Logix controller's templates show (each atomic member at a multiple of its
size, a structure member at a multiple of 4, the size a multiple of 4, or of
8 with a LINT inside; a BOOL member a bit of its host SINT, the export's
hidden ``ZZZZZZZZZZ...`` member); clients read the offsets from the template,
so they need no more than that it is consistent.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .tagnames import STRING_HANDLE

# CIP type codes of the atomic types (CIP Vol. 1 appendix C).
ATOMIC_CODES = {"BOOL": 0xC1, "SINT": 0xC2, "INT": 0xC3, "DINT": 0xC4, "LINT": 0xC5, "REAL": 0xCA}
ATOMIC_SIZES = {0xC1: 1, 0xC2: 1, 0xC3: 2, 0xC4: 4, 0xC5: 8, 0xCA: 4}
STRUCT_BIT = 0x8000
STRING_SIZE = 88  # DINT LEN + SINT[82] DATA + 2 bytes of padding
# Template instances of the predefined structures: 0x0F00 and up, outside
# the 0x100..0xEFF range CIP leaves to user types (pycomm3 names a
# template outside it by its first name, as Logix's predefined ones are
# named). The numbers are a softplc_lite choice.
PREDEFINED_INSTANCES = {"TIMER": 0x0F83, "COUNTER": 0x0F82, "CONTROL": 0x0F81,
                        "FBD_TIMER": 0x0F84, "FBD_COUNTER": 0x0F85, "FBD_ONESHOT": 0x0F86}
FIRST_USER_INSTANCE = 0x100
ACCESS = {"READ/WRITE": "rw", "READ ONLY": "ro", "NONE": "none"}


def access_of(text: str | None) -> str:
    return ACCESS.get((text or "Read/Write").strip().upper(), "rw")


@dataclass(frozen=True)
class Member:
    """One member of a template. ``kind``: "atomic", "bit" (a BOOL kept in
    a bit of its ``host``), "bool" (a BOOL of its own: a byte, bit 0;
    module-defined types have them), "struct" (``template``), "string"."""

    name: str
    kind: str
    code: int  # the CIP type word: an atomic code, or STRUCT_BIT | template instance
    offset: int
    dim: int = 0  # an array member's length
    bit: int | None = None  # a bit member: its bit in the host's value
    host: str | None = None  # a bit member's host member (upper-cased)
    template: int | None = None
    hidden: bool = False
    access: str = "rw"

    @property
    def key(self) -> str:
        return self.name.upper()

    @property
    def size(self) -> int:
        """Bytes of one element."""
        return ATOMIC_SIZES.get(self.code, 0)


@dataclass(frozen=True)
class Template:
    """A structure type as the Template object (class 0x6C) serves it."""

    instance: int
    handle: int  # the structure handle a read or write names it by
    name: str
    size: int
    members: tuple[Member, ...]
    predefined: bool

    def member(self, name: str) -> Member | None:
        upper = name.upper()
        return next((m for m in self.members if m.key == upper), None)

    def definition(self) -> bytes:
        """Attribute-less Read's data: 8 bytes a member (UINT array size or
        bit, UINT type, UDINT offset), then the name and the member names,
        NUL-terminated, padded to whole 32-bit words. A user type's name is
        followed by ``;n`` and two bytes a member (pylogix reads the second's
        low two bits as the member's access, 0 meaning hidden); a predefined
        type's name stands alone, as pycomm3 expects of one."""
        import struct

        out = bytearray()
        for m in self.members:
            info = m.dim
            offset = m.offset
            if m.kind == "bit":
                # pycomm3 takes a bit member as a bit of the byte at its offset
                offset, info = m.offset + m.bit // 8, m.bit % 8
            elif m.kind == "bool":
                info = 0  # bit 0 of its own byte
            out += struct.pack("<HHI", info, m.code, offset)
        name = self.name.encode("ascii", "replace")
        if not self.predefined:
            name += b";n" + b"".join(bytes((0x41, 0x40 if m.hidden else 0x43)) for m in self.members)
        out += name + b"\x00" + b"".join(m.name.encode("ascii", "replace") + b"\x00" for m in self.members)
        out += bytes(-len(out) % 4)
        return bytes(out)


@dataclass(frozen=True)
class LeafAt:
    """An atomic leaf's storage: file ``file`` (``letter`` its type), from
    item ``first`` (a bit number in a B file)."""

    file: str
    letter: str
    first: int
    count: int


@dataclass(frozen=True)
class LogixTag:
    """A tag as clients reach it."""

    name: str
    scope: str | None  # None: the controller's; else the program's name
    code: int  # an atomic code, or STRUCT_BIT | template instance (STRING: STRUCT_BIT | 0x0FCE)
    kind: str  # "atomic", "struct", "string"
    dims: tuple[int, ...]
    access: str  # "rw", "ro", "none"
    leaves: dict  # member path (upper-cased names) -> LeafAt
    template: int | None = None
    alias_of: "str | None" = None  # an alias: the tag path it stands for (resolved by the server)


@dataclass
class LogixView:
    """Every tag by scope, the templates by instance, the programs."""

    tags: dict[str | None, list[LogixTag]] = field(default_factory=dict)
    templates: dict[int, Template] = field(default_factory=dict)
    programs: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)  # tags not served, and why

    def find(self, name: str, scope: str | None) -> LogixTag | None:
        upper = name.upper()
        for tag in self.tags.get(scope, []):
            if tag.name.upper() == upper:
                return tag
        return None

    def program(self, name: str) -> str | None:
        upper = name.upper()
        return next((p for p in self.programs if p.upper() == upper), None)


def _align(at: int, to: int) -> int:
    return at + (-at % to)


class _Builder:
    def __init__(self) -> None:
        self.view = LogixView()
        self.by_type: dict[str, int] = {}
        self.next_user = FIRST_USER_INSTANCE

    def type_code(self, t) -> tuple[str, int, int | None]:
        """(kind, CIP type word, template instance) of a LogixType."""
        if t.kind == "atomic":
            return "atomic", ATOMIC_CODES[t.name], None
        if t.kind == "string":
            if t.chars != 82:
                raise ValueError(f"string type {t.name} of {t.chars} characters is not served yet (STRING is)")
            return "string", STRUCT_BIT | STRING_HANDLE, None
        instance = self.template(t)
        return "struct", STRUCT_BIT | instance, instance

    def template(self, t) -> int:
        key = t.name.upper()
        if key in self.by_type:
            return self.by_type[key]
        predefined = key in PREDEFINED_INSTANCES
        if predefined:
            instance = PREDEFINED_INSTANCES[key]
        else:
            instance = self.next_user
            self.next_user += 1
        self.by_type[key] = instance
        members: list[Member] = []
        at, largest = 0, 4
        positions: dict[str, int] = {}
        for m in t.members:
            if m.host is not None:
                continue
            kind, code, sub = self.type_code(m.type)
            if kind == "atomic" and m.type.name == "BOOL":
                if m.dim:
                    raise ValueError(f"{t.name}.{m.name}: a BOOL array member is not served yet")
                kind = "bool"
            if kind in ("atomic", "bool"):
                size = ATOMIC_SIZES[code]
                align = size
            elif kind == "string":
                size, align = STRING_SIZE, 4
            else:
                size = self.view.templates[sub].size
                align = 8 if self.view.templates[sub].size % 8 == 0 and _has_lint(self.view.templates[sub],
                                                                                   self.view.templates) else 4
            largest = max(largest, align)
            at = _align(at, align)
            positions[m.name.upper()] = at
            members.append(Member(m.name, kind, code, at, m.dim, template=sub, hidden=m.hidden,
                                  access=access_of(m.external_access)))
            at += size * max(m.dim, 1)
        for m in t.members:
            if m.host is None:
                continue
            host = m.host.upper()
            members.append(Member(m.name, "bit", ATOMIC_CODES["BOOL"], positions[host], bit=m.bit, host=host,
                                  hidden=m.hidden, access=access_of(m.external_access)))
        # a bit member stays beside its host in the list, as the export orders them
        order = {mt.name.upper(): k for k, mt in enumerate(t.members)}
        members.sort(key=lambda m: order[m.key])
        size = _align(max(at, 1), largest)
        handle = instance if predefined else _handle(t.name, members, size)
        self.view.templates[instance] = Template(instance, handle, t.name, size, tuple(members), predefined)
        return instance


def _has_lint(template: Template, templates: dict[int, Template]) -> bool:
    return any(m.code == ATOMIC_CODES["LINT"] or (m.template is not None and _has_lint(templates[m.template],
                                                                                        templates))
               for m in template.members)


def _handle(name: str, members: list[Member], size: int) -> int:
    """A user type's structure handle: Logix's is a CRC of the definition;
    here a CRC-16 of the name, the members and the size (a choice), never
    one of the predefined handles."""
    import binascii

    text = name.upper() + ";" + ",".join(f"{m.key}:{m.code}:{m.offset}:{m.dim}:{m.bit}" for m in members)
    value = binascii.crc_hqx(f"{text};{size}".encode(), 0)
    return value if value not in (STRING_HANDLE, *PREDEFINED_INSTANCES.values()) else value ^ 0x5555


def build_view(directory, programs: list[str] | tuple = ()) -> LogixView:
    """The view of a ``logix.tags.TagDirectory``: every tag it lays out
    (controller tags, then each program's), aliases as the paths they
    stand for; a tag of a type not held, or not served yet, in ``skipped``.
    ``programs``: every program's name, those without tags too."""
    b = _Builder()
    view = b.view
    for scope, names in directory.scopes.items():
        label = None if scope is None else _program_name(directory, scope)
        if label is not None:
            view.programs.append(label)
        out = view.tags.setdefault(label, [])
        for declared in names.values():
            tag = declared.tag
            access = access_of(tag.external_access)
            if declared.type is None:
                if declared.opaque is not None:
                    view.skipped.append(f"{tag.name}: {declared.opaque}")
                elif tag.alias_for:
                    out.append(LogixTag(tag.name, label, 0, "alias", (), access, {}, alias_of=tag.alias_for))
                continue
            try:
                kind, code, template = b.type_code(declared.type)
            except ValueError as e:
                view.skipped.append(f"{tag.name}: {e}")
                continue
            leaves = {path: LeafAt(f"{leaf.letter}{leaf.file}", leaf.letter, leaf.first, leaf.count)
                      for path, leaf in declared.leaves.items()}
            out.append(LogixTag(tag.name, label, code, kind, tuple(declared.dims), access, leaves, template))
    for name in programs:
        if view.program(name) is None:
            view.programs.append(name)
            view.tags.setdefault(name, [])
    return view


def _program_name(directory, scope: str) -> str:
    """A program's name as the export spells it (scopes are upper-cased)."""
    for d in directory.scopes.get(scope, {}).values():
        if d.scope:
            return d.scope
    return scope
