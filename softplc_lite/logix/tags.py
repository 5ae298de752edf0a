"""Tags laid out over the data table, and tag paths resolved to addresses.

Every atomic leaf of a tag (a DINT tag, a REAL member of a UDT, an INT array,
the PRE of a TIMER) lives in data table items of its width (types.ATOMIC):
so the engine, both executors, forces, snapshots, the watch grid and the
servers, which all work on the data table, see tags without knowing of
them; ``TagDirectory`` names them. The layout (docs/logix.md, "Tags over the
data table"; every rule here is a softplc_lite choice):

- A leaf that is one item (a scalar tag, or a member of a scalar structure)
  takes the next item of a file shared by the scalars of its width (16
  BOOLs a word of a shared B file).
- A leaf of an array (an array tag's elements, or a member of an array of
  structures: ``Tanks[i].Level`` for every i) takes a file of its own, item
  k for flat index k (row-major over every dimension on the way): a
  variable index past the array's end is then past the file's end, a major
  fault with code 20, as Logix faults an out-of-range subscript (major
  fault type 4, code 20: 1756-PM014, "Major fault codes").
- A BOOL member of a user-defined type is the bit of its hidden SINT host
  the export names; TIMER, COUNTER and CONTROL status bits are bits of
  their CTL DINT (types.PREDEFINED).
- A string is one ST element.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..datatable import Address, DataTable
from ..datatable.filetypes import MAX_ELEMENTS
from .l5k_scan import split_commas
from .model import Problem, Tag
from .types import LogixType, TypeSystem

FIRST_FILE = 10  # below: the PLC-5 default files (O0 I1 S2 B3 T4 C5 R6 N7 F8)
WORD_BITS = 16

# Logix's status flags (1756-PM001, "Access status flags"), as PLC-5 status bits:
# S:0/0..3 are the arithmetic flags, S:1/15 the first pass.
STATUS_FLAGS = {"S:C": Address("S", 2, 0, None, 0), "S:V": Address("S", 2, 0, None, 1),
                "S:Z": Address("S", 2, 0, None, 2), "S:N": Address("S", 2, 0, None, 3),
                "S:FS": Address("S", 2, 1, None, 15), "S:MINOR": Address("S", 2, 10, None, 14)}


@dataclass
class Leaf:
    """An atomic leaf's storage: ``count`` items of file ``letter`` +
    ``file`` from item ``first`` (for a B file, ``first`` counts bits)."""

    letter: str
    file: int
    first: int
    count: int


@dataclass
class Declared:
    """A tag as the directory holds it: its type, dimensions, scope
    (None: the controller's) and where its leaves are (by member path)."""

    tag: Tag
    type: LogixType | None
    dims: tuple[int, ...]
    scope: str | None
    leaves: dict[tuple[str, ...], Leaf] = field(default_factory=dict)
    opaque: str | None = None  # why the tag is not laid out (a type softplc_lite does not hold)


@dataclass
class Resolved:
    """A tag path resolved. For an atomic value: ``address`` (a bit, a word,
    an element; its element may come from an index tag). For a structure,
    a string or a whole array: ``address`` None and ``node`` says what it
    is; ``leaf_addresses`` lists its atomic leaves."""

    text: str
    type: LogixType
    dims: tuple[int, ...]
    address: Address | None
    declared: Declared | None = None
    path: tuple[str, ...] = ()
    flat: int = 0  # the flat index reached (constant indexes)
    bit: int | None = None
    terms: list = field(default_factory=list)  # indexes made at run time: [text, dimension, stride]


class PathError(Exception):
    def __init__(self, message: str, offset: int = 0) -> None:
        super().__init__(message)
        self.offset = offset


class NotRun(PathError):
    """A path through a tag softplc_lite does not lay out (a type it does
    not hold yet): not a mistake of the export; the rung is not run."""


_STEP = re.compile(r"\s*(?:\.\s*([A-Za-z_][A-Za-z0-9_]*|[0-9]+)|\[((?:[^\[\]]|\[[^\[\]]*\])*)\]|\.\s*\[((?:[^\[\]]|\[[^\[\]]*\])*)\])")
_PROGRAM_SCOPED = re.compile(r"\s*Program:([A-Za-z_][A-Za-z0-9_]*)\.", re.IGNORECASE)
_OBJECT_ATTRIBUTE = re.compile(r"(Task|Program):([A-Za-z_][A-Za-z0-9_]*)\.([A-Za-z_][A-Za-z0-9_]*)",
                               re.IGNORECASE)
_NAME = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*(?::[A-Za-z0-9_]+)*)")


def _count(dims) -> int:
    n = 1
    for d in dims:
        n *= d
    return n


