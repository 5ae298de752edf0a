"""Add-On Instructions (1756-PM010, Logix 5000 Controllers Add-On
Instructions): each definition a data type, each call a copy of its Logic.
docs/logix.md, "Add-On Instructions", says it for users; the rules:

- **The instance type** (``add_instance_types``): a structure named as the
  AOI whose members are EnableIn, EnableOut, the Input and Output parameters
  and the local tags, in the export's order (an InOut parameter is a
  reference, not a member: PM010 "Parameters"). Every BOOL member is a bit of
  a hidden DINT host (32 a host, the hosts first), as the export's L5K data
  packs them (``[1,0.0,...]``: EnableIn is bit 0, EnableOut bit 1): a
  softplc choice of layout that reads both data forms. A tag of the AOI's type
  is laid out as any structure (tags.py); the parameters' DefaultData and the
  local tags' data are each instance's values before the tag's own data
  (``AoiCalls.defaults``).
- **A call** ``Name(instance, arg...)``: the arguments follow the required
  parameters in order (PM010 "Parameters": an Input argument a tag or a
  constant, an Output one a tag, an InOut one a tag of the parameter's type).
  The Logic routine is translated once per call site into a program file of
  its own, in which a parameter or local tag is ``instance.Member`` and an
  InOut parameter is the argument passed (a variable index of the instance or
  of an InOut argument is computed once at the call, as Logix binds the
  reference when the instruction is called). The rung gets, where the call
  stands, ``LAIN ... XIC EnableIn JSR logic LAOUT ...``
  (ladder/instr/logix_aoi.py): EnableIn is the rung-in, the inputs are copied
  in, the Logic runs if EnableIn is true (the EnableInFalse routine if not,
  when the export says to run one), the outputs are copied out and EnableOut
  is the rung-out. A Prescan routine the export says to run runs at the call
  in the first scan (S:FS), before the Logic: the engine has no prescan. A
  call inside an AOI's logic (nesting) is made the same way.
- **Not run**: a source-protected AOI (its logic cannot be read), one whose
  Logic is neither RLL nor ST, one whose instance type is not held, one with an InOut
  parameter of a type not held (MODULE): each call is a warning and its rung
  is not run. A call's wrong operand count or argument kind, or an AOI that
  calls itself, is an error at the call.
- **An AOI no rung calls** has its logic made once over hidden storage, in a
  file no rung calls, so its problems are said (``check_uncalled``).
"""

from __future__ import annotations

import re

from ..ladder.ast import AddressRef, Branch, Const, Instruction, Pos, ProgramFile
from . import model
from .expr import ExprError, number, parse_expression
from .initial import apply_initial
from .l5k_scan import split_commas
from .languages import LANGUAGES, routine_rungs
from .rungs import RoutineContext, _at, _resolve_ref
from .tags import _NAME, STATUS_FLAGS, Declared, Leaf, NotRun, PathError, Resolved, TagDirectory
from .types import PREDEFINED, MemberType, LogixType, TypeSystem

ENABLE = ("ENABLEIN", "ENABLEOUT")
HOST = "__Bools{}"  # a hidden BOOL host (two underscores: no Logix name has them)
HIDDEN = "__AOI{}"  # a call's index computed once (see _bind)
HOST_BITS = 32
NO_LIMIT = 2 ** 31 - 1
HAS_EIF = 1


def _members(aoi: model.AddOnInstruction) -> list[model.Tag]:
    """The instance's members: EnableIn and EnableOut (Logix's own, kept
    even where a hand-made export leaves them out), the Input and Output
    parameters, the local tags."""
    named = {p.name.upper() for p in aoi.parameters}
    enable = [model.Tag(n, "BOOL", usage=u, pos=aoi.pos) for n, u in (("EnableIn", "Input"), ("EnableOut", "Output"))
              if n.upper() not in named]
    return enable + [p for p in aoi.parameters if (p.usage or "").upper() != "INOUT"] + list(aoi.local_tags)


def _is_bool(tag: model.Tag) -> bool:
    return (tag.data_type or "").upper() == "BOOL" and not tag.dims


