"""Stage 3 (reference): a plain tree-walking interpreter over the AST.

Slow and obvious on purpose: every operand is resolved through
``DataTable.resolve`` each time it is used, every rung walks its elements.
The differential tests run random programs through this and the compiler
and require identical data tables. Kernels with real logic (timers,
counters, math stores, strings) are shared from semantics.py; contacts,
coils, branches, compares, operand access, expressions and control flow are
written here a second time, one rule per instruction in ``RULES`` (mnemonic
-> function), as the compiler has one template per instruction
(ladder/templates.py).
"""

from __future__ import annotations

from typing import Callable

from ..datatable import DataTable, data_bit_mask
from ..datatable.errors import AddressRangeError
from .ast import AddressRef, Branch, Const, Instruction, Program, Rung, address_refs, walk
from .compiler import RET, TND, EndScan, describe, labels_of
from .resolvers import address_fault
from .bound import ReferenceAccess
from .expr import evaluate
from .instr import BOUND
from .semantics import BASE_MS, Machine, MajorFault, lim, source_units
from . import status as S

# Instructions whose operands are only touched when the rung is true (the
# compiled path resolves them inside its "if c:").
_WHEN_TRUE = {
    "CMP", "ADD", "SUB", "MUL", "DIV", "MOD", "NEG", "ABS", "SQR", "MOV", "CPT", "CLR", "AND",
    "OR", "XOR", "NOT", "MVM", "COP", "FLL", "BTD", "RES", "ACI", "AIC", "ACN", "AEX", "ASC", "ASR",
}


class _Jump(Exception):
    def __init__(self, target: int) -> None:
        self.target = target


class ReferenceFile:
    """One program file as rung callables, each its own block, like a
    CompiledFile (ladder/blocks.py)."""

    def __init__(self, interp: "Interpreter", number: int, rungs: list[Rung]) -> None:
        self.number = number
        self.labels = labels_of(rungs)
        self.has_mcr = any(
            isinstance(el, Instruction) and el.mnemonic == "MCR" for r in rungs for el in r.elements
        )
        self.blocks = [self._callable(interp, r) for r in rungs]  # a block per rung
        self.starts = range(len(rungs))

    def block_index(self, rung: int) -> int:
        return rung

    def isolate(self, rung: int) -> int:
        return rung

    def split_rungs(self) -> None:
        pass  # a block a rung already

    def where(self, filename: str, lineno: int):
        return None, None  # the interpreter names the instruction itself

    def _callable(self, interp: "Interpreter", rung: Rung):
        def run(c: bool):
            try:
                interp.series(rung.elements, c, rung, self)
            except _Jump as j:
                return j.target
            return None
        return run


