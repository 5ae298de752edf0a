"""I/O module tags as simulated I/O: each module tag of an export
(``Local:1:I``, ``Local:4:C``, ``Drive1:O``) becomes a controller-scoped
tag of its module-defined type, laid out over the data table like any tag,
so rungs, ``--set``, ``--force``, ``--print``, the watch view and the
servers reach it by its path (``Local:1:I.Data.3``, ``Local:4:I.Ch0Fault``).
docs/logix.md ("I/O modules") says it for users; the rules, each a
softplc_lite choice:

- A module-defined type (``AB:1756_IF4_Float:I:0``) is what the tag's
  decorated data shows: each ``DataValueMember`` a member of its DataType,
  each ``ArrayMember`` an array member of its Dimensions (one of none is
  left out: it holds nothing), each ``StructureMember`` (and each structure
  element of an ``ArrayMember``) a member of a module-defined type
  described the same way. The export names these types but never defines
  them (Rockwell's module profiles do), so the decorated data is the only
  description there is. A BOOL member is a
  stand-alone BOOL, as the decorated view shows it (``Ch0Fault``): it is
  reached by name; Logix also shows many of them as a bit of another
  member (``ChannelFaults.0``), a link softplc_lite does not keep.
- A tag whose type the export does not describe (an L5K export, whose
  module data is positional without member names; an L5X tag with L5K data
  only) is not laid out: one warning for its module, and a rung that uses
  the tag is not run (a warning), never an error. So is a rung that uses a
  module tag the export has no data for: a name whose first part is one of
  the export's modules or chassis (``Local:0:O`` where slot 0 holds no
  output module), or any module tag of an export without modules (a
  program or routine export).
- An inhibited module's tags exist and behave as any other module's: the
  I/O is simulated, so there is no connection to inhibit.
- A type described twice alike is one type; described differently (two
  modules of one type name showing other members), the first description
  is used and the others are warned of.
"""

from __future__ import annotations

from . import model
from .model import DataType, Member, Problem, Tag
from .tags import Declared, TagDirectory
from .types import PREDEFINED


# -- reading: the decorated data of a module tag described as DataTypes -------------------------

def describe_structure(node, out: list[DataType]) -> str | None:
    """Describe the module-defined type of the decorated ``Structure``
    ``node`` (an L5X element: ``tag``, ``attrs``, ``children``, ``pos``) and
    of the structures nested in it, appended to ``out`` unless an equal
    description of the same name is there. Returns the type's name."""
    name = node.attrs.get("DataType")
    if not name or name.upper() in PREDEFINED:
        return name
    dt = DataType(name, pos=node.pos)
    for c in node.children:
        mname = c.attrs.get("Name")
        if not mname or c.tag not in ("DataValueMember", "ArrayMember", "StructureMember"):
            continue
        mtype = c.attrs.get("DataType") or ""
        dim = 0
        if c.tag == "ArrayMember":
            dim = 1
            for part in (c.attrs.get("Dimensions") or "0").split(","):
                dim *= int(part) if part.strip().isdigit() else 0
            if dim == 0:  # no element (a generic module's empty config Data): nothing to hold
                continue
            element = next((e.children[0] for e in c.children if e.tag == "Element" and e.children), None)
            if element is not None and element.tag == "Structure":
                mtype = describe_structure(element, out) or mtype
        elif c.tag == "StructureMember":
            mtype = describe_structure(c, out) or mtype
        dt.members.append(Member(mname, mtype, dimension=dim, radix=c.attrs.get("Radix"), pos=c.pos))
    if not any(_same(dt, d) for d in out):
        out.append(dt)
    return name


def _shape(d: DataType) -> list[tuple[str, str, int]]:
    return [(m.name.upper(), m.data_type.upper(), m.dimension) for m in d.members]


def _same(a: DataType, b: DataType) -> bool:
    return a.name.upper() == b.name.upper() and _shape(a) == _shape(b)


# -- loading: module tags declared as controller tags -------------------------------------------