def add_types(types: TypeSystem, data_types: list[model.DataType], aois: list[model.AddOnInstruction]) -> None:
    """The export's user-defined types and AOI instance types into
    ``types``: each may use the other (a UDT member of an AOI's type, an AOI
    local tag of a UDT), so a type not held for a type made after it is made
    again, until no more is."""
    types.add_data_types(data_types)
    add_instance_types(types, aois)
    while True:
        retry = [d for d in data_types if d.members and d.name.upper() not in types.types
                 and d.name.upper() in types.held_not]
        again = [a for a in aois if a.name.upper() not in types.types]
        if not retry and not again:
            return
        held = len(types.types)
        for name in [d.name for d in retry] + [a.name for a in again]:
            types.held_not.pop(name.upper(), None)
        types.add_data_types(retry)
        add_instance_types(types, again)
        if len(types.types) == held:
            return


def add_instance_types(types: TypeSystem, aois: list[model.AddOnInstruction]) -> None:
    """Each AOI's instance type into ``types`` (an AOI's local tag may be of
    another AOI's type: resolved in the order they depend on each other)."""
    pending = {a.name.upper(): a for a in aois}
    for key, aoi in list(pending.items()):
        if key in types.types:
            types.problems.append(model.Problem(aoi.pos, f"Add-On Instruction {aoi.name}: a data type of that name "
                                                         f"exists already"))
            del pending[key]
    progress = True
    while pending and progress:
        progress = False
        for key, aoi in list(pending.items()):
            t = _instance_type(aoi, types, pending)
            if t is not None:
                types.types[key] = t
                del pending[key]
                progress = True
    for key, aoi in pending.items():
        if key not in types.held_not:
            types.held_not[key] = f"Add-On Instruction {aoi.name} uses itself as a local tag's type"


