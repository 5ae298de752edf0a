"""Logix data types as softplc_lite lays them out: the atomic types, the
predefined structures (TIMER, COUNTER, CONTROL, STRING, the function-block
FBD_TIMER, FBD_COUNTER and FBD_ONESHOT) and an export's user-defined types,
each resolved once into a ``LogixType``.

A structure's members are listed as Logix lists them (1756-PM020, Logix 5000
Controllers I/O and Tag Data: "Data Types"): a BOOL member of a user-defined
type is a bit of a hidden SINT host member (the export names the host and the
bit: ``Target``, ``BitNumber``); the status bits of TIMER, COUNTER and CONTROL
are bits of their first DINT (EN is bit 31, TT 30, DN 29 ...), which an export
never names, so softplc_lite calls it ``CTL`` (a choice: hidden, as Logix
hides it). STRING (and every type of the string family) is LEN and DATA;
softplc_lite keeps a string whole in an ST element (docs/logix.md).

FBD_TIMER, FBD_COUNTER and FBD_ONESHOT have the members 1756-RM003 lists
for TONR/TOFR/RTOR, CTUD and OSRI/OSFI ("FBD_TIMER Structure" ...); Logix
does not publish where their BOOLs are stored, so softplc_lite packs them
into one hidden DINT, ``CTL`` again (EnableIn bit 0, then each BOOL in
RM003's order: ladder/instr/logix_fbd.py's ``TIMER_BITS`` ...; a choice),
with the edge memories of CTUD and the one-shots (the one-shot's hidden
storage bit) as bits 16 and 17 of it that no member names. InstructFault and PresetInv are bits 0 and 1 of Status, as
RM003 says (Status.0, Status.1). An export's positional (L5K) value of one
of these types is not read, since its layout is Logix's own
(``LogixType.positional``); the decorated value (an L5X's) is, by name.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..ladder.instr.logix_fbd import COUNTER_BITS, ONESHOT_BITS, STATUS_BITS, TIMER_BITS
from .model import DataType, Problem

# Atomic type -> (data table file type letter, bits). BOOL tags are bits of B
# files, 16 a word; the others one item each of the file type of their width.
ATOMIC: dict[str, tuple[str, int]] = {
    "BOOL": ("B", 1),
    "SINT": ("SI", 8),
    "INT": ("N", 16),
    "DINT": ("L", 32),
    "LINT": ("LI", 64),
    "REAL": ("F", 32),
}
STRING_CHARS = 82  # DATA of the predefined STRING (1756-PM020, "STRING data type")
#: A string type longer than STRING_CHARS lives in an SL file of this many
#: code units an element (datatable/filetypes.py LONG_STRING_CHARS).
LONG_STRING_CHARS = 5000


@dataclass
class MemberType:
    """One member: ``bit`` set for a BOOL packed in ``host`` (another
    member's name); ``dim`` a member array's length (0: none)."""

    name: str
    type: "LogixType"
    dim: int = 0
    hidden: bool = False
    host: str | None = None
    bit: int | None = None
    external_access: str = "Read/Write"
    description: str | None = None


@dataclass
class LogixType:
    """``kind``: "atomic", "struct" or "string". An atomic type has its
    file ``letter`` and ``bits``; a structure its members in order (by
    upper-cased name in ``by_name``); a string type its DATA length."""

    name: str
    kind: str
    letter: str | None = None
    bits: int = 0
    members: list[MemberType] = field(default_factory=list)
    by_name: dict[str, MemberType] = field(default_factory=dict)
    chars: int = 0
    builtin: bool = False
    positional: bool = True  # an export's positional (L5K) value is read in ``members``' order

    def member(self, name: str) -> MemberType | None:
        return self.by_name.get(name.upper())

    @property
    def is_atomic(self) -> bool:
        return self.kind == "atomic"

    def visible_members(self) -> list[MemberType]:
        return [m for m in self.members if not m.hidden]


def _struct(name: str, members: list[MemberType], positional: bool = True) -> LogixType:
    t = LogixType(name, "struct", members=members, builtin=True, positional=positional)
    t.by_name = {m.name.upper(): m for m in members}
    return t


_ATOMIC_TYPES = {name: LogixType(name, "atomic", letter, bits, builtin=True) for name, (letter, bits) in ATOMIC.items()}


def _status(word: str, *bits: tuple[str, int]) -> list[MemberType]:
    return [MemberType(n, _ATOMIC_TYPES["BOOL"], host=word, bit=b) for n, b in bits]


def _dint(name: str, hidden: bool = False) -> MemberType:
    return MemberType(name, _ATOMIC_TYPES["DINT"], hidden=hidden)


def _fbd(name: str, bits: tuple[str, ...], dints: tuple[str, ...], status: bool = False) -> LogixType:
    """A function-block structure: ``bits`` in CTL from bit 0, then ``dints``
    (and, for the timers, Status with InstructFault and PresetInv)."""
    members = [_dint("CTL", True), *(_dint(n) for n in dints), *_status("CTL", *((n, k) for k, n in enumerate(bits)))]
    if status:
        members += [_dint("Status"), *_status("Status", *STATUS_BITS)]
    return _struct(name, members, positional=False)


# 1756-RM003 (Logix 5000 Controllers General Instructions): TIMER, COUNTER and CONTROL structures,
# and the FBD_TIMER, FBD_COUNTER and FBD_ONESHOT structures of TONR, TOFR, RTOR, CTUD, OSRI, OSFI.
PREDEFINED: dict[str, LogixType] = {
    **_ATOMIC_TYPES,
    "TIMER": _struct("TIMER", [_dint("CTL", True), _dint("PRE"), _dint("ACC"),
                               *_status("CTL", ("EN", 31), ("TT", 30), ("DN", 29))]),
    "COUNTER": _struct("COUNTER", [_dint("CTL", True), _dint("PRE"), _dint("ACC"),
                                   *_status("CTL", ("CU", 31), ("CD", 30), ("DN", 29), ("OV", 28), ("UN", 27))]),
    "CONTROL": _struct("CONTROL", [_dint("CTL", True), _dint("LEN"), _dint("POS"),
                                   *_status("CTL", ("EN", 31), ("EU", 30), ("DN", 29), ("EM", 28), ("ER", 27),
                                            ("UL", 26), ("IN", 25), ("FD", 24))]),
    "STRING": LogixType("STRING", "string", letter="ST", chars=STRING_CHARS, builtin=True),
    "FBD_TIMER": _fbd("FBD_TIMER", TIMER_BITS, ("PRE", "ACC"), status=True),
    "FBD_COUNTER": _fbd("FBD_COUNTER", COUNTER_BITS, ("PRE", "ACC")),
    "FBD_ONESHOT": _fbd("FBD_ONESHOT", ONESHOT_BITS, ()),
    # MESSAGE: the members a rung reads of a MSG's tag; softplc_lite sends no message (MSG is not
    # run), so its status bits stay as the export or the program leaves them (docs/logix.md).
    "MESSAGE": _struct("MESSAGE", [MemberType("FLAGS", _ATOMIC_TYPES["INT"]),
                                   *_status("FLAGS", ("EW", 2), ("ER", 4), ("DN", 5), ("ST", 6), ("EN", 7),
                                            ("TO", 8), ("EN_CC", 9)),
                                   MemberType("ERR", _ATOMIC_TYPES["INT"]), _dint("EXERR"),
                                   MemberType("ERR_SRC", _ATOMIC_TYPES["SINT"]),
                                   MemberType("DN_LEN", _ATOMIC_TYPES["INT"]),
                                   MemberType("REQ_LEN", _ATOMIC_TYPES["INT"]),
                                   _dint("DestinationLink"), _dint("DestinationNode"), _dint("SourceLink"),
                                   _dint("Class"), _dint("Attribute"), _dint("Instance"),
                                   _dint("LocalIndex"), _dint("Channel"), _dint("Rack"), _dint("Group"),
                                   _dint("Slot"), _dint("RemoteIndex"),
                                   MemberType("RemoteElement", LogixType("STRING", "string", letter="ST", chars=STRING_CHARS,
                                                                         builtin=True)),
                                   MemberType("Path", LogixType("STRING", "string", letter="ST", chars=STRING_CHARS,
                                                                builtin=True)),
                                   _dint("UnconnectedTimeout"), _dint("ConnectionRate"),
                                   MemberType("TimeoutMultiplier", _ATOMIC_TYPES["SINT"])]),
}


class TypeSystem:
    """The types a project may use: the predefined ones and its user-defined
    types (and, later, its AOIs' instance types), resolved with every
    problem said: an unknown member type, a cycle, a BIT member whose host is
    missing, a string type longer than an ST element holds."""

    def __init__(self) -> None:
        self.types: dict[str, LogixType] = {k.upper(): v for k, v in PREDEFINED.items()}
        self.problems: list[Problem] = []
        self.held_not: dict[str, str] = {}  # a user type softplc_lite does not lay out -> why
        self.warnings: list[Problem] = []  # string types taken from their names (implied)

    def implied(self, name: str | None, pos) -> LogixType | None:
        """A string type the export uses but does not define (a program
        export leaves its types out), named as Studio 5000 names string types
        of N characters (``STRING_16``, ``STRING20``): taken as one of N, with
        a warning (a softplc choice)."""
        m = re.fullmatch(r"STRING_?([0-9]+)", (name or "").upper())
        if m is None or not 0 < int(m.group(1)) <= LONG_STRING_CHARS or name.upper() in self.held_not:
            return None
        chars = int(m.group(1))
        t = self.types[name.upper()] = LogixType(name, "string", letter="ST" if chars <= STRING_CHARS else "SL",
                                                 chars=chars)
        self.warnings.append(Problem(pos, f"data type {name} is not in the export: taken as a string type of "
                                          f"{chars} characters, as its name says"))
        return t

    def get(self, name: str | None) -> LogixType | None:
        return self.types.get((name or "").upper())

    @property
    def not_held(self) -> "_NotHeld":
        return _NotHeld(self)

    def add_data_types(self, data_types: list[DataType]) -> None:
        pending = {d.name.upper(): d for d in data_types}
        for d in data_types:
            if not d.members:
                # No members: a type of Logix's own that the export names (Studio writes them as
                # ProductDefined: BOOL, TIMER, UINT ...), not a definition: the predefined one stands,
                # and one softplc_lite does not hold is not held.
                pending.pop(d.name.upper(), None)
                if d.name.upper() not in PREDEFINED:
                    self.held_not[d.name.upper()] = f"data type {d.name} is not one softplc_lite holds yet"
            elif d.name.upper() in PREDEFINED:
                # Logix's own definition of a predefined type (Studio may write it, as ProductDefined):
                # softplc_lite's layout of it stands (no user type may take a predefined type's name).
                pending.pop(d.name.upper(), None)
        resolving: list[str] = []

        def resolve(d: DataType) -> LogixType | None:
            key = d.name.upper()
            if key in self.types:
                return self.types[key]
            if key in resolving:
                self.problems.append(Problem(d.pos, f"data type {d.name} contains itself "
                                                    f"({' -> '.join(resolving[resolving.index(key):] + [key])})"))
                return None
            resolving.append(key)
            try:
                t = self._resolve(d, pending, resolve)
            finally:
                resolving.pop()
            if t is not None:
                self.types[key] = t
            return t

        for d in data_types:
            if d.name.upper() in pending:
                resolve(d)

    def _resolve(self, d: DataType, pending: dict, resolve) -> LogixType | None:
        if d.family.lower().startswith("string"):
            data = next((m for m in d.members if m.name.upper() == "DATA"), None)
            chars = data.dimension if data is not None else 0
            if not 0 < chars <= LONG_STRING_CHARS:
                self.held_not[d.name.upper()] = (f"string type {d.name} holds {chars} characters; softplc_lite "
                                                 f"holds strings of 1 to {LONG_STRING_CHARS}")
                return None
            return LogixType(d.name, "string", letter="ST" if chars <= STRING_CHARS else "SL", chars=chars)
        members: list[MemberType] = []
        ok = True
        for m in d.members:
            if m.data_type.upper() == "BIT":
                host = next((h for h in d.members if h.name.upper() == (m.target or "").upper()), None)
                if host is None or m.bit_number is None:
                    self.problems.append(Problem(m.pos, f"BIT member {m.name} of {d.name}: expected the host member "
                                                        f"(Target) and BitNumber of a member that exists"))
                    ok = False
                    continue
                members.append(MemberType(m.name, PREDEFINED["BOOL"], host=host.name, bit=m.bit_number,
                                          external_access=m.external_access, description=m.description))
                continue
            t = self.types.get(m.data_type.upper())
            if t is None and m.data_type.upper() in pending:
                t = resolve(pending[m.data_type.upper()])
            elif t is None:
                t = self.implied(m.data_type, m.pos)
            if t is None:
                if d.name.upper() not in self.held_not:
                    self.held_not[d.name.upper()] = (f"data type {d.name}: its member {m.name} is a "
                                                     f"{m.data_type}, which softplc_lite does not hold yet")
                ok = False
                continue
            members.append(MemberType(m.name, t, dim=m.dimension, hidden=m.hidden,
                                      external_access=m.external_access, description=m.description))
        if not ok:
            return None
        t = LogixType(d.name, "struct", members=members)
        t.by_name = {m.name.upper(): m for m in members}
        return t


class _NotHeld:
    """``not_held.get(type name)``: why a type softplc_lite does not lay out
    is not held, or None for one it holds. A name neither predefined here
    nor defined by the export is a type of Logix's or of a module's
    (MESSAGE, ALARM_DIGITAL, AB:1756_DI:I:0 ...): Studio 5000 wrote the
    export, so the name is no mistake."""

    def __init__(self, types: TypeSystem) -> None:
        self.types = types

    def get(self, name: str) -> str | None:
        if self.types.get(name) is not None:
            return None
        known = self.types.held_not.get(name.upper())
        if known is not None:
            return known
        return f"data type {name} is not one softplc_lite holds yet"
