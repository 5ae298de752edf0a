"""Stage 3 (reference): a plain tree-walking interpreter over the AST.

Slow and obvious on purpose: every operand is resolved through
``DataTable.resolve`` each time it is used, every rung walks its elements.
The differential tests run random programs through this and the compiler
and require identical data tables. Kernels with real logic (timers,
counters, math stores, strings) are shared from semantics.py; contacts,
coils, branches, compares, operand access, expressions and control flow are
written here a second time.
"""

from __future__ import annotations

from ..datatable import DataTable, bit_mask
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
        mask = bit_mask(bit)
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
        m, ops, mc = ins.mnemonic, ins.operands, self.m
        if m in _WHEN_TRUE and not c:
            return c
        if m == "XIC":
            on = self.bit(ops[0])  # resolved even on a false rung, as compiled code does
            return c and on
        if m == "XIO":
            on = self.bit(ops[0])
            return c and not on
        if m == "OTE":
            self.set_bit(ops[0], c)
        elif m in ("OTL", "OTU"):
            d, i, bit = self.loc(ops[0])  # resolved even on a false rung, as compiled code does
            if c:
                mask = bit_mask(bit)
                d[i] = (d[i] | mask) if m == "OTL" else (d[i] & ~mask)
        elif m == "ONS":
            stored = self.bit(ops[0])
            self.set_bit(ops[0], c)
            return c and not stored
        elif m in ("OSR", "OSF"):
            # Resolve both once, storage first, as compiled code does: writing
            # the output bit may change a word the storage address goes through.
            sd, si, sbit = self.loc(ops[0])
            od, oi, obit = self.loc(ops[1])
            stored = (sd[si] >> sbit) & 1
            fire = (c and not stored) if m == "OSR" else (not c and stored)
            omask, smask = bit_mask(obit), bit_mask(sbit)
            od[oi] = (od[oi] | omask) if fire else (od[oi] & ~omask)
            sd[si] = (sd[si] | smask) if c else (sd[si] & ~smask)
        elif m in ("TON", "TOF", "RTO"):
            d, i, _ = self.loc(ops[0])
            getattr(mc, m.lower())(d, i, c, BASE_MS[ops[1].value])
        elif m in ("CTU", "CTD"):
            d, i, _ = self.loc(ops[0])
            getattr(mc, m.lower())(d, i, c)
        elif m == "RES":
            d, i, _ = self.loc(ops[0])
            mc.res(d, i)
        elif m in ("EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ"):
            a, b = self.read(ops[0]), self.read(ops[1])
            result = {"EQU": a == b, "NEQ": a != b, "LES": a < b, "LEQ": a <= b,
                      "GRT": a > b, "GEQ": a >= b}[m]
            return c and result
        elif m == "LIM":
            lo, t, hi = (self.read(o) for o in ops)
            return c and lim(lo, t, hi)
        elif m == "MEQ":
            s, mask, cmp_ = (self.read(o) for o in ops)
            return c and (s & mask) == (cmp_ & mask)
        elif m == "CMP":
            return bool(self.expr(ops[0]))
        elif m in ("ADD", "SUB", "DIV", "MOD"):
            a, b = self.read(ops[0]), self.read(ops[1])
            d, i, _ = self.loc(ops[2])
            getattr(mc, m.lower())(a, b, d, i)
        elif m == "MUL":
            a, b = self.read(ops[0]), self.read(ops[1])
            d, i, _ = self.loc(ops[2])
            mc.store(a * b, d, i)
        elif m == "NEG":
            v = self.read(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.neg(v, d, i)
        elif m in ("ABS", "MOV"):
            v = self.read(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.store(abs(v) if m == "ABS" else v, d, i)
        elif m == "SQR":
            v = self.read(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.sqr(v, d, i)
        elif m == "CPT":
            compute = self.prepare(ops[1])
            d, i, _ = self.loc(ops[0])
            mc.store(compute(), d, i)
        elif m == "CLR":
            d, i, _ = self.loc(ops[0])
            mc.clear(d, i)
        elif m in ("AND", "OR", "XOR"):
            a, b = self.read(ops[0]), self.read(ops[1])
            d, i, _ = self.loc(ops[2])
            mc.logic(a & b if m == "AND" else a | b if m == "OR" else a ^ b, d, i)
        elif m == "NOT":
            v = self.read(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.logic(~v, d, i)
        elif m == "MVM":
            s, mask = self.read(ops[0]), self.read(ops[1])
            d, i, _ = self.loc(ops[2])
            mc.logic((d[i] & ~mask) | (s & mask), d, i)
        elif m in ("COP", "FLL"):
            n = ops[2].value * ops[1].address.ftype.words_per_element
            if m == "COP":
                sd, si = self._block(ops[0], source_units(n, ops[0].address.ftype, ops[1].address.ftype))
                dd, di = self._block(ops[1], n)
                mc.cop(sd, si, dd, di, n)
            else:
                v = self.read(ops[0])
                dd, di = self._block(ops[1], n)
                mc.fll(v, dd, di, n)
        elif m == "BTD":
            src = self.read(ops[0])
            d, i, _ = self.loc(ops[2])
            mc.btd(src, ops[1].value, d, i, ops[3].value, ops[4].value)
        elif m == "JMP":
            if c:
                raise _Jump(pfile.labels[ops[0].value])
        elif m == "JSR":
            if c:
                if len(ops) > 1:
                    self.jsr(ops[0].value, ins)  # the engine moves the parameters
                else:
                    self.jsr(ops[0].value)
        elif m == "RET":
            if c:
                raise _Jump(ins if ops else RET)  # with values: the engine reads them (Engine.run_file)
        elif m == "TND":
            if c:
                raise _Jump(TND)
        elif m == "MCR":
            self.zone[0] = c if rung.elements[0] is not ins else True
        elif m == "AFI":
            return False
        elif m in ("LBL", "SBR"):
            pass
        elif m == "ACI":
            sd, si, _ = self.loc(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.aci(sd, si, d, i)
        elif m == "AIC":
            v = self.read(ops[0])
            d, i, _ = self.loc(ops[1])
            mc.aic(v, d, i)
        elif m == "ACN":
            (ad, ai, _), (bd, bi, _), (d, i, _) = (self.loc(o) for o in ops)
            mc.acn(ad, ai, bd, bi, d, i)
        elif m == "AEX":
            sd, si, _ = self.loc(ops[0])
            index, count = self.read(ops[1]), self.read(ops[2])
            d, i, _ = self.loc(ops[3])
            mc.aex(sd, si, index, count, d, i)
        elif m == "ASC":  # AB order: source (searched for), index, string search (examined), result
            qd, qi, _ = self.loc(ops[0])
            index = self.read(ops[1])
            (sd, si, _), (d, i, _) = self.loc(ops[2]), self.loc(ops[3])
            mc.asc(qd, qi, index, sd, si, d, i)
        elif m == "ASR":
            (ad, ai, _), (bd, bi, _) = self.loc(ops[0]), self.loc(ops[1])
            return mc.asr(ad, ai, bd, bi)
        elif id(ins) in self.bound:
            return self.bound[id(ins)](c)
        elif id(ins) in self.modules:
            return self.modules[id(ins)](c)
        else:
            raise NotImplementedError(f"the reference interpreter has no rule for {m}")
        return c

    def _block(self, ref, n):
        d, i, _ = self.loc(ref)
        if i + n > len(d):
            raise MajorFault(S.FAULT_BLOCK_RANGE,
                             f"{n} words from {ref.address} run past the end of the file ({len(d)} words)")
        return d, i


def interpret_file(program: Program, number: int, table: DataTable, machine: Machine, jsr, zone: list,
                   module_instance=None) -> ReferenceFile:
    interp = Interpreter(table, machine, jsr, zone)
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

