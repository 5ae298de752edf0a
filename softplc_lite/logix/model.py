"""A Studio 5000 export as read: what an L5X (XML) or L5K (text) file
holds, in one shape for both formats, every part with its position in the
file. Nothing here is checked against anything else (a tag's data type
existing, a rung's text parsing): that is the loader's work, which reports
every problem at once with these positions.

The names and kinds follow the export's own (Logix 5000 Controllers Import/
Export, 1756-RM084): a ``Tag`` has a ``TagType`` of Base or Alias, a
``Routine`` a ``Type`` of RLL, ST, FBD or SFC, a ``Task`` a ``Type`` of
CONTINUOUS, PERIODIC or EVENT. Names keep their spelling; Logix compares
them without regard to case, and so do the lookups here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from ..ladder.ast import NOWHERE, Pos

# An initial value as the export writes it, before any type is applied:
#   Decorated ("Decorated" data in L5X): int | float | str (a STRING's text) | list (an array's
#     elements) | dict (a structure's members by name, in the export's order)
#   Positional (L5K, and L5X's Format="L5K" data): nested lists of int | float | str, in the
#     type's member order (hidden members included), as the export writes them
Value = Union[int, float, str, list, dict]


@dataclass
class InitialValue:
    """A tag's data: ``form`` is "decorated" (members by name) or
    "positional" (the L5K form: members in the type's order); ``data`` the
    value tree (see ``Value``)."""

    form: str
    data: Value
    pos: Pos = NOWHERE


@dataclass
class Member:
    """One member of a user-defined data type. A BIT member lives in a
    bit of a hidden SINT host member (``target``, ``bit_number``), as
    Logix packs BOOL members."""

    name: str
    data_type: str  # "BIT" for a BOOL packed in a host member
    dimension: int = 0  # a member array's length (0: not an array)
    hidden: bool = False
    target: str | None = None
    bit_number: int | None = None
    external_access: str = "Read/Write"
    description: str | None = None
    radix: str | None = None
    pos: Pos = NOWHERE


@dataclass
class DataType:
    name: str
    members: list[Member] = field(default_factory=list)
    family: str = "NoFamily"  # StringFamily: a string type (LEN and DATA)
    description: str | None = None
    pos: Pos = NOWHERE


@dataclass
class Tag:
    """A tag, an AOI parameter or an AOI local tag. ``dims`` is () for a
    scalar, else up to three dimensions (``DINT[2,3]`` is (2, 3)). An alias
    has ``alias_for`` (a tag path) and no data type of its own. ``usage``:
    an AOI parameter's Input, Output or InOut (None for other tags)."""

    name: str
    data_type: str | None
    dims: tuple[int, ...] = ()
    tag_type: str = "Base"  # Base, Alias, Produced, Consumed
    alias_for: str | None = None
    external_access: str = "Read/Write"  # Read/Write, Read Only, None
    constant: bool = False
    description: str | None = None
    radix: str | None = None
    value: InitialValue | None = None
    usage: str | None = None
    required: bool = False
    visible: bool = True
    pos: Pos = NOWHERE


@dataclass
class Rung:
    """One rung: its neutral text as exported (``XIC(a)OTE(b);``), its
    comment, and where the text starts."""

    number: int
    text: str
    comment: str | None = None
    kind: str = "N"  # L5X's Rung Type: N (normal); edit markers otherwise
    pos: Pos = NOWHERE


@dataclass
class Line:
    """One line of a Structured Text routine."""

    number: int
    text: str
    pos: Pos = NOWHERE


@dataclass
class Routine:
    name: str
    kind: str  # RLL, ST, FBD, SFC
    rungs: list[Rung] = field(default_factory=list)  # RLL
    lines: list[Line] = field(default_factory=list)  # ST
    description: str | None = None
    encoded: bool = False  # source-protected (L5X EncodedData): its content cannot be read
    pos: Pos = NOWHERE


@dataclass
class Program:
    name: str
    main_routine: str | None = None
    fault_routine: str | None = None
    disabled: bool = False  # the program's inhibit
    tags: list[Tag] = field(default_factory=list)
    routines: list[Routine] = field(default_factory=list)
    description: str | None = None
    pos: Pos = NOWHERE


@dataclass
class AddOnInstruction:
    """An Add-On Instruction definition: its parameters (EnableIn and
    EnableOut among them, as the export lists them), local tags and
    routines (Logic, and Prescan, Postscan, EnableInFalse if any)."""

    name: str
    parameters: list[Tag] = field(default_factory=list)
    local_tags: list[Tag] = field(default_factory=list)
    routines: list[Routine] = field(default_factory=list)
    revision: str | None = None
    description: str | None = None
    encoded: bool = False  # source-protected (L5X EncodedData): parameters only, no routines
    # the scan modes the export says to run (ExecutePrescan, ExecutePostscan, ExecuteEnableInFalse),
    # as routine names upper-cased: PRESCAN, POSTSCAN, ENABLEINFALSE; None when the export does not say
    scan_modes: set[str] | None = None
    pos: Pos = NOWHERE


@dataclass
class Task:
    name: str
    kind: str = "CONTINUOUS"  # CONTINUOUS, PERIODIC, EVENT
    rate_ms: float | None = None  # a periodic task's period
    priority: int = 10
    watchdog_ms: float = 500.0
    inhibited: bool = False
    programs: list[str] = field(default_factory=list)  # scheduled, in order
    pos: Pos = NOWHERE


@dataclass
class ModuleTag:
    """A module's input, output or config tag as the export describes it:
    ``Local:1:I`` is module Local's slot 1 input. ``data_type`` is the
    module-defined type's name (``AB:1756_DI:I:0``); ``value`` its data,
    whose decorated structure also tells its members."""

    name: str
    data_type: str | None
    value: InitialValue | None = None
    pos: Pos = NOWHERE


@dataclass
class Module:
    name: str
    catalog_number: str | None = None
    parent: str | None = None
    slot: int | None = None  # the port address on its parent's backplane, when one
    inhibited: bool = False
    tags: list[ModuleTag] = field(default_factory=list)
    pos: Pos = NOWHERE


@dataclass
class Project:
    """A whole export. ``target_type`` says what was exported: Controller,
    Program, Routine, AddOnInstructionDefinition, DataType, Rung (L5X's
    TargetType; a whole L5K is a Controller). A partial export holds the
    parts its target needs (the routine, and the tags and types it uses,
    where the export includes them)."""

    source: str
    format: str  # "L5X" or "L5K"
    target_type: str = "Controller"
    target_name: str | None = None
    controller: str | None = None
    processor_type: str | None = None
    software_revision: str | None = None
    data_types: list[DataType] = field(default_factory=list)
    add_on_instructions: list[AddOnInstruction] = field(default_factory=list)
    modules: list[Module] = field(default_factory=list)
    # The module-defined types (AB:1756_DI:I:0 ...) the modules' decorated data shows, one per
    # name and shape, nested ones included: an export names them but never defines them.
    module_types: list[DataType] = field(default_factory=list)
    tags: list[Tag] = field(default_factory=list)  # controller scope
    programs: list[Program] = field(default_factory=list)
    tasks: list[Task] = field(default_factory=list)


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an export: where, and what was expected."""

    pos: Pos
    message: str

    def __str__(self) -> str:
        return f"{self.pos}: {self.message}"


class ExportError(Exception):
    """An export that cannot be read: every problem found, at once."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        super().__init__("\n".join(str(p) for p in problems))
