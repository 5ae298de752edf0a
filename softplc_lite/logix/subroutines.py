"""JSR, SBR and RET parameters that are not one number: a BOOL, a string,
a structure (a user-defined type, TIMER ...) or an array, passed by value as
1756-RM003 passes every parameter ("Jump to Subroutine (JSR), Subroutine
(SBR), Return (RET)": the input values are copied into the SBR's tags when
the JSR runs, the RET's values into the JSR's return tags when the routine
returns; a structure or an array is copied whole, of the same type).

The ladder's JSR, SBR and RET pass numbers (rungs.py keeps those there); a
parameter of another kind is copied by instructions the translation puts
around them, which belong to the call site (the design is a softplc_lite
choice; docs/logix.md, "Subroutines with parameters"):

- **Inputs**: just before the JSR, in the caller's rung, each such argument
  is copied into the tag the callee's SBR names at that place (a BOOL by
  ``[XIC src OTL dest, XIO src OTU dest]``, anything else by COP's LCOPs,
  logix/copy.py, leaf by leaf). The SBR leaves such a parameter out: the
  caller has written it.
- **Returns**: the RET copies each such value into a hidden return slot of
  the routine (one a position, of the RET value's type) and latches the
  routine's hidden "returned" bit; the caller, just after its JSR, copies
  each slot into its own return tag when that bit is set, then unlatches it
  (the bit is unlatched before the JSR too). Nothing runs between the RET
  and the copy after its JSR, so the values go to the caller that is
  returning, however many call sites, and through recursion. A routine that
  ends without a RET with values leaves the return tags as they were.

A routine's plan (which positions are copied, and its slots) is made once,
from its own text, the first time a JSR to it or its own SBR or RET is
translated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..datatable import Address
from ..ladder.ast import AddressRef, Branch, Const, Instruction
from . import copy
from .expr import ExprError, number
from .neutral import NBranch, NeutralError, instructions_in, parse_rung
from .operands import Skip
from .tags import WORD_BITS, Declared, NotRun, PathError, Resolved


def copied(r: Resolved) -> bool:
    """A parameter of this kind is copied around the ladder's JSR/SBR/RET,
    not passed by them (they pass numbers)."""
    return r.address is None or r.address.bit is not None or r.type.name == "BOOL" or r.type.kind == "string"


@dataclass
class Plan:
    """What a routine's parameters are: for each SBR operand and each RET
    value position, None (a number: the ladder passes it) or the Resolved of
    a copied one (the SBR's target; a RET position's hidden slot)."""

    routine: str
    inputs: list = field(default_factory=list)
    returns: list = field(default_factory=list)
    returned: Address | None = None  # the hidden bit a RET with copied values latches

    @property
    def copies(self) -> bool:
        return any(r is not None for r in self.inputs + self.returns)


def _dummy_index(terms, constant, count):
    return Address("L", 0, 0)  # classification only: the real index is made where the copy is


class Subroutines:
    """The plans of one program's routines."""

    def __init__(self, prog, directory) -> None:
        self.routines = {r.name.upper(): r for r in prog.routines}
        self.scope = prog.name
        self.directory = directory
        self.plans: dict[str, Plan | None] = {}

    def plan(self, name: str) -> Plan | None:
        key = name.upper()
        if key not in self.plans:
            self.plans[key] = self._make(self.routines.get(key))
        return self.plans[key]

    def _classify(self, text: str) -> Resolved | None:
        try:
            r = self.directory.resolve(text.strip(), self.scope, _dummy_index)
        except PathError:
            return None  # a number, or a mistake the routine's own translation reports
        return r if copied(r) else None

    def _make(self, routine) -> Plan | None:
        if routine is None or routine.kind != "RLL":
            return None
        plan = Plan(routine.name)
        # A return position is copied when a RET's value or a caller's return tag there is not a
        # number (RET(1) may return a BOOL); its slot has the type of the first such one, a RET's first.
        values: list = []
        for k, elements in enumerate(self._rungs(routine)):
            if k == 0 and elements and not isinstance(elements[0], NBranch) and elements[0].mnemonic == "SBR":
                plan.inputs = [self._classify(text) for text, _ in elements[0].operands]
            for ins in instructions_in(elements):
                if ins.mnemonic == "RET" and ins.operands:
                    _merge(values, [self._classify(text) for text, _ in ins.operands])
        targets: list = []
        for caller in self.routines.values():
            for elements in self._rungs(caller):
                for ins in instructions_in(elements):
                    if ins.mnemonic == "JSR" and len(ins.operands) > 2 and \
                            ins.operands[0][0].strip().upper() == routine.name.upper():
                        count = number(ins.operands[1][0])
                        if isinstance(count, int) and 0 <= count:
                            _merge(targets, [self._classify(t) for t, _ in ins.operands[2 + count:]])
        for p in range(max(len(values), len(targets))):
            like = _at(values, p) or _at(targets, p)
            plan.returns.append(None if like is None else self._slot(like))
        if any(r is not None for r in plan.returns):
            plan.returned = self._bit()
        return plan

    def _rungs(self, routine):
        if routine.kind != "RLL":
            return
        for rung in routine.rungs:
            try:
                yield parse_rung(rung.text)
            except NeutralError:
                continue

    def _bit(self) -> Address:
        leaf = self.directory.alloc.one("B")
        return Address("B", leaf.file, leaf.first // WORD_BITS, None, leaf.first % WORD_BITS)

    def _slot(self, like: Resolved) -> Resolved:
        """Hidden storage of ``like``'s type and dimensions, reached by no name."""
        if like.address is not None and (like.address.bit is not None or like.type.name == "BOOL"):
            return Resolved(like.text, like.type, (), self._bit())
        d = Declared(None, like.type, tuple(like.dims), None)
        count = 1
        for n in like.dims:
            count *= n
        self.directory.lay_out(d, like.type, (), count)
        address = None
        if not like.dims and like.type.kind == "string":
            leaf = d.leaves[()]
            address = Address(leaf.letter, leaf.file, leaf.first)
        return Resolved(like.text, like.type, tuple(like.dims), address, d)


def _merge(into: list, kinds: list) -> None:
    """Keep the first copied kind seen at each position."""
    into += [None] * (len(kinds) - len(into))
    for p, kind in enumerate(kinds):
        if into[p] is None:
            into[p] = kind


def _at(items: list, p: int):
    return items[p] if p < len(items) else None


def copy_value(source: Resolved | int, dest: Resolved, where, pos, ctx) -> list:
    """The elements that copy ``source`` (a resolved tag, or a number for a
    BOOL) into ``dest`` on a true rung, as a MOV or COP would; raises Skip
    when the kinds differ."""
    if dest.address is not None and (dest.address.bit is not None or dest.type.name == "BOOL"):
        target = AddressRef(dest.address, pos)
        if isinstance(source, int):
            if source not in (0, 1):
                raise Skip(f"{source} into a BOOL parameter: expected 0 or 1")
            return [Instruction("OTL" if source else "OTU", [target], pos)]
        if not isinstance(source, Resolved) or source.address is None or \
                (source.address.bit is None and source.type.name != "BOOL"):
            raise Skip(f"a {_kind(source)} passed to a BOOL parameter: softplc_lite passes a BOOL to a BOOL")
        bit = AddressRef(source.address, where)
        return [Branch([[Instruction("XIC", [bit], pos), Instruction("OTL", [target], pos)],
                        [Instruction("XIO", [bit], pos), Instruction("OTU", [target], pos)]], pos)]
    if not isinstance(source, Resolved) or source.address is not None and source.type.kind != "string":
        raise Skip(f"a {_kind(source)} passed to a {_kind(dest)} parameter: the types must match (1756-RM003)")
    if tuple(source.dims) != tuple(dest.dims):
        raise Skip(f"a {_kind(source)} passed to a {_kind(dest)} parameter: the types must match (1756-RM003)")
    count = 1
    for n in dest.dims:
        count *= n
    return copy.copy_run(copy.element_run(source, where, ctx), where, copy.element_run(dest, pos, ctx),
                         Const(count, pos), pos)


def _kind(r) -> str:
    if isinstance(r, int | float):
        return "number"
    if r.address is not None and (r.address.bit is not None or r.type.name == "BOOL"):
        return "BOOL"
    return f"{r.type.name}{'[' + ','.join(map(str, r.dims)) + ']' if r.dims else ''}"


def returned_copies(plan: Plan, pairs: list, pos) -> list:
    """After a JSR: the copies of the slots into the caller's return tags
    (``pairs``: lists of elements, one a copied return), run only when the
    routine returned with values, then the "returned" bit unlatched. The
    rung's condition passes on unchanged (the NOP leg)."""
    flag = AddressRef(plan.returned, pos)
    leg = [Instruction("XIC", [flag], pos)] + [e for p in pairs for e in p] + [Instruction("OTU", [flag], pos)]
    return [Branch([leg, [Instruction("NOP", [], pos)]], pos)]



def jsr(el, pos, rung, ctx, plan: Plan, file: int, count: int) -> list | None:
    """JSR(routine, count, inputs..., returns...) to a routine with copied
    parameters: [unlatch "returned"] input copies, the ladder's JSR with the
    numbers, [the return copies]; or None (a problem or warning said)."""
    from . import rungs

    ops = el.operands[2:]
    kept, before, after = [], [], []
    k = 0
    try:
        for k, (text, column) in enumerate(ops):
            where = rungs._at(rung.pos, rung.text, column)
            if k < count:
                target = plan.inputs[k] if k < len(plan.inputs) else None
                if target is None:
                    kept.append((text, column))
                    continue
                value = number(text)
                source = value if value is not None else rungs._resolve(text.strip(), where, ctx)
                before += copy_value(source, rungs._resolve(target.text, pos, ctx), where, pos, ctx)
            else:
                slot = plan.returns[k - count] if k - count < len(plan.returns) else None
                if slot is None:
                    kept.append((text, column))
                    continue
                if number(text) is not None:
                    raise PathError("expected a tag to receive the parameter, found a number")
                after.append(copy_value(slot, rungs._resolve(text.strip(), where, ctx), pos, where, ctx))
    except (Skip, NotRun) as e:
        ctx.warn(rungs._at(rung.pos, rung.text, ops[k][1]), f"rung {rung.number}: JSR parameter {ops[k][0]!r}: "
                                                            f"{e}; the rung is not run")
        ctx.skip = True
        return None
    except (PathError, ExprError) as e:
        ctx.problem(rungs._at(rung.pos, rung.text, ops[k][1] + e.offset), f"rung {rung.number}: JSR parameter "
                                                                          f"{ops[k][0]!r}: {e}")
        return None
    inputs = sum(1 for k, (text, column) in enumerate(ops) if k < count and (text, column) in kept)
    params = rungs._parameters(_Operands(el.mnemonic, kept), rung, ctx, 0, inputs) if kept else []
    if params is None:
        return None
    call = Instruction("JSR", [Const(file, pos)] + ([Const(inputs, pos)] + params if kept else []), pos)
    if not after:
        return before + [call]
    return [Instruction("OTU", [AddressRef(plan.returned, pos)], pos)] + before + [call] + \
        returned_copies(plan, after, pos)


@dataclass
class _Operands:
    mnemonic: str
    operands: list


def sbr_ret(el, pos, rung, ctx, plan: Plan) -> list | None:
    """SBR(parameters...) without the copied ones (the caller writes them);
    RET(values...): each copied value into its slot, "returned" latched,
    then the ladder's RET with the numbers."""
    from . import rungs

    copies, kept = [], []
    for k, (text, column) in enumerate(el.operands):
        wanted = plan.inputs if el.mnemonic == "SBR" else plan.returns
        target = wanted[k] if k < len(wanted) else None
        if target is None:
            kept.append((text, column))
            continue
        if el.mnemonic == "SBR":
            continue
        where = rungs._at(rung.pos, rung.text, column)
        try:
            value = number(text)
            source = value if value is not None else rungs._resolve(text.strip(), where, ctx)
            copies += copy_value(source, target, where, pos, ctx)
        except (Skip, NotRun) as e:
            ctx.warn(where, f"rung {rung.number}: RET value {text!r}: {e}; the rung is not run")
            ctx.skip = True
            ctx.parameters_not_run = True
            return None
        except (PathError, ExprError) as e:
            ctx.problem(rungs._at(rung.pos, rung.text, column + e.offset), f"rung {rung.number}: RET value "
                                                                           f"{text!r}: {e}")
            return None
    params = rungs._parameters(_Operands(el.mnemonic, kept), rung, ctx, 0,
                               len(kept) if el.mnemonic == "RET" else 0)
    if params is None:
        return None
    if el.mnemonic == "RET" and plan.returned is not None and copies:
        copies.append(Instruction("OTL", [AddressRef(plan.returned, pos)], pos))
    return copies + [Instruction(el.mnemonic, params, pos)]