class Interpreter:
    def __init__(self, table: DataTable, machine: Machine, jsr, zone: list) -> None:
        self.modules: dict[int, object] = {}  # id(Instruction) -> module (TLM) instance
        self.bound: dict[int, object] = {}  # id(Instruction) -> bound instruction (ladder/instr/)
        self.table = table
        self.m = machine
        self.jsr = jsr
        self.zone = zone

    # -- operands -----------------------------------------------------------------
    def loc(self, ref: AddressRef):
        try:
            f, index, bit = self.table.resolve(ref.address)
        except AddressRangeError as e:
            raise address_fault(ref.address, e) from None
        return f.data, index, bit

    def read(self, operand):
        if isinstance(operand, Const):
            return operand.value
        d, i, bit = self.loc(operand)
        if bit is not None:
            return (d[i] >> bit) & 1
        return d[i]

    def bit(self, ref) -> bool:
        d, i, bit = self.loc(ref)
        return bool((d[i] >> bit) & 1)

    def set_bit(self, ref, on: bool) -> None:
        d, i, bit = self.loc(ref)
        mask = data_bit_mask(d, bit)
        d[i] = (d[i] | mask) if on else (d[i] & ~mask)

    def expr(self, node):
        return self.prepare(node)()

    def prepare(self, node):
        """Resolve every address of an expression now, in tree order, and
        return a thunk that computes it. Compiled code resolves all indirect
        addresses before it computes (and before a CPT's destination), so an
        address fault comes before any minor fault (division by zero) the
        computation would set, and a minor fault cannot move an address."""
        locs = {id(leaf): self.loc(leaf) for leaf in address_refs(node)}

        def read(ref):
            d, i, bit = locs[id(ref)]
            return d[i] if bit is None else (d[i] >> bit) & 1

        return lambda: evaluate(node, read, self.m)

    # -- rungs ----------------------------------------------------------------------------
    def series(self, elements, c: bool, rung: Rung, pfile: ReferenceFile) -> bool:
        for el in elements:
            if isinstance(el, Branch):
                out = False
                for leg in el.legs:
                    out = self.series(leg, c, rung, pfile) or out
                c = out
            else:
                try:
                    c = self.instruction(el, c, rung, pfile)
                except (_Jump, EndScan):  # control flow (EndScan: a TND inside a JSR)
                    raise
                except MajorFault as fault:
                    if fault.instruction is None:
                        fault.instruction = describe(el)
                    raise
                except Exception as exc:  # a bug: contained as a fault naming the instruction
                    fault = MajorFault(S.FAULT_INTERNAL, f"internal error: {type(exc).__name__}: {exc}")
                    fault.instruction = describe(el)
                    raise fault from exc
        return c

    def instruction(self, ins: Instruction, c: bool, rung: Rung, pfile: ReferenceFile) -> bool:
        m = ins.mnemonic
        if m in _WHEN_TRUE and not c:
            return c
        rule = RULES.get(m)
        if rule is not None:
            return rule(self, ins, c, rung, pfile)
        instance = self.modules.get(id(ins))
        if instance is None:
            raise NotImplementedError(f"the reference interpreter has no rule for {m}")
        return instance(c)

    def _block(self, ref, n):
        d, i, _ = self.loc(ref)
        if i + n > len(d):
            raise MajorFault(S.FAULT_BLOCK_RANGE,
                             f"{n} words from {ref.address} run past the end of the file ({len(d)} words)")
        return d, i


# -- the rules: mnemonic -> rule(interpreter, instruction, rung-in, rung, file) -> rung-out --------

Rule = Callable[[Interpreter, Instruction, bool, Rung, ReferenceFile], bool]
RULES: dict[str, Rule] = {}


def rule(*mnemonics: str):
    """Register the interpreter's rule for ``mnemonics``."""
    def register(fn: Rule) -> Rule:
        for m in mnemonics:
            RULES[m] = fn
        return fn
    return register


@rule("XIC")
def _xic(it, ins, c, rung, pfile):
    on = it.bit(ins.operands[0])  # resolved even on a false rung, as compiled code does
    return c and on


@rule("XIO")
def _xio(it, ins, c, rung, pfile):
    on = it.bit(ins.operands[0])
    return c and not on


@rule("OTE")
def _ote(it, ins, c, rung, pfile):
    it.set_bit(ins.operands[0], c)
    return c


@rule("OTL", "OTU")
def _latch(it, ins, c, rung, pfile):
    d, i, bit = it.loc(ins.operands[0])  # resolved even on a false rung, as compiled code does
    if c:
        mask = data_bit_mask(d, bit)
        d[i] = (d[i] | mask) if ins.mnemonic == "OTL" else (d[i] & ~mask)
    return c


@rule("ONS")
def _ons(it, ins, c, rung, pfile):
    stored = it.bit(ins.operands[0])
    it.set_bit(ins.operands[0], c)
    return c and not stored


@rule("OSR", "OSF")
def _one_shot(it, ins, c, rung, pfile):
    # Resolve both once, storage first, as compiled code does: writing
    # the output bit may change a word the storage address goes through.
    sd, si, sbit = it.loc(ins.operands[0])
    od, oi, obit = it.loc(ins.operands[1])
    stored = (sd[si] >> sbit) & 1
    fire = (c and not stored) if ins.mnemonic == "OSR" else (not c and stored)
    omask, smask = data_bit_mask(od, obit), data_bit_mask(sd, sbit)
    od[oi] = (od[oi] | omask) if fire else (od[oi] & ~omask)
    sd[si] = (sd[si] | smask) if c else (sd[si] & ~smask)
    return c


