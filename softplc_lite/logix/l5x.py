"""Read a Studio 5000 L5X export (XML) into a ``model.Project``, every
part with its line and column (1-based) in the file.

The file is parsed by expat, which gives each element's position; a
rung's, an ST line's and a comment's position is where its text starts
(inside the CDATA section). Partial exports (TargetType Program, Routine,
Rung, AddOnInstructionDefinition, DataType, Module) hold their parts under
``Controller Use="Context"`` and ``Use="Target"`` elements in the same
places a whole controller does, so one walk reads every kind. A
source-protected AOI or routine (``EncodedData``) is kept with ``encoded``
set, an AOI with its parameters, which are in clear. An element's text is
its CDATA sections' text when it has any, so a pretty-printed file's
indentation is never part of a rung or an ST line.

Tag data: a tag's ``Data`` elements are read ``Format="Decorated"`` first
(members by name), else ``Format="String"`` (a STRING's text), else
``Format="L5K"`` (positional); ``prefer="positional"`` reads the L5K form
first instead, which is what an L5K file holds for the same tag.

Module tag names, a choice following what the exports we gathered show
(rungs of public exports name ``Local:2:I``, ``Local:5:O`` for modules in
the controller's chassis, and Ethernet devices by their own name): a
module whose upstream port is a backplane (ICP, PointIO, Compact ...:
any upstream port not Ethernet, with a numeric Address) sits in its
parent's chassis at that slot, and its tags are
``<ParentModule>:<slot>:<suffix>`` (``Local:1:I`` for the controller's
chassis, ``RemoteAdapter:3:I`` in a remote one); any other module's tags
are ``<Name>:<suffix>``. The suffix is ``C`` for the ConfigTag, and for a
Connection's InputTag and OutputTag its ``InputTagSuffix`` and
``OutputTagSuffix`` when given, else ``I`` and ``O``.

Every problem found is collected and raised at the end as one
``ExportError``; reading goes on past a bad part.
"""

from __future__ import annotations

import xml.parsers.expat as expat
from dataclasses import dataclass, field

from ..ladder.ast import Pos
from .exportfile import read_export
from .modules import describe_structure
from .model import (AddOnInstruction, DataType, ExportError, InitialValue, Line, Member, Module,
                    ModuleTag, Problem, Program, Project, Routine, Rung, Tag, Task)
from .values import MAX_DEPTH, ValueSyntax, flag, parse_l5k_value, parse_quoted, scan_modes, typed_scalar

TARGET_TYPES = ("Controller", "Program", "Routine", "Rung", "AddOnInstructionDefinition", "DataType", "Module")


@dataclass
class _Node:
    tag: str
    attrs: dict
    pos: Pos
    children: list = field(default_factory=list)
    parts: list = field(default_factory=list)  # character data outside CDATA sections
    cdata: list | None = None  # character data inside CDATA sections, once one is seen
    text_pos: Pos | None = None  # where the text starts: a CDATA section's first character,
    # else the first non-blank character

    def child(self, tag: str) -> "_Node | None":
        for c in self.children:
            if c.tag == tag:
                return c
        return None

    def all(self, tag: str) -> list["_Node"]:
        return [c for c in self.children if c.tag == tag]

    @property
    def text(self) -> str:
        """The CDATA sections' text when there are any (the blanks of a
        pretty-printed file around them are not the text), else all text."""
        return "".join(self.cdata if self.cdata is not None else self.parts)


def _parse(data: bytes | str, source: str) -> _Node:
    parser = expat.ParserCreate()
    root = _Node("#document", {}, Pos(source, 1, 1))
    stack = [root]

    def start(tag, attrs):
        node = _Node(tag, attrs, Pos(source, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1))
        stack[-1].children.append(node)
        stack.append(node)

    def end(tag):
        stack.pop()

    in_cdata = False

    def cdata_start():
        nonlocal in_cdata
        in_cdata = True
        node = stack[-1]
        if node.cdata is None:
            node.cdata = []
            # the text starts after "<![CDATA[", which expat reports at its "<"
            node.text_pos = Pos(source, parser.CurrentLineNumber, parser.CurrentColumnNumber + 10)

    def cdata_end():
        nonlocal in_cdata
        in_cdata = False

    def chars(data):
        node = stack[-1]
        if in_cdata:
            node.cdata.append(data)
            return
        if node.text_pos is None:
            stripped = data.lstrip()
            if stripped:
                skipped = data[:len(data) - len(stripped)]
                line = parser.CurrentLineNumber + skipped.count("\n")
                if "\n" in skipped:
                    col = len(skipped) - skipped.rfind("\n")
                else:
                    col = parser.CurrentColumnNumber + 1 + len(skipped)
                node.text_pos = Pos(source, line, col)
        node.parts.append(data)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartCdataSectionHandler = cdata_start
    parser.EndCdataSectionHandler = cdata_end
    parser.buffer_text = False
    parser.Parse(data, True)
    return root