def declare_module_tags(project: model.Project, directory: TagDirectory,
                        problems: list[Problem], warnings: list[Problem]) -> None:
    """Add the module-defined types to ``directory``'s type system and
    declare every module tag as a controller-scoped tag of its type, its
    data the initial value."""
    types = directory.types
    chosen: dict[str, DataType] = {}
    for d in project.module_types:
        first = chosen.setdefault(d.name.upper(), d)
        if first is not d:
            warnings.append(Problem(d.pos, f"module-defined type {d.name} is shown with other members than at "
                                           f"{first.pos}: the first is used"))
    new = [d for d in chosen.values() if types.get(d.name) is None]
    before = len(types.problems)
    types.add_data_types(new)
    warnings += [Problem(p.pos, f"module-defined type: {p.message}; tags of it are not laid out")
                 for p in types.problems[before:]]
    del types.problems[before:]
    controller = directory.scopes[None]
    directory.absent = _absent(project)
    for module in project.modules:
        undescribed = []
        for mt in module.tags:
            key = mt.name.upper()
            if key in controller:
                warnings.append(Problem(mt.pos, f"module {module.name or module.catalog_number}: its tag {mt.name} "
                                                f"has the name of a tag declared before: left out"))
                continue
            tag = _tag(mt, types)
            if tag is None:
                undescribed.append(mt)
                reason = f"a module tag whose members the export does not describe ({_why(project, mt)})"
                controller[key] = Declared(Tag(mt.name, mt.data_type, pos=mt.pos), None, (), None, opaque=reason)
                continue
            directory.declare(tag)
        if undescribed:
            names = ", ".join(t.name for t in undescribed)
            warnings.append(Problem(module.pos, f"module {module.name or module.catalog_number}: "
                                                f"{_why(project, undescribed[0])}, so its tags ({names}) are not "
                                                f"laid out; rungs that use them are not run"))


def _absent(project: model.Project) -> "_Absent":
    """Why a module tag name (``Local:0:O``) that the export does not
    hold is used, or None for a name that is no module's: the export holds
    its modules without that tag's data (a slot with no module, a
    connection with no output), or no modules at all (a partial export)."""
    modules = {m.name.upper() for m in project.modules if m.name}
    modules |= {(m.parent or "").upper() for m in project.modules if m.parent}
    return _Absent(frozenset(modules), not project.modules)


class _Absent:
    """_absent's answer, an object rather than a closure so that the tag
    directory holding it pickles (a failed test's drawing keeps it)."""

    def __init__(self, modules: frozenset[str], partial: bool) -> None:
        self.modules = modules
        self.partial = partial

    def __call__(self, name: str) -> str | None:
        head, colon, _ = name.partition(":")
        if not colon:
            return None
        if self.partial:
            return f"module tag {name}: the export holds no modules"
        if head.upper() in self.modules:
            return f"module tag {name}: the export's modules have no data for it"
        return None


def _why(project: model.Project, mt: model.ModuleTag) -> str:
    if project.format == "L5K":
        return "an L5K export gives module data by position, without member names"
    if mt.data_type is None:
        return "its data is not in decorated form"
    return f"its type {mt.data_type} is named without its members"


def _tag(mt: model.ModuleTag, types) -> Tag | None:
    """The controller tag module tag ``mt`` is, or None when its type is
    not described. Positional data (L5K form) is left out: it holds BOOL
    members as bits of other members, which this layout does not."""
    if mt.data_type is None or (types.get(mt.data_type) is None and mt.data_type.upper() not in types.held_not):
        return None
    value = mt.value if mt.value is not None and mt.value.form == "decorated" else None
    dims: tuple[int, ...] = ()
    t = types.get(mt.data_type)
    if value is not None and isinstance(value.data, list) and t is not None:  # an Array of the type
        dims = (len(value.data),) if value.data else ()
    return Tag(mt.name, mt.data_type, dims=dims, value=value, pos=mt.pos)