@rule("TON", "TOF", "RTO")
def _timer(it, ins, c, rung, pfile):
    d, i, _ = it.loc(ins.operands[0])
    getattr(it.m, ins.mnemonic.lower())(d, i, c, BASE_MS[ins.operands[1].value])
    return c


@rule("CTU", "CTD")
def _counter(it, ins, c, rung, pfile):
    d, i, _ = it.loc(ins.operands[0])
    getattr(it.m, ins.mnemonic.lower())(d, i, c)
    return c


@rule("RES")
def _res(it, ins, c, rung, pfile):
    d, i, _ = it.loc(ins.operands[0])
    it.m.res(d, i)
    return c


_COMPARE = {"EQU": lambda a, b: a == b, "NEQ": lambda a, b: a != b, "LES": lambda a, b: a < b,
            "LEQ": lambda a, b: a <= b, "GRT": lambda a, b: a > b, "GEQ": lambda a, b: a >= b}


@rule(*_COMPARE)
def _compare(it, ins, c, rung, pfile):
    a, b = it.read(ins.operands[0]), it.read(ins.operands[1])
    return c and _COMPARE[ins.mnemonic](a, b)


@rule("LIM")
def _lim(it, ins, c, rung, pfile):
    lo, t, hi = (it.read(o) for o in ins.operands)
    return c and lim(lo, t, hi)


@rule("MEQ")
def _meq(it, ins, c, rung, pfile):
    s, mask, cmp_ = (it.read(o) for o in ins.operands)
    return c and (s & mask) == (cmp_ & mask)


@rule("CMP")
def _cmp(it, ins, c, rung, pfile):
    return bool(it.expr(ins.operands[0]))


@rule("ADD", "SUB", "DIV", "MOD")
def _math(it, ins, c, rung, pfile):
    ops = ins.operands
    a, b = it.read(ops[0]), it.read(ops[1])
    d, i, _ = it.loc(ops[2])
    getattr(it.m, ins.mnemonic.lower())(a, b, d, i)
    return c


@rule("MUL")
def _mul(it, ins, c, rung, pfile):
    ops = ins.operands
    a, b = it.read(ops[0]), it.read(ops[1])
    d, i, _ = it.loc(ops[2])
    it.m.store(a * b, d, i)
    return c


