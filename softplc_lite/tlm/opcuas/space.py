"""The OPC UA address space as both processes know it: built in the runtime
from the data table, the program's symbols and the configuration, pickled
to the server process, where asyncua_glue.py makes its nodes.

Every variable names where its value lies in the shared image (the whole
data table, each file at its own offset, as ENIPS lays it out), so the
server process decodes a scan's values from one consistent copy. The
NodeIds are strings in the server's namespace (docs/opcuas.md, "The
address space"): an element or bit by its address (``N7:0``, ``B3:0/5``,
``T4:0.ACC``, ``T4:0/DN``), a symbol by its name, the module's own nodes
by a name that starts with ``$`` (no address or symbol does).
"""

from __future__ import annotations

import struct
from array import array
from dataclasses import dataclass, field

from ...datatable import DataTableError, parse_address
from ...datatable.filetypes import Storage
from ...datatable.table import read_string
from ...ladder import status as S

NAMESPACE = "urn:softplc-lite:opcuas"  # the server's namespace URI: index 2 in a server with no others
APP, DATA_FILES, PLC = "$APP", "$DataFiles", "$PLC"
MODE, FAULT_CODE, SCAN_TIME = "$PLC.Mode", "$PLC.FaultCode", "$PLC.ScanTime"
MODES = {0: "PROGRAM", 1: "RUN", 2: "TEST", 3: "FAULTED"}  # S:105 (ladder/status.py)
BIT_FILES = ("B", "O", "I")  # files whose elements are browsable bit by bit: a choice (docs/opcuas.md)

# OPC UA built-in types (OPC 10000-6, 5.1.2) of each storage's items
KIND_OF_STORAGE = {Storage.WORD: "Int16", Storage.FLOAT: "Float", Storage.LONG: "Int32", Storage.BYTE: "SByte",
                   Storage.LONG64: "Int64"}
_BITS_FORMAT = {1: "=b", 2: "=h", 4: "=i", 8: "=q"}  # a Boolean's host item, by its size
_FORMATS = {"Boolean": "=h", "Int16": "=h", "Float": "=f", "SByte": "=b", "Int64": "=q", "Mode": "=h"}


@dataclass(frozen=True)
class Slot:
    """One data file in the image."""

    name: str  # N7
    letter: str
    typecode: str
    itemsize: int
    offset: int  # bytes, in the image
    items: int
    per: int  # items an element


@dataclass(frozen=True)
class Var:
    node: str  # the NodeId's string
    name: str  # the browse name
    parent: str
    kind: str  # Boolean, Int16, Int32, Float, String, SByte, Int64; Mode: S:105 as words
    offset: int  # of the item in the image, bytes
    slot: int  # its file's index in Space.slots: values are decoded again only where a file changed
    bit: int = -1
    size: int = 2  # bytes the value takes
    description: str = ""
    writable: bool = False  # a <Writable> covers its element


@dataclass(frozen=True)
class Obj:
    node: str
    name: str
    parent: str  # "" for the app's object (under the Objects folder)
    description: str = ""