def read_l5x(path_or_text, source_name: str | None = None, prefer: str = "decorated") -> Project:
    """Read an L5X export: a path, or the XML text itself (a str starting
    with ``<``); ``source_name`` names it in positions (the path by
    default). ``prefer="positional"`` reads tag data in its L5K form first."""
    if isinstance(path_or_text, str) and path_or_text.lstrip("\ufeff \t\r\n").startswith("<"):
        data, source = path_or_text.lstrip("\ufeff").encode("utf-8"), source_name or "<l5x>"
    else:
        data, source = read_export(path_or_text, source_name)
    try:
        root = _parse(data, source)
    except expat.ExpatError as e:
        message = expat.ErrorString(e.code)
        raise ExportError([Problem(Pos(source, e.lineno, e.offset + 1), f"malformed XML: {message}")]) from None
    except (LookupError, UnicodeError, ValueError) as e:  # an encoding Python does not know, bytes not in it
        raise ExportError([Problem(Pos(source, 1, 1), f"expected UTF-8 (or the encoding the XML declaration names): {e}")]) from None
    reader = _Reader(source, prefer)
    project = reader.project(root)
    if reader.problems:
        raise ExportError(reader.problems)
    return project



def _dims(text: str | None) -> tuple[int, ...]:
    if not text:
        return ()
    parts = text.replace(",", " ").split()
    dims = tuple(int(p) for p in parts)
    return () if dims == (0,) else dims