@rule("NEG")
def _neg(it, ins, c, rung, pfile):
    v = it.read(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.neg(v, d, i)
    return c


@rule("ABS", "MOV")
def _move(it, ins, c, rung, pfile):
    v = it.read(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.store(abs(v) if ins.mnemonic == "ABS" else v, d, i)
    return c


@rule("SQR")
def _sqr(it, ins, c, rung, pfile):
    v = it.read(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.sqr(v, d, i)
    return c


@rule("CPT")
def _cpt(it, ins, c, rung, pfile):
    compute = it.prepare(ins.operands[1])
    d, i, _ = it.loc(ins.operands[0])
    it.m.store(compute(), d, i)
    return c


@rule("CLR")
def _clr(it, ins, c, rung, pfile):
    d, i, _ = it.loc(ins.operands[0])
    it.m.clear(d, i)
    return c


@rule("AND", "OR", "XOR")
def _logic(it, ins, c, rung, pfile):
    ops, m = ins.operands, ins.mnemonic
    a, b = it.read(ops[0]), it.read(ops[1])
    d, i, _ = it.loc(ops[2])
    it.m.logic(a & b if m == "AND" else a | b if m == "OR" else a ^ b, d, i)
    return c


@rule("NOT")
def _not(it, ins, c, rung, pfile):
    v = it.read(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.logic(~v, d, i)
    return c


@rule("MVM")
def _mvm(it, ins, c, rung, pfile):
    ops = ins.operands
    s, mask = it.read(ops[0]), it.read(ops[1])
    d, i, _ = it.loc(ops[2])
    it.m.logic((d[i] & ~mask) | (s & mask), d, i)
    return c


@rule("COP", "FLL")
def _file(it, ins, c, rung, pfile):
    ops = ins.operands
    n = ops[2].value * ops[1].address.ftype.words_per_element
    if ins.mnemonic == "COP":
        sd, si = it._block(ops[0], source_units(n, ops[0].address.ftype, ops[1].address.ftype))
        dd, di = it._block(ops[1], n)
        it.m.cop(sd, si, dd, di, n)
    else:
        v = it.read(ops[0])
        dd, di = it._block(ops[1], n)
        it.m.fll(v, dd, di, n)
    return c


@rule("BTD")
def _btd(it, ins, c, rung, pfile):
    ops = ins.operands
    src = it.read(ops[0])
    d, i, _ = it.loc(ops[2])
    it.m.btd(src, ops[1].value, d, i, ops[3].value, ops[4].value)
    return c


@rule("JMP")
def _jmp(it, ins, c, rung, pfile):
    if c:
        raise _Jump(pfile.labels[ins.operands[0].value])
    return c


@rule("JSR")
def _jsr(it, ins, c, rung, pfile):
    if c:
        if len(ins.operands) > 1:
            it.jsr(ins.operands[0].value, ins)  # the engine moves the parameters
        else:
            it.jsr(ins.operands[0].value)
    return c


@rule("RET")
def _ret(it, ins, c, rung, pfile):
    if c:
        raise _Jump(ins if ins.operands else RET)  # with values: the engine reads them (Engine.run_file)
    return c


@rule("TND")
def _tnd(it, ins, c, rung, pfile):
    if c:
        raise _Jump(TND)
    return c


@rule("MCR")
def _mcr(it, ins, c, rung, pfile):
    it.zone[0] = c if rung.elements[0] is not ins else True
    return c


@rule("AFI")
def _afi(it, ins, c, rung, pfile):
    return False


@rule("LBL", "SBR")
def _nothing(it, ins, c, rung, pfile):
    return c


@rule("ACI")
def _aci(it, ins, c, rung, pfile):
    sd, si, _ = it.loc(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.aci(sd, si, d, i)
    return c


@rule("AIC")
def _aic(it, ins, c, rung, pfile):
    v = it.read(ins.operands[0])
    d, i, _ = it.loc(ins.operands[1])
    it.m.aic(v, d, i)
    return c


@rule("ACN")
def _acn(it, ins, c, rung, pfile):
    (ad, ai, _), (bd, bi, _), (d, i, _) = (it.loc(o) for o in ins.operands)
    it.m.acn(ad, ai, bd, bi, d, i)
    return c


@rule("AEX")
def _aex(it, ins, c, rung, pfile):
    ops = ins.operands
    sd, si, _ = it.loc(ops[0])
    index, count = it.read(ops[1]), it.read(ops[2])
    d, i, _ = it.loc(ops[3])
    it.m.aex(sd, si, index, count, d, i)
    return c


@rule("ASC")
def _asc(it, ins, c, rung, pfile):  # AB order: source (searched for), index, string search (examined), result
    ops = ins.operands
    qd, qi, _ = it.loc(ops[0])
    index = it.read(ops[1])
    (sd, si, _), (d, i, _) = it.loc(ops[2]), it.loc(ops[3])
    it.m.asc(qd, qi, index, sd, si, d, i)
    return c


@rule("ASR")
def _asr(it, ins, c, rung, pfile):
    (ad, ai, _), (bd, bi, _) = it.loc(ins.operands[0]), it.loc(ins.operands[1])
    return it.m.asr(ad, ai, bd, bi)


@rule(*BOUND)
def _bound(it, ins, c, rung, pfile):
    return it.bound[id(ins)](c)  # the object ladder/instr/ bound to this instruction


def interpret_file(program: Program, number: int, table: DataTable, machine: Machine, jsr, zone: list,
                   module_instance=None, interpreter=Interpreter) -> ReferenceFile:
    """``interpreter``: the Interpreter class to run the file with (a subclass
    may watch the scan: testing/coverage.py records what each rung does)."""
    interp = interpreter(table, machine, jsr, zone)
    rungs = program.files[number].rungs
    access = ReferenceAccess(table, machine)
    for rung in rungs:
        for ins in walk(rung.elements):
            bound = BOUND.get(ins.mnemonic)
            if bound is not None:
                interp.bound[id(ins)] = bound.bind(ins, access)
            elif module_instance is not None:
                instance = module_instance(ins, access)
                if instance is not None:
                    interp.modules[id(ins)] = instance
    return ReferenceFile(interp, number, rungs)

