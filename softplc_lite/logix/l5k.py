"""Read a Studio 5000 L5K export (text) into a ``model.Project``, every
part with its line and column (1-based) in the file.

The file is ``IE_VER := n;`` and one ``CONTROLLER name (attributes) ...
END_CONTROLLER`` block holding DATATYPE, MODULE,
ADD_ON_INSTRUCTION_DEFINITION, TAG, PROGRAM and TASK blocks (Logix 5000
Controllers Import/Export, 1756-RM084, "L5K"). Attributes are
``(Name := value, ...)``; a tag is ``Name : TYPE[dims] (attributes) :=
value;`` or an alias ``Name OF Target.Path (attributes);``; a ladder
routine's lines are ``RC: "comment";`` (for the rung after it) and ``N:
rung text;`` (a rung may span lines, its strings may hold ``;``); a
Structured Text routine's lines each start with ``'``. ``(* ... *)`` is a
comment between statements. A source-protected AOI or routine
(``ENCODED_DATA (EncodedType := ...)``) is kept with ``encoded`` set, an
AOI with its parameters, which are in clear. Blocks this reader has no use
for (CONFIG, TREND, HISTORY_ENTRY, FBD and SFC routines' content ...) are
skipped to their END_ word. A value may be followed by ``, TagForceData :=
[...]``: forces are not read.

Values are the positional L5K form (``InitialValue(form="positional")``).
The same choices as the L5X reader, so both give equal Projects for the
same controller: a task's rate is kept for PERIODIC and EVENT tasks only
(L5K writes a Rate for a continuous task too, L5X does not); module tags
are ``<Parent>:<Slot>:<suffix>`` for a module with a ``Slot`` and
``<Name>:<suffix>`` otherwise, the suffix C, I and O for ConfigData,
InputData and OutputData. L5K names no module-defined data type, so a
module tag's ``data_type`` is None. A module's ``Mode`` bit 2 is taken as
its inhibit (bit 0 matches L5X's MajorFault in the exports we have; the
inhibit bit is our reading, not confirmed in a manual).

Every problem found is collected and raised at the end as one
``ExportError``; reading goes on past a bad part.
"""

from __future__ import annotations

import re

from .exportfile import read_export
from .model import (AddOnInstruction, DataType, ExportError, InitialValue, Line, Member, Module,
                    ModuleTag, Program, Project, Routine, Rung, Tag, Task)
from .l5k_scan import IDENT, Scanner, split_attrs, split_commas
from .values import ValueSyntax, flag, parse_l5k_value, parse_number, scan_modes, unescape

_TYPE = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_:]*)\s*(?:\[([^\]]*)\])?")
_VERSION = re.compile(r"Version\s*:=\s*RSLogix 5000 v([\d.]+)")
_DATA_SUFFIX = {"configdata": "C", "inputdata": "I", "outputdata": "O"}


def read_l5k(path_or_text, source_name: str | None = None) -> Project:
    """Read an L5K export: a path, or the text itself (a str with a line
    break); ``source_name`` names it in positions (the path by default)."""
    if isinstance(path_or_text, str) and "\n" in path_or_text:
        text, source = path_or_text, source_name or "<l5k>"
    else:
        data, source = read_export(path_or_text, source_name)
        text = data.decode("utf-8-sig", errors="replace")
    reader = _Reader(text.lstrip("\ufeff"), source)
    project = reader.file()
    if reader.problems:
        raise ExportError(reader.problems)
    return project