class Allocator:
    """Hands out data table storage: shared files for one-item leaves, a file
    of its own for each array leaf."""

    def __init__(self, table: DataTable) -> None:
        self.table = table
        self.next_file = FIRST_FILE
        self.shared: dict[str, tuple[int, int]] = {}  # letter -> (file, next item or bit)

    def _new_file(self, letter: str, items: int) -> int:
        used = {f.number for f in self.table.files()}
        while self.next_file in used:
            self.next_file += 1
        number = self.next_file
        self.next_file += 1
        self.table.create_file(letter, number, max(items, 1))
        return number

    def one(self, letter: str) -> Leaf:
        limit = MAX_ELEMENTS * (WORD_BITS if letter == "B" else 1)
        file, at = self.shared.get(letter, (None, limit))
        if at >= limit:
            file, at = self._new_file(letter, 1), 0
        self.shared[letter] = (file, at + 1)
        if letter == "B":
            self.table.create_file("B", file, at // WORD_BITS + 1)
        else:
            self.table.create_file(letter, file, at + 1)
        return Leaf(letter, file, at, 1)

    def many(self, letter: str, count: int) -> Leaf:
        items = -(-count // WORD_BITS) if letter == "B" else count
        if items > MAX_ELEMENTS:
            raise PathError(f"{count} elements: an array leaf takes at most {MAX_ELEMENTS} data table items "
                            f"(a softplc_lite limit)")
        return Leaf(letter, self._new_file(letter, items), 0, count)


class TagDirectory:
    """Tags by scope and name, laid out in ``table`` as they are declared."""

    def __init__(self, table: DataTable, types: TypeSystem) -> None:
        self.table = table
        self.types = types
        self.alloc = Allocator(table)
        self.scopes: dict[str | None, dict[str, Declared]] = {None: {}}
        self.problems: list[Problem] = []
        self.warnings: list[Problem] = []
        # (class, instance, attribute), upper case -> the item that holds it: the task and program
        # attributes a program reads and writes with GSV/SSV (logix/tasks.py lays them out)
        self.objects: dict[tuple[str, str, str], Address] = {}
        self.absent = None  # name -> why an undeclared name is not the export's mistake, or None

    # -- declaring -------------------------------------------------------------------------
    def declare(self, tag: Tag, scope: str | None = None) -> Declared | None:
        names = self.scopes.setdefault(scope.upper() if scope else None, {})
        key = tag.name.upper()
        where = f"program {scope}" if scope else "the controller"
        if key in names:
            self.problems.append(Problem(tag.pos, f"tag {tag.name} is declared twice in {where}'s tags"))
            return None
        if tag.tag_type == "Alias" or tag.alias_for:
            d = names[key] = Declared(tag, None, (), scope)
            return d
        t = self.types.get(tag.data_type) or self.types.implied(tag.data_type, tag.pos)
        if t is None:
            reason = self.types.not_held.get(tag.data_type or "")
            if reason is None:
                self.problems.append(Problem(tag.pos, f"tag {tag.name}: unknown data type {tag.data_type!r}"))
                return None
            self.warnings.append(Problem(tag.pos, f"tag {tag.name}: {reason}; rungs that use it are not run"))
            d = names[key] = Declared(tag, None, (), scope, opaque=reason)
            return d
        if len(tag.dims) > 3 or any(d <= 0 for d in tag.dims):
            self.problems.append(Problem(tag.pos, f"tag {tag.name}: dimensions {list(tag.dims)}: expected 1 to 3 "
                                                  f"dimensions, each at least 1"))
            return None
        d = Declared(tag, t, tuple(tag.dims), scope)
        try:
            self.lay_out(d, t, (), _count(d.dims))
        except PathError as e:  # larger than the table holds: a limit of softplc_lite's, not a mistake
            reason = str(e)
            self.warnings.append(Problem(tag.pos, f"tag {tag.name}: {reason}; rungs that use it are not run"))
            d = names[key] = Declared(tag, None, (), scope, opaque=reason)
            return d
        names[key] = d
        return d

    def lay_out(self, d: Declared, t: LogixType, path: tuple[str, ...], count: int) -> None:
        """Give each atomic leaf of ``d`` (of type ``t``, ``count`` of it) its
        data-table words: the tags' own layout, and an Add-On Instruction's or
        a subroutine's parameters laid out like a tag (aoi.py, subroutines.py)."""
        if t.kind == "atomic":
            d.leaves[path] = self.alloc.one(t.letter) if count == 1 else self.alloc.many(t.letter, count)
            return
        if t.kind == "string":
            letter = t.letter or "ST"  # SL: a string type longer than an ST element holds
            d.leaves[path] = self.alloc.one(letter) if count == 1 else self.alloc.many(letter, count)
            return
        for m in t.members:
            if m.host is not None:
                continue  # a bit of its host's leaf
            self.lay_out(d, m.type, path + (m.name.upper(),), count * max(m.dim, 1))

    def hidden_index(self) -> Address:
        """A DINT of its own for an index made at run time (LIDX writes it)."""
        leaf = self.alloc.one("L")
        return Address("L", leaf.file, leaf.first)

    # -- resolving -------------------------------------------------------------------------
    def find(self, name: str, scope: str | None) -> Declared | None:
        if scope:
            d = self.scopes.get(scope.upper(), {}).get(name.upper())
            if d is not None:
                return d
        return self.scopes[None].get(name.upper())

    def resolve(self, text: str, scope: str | None = None, index_of=None, _depth: int = 0) -> Resolved:
        """The tag path ``text`` (``Tank.Level``, ``Arr[3,1].5``, ``T1.DN``,
        ``Tanks[i].Level``) seen from program ``scope``. ``index_of(text)``
        resolves a non-constant index to the Address of the integer holding
        it (None: only constant indexes). Raises PathError with the offset
        in ``text`` of what is wrong and what was expected."""
        flag = STATUS_FLAGS.get(text.strip().upper())
        if flag is not None:
            return Resolved(text, self.types.get("BOOL"), (), flag)
        scoped = _PROGRAM_SCOPED.match(text)
        if scoped:  # Program:Name.Tag, a program's tag named from outside it (as Logix names it)
            program = scoped.group(1)
            if program.upper() not in self.scopes:
                raise PathError(f"no program {program!r}", scoped.start(1))
            inner = self.resolve(text[scoped.end():], program, index_of, _depth)
            return inner
        m = _NAME.match(text)
        if not m:
            raise PathError("expected a tag name", 0)
        name = m.group(1)
        d = self.find(name, scope)
        if d is None:
            why = self.absent(name) if self.absent is not None else None
            if why is not None:  # a name the export does not hold but Logix would (modules.py)
                raise NotRun(why, m.start(1))
            raise PathError(f"unknown tag {name!r}" + (f" (in program {scope} or the controller)" if scope else ""),
                            m.start(1))
        if d.opaque is not None:
            raise NotRun(f"tag {d.tag.name}: {d.opaque}", m.start(1))
        if d.type is None:  # an alias: the path goes on from its target
            if _depth > 8:
                raise PathError(f"alias {name} leads to itself", m.start(1))
            target = self.resolve(d.tag.alias_for or "", d.scope, index_of, _depth + 1)
            rest = text[m.end():]
            if not rest.strip():
                return Resolved(text, target.type, target.dims, target.address, target.declared, target.path,
                                target.flat, target.bit)
            return self.walk(text, m.end(), target.declared, target.type, target.dims, target.path,
                              target.flat, index_of, target.bit, var=target.terms)
        return self.walk(text, m.end(), d, d.type, d.dims, (), 0, index_of, None, var=None)

    def walk(self, text, at, d, t, dims, path, flat, index_of, bit, var):
        """Follow ``[..]``, ``.member``, ``.bit`` and ``.[bit]`` steps from
        ``at`` (a tag path's, or an Add-On Instruction parameter's, aoi.py). An index that is not a constant is a term of the flat index
        (its text, its dimension, its stride), made at run time (``_finish``)."""
        terms: list[list] = list(var or [])
        bit_term = None
        while at < len(text) and text[at:].strip():
            m = _STEP.match(text, at)
            if not m:
                raise PathError("expected .member, .bit or [index]", at)
            member, index, bit_index = m.group(1), m.group(2), m.group(3)
            if index is not None:
                if not dims:
                    raise PathError(f"{text[:m.start()].strip()} is not an array", m.start())
                parts = [part.strip() for part, _ in split_commas(index)]  # i, j+1: top-level commas
                if len(parts) != len(dims):
                    raise PathError(f"{len(parts)} index{'es' if len(parts) != 1 else ''} for an array of "
                                    f"{len(dims)} dimension{'s' if len(dims) != 1 else ''}", m.start() + 1)
                for p, size in zip(parts, dims):
                    flat *= size
                    for term in terms:
                        term[2] *= size
                    if re.fullmatch(r"[0-9]+", p):
                        k = int(p)
                        if k >= size:
                            raise PathError(f"index {k} is past the end of a dimension of {size}", m.start() + 1)
                        flat += k
                    else:
                        terms.append([p, size, 1])
                dims = ()
                at = m.end()
                continue
            if dims:
                raise PathError(f"{text[:m.start()].strip()} is an array: expected [index] before "
                                f".{member or '[' + (bit_index or '') + ']'}", m.start())
            if bit_index is not None or (member is not None and member.isdigit()):
                if t.kind != "atomic" or t.name in ("BOOL", "REAL"):
                    raise PathError(f"a bit of {t.name}: expected an integer (SINT, INT, DINT, LINT)", m.start())
                if bit_index is not None:
                    bit_term = (bit_index.strip(), t.bits)
                else:
                    b = int(member)
                    if b >= t.bits:
                        raise PathError(f"bit {b} of a {t.name}: expected 0 to {t.bits - 1}", m.start() + 1)
                    bit = b
                at = m.end()
                if text[at:].strip():
                    raise PathError("nothing may follow a bit number", at)
                break
            if t.kind == "string" and member.upper() == "LEN":
                leaf_path, at = path, m.end()
                if text[at:].strip():
                    raise PathError("nothing may follow LEN", at)
                r = self._finish(text, d, leaf_path, flat, None, terms, None, t=t, index_of=index_of)
                r.address = Address(r.address.type_letter, r.address.file, r.address.element, "LEN")
                r.type = self.types.get("DINT")
                return r
            if t.kind == "string" and member.upper() == "DATA":
                return self._character(text, m, d, t, path, flat, terms, index_of)
            if t.kind != "struct":
                raise PathError(f"{t.name} has no member {member}" + (" (a string has LEN and DATA)" if t.kind ==
                                                                      "string" else ""), m.start() + 1)
            mt = t.member(member)
            if mt is None:
                names = ", ".join(x.name for x in t.visible_members())
                raise PathError(f"{t.name} has no member {member} (it has {names})", m.start() + 1)
            if mt.host is not None:
                host = t.member(mt.host)
                path, t, bit = path + (host.name.upper(),), host.type, mt.bit
                at = m.end()
                if text[at:].strip():
                    raise PathError(f"{member} is a BOOL: nothing may follow it", at)
                return self._finish(text, d, path, flat, bit, terms, None, boolean=True, index_of=index_of)
            path = path + (mt.name.upper(),)
            t = mt.type
            dims = (mt.dim,) if mt.dim else ()
            at = m.end()
        if dims or t.kind == "struct":
            r = Resolved(text, t, dims, None, d, path, flat, bit)
            r.terms = terms
            return r
        # an atomic value, or a string's ST element
        return self._finish(text, d, path, flat, bit, terms, bit_term, t=t, index_of=index_of)

    def _character(self, text, m, d, t, path, flat, terms, index_of) -> Resolved:
        """``Str.DATA[k]``: code unit k of the string element, the data table
        word member DATAk, typed SINT (docs/logix.md). Only a constant k:
        the member of an element is not computed at run time."""
        step = _STEP.match(text, m.end())
        if step is None or step.group(2) is None:
            raise PathError(f"{t.name}.DATA is SINT[{t.chars}]: expected [index] after DATA", m.end())
        k_text = step.group(2).strip()
        if not re.fullmatch(r"[0-9]+", k_text):
            raise NotRun("a string's DATA indexed at run time is not reached (a constant index is)",
                         step.start() + 1)
        k = int(k_text)
        if k >= t.chars:
            raise PathError(f"index {k} is past the end of {t.name}.DATA (SINT[{t.chars}])", step.start() + 1)
        if text[step.end():].strip():
            raise NotRun("a bit of a string's character is not reached", step.end())
        if terms:
            raise NotRun("a string's DATA in an array indexed at run time is not reached", m.start())
        r = self._finish(text, d, path, flat, None, terms, None, t=t, index_of=index_of)
        r.address = Address(r.address.type_letter, r.address.file, r.address.element, f"DATA{k}")
        r.type = self.types.get("SINT")
        return r

    def _finish(self, text, d, path, flat, bit, terms, bit_term, t=None, boolean=False, index_of=None) -> Resolved:
        leaf = d.leaves.get(path)
        if leaf is None:
            raise PathError(f"{text}: no storage (a softplc_lite bug)", 0)
        result_type = self.types.get("BOOL") if boolean or bit is not None or bit_term else t
        if (terms or bit_term) and index_of is None:
            raise PathError("an index or bit computed at run time: name a constant one here", 0)
        item = leaf.first + flat
        if bit_term is not None:
            bit = index_of([(bit_term[0], bit_term[1], 1)], 0, bit_term[1])
        if terms:
            element = index_of([tuple(term) for term in terms], item, leaf.count)
            if leaf.letter == "B":
                return Resolved(text, result_type, (), Address("B", leaf.file, None, None, element), d, path)
            return Resolved(text, result_type, (), Address(leaf.letter, leaf.file, element, None, bit), d, path)
        if leaf.letter == "B":
            return Resolved(text, result_type, (), Address("B", leaf.file, item // WORD_BITS, None,
                                                           item % WORD_BITS), d, path, flat)
        return Resolved(text, result_type, (), Address(leaf.letter, leaf.file, item, None, bit), d, path, flat, bit)


class TagSymbols(dict):
    """A Logix app's ``program.symbols``: no PLC-5 symbols, and every place
    that takes a name (--print, --set, --force, the watch view, the test
    runner's scenarios, trends) resolves a tag path through the directory
    (ladder/symbols.py calls ``resolve_path``). A task's or program's
    attribute (``directory.objects``) is named ``Task:Name.Attribute`` or
    ``Program:Name.Attribute`` (``Program:Service.DisableFlag``), where no
    tag has that path."""

    def __init__(self, directory: TagDirectory) -> None:
        super().__init__()
        self.directory = directory

    def resolve_path(self, text: str) -> Address:
        from ..ladder.symbols import SymbolError

        try:
            r = self.directory.resolve(text)
        except PathError as e:
            m = _OBJECT_ATTRIBUTE.fullmatch(text.strip())
            found = m and self.directory.objects.get((m.group(1).upper(), m.group(2).upper(), m.group(3).upper()))
            if found:
                return found
            raise SymbolError(text, e.offset, str(e)) from None
        if r.address is None:
            raise SymbolError(text, len(text), f"{text} is a {r.type.name}{' array' if r.dims else ''}: "
                                               f"name one of its values")
        return r.address

    def __reduce__(self):  # a program copy (pickled, deep-copied) keeps the directory
        return (TagSymbols, (self.directory,))


def _unflatten(flat: int, dims: list[int]) -> list[int]:
    out = []
    for size in reversed(dims):
        flat, k = divmod(flat, size)
        out.append(k)
    return out[::-1]


class TagNames:
    """Addresses back to tag paths: what the watch view, fmt and messages
    show for an operand of a Logix app (``Tanks[1].Level`` for F12:1,
    ``SettleTimer.DN`` for a bit of its CTL, ``Tanks[0].Fill`` for a bit of
    its hidden host)."""

    def __init__(self, directory: TagDirectory) -> None:
        self.by_file: dict[int, list[tuple[Declared, tuple[str, ...], Leaf]]] = {}
        for scope in directory.scopes.values():
            for d in scope.values():
                for path, leaf in d.leaves.items():
                    self.by_file.setdefault(leaf.file, []).append((d, path, leaf))

    def name_of(self, address: Address, scope: str | None = None) -> str | None:
        """The tag path ``address`` is, or None (not a tag's item; an
        indirect element). A program's tag is ``Program:Name.Tag`` unless
        ``scope`` is that program (as Logix names it from outside)."""
        if not isinstance(address.file, int) or not isinstance(address.element, int) or address.member:
            return None
        if address.bit is not None and not isinstance(address.bit, int):
            return None
        b_file = address.type_letter == "B"
        item = address.element * WORD_BITS + (address.bit or 0) if b_file else address.element
        for d, path, leaf in self.by_file.get(address.file, ()):
            if leaf.letter == address.type_letter and leaf.first <= item < leaf.first + leaf.count:
                text = _path_text(d, path, item - leaf.first, None if b_file else address.bit)
                if d.scope and (scope or "").upper() != d.scope.upper():
                    text = f"Program:{d.scope}.{text}"
                return text
        return None


def _path_text(d: Declared, path: tuple[str, ...], flat: int, bit: int | None) -> str:
    steps: list[tuple[str | None, list[int]]] = [(None, list(d.dims))]
    t, parent = d.type, None
    for key in path:
        m = t.member(key)
        steps.append((m.name, [m.dim] if m.dim else []))
        parent, t = t, m.type
    dims = [n for _, ds in steps for n in ds]
    indexes = _unflatten(flat, dims)
    hosted = None
    if bit is not None and parent is not None:  # a BOOL member kept in this bit of its host
        hosted = next((m.name for m in parent.members if m.host and m.host.upper() == path[-1] and m.bit == bit),
                      None)
    text, at = d.tag.name, 0
    for name, ds in steps:
        if name is not None:
            text += f".{hosted if hosted and name.upper() == path[-1] else name}"
        if ds:
            text += "[" + ",".join(str(i) for i in indexes[at:at + len(ds)]) + "]"
            at += len(ds)
    return text if bit is None or hosted else f"{text}.{bit}"