@dataclass
class Space:
    app: str
    slots: list[Slot] = field(default_factory=list)
    objects: list[Obj] = field(default_factory=list)  # parents before children
    variables: list[Var] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)  # symbols not exposed, and why
    open: dict[str, list[tuple[int, int]]] = field(default_factory=dict)  # file -> [first element, end)
    # a Studio 5000 export's: what its <Writable tag>s open and what its External Access keeps closed
    # (enips/logixconfig.py), file -> [first item, end), bits in a B file
    tags_open: dict[str, list[tuple[int, int]]] | None = None
    tags_closed: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    tag_paths: tuple[str, ...] = ()  # the paths its <Writable tag>s name, upper case, no spaces

    def names_opened(self, node: str) -> bool:
        """Whether a <Writable tag> names the variable ``node`` (a tag path):
        it, or a tag, element or structure holding it, or a bit of it (an
        integer's bit: the integer is what a client writes). A BOOL member
        shares its storage with its neighbours, which the ranges cannot
        tell apart; the path can, so an opened ``Tanks[0].Fill`` leaves
        ``Tanks[0].Drain`` read-only."""
        n = node.upper()
        return any(n == p or n.startswith((p + ".", p + "[")) or (p.startswith(n + ".") and p[len(n) + 1:].isdigit())
                   for p in self.tag_paths)

    def opens(self, file: str, element: int) -> bool:
        """Whether a <Writable> covers the element."""
        return any(lo <= element < hi for lo, hi in self.open.get(file, ()))

    def may_write(self, slot: Slot, item: int, bit: int = -1) -> bool:
        """Whether a client may write ``item`` of ``slot`` (its ``bit`` in a
        Logix app's B file, whose BOOL tags share words)."""
        if self.tags_open is None:
            return self.opens(slot.name, item // slot.per)
        unit = item * 16 + bit if slot.letter == "B" and bit >= 0 else item
        inside = lambda ranges: any(lo <= unit < hi for lo, hi in ranges.get(slot.name, ()))  # noqa: E731
        return inside(self.tags_open) and not inside(self.tags_closed)

    @property
    def image_bytes(self) -> int:
        if not self.slots:
            return 0
        last = self.slots[-1]
        return last.offset + last.items * last.itemsize

    def regions(self) -> list[tuple[str, int, int, int]]:
        return [(s.name, 0, s.items, s.offset) for s in self.slots]


def decode(var: Var, raw: bytes | memoryview):
    """A variable's value from the image's bytes."""
    kind = var.kind
    if kind == "String":
        words = array("h")
        words.frombytes(bytes(raw[var.offset:var.offset + var.size]))
        return read_string(words, 0, len(words) - 1)
    if kind == "Int32":
        return struct.unpack_from("=i", raw, var.offset)[0]
    if kind == "Boolean":
        return bool(struct.unpack_from(_BITS_FORMAT[var.size], raw, var.offset)[0] >> var.bit & 1)
    value = struct.unpack_from(_FORMATS[kind], raw, var.offset)[0]
    if kind == "Mode":
        return MODES.get(value, f"mode {value}")
    return value


def rung_comments(program) -> dict[str, str]:
    """Each element's rung comment: the comment of the first commented rung
    that names it, by its address or a symbol (a choice: the rung that uses
    a value first is the one whose comment says what it is for); keyed by
    the element's address (``N7:5``, ``O:0``)."""
    from ...ladder.ast import AddressRef, Instruction, SymbolRef, walk

    found: dict[str, str] = {}
    if program is None:
        return found
    symbols = {name.upper(): decl.address for name, decl in program.symbols.items()}
    for f in sorted(program.files.values(), key=lambda f: f.number):
        for rung in f.rungs:
            if not rung.comment:
                continue
            for instr in walk(rung.elements):
                if not isinstance(instr, Instruction):
                    continue
                for op in instr.operands:
                    address = op.address if isinstance(op, AddressRef) else \
                        symbols.get(op.name.upper()) if isinstance(op, SymbolRef) else None
                    if address is not None and address.is_direct and address.element is not None:
                        found.setdefault(_element_text(address), " ".join(rung.comment.split()))
    return found


def _element_text(a) -> str:
    return f"{a.type_letter}:{a.element}" if a.type_letter in ("O", "I", "S") else f"{a.file_name()}:{a.element}"


def build_space(table, app: str, config, symbols: dict | None = None, directory=None, comments=None,
                tag_ranges=None) -> Space:
    """The address space of ``table``: ``symbols`` (a program's, name ->
    declaration) and the data files as ``config`` exposes them, and the
    PLC's mode, fault code and scan time always; for a Studio 5000 export,
    its tag ``directory``'s tags in place of the symbols and the files.
    ``comments``: each element's rung comment (``rung_comments``), which
    its nodes' Descriptions say; ``tag_ranges``: the export's (open, closed)
    storage, by file (enips/logixconfig.py)."""
    comments = comments or {}
    space = Space(app)
    if directory is not None:
        space.tags_open, space.tags_closed = tag_ranges or ({}, {})
        space.tag_paths = tuple(w.tag.upper().replace(" ", "") for w in getattr(config, "writable", ())
                                if getattr(w, "tag", None))
    for w in getattr(config, "writable", ()):
        if w.address is None:
            continue
        space.open.setdefault(w.file, []).append((w.address.element, w.last + 1))
    offset = 0
    for f in table.files():
        space.slots.append(Slot(f.name, f.ftype.letter, f.data.typecode, f.data.itemsize, offset, len(f.data),
                                f.ftype.words_per_element))
        offset += len(f.data) * f.data.itemsize
        offset += -offset % 8  # each file aligned: a float or long file's items stay whole
    by_name = {s.name: (k, s, f) for k, (s, f) in enumerate(zip(space.slots, table.files()))}
    space.objects.append(Obj(APP, app, "", f"The PLC {app} (softplc_lite)"))
    space.objects.append(Obj(PLC, "PLC", APP, "The PLC's mode, fault code and scan time"))
    k, s_slot, _ = by_name["S2"]
    at = lambda word: s_slot.offset + word * s_slot.itemsize  # noqa: E731
    space.variables += [
        Var(MODE, "Mode", PLC, "Mode", at(S.MODE_WORD), k, description="PROGRAM, RUN, TEST or FAULTED (S:105)"),
        Var(FAULT_CODE, "FaultCode", PLC, "Int16", at(S.MAJOR_FAULT_CODE), k,
            description="The major fault code, 0 when none (S:12)"),
        Var(SCAN_TIME, "ScanTime", PLC, "Int16", at(S.LAST_SCAN_MS), k, description="The last scan's time, ms (S:8)")]
    if directory is not None:
        if config.tags:
            from .logixspace import add_tags

            add_tags(space, by_name, directory)
        return space
    named: dict[str, list[str]] = {}
    if config.symbols and symbols:
        for decl in sorted(symbols.values(), key=lambda d: d.name.upper()):
            text = str(decl.address)
            problem = _add_symbol(space, by_name, decl.name, text, comments)
            if problem:
                space.skipped.append(f"symbol {decl.name} ({text}): {problem}")
            else:
                named.setdefault(text, []).append(decl.name)
    if config.data_files:
        space.objects.append(Obj(DATA_FILES, "DataFiles", APP, "The data table, by file, element and bit"))
        for k, (slot, f) in enumerate(zip(space.slots, table.files())):
            _add_file(space, k, slot, f.ftype, named, comments)
    return space


def _described(names: list[str] | None, comment: str | None) -> str:
    said = f"Symbol {', '.join(names)}" if names else ""
    return f"{said}: {comment}" if said and comment else said or comment or ""


def _element(space: Space, k: int, slot: Slot, ftype, element: int, node: str, name: str, parent: str,
             description: str = "", bits: bool = False) -> None:
    """The element ``element`` of a file as ``node``: a variable, or an
    object with its members and status bits."""
    first = slot.offset + element * slot.per * slot.itemsize
    w = space.opens(slot.name, element)
    if ftype.letter in ("ST", "SL"):
        space.variables.append(Var(node, name, parent, "String", first, k, size=slot.per * 2, description=description,
                                   writable=w))
        return
    if ftype.word_members:  # a timer, counter or control: an object
        space.objects.append(Obj(node, name, parent, description))
        for m in ftype.word_members:
            space.variables.append(Var(f"{node}.{m.name}", m.name, node, "Int16", first + m.offset * 2, k, writable=w))
        for b in ftype.bit_members:
            space.variables.append(Var(f"{node}.{b.name}" if not node[0].isdigit() and ":" not in node
                                       else f"{node}/{b.name}", b.name, node, "Boolean", first + b.word * 2, k,
                                       bit=b.bit, writable=w))
        return
    kind = KIND_OF_STORAGE[ftype.storage]
    space.variables.append(Var(node, name, parent, kind, first, k, size=slot.itemsize, description=description,
                               writable=w))
    if bits:
        for b in range(16):
            space.variables.append(Var(f"{node}/{b}", str(b), node, "Boolean", first, k, bit=b, writable=w))


def _add_file(space: Space, k: int, slot: Slot, ftype, named: dict[str, list[str]], comments: dict) -> None:
    space.objects.append(Obj(slot.name, slot.name, DATA_FILES, f"{ftype.title} file"))
    bits = ftype.letter in BIT_FILES
    for e in range(slot.items // slot.per):
        address = f"{slot.name}:{e}" if ftype.letter not in ("O", "I", "S") else f"{ftype.letter}:{e}"
        _element(space, k, slot, ftype, e, address, address, slot.name, _described(named.get(address), comments.get(address)), bits)


def _add_symbol(space: Space, by_name: dict, name: str, text: str, comments: dict) -> str | None:
    """The symbol ``name`` at ``text`` as a variable or object under the
    app's; why not, or None."""
    try:
        a = parse_address(text)
    except DataTableError as e:
        return str(e)
    if not a.is_direct or a.element is None:
        return "not a direct address of an element"
    found = by_name.get(a.file_name())
    if found is None:
        return f"no file {a.file_name()} in the data table"
    k, slot, f = found
    ftype = f.ftype
    if (a.element + 1) * slot.per > slot.items:
        return f"past the end of {slot.name}"
    first = slot.offset + a.element * slot.per * slot.itemsize
    w = space.opens(slot.name, a.element)
    comment = comments.get(_element_text(a))
    text = f"{text}: {comment}" if comment else text
    if a.member is not None:
        m = next(m for m in ftype.word_members if m.name == a.member)
        space.variables.append(Var(name, name, APP, "Int16", first + m.offset * 2, k, description=text, writable=w))
        return None
    if a.bit is not None:
        if ftype.storage is not Storage.WORD:
            return "a bit of a file whose items are not words: read its element"
        space.variables.append(Var(name, name, APP, "Boolean", first, k, bit=a.bit, description=text, writable=w))
        return None
    _element(space, k, slot, ftype, a.element, name, name, APP, text)
    return None