def _instance_type(aoi, types: TypeSystem, pending) -> LogixType | None:
    members = _members(aoi)
    bools = [m for m in members if _is_bool(m)]
    hosts = [MemberType(HOST.format(k), PREDEFINED["DINT"], hidden=True)
             for k in range(-(-len(bools) // HOST_BITS))]
    out = list(hosts)
    k = 0
    for m in members:
        if _is_bool(m):
            out.append(MemberType(m.name, PREDEFINED["BOOL"], host=hosts[k // HOST_BITS].name, bit=k % HOST_BITS,
                                  external_access=m.external_access, description=m.description))
            k += 1
            continue
        key = (m.data_type or "").upper()
        t = types.types.get(key)
        if t is None:
            if key in pending:
                return None  # another AOI not yet made
            types.held_not[aoi.name.upper()] = (f"Add-On Instruction {aoi.name}: its {m.name} is a {m.data_type}, "
                                                f"which softplc_lite does not hold yet")
            pending.pop(aoi.name.upper(), None)
            return None
        if len(m.dims) > 1:
            types.held_not[aoi.name.upper()] = (f"Add-On Instruction {aoi.name}: its {m.name} has "
                                                f"{len(m.dims)} dimensions; softplc_lite holds members of one")
            pending.pop(aoi.name.upper(), None)
            return None
        out.append(MemberType(m.name, t, dim=m.dims[0] if m.dims else 0, external_access=m.external_access,
                              description=m.description))
    t = LogixType(aoi.name, "struct", members=out)
    t.by_name = {m.name.upper(): m for m in out}
    return t


class _Names:
    """The names an AOI's logic sees, for one call: each parameter and local
    tag is a path of the caller's (``mapping``), an index computed at the
    call is its hidden DINT (``hidden``); anything else is not the AOI's to
    name. Everything else is the tag directory's."""

    def __init__(self, directory: TagDirectory, mapping: dict[str, str], hidden: dict, aoi: str) -> None:
        self.directory = directory
        self.mapping = mapping
        self.hidden = hidden
        self.aoi = aoi

    def __getattr__(self, name):
        return getattr(self.directory, name)

    def resolve(self, text: str, scope=None, index_of=None, _depth: int = 0) -> Resolved:
        if text.strip().upper() in STATUS_FLAGS:
            return self.directory.resolve(text, scope, index_of)
        m = _NAME.match(text)
        if m is None:
            raise PathError("expected a tag name", 0)
        key = m.group(1).upper()
        if key in self.hidden and isinstance(self.hidden[key], Declared):
            return self._resolve_top(text, scope, index_of)
        if key in self.hidden and not text[m.end():].strip():
            return Resolved(text, PREDEFINED["DINT"], (), self.hidden[key])
        target = self.mapping.get(key)
        if target is None:
            raise PathError(f"unknown tag {m.group(1)!r}: the logic of Add-On Instruction {self.aoi} names only its "
                            f"parameters and local tags", m.start(1))
        try:
            return self._resolve_top(target + text[m.end():], scope, index_of)
        except PathError as e:
            at = e.offset - len(target) + m.end()
            raise type(e)(str(e), at if at >= m.end() else m.start(1)) from None

    def _resolve_top(self, text: str, scope, index_of) -> Resolved:
        """A path of the outermost caller: a tag's, or one of a hidden tag
        that stands for an instance or argument when an AOI no rung calls is
        checked (``AoiCalls.check_uncalled``)."""
        m = _NAME.match(text)
        h = self.hidden.get(m.group(1).upper()) if m else None
        if isinstance(h, Declared):
            return self.directory.walk(text, m.end(), h, h.type, h.dims, (), 0, index_of, None, var=None)
        return self.directory.resolve(text, scope, index_of)

    def head(self, text: str) -> str:
        m = _NAME.match(text)
        if m is None or m.group(1).upper() in self.hidden:
            return text
        target = self.mapping.get(m.group(1).upper())
        if target is None:
            raise PathError(f"unknown tag {m.group(1)!r}: the logic of Add-On Instruction {self.aoi} names only its "
                            f"parameters and local tags", m.start(1))
        return target + text[m.end():]


class AoiCalls:
    """The project's AOIs, and the program files their calls make (numbered
    by ``files`` once every routine is translated)."""

    def __init__(self, project: model.Project, directory: TagDirectory, types: TypeSystem) -> None:
        self.defs = {a.name.upper(): a for a in project.add_on_instructions}
        self.directory = directory
        self.types = types
        self.made: list[tuple[ProgramFile, Instruction]] = []  # a file and the JSR to it
        self.hidden: dict = {}  # name -> an index's Address (see _bind), or a Declared (check_uncalled)
        self.called: set[str] = set()
        self.stack: list[str] = []
        self.said: set = set()  # problems of an AOI's logic said once, not at every call
        self._index = None  # an index item for _shape, which makes no code

    def defines(self, mnemonic: str) -> bool:
        return mnemonic.upper() in self.defs

    # -- instance values -------------------------------------------------------------------
    def defaults(self, d: Declared, writer, problems) -> None:
        """The AOI's default values into instance tag ``d`` (every element of
        an array of instances), before the tag's own data."""
        aoi = self.defs.get(d.type.name.upper()) if d.type is not None else None
        if aoi is None or d.type is not self.types.get(aoi.name):
            return
        n = 1
        for size in d.dims:
            n *= size
        for src in _members(aoi):
            m = d.type.member(src.name)
            if m is None:
                continue
            if m.host is not None:
                leaf = d.leaves.get((m.host.upper(),))
                data = src.value.data if src.value is not None else 0
                if leaf is not None and isinstance(data, (int, float)):
                    for e in range(n):
                        writer.put(leaf, e, int(data) & 1, m.bit)
                continue
            key = m.name.upper()
            for e in range(n):
                leaves = {}
                for path, leaf in d.leaves.items():
                    if path[:1] == (key,):
                        per = leaf.count // n
                        leaves[path[1:]] = Leaf(leaf.letter, leaf.file, leaf.first + e * per, per)
                sub = Declared(model.Tag(f"{d.tag.name}.{src.name}", src.data_type, value=src.value, pos=src.pos),
                               m.type, (m.dim,) if m.dim else (), d.scope, leaves)
                self.defaults(sub, writer, problems)
                apply_initial(sub, writer, problems)

    # -- calls -----------------------------------------------------------------------------
    def call(self, el, pos: Pos, rung: model.Rung, ctx: RoutineContext) -> Instruction | None:
        """The ladder of one call (its LAIN and routine legs put in
        ``ctx.before``, the LAOUT returned), or None (a problem or warning
        said; ``ctx.skip`` set when the rung is not run)."""
        aoi = self.defs[el.mnemonic.upper()]
        label = f"rung {rung.number}: {aoi.name}"

        def not_run(why: str) -> None:
            ctx.warn(pos, f"{label}: {why}; the rung is not run")
            ctx.skip = True

        if aoi.encoded:
            return not_run("source protected: its logic cannot be read")
        t = self.types.get(aoi.name)
        if t is None or t.kind != "struct":
            return not_run(self.types.held_not.get(aoi.name.upper(), "its instance type is not held"))
        routines = {r.name.upper(): r for r in aoi.routines}
        logic = routines.get("LOGIC")
        if logic is None or logic.encoded:
            return not_run("its Logic routine is not in the export")
        if logic.kind not in LANGUAGES:
            return not_run(f"its Logic routine is {logic.kind}: not yet run by softplc_lite")
        if aoi.name.upper() in self.stack:
            chain = " -> ".join(self.defs[k].name for k in self.stack[self.stack.index(aoi.name.upper()):] +
                                [aoi.name.upper()])
            ctx.problem(pos, f"{label}: an Add-On Instruction may not call itself ({chain})")
            return None
        required = [p for p in aoi.parameters if p.required and p.name.upper() not in ENABLE]
        if len(el.operands) != 1 + len(required):
            names = ", ".join(f"{p.name} ({p.usage})" for p in required)
            ctx.problem(pos, f"{label} takes {1 + len(required)} operand{'s' if required else ''}: its instance"
                             f"{', then ' + names if required else ''}; found {len(el.operands)}")
            return None
        where = [_at(rung.pos, rung.text, column) for _, column in el.operands]
        before = len(ctx.problems)
        inst_text = el.operands[0][0].strip()
        shape = self._shape(inst_text, where[0], ctx, label, "instance")
        if shape is not None and (shape.type is not t or shape.dims):
            ctx.problem(where[0], f"{label} instance {inst_text!r}: expected a tag of type {aoi.name}, found "
                                  f"{shape.type.name}{' array' if shape.dims else ''}")
        inouts = []
        for p, (text, _), w in zip(required, el.operands[1:], where[1:]):
            if (p.usage or "").upper() == "INOUT":
                inouts.append((p, text.strip(), w))
                why = self.types.not_held.get(p.data_type or "")
                if why is not None:  # a MODULE (an I/O module object), a type of Logix's softplc_lite does not hold
                    not_run(f"its InOut parameter {p.name}: {why}")
                    continue
                if number(text) is not None:
                    ctx.problem(w, f"{label} {p.name}: an InOut parameter is passed by reference: expected a tag, "
                                   f"found {text.strip()!r}")
                    continue
                arg = self._shape(text.strip(), w, ctx, label, p.name)
                if arg is not None and not _fits(arg, p):
                    found = f"{arg.type.name}{list(arg.dims) if arg.dims else ''}"
                    wanted = f"{p.data_type}{list(p.dims) if p.dims else ''}"
                    size = "; an array of any size" if p.dims else ""
                    ctx.problem(w, f"{label} {p.name}: expected a {wanted} tag (the InOut parameter's type{size}), "
                                   f"found {found}")
        if len(ctx.problems) > before or ctx.skip:
            return None
        try:
            inst = self._bind(inst_text, where[0], ctx)
            mapping = {m.name.upper(): f"{inst}.{m.name}" for m in _members(aoi)}
            for p, text, w in inouts:
                mapping[p.name.upper()] = self._bind(text, w, ctx)
        except (PathError, ExprError) as e:
            ctx.problem(pos, f"{label}: {e}")
            return None
        names = _Names(self.directory, mapping, self.hidden, aoi.name)
        member_ctx = RoutineContext(names, ctx.scope, {}, ctx.source, f"{aoi.name}.Logic")

        def member(name: str) -> AddressRef:
            return _resolve_ref(name, pos, member_ctx)

        try:
            ein, eout = member("EnableIn"), member("EnableOut")
        except (PathError, ExprError) as e:
            ctx.problem(pos, f"{label}: EnableIn, EnableOut: {e}")
            return None
        if ein.address.bit is None or eout.address.bit is None:
            ctx.problem(pos, f"{label}: EnableIn and EnableOut: expected BOOL parameters")
            return None
        inputs, outputs = [], []
        for p, (text, _), w in zip(required, el.operands[1:], where[1:]):
            usage = (p.usage or "").upper()
            if usage == "INOUT":
                continue
            pt = self.types.get(p.data_type)
            if pt is None or not pt.is_atomic or p.dims:  # a copy is of one number, as Logix's are
                not_run(f"its {p.usage} parameter {p.name} is a {p.data_type}{list(p.dims) if p.dims else ''}: "
                        f"Logix passes Input and Output parameters of atomic types only (1756-PM010, \"Passing "
                        f"arguments to parameters by reference or by value\"; a structure, string or array is an "
                        f"InOut)")
                continue
            try:
                arg = self._argument(text.strip(), w, ctx, usage == "INPUT", _is_bool(p))
            except NotRun as e:
                not_run(f"{p.name} {text.strip()!r}: {e}")
                continue
            except (PathError, ExprError) as e:
                ctx.problem(w, f"{label} {p.name} {text.strip()!r}: {e}")
                continue
            (inputs if usage == "INPUT" else outputs).append((p.name, arg))
        if len(ctx.problems) > before or ctx.skip:
            return None
        try:
            copy_in = [op for name, arg in inputs for op in (arg, member(name))]
            copy_out = [op for name, arg in outputs for op in (member(name), arg)]
        except (PathError, ExprError) as e:  # an instance member softplc_lite cannot reach (a bug if ever)
            ctx.problem(pos, f"{label}: {e}")
            return None
        ctx.before += member_ctx.before
        eif = self._scan_mode(aoi, "ENABLEINFALSE", pos, label, ctx)
        prescan = self._scan_mode(aoi, "PRESCAN", pos, label, ctx)
        flags = Const(HAS_EIF if eif else 0, pos)
        self.called.add(aoi.name.upper())
        legs = [[Instruction("XIC", [ein], pos), self._routine(aoi, logic, mapping, inst, ctx, pos)]]
        if eif is not None:
            legs.append([Instruction("XIO", [ein], pos), self._routine(aoi, eif, mapping, inst, ctx, pos)])
        if prescan is not None:  # the first scan, before the Logic (docs/logix.md: Logix's prescan, as near as it goes)
            legs.insert(0, [Instruction("XIC", [AddressRef(STATUS_FLAGS["S:FS"], pos)], pos),
                            self._routine(aoi, prescan, mapping, inst, ctx, pos)])
        ctx.before.append(Instruction("LAIN", [ein, eout, flags] + copy_in, pos))
        ctx.before += legs[0] if len(legs) == 1 else [Branch(legs, pos)]
        return Instruction("LAOUT", [ein, eout, flags] + copy_out, pos)

    def _scan_mode(self, aoi, name: str, pos, label: str, ctx) -> model.Routine | None:
        """The AOI's EnableInFalse or Prescan routine when the export says
        to run it (``ExecuteEnableInFalse``, ``ExecutePrescan``; an export
        that says neither: when it has the routine); one not in ladder is a
        warning, and not run."""
        routine = next((r for r in aoi.routines if r.name.upper() == name), None)
        if routine is None or (aoi.scan_modes is not None and name not in aoi.scan_modes):
            return None
        if routine.kind not in LANGUAGES or routine.encoded:
            kind = "source protected" if routine.encoded else routine.kind
            ctx.warn(pos, f"{label}: its {routine.name} routine is {kind}: not run by softplc_lite")
            return None
        return routine

    def _shape(self, text, pos, ctx, label, what) -> Resolved | None:
        """What ``text`` names (its type and dimensions), without making its
        run-time indexes; None with the problem said."""
        try:
            return ctx.directory.resolve(text, ctx.scope, lambda *args: self._any_index())
        except NotRun as e:
            ctx.warn(pos, f"{label} {what} {text!r}: {e}; the rung is not run")
            ctx.skip = True
        except PathError as e:
            ctx.problem(Pos(pos.source, pos.line, pos.column + e.offset), f"{label} {what} {text!r}: {e}")
        return None

    def _any_index(self):
        if self._index is None:
            self._index = self.directory.hidden_index()
        return self._index

    def _argument(self, text, pos, ctx, is_input: bool, is_bool: bool):
        value = number(text)
        if value is not None:
            if not is_input:
                raise PathError("expected a tag to receive the Output parameter, found a number")
            return Const(value, pos)
        ref = _resolve_ref(text, pos, ctx)
        if is_bool and ref.address.bit is None:
            raise PathError("expected a BOOL or a bit (Tag.5) for a BOOL parameter")
        return ref

    def _bind(self, text: str, pos: Pos, ctx) -> str:
        """``text`` as a path of the outermost caller: its first name through
        the caller's own names (a call inside an AOI's logic), every index that
        is not a constant a hidden DINT an LIDX computes at the call."""
        if isinstance(ctx.directory, _Names):
            text = ctx.directory.head(text)
        out, k = [], 0
        while k < len(text):
            if text[k] != "[":
                out.append(text[k])
                k += 1
                continue
            depth, end = 0, k
            for end in range(k, len(text)):
                depth += {"[": 1, "]": -1}.get(text[end], 0)
                if depth == 0:
                    break
            parts = []
            for part in (piece.strip() for piece, _ in split_commas(text[k + 1:end])):
                if re.fullmatch(r"[0-9]+", part) or part.upper() in self.hidden:
                    parts.append(part)
                    continue
                name = HIDDEN.format(len(self.hidden))
                address = self.directory.hidden_index()
                expr = parse_expression(part, pos, lambda path, offset: _resolve_ref(path, pos, ctx))
                ctx.before.append(Instruction("LIDX", [AddressRef(address, pos), Const(0, pos), expr,
                                                       Const(NO_LIMIT, pos), Const(1, pos)], pos))
                self.hidden[name.upper()] = address
                parts.append(name)
            out.append("[" + ",".join(parts) + "]")
            k = end + 1
        return "".join(out)

    def _routine(self, aoi, routine: model.Routine, mapping, inst: str, ctx, pos: Pos) -> Instruction:
        """``routine`` of ``aoi`` translated for one call into a program file,
        and the JSR to it (its file numbered by ``files``)."""
        names = _Names(self.directory, mapping, self.hidden, aoi.name)
        inner = RoutineContext(names, ctx.scope, {}, ctx.source, f"{aoi.name}.{routine.name}")
        inner.aoi = self
        self.stack.append(aoi.name.upper())
        try:
            rungs, listing = routine_rungs(routine, inner)
        finally:
            self.stack.pop()
        for source, into in ((inner.problems, ctx.problems), (inner.warnings, ctx.warnings)):
            for p in source:
                if (p.pos, p.message) not in self.said:
                    self.said.add((p.pos, p.message))
                    into.append(p)
        jsr = Instruction("JSR", [Const(0, pos)], pos)
        # Named as the caller's program's (its scope: logix/names.py), the watch view shows Ramp.Logic(Ramp1).
        shown = re.sub(r"__AOI[0-9]+", lambda m: self.hidden[m.group(0)].tag.name
                       if isinstance(self.hidden.get(m.group(0)), Declared) else "?", inst)
        name = f"{ctx.scope + '.' if ctx.scope else ''}{aoi.name}.{routine.name}({shown})"
        self.made.append((ProgramFile(0, name, rungs, routine.pos, listing), jsr))
        return jsr

    def check_uncalled(self, source: str, problems: list, warnings: list) -> None:
        """The logic of each AOI no rung calls (an AOI's own export), made
        once over hidden storage for an instance and its InOut arguments, in a
        file no rung calls: its problems are said as a call's would be."""
        for key, aoi in self.defs.items():
            t = self.types.get(aoi.name)
            routines = {r.name.upper(): r for r in aoi.routines}
            logic = routines.get("LOGIC")
            if key in self.called or aoi.encoded or t is None or t.kind != "struct" or logic is None \
                    or logic.kind not in LANGUAGES or logic.encoded:
                continue
            inst = self._hidden_tag(aoi.name, t, ())
            mapping = {m.name.upper(): f"{inst}.{m.name}" for m in _members(aoi)}
            for p in aoi.parameters:
                if (p.usage or "").upper() == "INOUT":
                    pt = self.types.get(p.data_type)
                    mapping[p.name.upper()] = pt and self._hidden_tag(p.name, pt, tuple(p.dims))
            if inst is None or not all(mapping.values()):
                continue  # an argument softplc_lite cannot stand in for: checked when a rung calls it
            ctx = RoutineContext(self.directory, None, {}, source, aoi.name)
            for name in ("LOGIC", "ENABLEINFALSE", "PRESCAN"):
                r = routines.get(name)
                if r is not None and r.kind in LANGUAGES and not r.encoded:
                    self._routine(aoi, r, mapping, "not called", ctx, r.pos)
            problems += ctx.problems
            warnings += ctx.warnings

    def _hidden_tag(self, name: str, t: LogixType, dims: tuple[int, ...]) -> str | None:
        d = Declared(model.Tag(name, t.name, dims), t, dims, None)
        count = 1
        for size in dims:
            count *= size
        try:
            self.directory.lay_out(d, t, (), count)
        except PathError:
            return None
        key = HIDDEN.format(len(self.hidden))
        self.hidden[key.upper()] = d
        return key

    def files(self, first: int) -> dict[int, ProgramFile]:
        """The calls' program files, numbered from ``first``."""
        out = {}
        for k, (pf, jsr) in enumerate(self.made):
            pf.number = first + k
            jsr.operands = [Const(pf.number, jsr.pos)]
            out[pf.number] = pf
        return out


def _fits(arg: Resolved, p: model.Tag) -> bool:
    """An InOut argument of the parameter's data type, with as many
    dimensions: an array parameter takes an array of another size (the
    logic reaches the argument's own elements, its SIZE)."""
    if (arg.type.name or "").upper() != (p.data_type or "").upper():
        return False
    return len(arg.dims) == len(p.dims)