class _Reader:
    def __init__(self, source: str, prefer: str) -> None:
        self.source = source
        self.prefer = prefer
        self.problems: list[Problem] = []
        self.module_types: list[DataType] = []

    def problem(self, pos: Pos, message: str) -> None:
        self.problems.append(Problem(pos, message))

    def name(self, node: _Node, what: str) -> str | None:
        name = node.attrs.get("Name")
        if not name:
            self.problem(node.pos, f"expected a Name attribute on this {what}")
            return None
        return name

    def description(self, node: _Node) -> str | None:
        d = node.child("Description")
        return d.text.strip() if d is not None else None

    def int_attr(self, node: _Node, attr: str, default=None):
        text = node.attrs.get(attr)
        if text is None:
            return default
        try:
            return int(text.replace("_", ""))
        except ValueError:
            try:
                return float(text)
            except ValueError:
                self.problem(node.pos, f"expected a number for {attr}, found {text!r}")
                return default

    # -- the whole file ------------------------------------------------------------------

    def project(self, document: _Node) -> Project:
        root = document.children[0] if document.children else None
        project = Project(source=self.source, format="L5X")
        if root is None or root.tag != "RSLogix5000Content":
            self.problem(root.pos if root else document.pos, "expected an RSLogix5000Content element at the top of an L5X export")
            return project
        project.target_type = root.attrs.get("TargetType", "Controller")
        project.target_name = root.attrs.get("TargetName")
        project.software_revision = root.attrs.get("SoftwareRevision")
        if project.target_type not in TARGET_TYPES:
            self.problem(root.pos, f"expected a TargetType of {', '.join(TARGET_TYPES)}, found {project.target_type!r}")
        controller = root.child("Controller")
        if controller is None and root.child("Module") is None:
            self.problem(root.pos, "expected a Controller element in the export")
            return project
        if controller is not None:
            project.controller = controller.attrs.get("Name")
            project.processor_type = controller.attrs.get("ProcessorType")
        # A module export holds its modules at the top, without a Controller.
        for section in (controller or root).children + (root.all("Module") if controller else []):
            if section.tag == "Module":
                project.modules.append(self.module(section))
            elif section.tag == "DataTypes":
                project.data_types += [d for d in map(self.data_type, section.all("DataType")) if d]
            elif section.tag == "Modules":
                project.modules += [m for m in map(self.module, section.all("Module")) if m]
            elif section.tag == "AddOnInstructionDefinitions":
                defs = [c for c in section.children if c.tag == "AddOnInstructionDefinition"
                        or (c.tag == "EncodedData" and c.attrs.get("EncodedType") == "AddOnInstructionDefinition")]
                project.add_on_instructions += [a for a in map(self.aoi, defs) if a]
            elif section.tag == "Tags":
                project.tags += self.tags(section, "Tag")
            elif section.tag == "Programs":
                project.programs += [p for p in map(self.program, section.all("Program")) if p]
            elif section.tag == "Tasks":
                project.tasks += [t for t in map(self.task, section.all("Task")) if t]
        project.module_types = self.module_types
        return project

    # -- data types ----------------------------------------------------------------------

    def data_type(self, node: _Node) -> DataType | None:
        name = self.name(node, "DataType")
        if name is None:
            return None
        dt = DataType(name, family=node.attrs.get("Family", "NoFamily"), description=self.description(node), pos=node.pos)
        members = node.child("Members")
        for m in members.all("Member") if members is not None else []:
            mname = self.name(m, "Member")
            if mname is None:
                continue
            dt.members.append(Member(
                mname, m.attrs.get("DataType", ""), dimension=self.int_attr(m, "Dimension", 0),
                hidden=flag(m.attrs.get("Hidden")), target=m.attrs.get("Target"),
                bit_number=self.int_attr(m, "BitNumber"),
                external_access=m.attrs.get("ExternalAccess", "Read/Write"),
                description=self.description(m), radix=m.attrs.get("Radix"), pos=m.pos))
        return dt

    # -- tags and their data -------------------------------------------------------------

    def tags(self, section: _Node, tag: str) -> list[Tag]:
        return [t for t in (self.tag(n) for n in section.all(tag)) if t]

    def tag(self, node: _Node) -> Tag | None:
        name = self.name(node, node.tag)
        if name is None:
            return None
        a = node.attrs
        tag_type = a.get("TagType", "Base")
        t = Tag(name, a.get("DataType"), dims=_dims(a.get("Dimensions")), tag_type=tag_type,
                alias_for=a.get("AliasFor"), external_access=a.get("ExternalAccess", "Read/Write"),
                constant=flag(a.get("Constant")), description=self.description(node), radix=a.get("Radix"),
                usage=a.get("Usage"), required=flag(a.get("Required")), visible=flag(a.get("Visible"), True),
                pos=node.pos)
        if tag_type == "Alias" and not t.alias_for:
            self.problem(node.pos, f"expected an AliasFor attribute on alias tag {name}")
        t.value = self.data(node, "DefaultData" if node.tag in ("Parameter", "LocalTag") else "Data")
        return t

    def data(self, node: _Node, tag: str) -> InitialValue | None:
        forms = {d.attrs.get("Format"): d for d in node.all(tag)}
        order = ("L5K", "Decorated", "String") if self.prefer == "positional" else ("Decorated", "String", "L5K")
        for fmt in order:
            d = forms.get(fmt)
            if d is None:
                continue
            try:
                if fmt == "L5K":
                    text = d.text.strip()
                    return InitialValue("positional", parse_l5k_value(text), d.text_pos or d.pos)
                if fmt == "String":
                    return InitialValue("decorated", parse_quoted(d.text.strip()), d.text_pos or d.pos)
                content = [c for c in d.children]
                if len(content) != 1:
                    self.problem(d.pos, "expected one DataValue, Array or Structure in decorated data")
                    return None
                return InitialValue("decorated", self.decorated(content[0]), d.pos)
            except ValueSyntax as e:
                at = d.text_pos or d.pos
                if fmt in ("L5K", "String") and d.text_pos is not None:
                    lead = len(d.text) - len(d.text.lstrip())
                    at = _advance(at, d.text[:lead + e.offset])
                self.problem(at, f"bad {fmt} data: {e.message}")
                return None
            except _BadValue as e:
                self.problem(e.node.pos, e.message)
                return None
        return None

    def decorated(self, node: _Node, depth: int = 0):
        a = node.attrs
        if depth > MAX_DEPTH:
            raise _BadValue(node, f"expected at most {MAX_DEPTH} levels of nested structures and arrays")
        if node.tag in ("DataValue", "DataValueMember"):
            if "Value" in a:
                try:
                    return typed_scalar(a["Value"], a.get("DataType"), a.get("Radix"))
                except ValueSyntax as e:
                    raise _BadValue(node, f"bad Value for {a.get('DataType') or 'a value'}: {e.message}") from None
            if node.text.strip():  # a string member's text
                try:
                    return parse_quoted(node.text.strip())
                except ValueSyntax as e:
                    raise _BadValue(node, f"bad string data: {e.message}") from None
            if (a.get("Radix") or "").upper() == "ASCII":  # an empty string member
                return ""
            raise _BadValue(node, f"expected a Value attribute on this {node.tag}")
        if node.tag in ("Structure", "StructureMember"):
            out = {}
            for c in node.children:
                if c.tag in ("DataValueMember", "StructureMember", "ArrayMember"):
                    if not c.attrs.get("Name"):
                        raise _BadValue(c, f"expected a Name attribute on this {c.tag}")
                    out[c.attrs["Name"]] = self.decorated(c, depth + 1)
            return out
        if node.tag in ("Array", "ArrayMember"):
            dims = None
            try:
                dims = _dims(a.get("Dimensions"))
            except ValueError:
                raise _BadValue(node, f"expected Dimensions like \"10\" or \"2,3\", found {a.get('Dimensions')!r}") from None
            elements = []
            for e in node.all("Element"):
                index = e.attrs.get("Index", "")
                try:
                    idx = tuple(int(i) for i in index.strip("[] ").split(","))
                except ValueError:
                    raise _BadValue(e, f"expected an Index like \"[3]\" or \"[1,2]\", found {index!r}") from None
                if "Value" in e.attrs:
                    try:
                        v = typed_scalar(e.attrs["Value"], a.get("DataType"), a.get("Radix"))
                    except ValueSyntax as err:
                        raise _BadValue(e, f"bad Value for {a.get('DataType') or 'an element'}: {err.message}") from None
                elif e.children:
                    v = self.decorated(e.children[0], depth + 1)
                else:
                    raise _BadValue(e, "expected a Value attribute or a Structure in this Element")
                elements.append((idx, v, e))
            return _nest(elements, dims, node)
        raise _BadValue(node, f"expected DataValue, Array or Structure, found {node.tag}")

    # -- modules --------------------------------------------------------------------------

    def module(self, node: _Node) -> Module | None:
        name = node.attrs.get("Name", "")  # a drive's peripheral modules have no name
        a = node.attrs
        m = Module(name, a.get("CatalogNumber"), parent=a.get("ParentModule"), inhibited=flag(a.get("Inhibited")), pos=node.pos)
        ports = node.child("Ports")
        for p in ports.all("Port") if ports is not None else []:
            address = p.attrs.get("Address", "")
            if flag(p.attrs.get("Upstream")) and p.attrs.get("Type") != "Ethernet" and address.isdigit():
                m.slot = int(address)
        prefix = f"{m.parent}:{m.slot}" if m.slot is not None and m.parent and m.parent != name else name
        comms = node.child("Communications")
        if comms is None or not prefix:
            return m
        for c in comms.all("ConfigTag"):
            m.tags.append(self.module_tag(c, f"{prefix}:C"))
        connections = comms.child("Connections")
        for conn in connections.all("Connection") if connections is not None else []:
            for tag, attr, default in (("InputTag", "InputTagSuffix", "I"), ("OutputTag", "OutputTagSuffix", "O")):
                for t in conn.all(tag):
                    m.tags.append(self.module_tag(t, f"{prefix}:{conn.attrs.get(attr) or default}"))
        return m

    def module_tag(self, node: _Node, name: str) -> ModuleTag:
        value = self.data(node, "Data")
        data_type = None
        for d in node.all("Data"):
            if d.attrs.get("Format") == "Decorated" and d.children:
                data_type = d.children[0].attrs.get("DataType")
                if d.children[0].tag == "Structure" and value is not None:  # its depth is bounded
                    describe_structure(d.children[0], self.module_types)
        return ModuleTag(name, data_type, value, node.pos)

    # -- AOIs, programs, routines, tasks ---------------------------------------------------

    def aoi(self, node: _Node) -> AddOnInstruction | None:
        name = self.name(node, "AddOnInstructionDefinition")
        if name is None:
            return None
        aoi = AddOnInstruction(name, revision=node.attrs.get("Revision"), description=self.description(node),
                               encoded=node.tag == "EncodedData", pos=node.pos)
        params = node.child("Parameters")
        if params is not None:
            aoi.parameters = self.tags(params, "Parameter")
        local = node.child("LocalTags")
        if local is not None:
            aoi.local_tags = self.tags(local, "LocalTag")
        aoi.routines = self.routines(node)
        aoi.scan_modes = scan_modes(node.attrs)
        return aoi

    def program(self, node: _Node) -> Program | None:
        name = self.name(node, "Program")
        if name is None:
            return None
        a = node.attrs
        p = Program(name, a.get("MainRoutineName"), a.get("FaultRoutineName"), flag(a.get("Disabled")),
                    description=self.description(node), pos=node.pos)
        tags = node.child("Tags")
        if tags is not None:
            p.tags = self.tags(tags, "Tag")
        p.routines = self.routines(node)
        return p

    def routines(self, node: _Node) -> list[Routine]:
        """A Routines section's routines, a source-protected one (EncodedData)
        kept by its name and Type with ``encoded`` set."""
        section = node.child("Routines")
        out = []
        for c in section.children if section is not None else []:
            if c.tag == "Routine":
                r = self.routine(c)
            elif c.tag == "EncodedData" and c.attrs.get("EncodedType") == "Routine":
                name = self.name(c, "EncodedData")
                r = name and Routine(name, c.attrs.get("Type", ""), description=self.description(c), encoded=True, pos=c.pos)
            else:
                continue
            if r:
                out.append(r)
        return out

    def routine(self, node: _Node) -> Routine | None:
        name = self.name(node, "Routine")
        if name is None:
            return None
        kind = node.attrs.get("Type", "")
        if not kind:  # a context routine of a rung export names no Type: its content tells
            kind = next((k for k in ("RLL", "ST", "FBD", "SFC") if node.child(k + "Content") is not None), "")
        r = Routine(name, kind, description=self.description(node), pos=node.pos)
        # A routine a partial export only refers to (Use="Reference") may name no Type.
        if kind not in ("RLL", "ST", "FBD", "SFC") and node.attrs.get("Use") != "Reference":
            self.problem(node.pos, f"expected a routine Type of RLL, ST, FBD or SFC, found {kind!r}")
        if kind == "RLL":
            content = node.child("RLLContent")
            for n in content.all("Rung") if content is not None else []:
                rung = self.rung(n)
                if rung is not None:
                    r.rungs.append(rung)
        elif kind == "ST":
            content = node.child("STContent")
            for n in content.all("Line") if content is not None else []:
                number = self.int_attr(n, "Number", len(r.lines))
                text = n.text if n.cdata is not None else n.text.strip()
                r.lines.append(Line(number, text, n.text_pos or n.pos))
        return r

    def rung(self, node: _Node) -> Rung | None:
        number = self.int_attr(node, "Number")
        if number is None:
            self.problem(node.pos, "expected a Number attribute on this Rung")
            return None
        text = node.child("Text")
        if text is None or not text.text.strip():
            self.problem(node.pos, f"expected a Text element with the rung's text in rung {number}")
            return None
        comment = node.child("Comment")
        body = text.text
        at = _advance(text.text_pos, body[:len(body) - len(body.lstrip())]) if text.text_pos else text.pos
        return Rung(number, body.strip(), comment.text.strip() if comment is not None else None,
                    node.attrs.get("Type", "N"), at)

    def task(self, node: _Node) -> Task | None:
        name = self.name(node, "Task")
        if name is None:
            return None
        a = node.attrs
        t = Task(name, a.get("Type", "CONTINUOUS"), priority=self.int_attr(node, "Priority", 10),
                 watchdog_ms=float(self.int_attr(node, "Watchdog", 500.0)),
                 inhibited=flag(a.get("InhibitTask")), pos=node.pos)
        if t.kind != "CONTINUOUS" and "Rate" in a:
            t.rate_ms = float(self.int_attr(node, "Rate", 0))
        scheduled = node.child("ScheduledPrograms")
        for s in scheduled.all("ScheduledProgram") if scheduled is not None else []:
            sname = self.name(s, "ScheduledProgram")
            if sname:
                t.programs.append(sname)
        return t


def _advance(pos: Pos, text: str) -> Pos:
    """The position just after ``text``, which starts at ``pos``."""
    if "\n" not in text:
        return Pos(pos.source, pos.line, pos.column + len(text))
    return Pos(pos.source, pos.line + text.count("\n"), len(text) - text.rfind("\n"))


class _BadValue(Exception):
    def __init__(self, node: _Node, message: str) -> None:
        super().__init__(message)
        self.node = node
        self.message = message


def _nest(elements: list, dims: tuple[int, ...] | None, node: _Node) -> list:
    """Decorated array elements (index tuple, value) as nested lists,
    the first index outermost."""
    if not elements:
        return []
    rank = len(elements[0][0])
    if dims and len(dims) != rank:
        dims = None
    out: list = []
    for idx, value, e in elements:
        if len(idx) != rank:
            raise _BadValue(e, f"expected an Index of {rank} dimension(s), found {len(idx)}")
        target = out
        for k, i in enumerate(idx):
            if i < 0 or (dims and i >= dims[k]):
                raise _BadValue(e, f"Index {list(idx)} is outside the array's Dimensions")
            last = k == rank - 1
            while len(target) <= i:
                target.append(None if last else [])
            if last:
                target[i] = value
            else:
                target = target[i]
    return out