class _Reader(Scanner):
    def value(self, text: str, at: int) -> InitialValue | None:
        # a value may be followed by ", TagForceData := [...]": the value is the first part
        text = next(split_commas(text))[0]
        lead = len(text) - len(text.lstrip())
        body = text.strip()
        if len(body) >= 2 and body[0] == '"' and body[-1] == '"':  # DefaultData := "[...]"
            body, lead = body[1:-1], lead + 1
        try:
            return InitialValue("positional", parse_l5k_value(body), self.pos(at + lead))
        except ValueSyntax as e:
            self.problem(at + lead + e.offset, f"bad value: {e.message}")
            return None

    # -- the file -------------------------------------------------------------------------

    def file(self) -> Project:
        project = Project(source=self.source, format="L5K")
        m = _VERSION.search(self.t, 0, 2000)
        if m:
            project.software_revision = m.group(1)
        while True:
            self.skip()
            if self.i >= self.n:
                break
            w = self.peek_word()
            if w == "IE_VER":
                self.statement()
            elif w == "CONTROLLER":
                at = self.word()[1]
                name, _, attrs = self.block_header("CONTROLLER")
                project.controller = project.target_name = name
                project.processor_type = attrs.get("processortype")
                self.controller(project, name, at)
            else:
                self.unexpected("IE_VER or CONTROLLER")
        if project.controller is None and not self.problems:
            self.problem(0, "expected a CONTROLLER block in the L5K export")
        return project

    def controller(self, p: Project, name: str, at: int) -> None:
        while not self.end_of("CONTROLLER", name, at):
            w = self.word()
            if w is None:
                self.unexpected("a DATATYPE, MODULE, TAG, PROGRAM, TASK or other block")
                continue
            kind, kat = w
            if kind == "DATATYPE":
                p.data_types.append(self.data_type(kat))
            elif kind == "MODULE":
                p.modules.append(self.module(kat))
            elif kind == "ADD_ON_INSTRUCTION_DEFINITION":
                p.add_on_instructions.append(self.aoi(kat))
            elif kind == "TAG":
                p.tags += self.decls("TAG", kat)
            elif kind == "PROGRAM":
                p.programs.append(self.program(kat))
            elif kind == "TASK":
                p.tasks.append(self.task(kat))
            elif kind == "ENCODED_DATA":
                self.encoded(kat, p.add_on_instructions, None)
            else:
                self.skip_block(kind, "", kat)

    def encoded(self, at: int, into_aois: list | None, into_routines: list | None) -> None:
        """``ENCODED_DATA (EncodedType := ..., Name := ...)``: a
        source-protected AOI (its parameters in clear, then the encoded
        logic) or routine, kept with ``encoded`` set."""
        attrs = self.attrs_here()
        kind, name = attrs.get("encodedtype", ""), attrs.get("name", "")
        if kind == "ADD_ON_INSTRUCTION_DEFINITION" and into_aois is not None:
            aoi = AddOnInstruction(name, revision=attrs.get("revision"), description=attrs.get("description"),
                                   encoded=True, pos=self.pos(at))
            into_aois.append(aoi)
            while not self.end_of("ENCODED_DATA", name, at):
                word = self.peek_word()
                if word in ("PARAMETERS", "LOCAL_TAGS"):
                    wat = self.word()[1]
                    (aoi.parameters if word == "PARAMETERS" else aoi.local_tags).extend(self.decls(word, wat))
                elif word == "HISTORY_ENTRY":
                    self.word()
                    self.skip_block(word, "", self.i)
                else:
                    self.skip_line()  # the encoded logic
            return
        if kind == "ROUTINE" and into_routines is not None:
            into_routines.append(Routine(name, attrs.get("type", "RLL"), description=attrs.get("description"),
                                         encoded=True, pos=self.pos(at)))
        self.skip_block("ENCODED_DATA", name, at)

    def data_type(self, at: int) -> DataType:
        name, _, attrs = self.block_header("DATATYPE")
        dt = DataType(name, family=attrs.get("familytype", "NoFamily"), description=attrs.get("description"), pos=self.pos(at))
        while not self.end_of("DATATYPE", name, at):
            self.skip()
            text, start, _ = self.statement()
            member = self.member(text, start)
            if member is not None:
                dt.members.append(member)
        return dt

    def member(self, text: str, start: int) -> Member | None:
        head, attr_text = split_attrs(text)
        attrs = self.attrs_at(attr_text, start + len(head))[0] if attr_text else {}
        m = re.fullmatch(r"\s*BIT\s+(\w+)\s+(\w+)\s*:\s*(\d+)\s*", head) or \
            re.fullmatch(r"\s*([A-Za-z_][\w:]*)\s+(\w+)\s*(?:\[\s*(\d+)\s*\])?\s*", head)
        if m is None:
            self.problem(start, f"expected a member (TYPE Name[dim] (attributes); or BIT Name Host : bit;), found {text.strip()[:40]!r}")
            return None
        common = dict(hidden=flag(attrs.get("hidden")), external_access=attrs.get("externalaccess", "Read/Write"),
                      description=attrs.get("description"), radix=attrs.get("radix"), pos=self.pos(start))
        if head.strip().startswith("BIT") and m.re.pattern.startswith(r"\s*BIT"):
            return Member(m.group(1), "BIT", target=m.group(2), bit_number=int(m.group(3)), **common)
        return Member(m.group(2), m.group(1), dimension=int(m.group(3) or 0), **common)

    def decls(self, kind: str, at: int, end: str | None = None) -> list[Tag]:
        """The tag declarations of a TAG, PARAMETERS or LOCAL_TAGS block."""
        tags = []
        while not self.end_of(end or kind, kind, at):
            self.skip()
            text, start, _ = self.statement()
            tag = self.decl(text, start)
            if tag is not None:
                tags.append(tag)
        return tags

    def decl(self, text: str, start: int) -> Tag | None:
        m = IDENT.match(text)
        if m is None:
            self.problem(start, f"expected a tag name, found {text.strip()[:30]!r}")
            return None
        name = m.group()
        rest, rat = text[m.end():], start + m.end()
        alias = re.match(r"\s+OF\s+", rest)
        if alias:
            target, attr_text = split_attrs(rest[alias.end():])
            attrs = self.attrs_at(attr_text, rat + alias.end() + len(target))[0] if attr_text else {}
            return self.tag(name, None, (), attrs, None, start, alias_for=target.strip())
        tm = re.match(r"\s*:", rest)
        if tm is None:
            self.problem(rat, f"expected : TYPE or OF Target after the tag name {name}")
            return None
        typ = _TYPE.match(rest, tm.end())
        if typ is None or not typ.group(1):
            self.problem(rat + tm.end(), f"expected a data type for tag {name}")
            return None
        dims: tuple[int, ...] = ()
        if typ.group(2) is not None:
            try:
                dims = tuple(int(d) for d in typ.group(2).split(","))
            except ValueError:
                self.problem(rat + typ.start(2), f"expected dimensions like [10] or [2,3], found [{typ.group(2)}]")
        after = rest[typ.end():]
        aat = rat + typ.end()
        attrs, used = self.attrs_at(after, aat)
        after, aat = after[used:], aat + used
        value = None
        vm = re.match(r"\s*:=", after)
        if vm:
            value = self.value(after[vm.end():], aat + vm.end())
        elif after.strip():
            self.problem(aat + len(after) - len(after.lstrip()), f"expected := value or ; after tag {name}, found {after.strip()[:20]!r}")
        if value is None and "defaultdata" in attrs:
            value = self.value(attrs["defaultdata"], start)
        return self.tag(name, typ.group(1), dims, attrs, value, start)

    def tag(self, name, data_type, dims, attrs, value, start, alias_for=None) -> Tag:
        return Tag(name, data_type, dims, tag_type=_tag_type(attrs, alias_for),
                   alias_for=alias_for, external_access=attrs.get("externalaccess", "Read/Write"),
                   constant=flag(attrs.get("constant")), description=attrs.get("description"),
                   radix=attrs.get("radix"), value=value, usage=attrs.get("usage") or _usage(attrs.get("type")),
                   required=flag(attrs.get("required")), visible=flag(attrs.get("visible"), True), pos=self.pos(start))

    # -- modules --------------------------------------------------------------------------

    def module(self, at: int) -> Module:
        name, _, attrs = self.block_header("MODULE")
        parent = attrs.get("parent")
        m = Module(name, attrs.get("catalognumber"), parent=parent, pos=self.pos(at))
        try:
            m.inhibited = bool(parse_number(attrs.get("mode", "0")) & 4)
            if "slot" in attrs and parent and parent != name:
                m.slot = int(parse_number(attrs["slot"]))
        except (ValueSyntax, TypeError):
            self.problem(at, "expected numbers for the module's Mode and Slot")
        prefix = f"{parent}:{m.slot}" if m.slot is not None else name
        self.module_body(m, prefix, "MODULE", name, at)
        return m

    def module_body(self, m: Module, prefix: str, kind: str, name: str, at: int) -> None:
        while not self.end_of(kind, name, at):
            w = self.word()
            if w is None:
                self.unexpected("module data or a CONNECTION")
                continue
            word, wat = w
            if word == "ExtendedProp":
                end = self.t.find("]]]", self.i)
                self.i = self.n if end < 0 else end + 3
            elif word == "CONNECTION":
                cname, cat, _ = self.block_header("CONNECTION")
                self.module_body(m, prefix, "CONNECTION", cname, cat)
            else:
                text, start, _ = self.statement()
                suffix = _DATA_SUFFIX.get(word.lower())
                if suffix is None:
                    continue  # force data, config scripts: nothing a soft PLC uses
                attrs, used = self.attrs_at(text, start)
                vm = re.match(r"\s*:=", text[used:])
                value = self.value(text[used + vm.end():], start + used + vm.end()) if vm else None
                m.tags.append(ModuleTag(f"{prefix}:{suffix}", None, value, self.pos(wat)))

    # -- AOIs, programs, routines, tasks ---------------------------------------------------

    def aoi(self, at: int) -> AddOnInstruction:
        name, _, attrs = self.block_header("ADD_ON_INSTRUCTION_DEFINITION")
        aoi = AddOnInstruction(name, revision=attrs.get("revision"), description=attrs.get("description"), pos=self.pos(at))
        while not self.end_of("ADD_ON_INSTRUCTION_DEFINITION", name, at):
            w = self.word()
            if w is None:
                self.unexpected("PARAMETERS, LOCAL_TAGS or a routine")
                continue
            word, wat = w
            if word == "PARAMETERS":
                aoi.parameters += self.decls("PARAMETERS", wat)
            elif word == "LOCAL_TAGS":
                aoi.local_tags += self.decls("LOCAL_TAGS", wat)
            elif not self.routine(word, wat, aoi.routines):
                self.skip_block(word, "", wat)
        aoi.scan_modes = scan_modes(attrs)
        return aoi

    def program(self, at: int) -> Program:
        name, _, attrs = self.block_header("PROGRAM")
        p = Program(name, attrs.get("main"), attrs.get("fault"), flag(attrs.get("disableflag")),
                    description=attrs.get("description"), pos=self.pos(at))
        while not self.end_of("PROGRAM", name, at):
            w = self.word()
            if w is None:
                self.unexpected("TAG or a routine")
                continue
            word, wat = w
            if word == "TAG":
                p.tags += self.decls("TAG", wat)
            elif word == "ENCODED_DATA":
                self.encoded(wat, None, p.routines)
            elif not self.routine(word, wat, p.routines):
                self.skip_block(word, "", wat)
        return p

    def routine(self, word: str, at: int, into: list[Routine]) -> bool:
        kinds = {"ROUTINE": "RLL", "ST_ROUTINE": "ST", "FBD_ROUTINE": "FBD", "SFC_ROUTINE": "SFC"}
        if word not in kinds:
            return False
        name, _, attrs = self.block_header(word)
        r = Routine(name, kinds[word], description=attrs.get("description"), pos=self.pos(at))
        into.append(r)
        if r.kind == "RLL":
            self.rungs(r, at)
        elif r.kind == "ST":
            self.st_lines(r, at)
        else:
            self.skip_block(word, name, at)
        return True

    def rungs(self, r: Routine, at: int) -> None:
        comment = None
        while not self.end_of("ROUTINE", r.name, at):
            m = re.compile(r"([A-Z]{1,3})\s*:").match(self.t, self.i)
            if m is None:
                self.unexpected("N: rung text; or RC: \"comment\";")
                continue
            label, self.i = m.group(1), m.end()
            text, start, ended = self.statement()
            lead = len(text) - len(text.lstrip())
            body = text.strip()
            if not ended:
                self.problem(m.start(), f"expected ; to end this {label}: line")
            if label == "RC":
                comment = self.comment(body, start + lead)
                continue
            if not body:
                self.problem(m.start(), f"expected the rung's text after {label}: in rung {len(r.rungs)}")
                comment = None
                continue
            # a long rung continues on indented lines: the break and indent are not rung text
            body = re.sub(r"[ \t]*\r?\n[ \t]*", "", body)
            r.rungs.append(Rung(len(r.rungs), body + ";", comment, label, self.pos(start + lead)))
            comment = None

    def comment(self, body: str, at: int) -> str | None:
        """A rung comment: one or more "quoted" parts (a long comment is
        written as parts on successive lines), joined."""
        parts = []
        k = 0
        while k < len(body):
            if body[k] in " \t\r\n":
                k += 1
                continue
            m = re.compile(r'"((?:[^"$]|\$.)*)"', re.S).match(body, k)
            if m is None:
                self.problem(at + k, 'expected a "quoted" comment after RC:')
                return None
            try:
                parts.append(unescape(m.group(1)))
            except ValueSyntax as e:
                self.problem(at + k + 1 + e.offset, f"bad comment: {e.message}")
                return None
            k = m.end()
        if not parts:
            self.problem(at, 'expected a "quoted" comment after RC:')
            return None
        return "".join(parts).strip()

    def st_lines(self, r: Routine, at: int) -> None:
        while True:
            while self.i < self.n and self.t[self.i] in " \t\r\n":
                self.i += 1
            if self.i < self.n and self.t[self.i] == "'":
                end = self.t.find("\n", self.i)
                end = self.n if end < 0 else end
                r.lines.append(Line(len(r.lines), self.t[self.i + 1:end].rstrip("\r"), self.pos(self.i + 1)))
                self.i = end
            elif self.end_of("ST_ROUTINE", r.name, at):
                return
            else:
                self.unexpected("a ' line of Structured Text or END_ST_ROUTINE")

    def task(self, at: int) -> Task:
        name, _, attrs = self.block_header("TASK")
        t = Task(name, attrs.get("type", "CONTINUOUS"), inhibited=flag(attrs.get("inhibittask")), pos=self.pos(at))
        try:
            t.priority = int(parse_number(attrs.get("priority", "10")))
            t.watchdog_ms = float(parse_number(attrs.get("watchdog", "500")))
            if t.kind != "CONTINUOUS" and "rate" in attrs:
                t.rate_ms = float(parse_number(attrs["rate"]))
        except ValueSyntax as e:
            self.problem(at, f"expected numbers for the task's Rate, Priority and Watchdog: {e.message}")
        while not self.end_of("TASK", name, at):
            text, start, ended = self.statement()
            program = text.strip()
            if not ended or not IDENT.fullmatch(program):
                self.problem(start + len(text) - len(text.lstrip()), f"expected a program name and ; in TASK {name}")
                continue
            t.programs.append(program)
        return t


def _usage(kind: str | None) -> str | None:
    return kind if kind in ("Input", "Output", "InOut") else None


def _tag_type(attrs: dict, alias_for: str | None) -> str:
    """L5X's TagType from what L5K writes: an alias is ``OF`` a target, a
    consumed tag names its Producer, a produced one its ProduceCount."""
    if alias_for:
        return "Alias"
    if "producer" in attrs:
        return "Consumed"
    return "Produced" if "producecount" in attrs else "Base"
