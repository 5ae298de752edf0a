"""Stage 3 (fast path): validated AST -> Python functions, one per rung.

Each program file becomes one generated module whose factory binds the data
arrays, bound kernel methods and resolvers as closure variables, then
defines ``r0, r1, ...``: ``def rK(c)`` takes the rung-in condition and returns
None, a rung index to jump to, or RET/TND. Direct addresses are resolved
once, at compile time, to ``fN[index]`` and literal masks. Indirect and
indexed addresses call a resolver each time they run.

Nothing from program text reaches the generated source except validated
tokens: file numbers, indexes, masks and constants are printed from ints
and floats with repr(), mnemonics select fixed templates, and expressions
are built from fixed operator tables (expr.to_python). A line table maps
each generated line back to its instruction for fault messages.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..gcpause import gc_paused
from ..datatable import DataTable, ValueKind, bit_mask
from ..datatable.filetypes import Storage
from . import status as S
from .ast import AddressRef, BinOp, Branch, Const, Element, Instruction, Program, Rung, UnaryOp, walk
from .bound import BoundAccess
from .expr import namespace as expr_namespace
from .expr import to_python
from .instr import BOUND
from .resolvers import resolver
from .semantics import BASE_MS, Machine, MajorFault, lim, source_units

RET = -1
TND = -2


class EndScan(Exception):
    """TND: end this scan now. Control flow, not an error: it passes up
    through JSR calls (both executors) to the engine."""


@dataclass
class CompiledFile:
    number: int
    rungs: list  # callables rK(c)
    has_mcr: bool
    source: str
    line_table: dict[int, Instruction] = field(default_factory=dict)


def describe(instr: Instruction) -> str:
    from .fmt import format_instruction

    return f"{format_instruction(instr, 'mnemonic')} at {instr.pos}"


class _FileCompiler:
    def __init__(self, table: DataTable, machine: Machine, number: int, labels: dict[int, int], zone: list,
                 module_instance=None) -> None:
        self.table = table
        self.module_instance = module_instance  # TLM instructions: Instruction -> callable(c) -> c
        self.zone = zone  # the file's MCR zone cell, shared with the engine's runner
        self.rung_elements: list = []
        self.machine = machine
        self.number = number
        self.labels = labels
        self.env: dict[str, object] = {}
        self.lines: list[str] = []
        self.line_instr: dict[int, Instruction] = {}
        self.current: Instruction | None = None
        self.temp = 0
        self.has_mcr = False

    # -- emitting ------------------------------------------------------------------------
    def emit(self, indent: int, text: str) -> None:
        self.lines.append("    " * indent + text)
        if self.current is not None:
            self.line_instr[len(self.lines)] = self.current

    def bind(self, name: str, value: object) -> str:
        self.env[name] = value
        return name

    def array_name(self, file) -> str:
        return self.bind(f"f{file.number}", file.data)

    # -- operands ----------------------------------------------------------------------------
    def location(self, ind: int, ref: AddressRef) -> tuple[str, str, str | None]:
        """Code for (array, index, mask) of an address operand; emits a
        resolver call first for indirect/indexed addresses."""
        a = ref.address
        if a.is_direct:
            f, index, bit = self.table.resolve(a)
            return self.array_name(f), repr(index), (repr(bit_mask(bit)) if bit is not None else None)
        k = self.temp
        self.temp += 1
        name = self.bind(f"_loc{len(self.env)}", resolver(self.table, a))
        self.emit(ind, f"_d{k}, _i{k}, _m{k} = {name}()")
        return f"_d{k}", f"_i{k}", (f"_m{k}" if a.kind is ValueKind.BIT else None)

    def value(self, ind: int, operand) -> str:
        if isinstance(operand, Const):
            return repr(operand.value)
        d, i, m = self.location(ind, operand)
        if m is not None:
            return f"(1 if {d}[{i}] & {m} else 0)"
        return f"{d}[{i}]"

    def expression(self, ind: int, node) -> str:
        return to_python(node, lambda ref: self.value(ind, ref))

    # -- rungs -------------------------------------------------------------------------------
    def rung(self, index: int, rung: Rung) -> None:
        self.current = None
        self.emit(1, f"def r{index}(c):")
        body_start = len(self.lines)
        self.series(2, rung.elements)
        if len(self.lines) == body_start:
            self.emit(2, "pass")

    def series(self, ind: int, elements) -> None:
        run: list[tuple[Element, str]] = []  # contacts waiting to be emitted as one expression
        for el in elements:
            expr = self.contact_expression(el)
            if expr is not None:
                run.append((el, expr))
                continue
            self.contact_run(ind, run)
            if isinstance(el, Branch):
                self.branch(ind, el)
            else:
                self.current = el
                self.instruction(ind, el)
                self.current = None
        self.contact_run(ind, run)

    def contact_run(self, ind: int, run: list) -> None:
        """Emit a run of contacts as one short-circuit line. Fewer generated
        lines: CPython's compile() was most of the load of a large program."""
        if not run:
            return
        first = run[0][0]
        self.current = first if isinstance(first, Instruction) else next(walk([first]))
        self.emit(ind, "c = c and " + " and ".join(expr for _, expr in run))
        self.current = None
        run.clear()

    def contact_expression(self, el) -> str | None:
        """A Python boolean for an XIC/XIO on a direct address, or a branch
        whose legs hold only such contacts; None for anything else. These
        read one bit and write nothing, so they can short-circuit as one
        expression (as the line-per-contact code already did): the result
        is the same whatever order, or whether, they are evaluated."""
        if isinstance(el, Branch):
            legs = []
            for leg in el.legs:
                terms = [self.contact_expression(e) for e in leg]
                if None in terms:
                    return None
                legs.append("True" if not terms else terms[0] if len(terms) == 1 else f"({' and '.join(terms)})")
            return f"({' or '.join(legs)})"
        if el.mnemonic not in ("XIC", "XIO") or not el.operands[0].address.is_direct:
            return None
        d, i, mk = self.location(0, el.operands[0])  # direct: emits nothing
        return f"{d}[{i}] & {mk} != 0" if el.mnemonic == "XIC" else f"not {d}[{i}] & {mk}"

    def branch(self, ind: int, branch: Branch) -> None:
        if all(isinstance(e, Instruction) and e.mnemonic in _PASS_THROUGH for leg in branch.legs for e in leg):
            # Parallel coils: every leg passes its rung-in on unchanged, so the
            # branch's rung-out is its rung-in; no bookkeeping needed.
            for leg in branch.legs:
                self.series(ind, leg)
            return
        k = self.temp
        self.temp += 1
        self.emit(ind, f"b{k} = c")
        self.emit(ind, f"o{k} = False")
        for leg in branch.legs:
            self.emit(ind, f"c = b{k}")
            self.series(ind, leg)
            self.emit(ind, f"o{k} = o{k} or c")
        self.emit(ind, f"c = o{k}")

    # -- instructions -------------------------------------------------------------------------------
    def instruction(self, ind: int, ins: Instruction) -> None:
        m = ins.mnemonic
        ops = ins.operands
        handler = getattr(self, f"i_{m}", None)
        if handler is not None:
            handler(ind, ops)
            return
        if m in _COMPARE:
            a, b = self.value(ind, ops[0]), self.value(ind, ops[1])
            self.emit(ind, f"c = c and {a} {_COMPARE[m]} {b}")
            return
        bound = BOUND.get(m)
        if bound is not None:
            # A bound instruction (ladder/instr/): one object per instruction.
            run = bound.bind(ins, BoundAccess(self.table, self.machine))
            self.emit(ind, f"c = {self.bind(f'_bi{len(self.env)}', run)}(c)")
            return
        instance = self.module_instance(ins) if self.module_instance is not None else None
        if instance is not None:
            # A module (TLM) instruction: its instance takes the rung-in and gives the rung-out.
            self.emit(ind, f"c = {self.bind(f'_tli{len(self.env)}', instance)}(c)")
            return
        raise NotImplementedError(f"no compiler template for {m}")  # validated programs never get here

    def i_XIC(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"c = c and {d}[{i}] & {mk} != 0")

    def i_XIO(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"c = c and not {d}[{i}] & {mk}")

    def i_OTE(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"{d}[{i}] = ({d}[{i}] | {mk}) if c else ({d}[{i}] & ~{mk})")

    def i_OTL(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"if c: {d}[{i}] |= {mk}")

    def i_OTU(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, f"if c: {d}[{i}] &= ~{mk}")

    def i_ONS(self, ind, ops):
        d, i, mk = self.location(ind, ops[0])
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if {d}[{i}] & {mk}: c = False")
        self.emit(ind + 1, f"else: {d}[{i}] |= {mk}")
        self.emit(ind, f"else: {d}[{i}] &= ~{mk}")

    def _one_shot(self, ind, ops, rising: bool):
        sd, si, sm = self.location(ind, ops[0])
        od, oi, om = self.location(ind, ops[1])
        stored = f"{sd}[{si}] & {sm}"
        fire = f"c and not {stored}" if rising else f"not c and {stored}"
        self.emit(ind, f"{od}[{oi}] = ({od}[{oi}] | {om}) if ({fire}) else ({od}[{oi}] & ~{om})")
        self.emit(ind, f"{sd}[{si}] = ({sd}[{si}] | {sm}) if c else ({sd}[{si}] & ~{sm})")

    def i_OSR(self, ind, ops):
        self._one_shot(ind, ops, True)

    def i_OSF(self, ind, ops):
        self._one_shot(ind, ops, False)

    def _timer(self, ind, ops, kernel: str):
        d, i, _ = self.location(ind, ops[0])
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind, f"{fn}({d}, {i}, c, {BASE_MS[ops[1].value]!r})")

    def i_TON(self, ind, ops):
        self._timer(ind, ops, "ton")

    def i_TOF(self, ind, ops):
        self._timer(ind, ops, "tof")

    def i_RTO(self, ind, ops):
        self._timer(ind, ops, "rto")

    def _counter(self, ind, ops, kernel: str):
        d, i, _ = self.location(ind, ops[0])
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind, f"{fn}({d}, {i}, c)")

    def i_CTU(self, ind, ops):
        self._counter(ind, ops, "ctu")

    def i_CTD(self, ind, ops):
        self._counter(ind, ops, "ctd")

    def i_RES(self, ind, ops):
        self.emit(ind, "if c:")
        d, i, _ = self.location(ind + 1, ops[0])
        self.emit(ind + 1, f"{self.bind('_res', self.machine.res)}({d}, {i})")

    def i_LIM(self, ind, ops):
        lo, t, hi = (self.value(ind, o) for o in ops)
        self.emit(ind, f"c = c and {self.bind('_lim', lim)}({lo}, {t}, {hi})")

    def i_MEQ(self, ind, ops):
        src, mask, cmp_ = (self.value(ind, o) for o in ops)
        self.emit(ind, f"c = c and ({src} & {mask}) == ({cmp_} & {mask})")

    def i_CMP(self, ind, ops):
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"c = bool({self.expression(ind + 1, ops[0])})")

    def _store(self, ind, dest, value_code: str, kernel: str = "store", value=None):
        d, i, _ = self.location(ind + 1, dest)
        if kernel == "store" and value is not None and _is_word(dest) and _word_valued(value):
            kernel = "store_word"
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind + 1, f"{fn}({value_code}, {d}, {i})")

    def _math2(self, ind, ops, kernel: str):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        d, i, _ = self.location(ind + 1, ops[2])
        if kernel in ("add", "sub") and all(_is_word(op) for op in ops):
            kernel += "_words"
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind + 1, f"{fn}({a}, {b}, {d}, {i})")

    def i_ADD(self, ind, ops):
        self._math2(ind, ops, "add")

    def i_SUB(self, ind, ops):
        self._math2(ind, ops, "sub")

    def i_DIV(self, ind, ops):
        self._math2(ind, ops, "div")

    def i_MOD(self, ind, ops):
        self._math2(ind, ops, "mod")

    def i_MUL(self, ind, ops):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        self._store(ind, ops[2], f"{a} * {b}")

    def i_NEG(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"{self.bind('_neg', self.machine.neg)}({v}, {d}, {i})")

    def i_ABS(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], f"abs({self.value(ind + 1, ops[0])})")

    def i_SQR(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"{self.bind('_sqr', self.machine.sqr)}({v}, {d}, {i})")

    def i_MOV(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], self.value(ind + 1, ops[0]), value=ops[0])

    def i_CPT(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[0], self.expression(ind + 1, ops[1]), value=ops[1])

    def i_CLR(self, ind, ops):
        self.emit(ind, "if c:")
        d, i, _ = self.location(ind + 1, ops[0])
        self.emit(ind + 1, f"{self.bind('_clear', self.machine.clear)}({d}, {i})")

    def _logic(self, ind, ops, symbol: str):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        self._store(ind, ops[2], f"{a} {symbol} {b}", "logic")

    def i_AND(self, ind, ops):
        self._logic(ind, ops, "&")

    def i_OR(self, ind, ops):
        self._logic(ind, ops, "|")

    def i_XOR(self, ind, ops):
        self._logic(ind, ops, "^")

    def i_NOT(self, ind, ops):
        self.emit(ind, "if c:")
        self._store(ind, ops[1], f"~{self.value(ind + 1, ops[0])}", "logic")

    def i_MVM(self, ind, ops):
        self.emit(ind, "if c:")
        src, mask = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        d, i, _ = self.location(ind + 1, ops[2])
        self.emit(ind + 1, f"{self.bind('_logic', self.machine.logic)}(({d}[{i}] & ~{mask}) | ({src} & {mask}), {d}, {i})")

    def _block(self, ind, ref: AddressRef, length: int, dest_ref: AddressRef) -> tuple[str, str, str]:
        """A block operand of a file instruction: array, start, word count.
        The element count comes from the destination's element size; a COP
        source of another storage (F vs words) spans the same bytes."""
        wpe = dest_ref.address.ftype.words_per_element
        needed = source_units(length * wpe, ref.address.ftype, dest_ref.address.ftype)
        d, i, _ = self.location(ind, ref)
        check = self.bind("_block_check", _block_check)
        self.emit(ind, f"{check}({d}, {i}, {needed!r}, {str(ref.address)!r})")
        return d, i, repr(length * wpe)

    def i_COP(self, ind, ops):
        self.emit(ind, "if c:")
        n = ops[2].value
        sd, si, count = self._block(ind + 1, ops[0], n, ops[1])
        dd, di, _ = self._block(ind + 1, ops[1], n, ops[1])
        self.emit(ind + 1, f"{self.bind('_cop', self.machine.cop)}({sd}, {si}, {dd}, {di}, {count})")

    def i_FLL(self, ind, ops):
        self.emit(ind, "if c:")
        v = self.value(ind + 1, ops[0])
        dd, di, count = self._block(ind + 1, ops[1], ops[2].value, ops[1])
        self.emit(ind + 1, f"{self.bind('_fll', self.machine.fll)}({v}, {dd}, {di}, {count})")

    def i_BTD(self, ind, ops):
        self.emit(ind, "if c:")
        src = self.value(ind + 1, ops[0])
        d, i, _ = self.location(ind + 1, ops[2])
        self.emit(ind + 1, f"{self.bind('_btd', self.machine.btd)}({src}, {ops[1].value!r}, {d}, {i}, "
                  f"{ops[3].value!r}, {ops[4].value!r})")

    # program control
    def i_JMP(self, ind, ops):
        self.emit(ind, f"if c: return {self.labels[ops[0].value]!r}")

    def i_LBL(self, ind, ops):
        pass

    def i_SBR(self, ind, ops):
        pass  # its parameters are written by the engine when a JSR enters the file (Engine.run_file)

    def _call(self) -> str:
        """``_calls[k]``: the instruction being compiled, for the engine to
        move its parameters (JSR inputs and returns, RET values)."""
        calls = self.env.setdefault("_calls", [])
        calls.append(self.current)
        return f"_calls[{len(calls) - 1}]"

    def i_JSR(self, ind, ops):
        if len(ops) > 1:
            self.emit(ind, f"if c: _jsr({ops[0].value!r}, {self._call()})")
        else:
            self.emit(ind, f"if c: _jsr({ops[0].value!r})")

    def i_RET(self, ind, ops):
        # A RET with values returns itself: run_file reads them, the JSR stores them.
        self.emit(ind, f"if c: return {self._call() if ops else repr(RET)}")

    def i_TND(self, ind, ops):
        self.emit(ind, f"if c: return {TND!r}")

    def i_MCR(self, ind, ops):
        self.has_mcr = True
        # An MCR alone on its rung ends the zone; with conditions before it, it starts one.
        conditional = self.rung_elements[0] is not self.current
        self.emit(ind, f"_zone[0] = {'c' if conditional else 'True'}")

    def i_AFI(self, ind, ops):
        self.emit(ind, "c = False")

    # strings
    def _strings(self, ind, kernel: str, ops, values=()):
        self.emit(ind, "if c:")
        args = []
        for k, op in enumerate(ops):
            if k in values:
                args.append(self.value(ind + 1, op))
            else:
                d, i, _ = self.location(ind + 1, op)
                args += [d, i]
        self.emit(ind + 1, f"{self.bind('_' + kernel, getattr(self.machine, kernel))}({', '.join(args)})")

    def i_ACI(self, ind, ops):
        self._strings(ind, "aci", ops)

    def i_AIC(self, ind, ops):
        self._strings(ind, "aic", ops, values=(0,))

    def i_ACN(self, ind, ops):
        self._strings(ind, "acn", ops)

    def i_AEX(self, ind, ops):
        self._strings(ind, "aex", ops, values=(1, 2))

    def i_ASC(self, ind, ops):
        # operands in AB order, as the kernel takes them: source (sought), index, string search, result
        self._strings(ind, "asc", ops, values=(1,))

    def i_ASR(self, ind, ops):
        self.emit(ind, "if c:")
        (ad, ai, _), (bd, bi, _) = self.location(ind + 1, ops[0]), self.location(ind + 1, ops[1])
        self.emit(ind + 1, f"c = {self.bind('_asr', self.machine.asr)}({ad}, {ai}, {bd}, {bi})")

    # -- the whole file -----------------------------------------------------------------------------
    def compile(self, rungs: list[Rung], jsr) -> CompiledFile:
        self.lines = ["def _factory(_env):"]
        header_at = len(self.lines)
        for k, rung in enumerate(rungs):
            self.rung_elements = rung.elements
            self.rung(k, rung)
        self.lines.append(f"    return [{', '.join(f'r{k}' for k in range(len(rungs)))}]")
        self.env["_jsr"] = jsr
        self.env["_zone"] = self.zone
        self.env.update(expr_namespace(self.machine))
        bindings = [f"    {name} = _env[{name!r}]" for name in sorted(self.env)]
        shift = len(bindings)
        line_table = {line + shift: ins for line, ins in self.line_instr.items()}
        functions = self._compile_chunks(len(rungs), shift)
        self.lines[header_at:header_at] = bindings
        source = "\n".join(self.lines) + "\n"
        return CompiledFile(self.number, functions, self.has_mcr, source, line_table)

    def _compile_chunks(self, count: int, shift: int) -> list:
        """Compile the rung functions CHUNK_RUNGS at a time, each chunk its own
        factory binding only the names it uses: CPython compiles one huge
        function body several times slower than the same code in small
        ones. Blank lines in front of each chunk keep every line at its
        number in the whole file's source (``source``, ``line_table``)."""
        starts = [i for i, line in enumerate(self.lines) if line.startswith("    def r")]
        starts.append(len(self.lines) - 1)  # the whole file's return line
        name = f"<ladder file {self.number}>"
        functions: list = []
        for a in range(0, count, CHUNK_RUNGS):
            b = min(a + CHUNK_RUNGS, count)
            body = self.lines[starts[a]:starts[b]]
            used = set(_IDENTIFIER.findall("\n".join(body)))
            bindings = [f"    {n} = _env[{n!r}]" for n in sorted(self.env) if n in used]
            pad = starts[a] + shift - 1 - len(bindings)
            text = "\n".join(["\n" * pad + "def _factory(_env):", *bindings, *body,
                              f"    return [{', '.join(f'r{k}' for k in range(a, b))}]"]) + "\n"
            scope: dict[str, object] = {}
            exec(compile(text, name, "exec"), scope)  # noqa: S102 - source built only from validated tokens
            functions += scope["_factory"](self.env)
        return functions


def _is_word(operand) -> bool:
    """A 16-bit word at run time, known at load: an integer constant in word
    range, or an address in a word file (not F, not L) (its type letter never changes, even
    when its file or element number is indirect)."""
    if isinstance(operand, Const):
        return isinstance(operand.value, int) and -32768 <= operand.value <= 32767
    # Storage.WORD only: an L element (Storage.LONG) is an integer but not 16-bit.
    return isinstance(operand, AddressRef) and operand.address.ftype.storage is Storage.WORD


def _word_valued(node) -> bool:
    """An integer whatever the data: words combined by + - * and negation."""
    if isinstance(node, BinOp):
        return node.op in ("+", "-", "*") and _word_valued(node.left) and _word_valued(node.right)
    if isinstance(node, UnaryOp):
        return node.op == "NEG" and _word_valued(node.operand)
    return _is_word(node)


# Outputs: they leave the rung condition as they found it.
_PASS_THROUGH = frozenset({"OTE", "OTL", "OTU"})

# Rungs per compiled chunk (see _FileCompiler._compile_chunks).
CHUNK_RUNGS = 200
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _block_check(d, i, n, text) -> None:
    if i + n > len(d):
        raise MajorFault(S.FAULT_BLOCK_RANGE, f"{n} words from {text} run past the end of the file ({len(d)} words)")


_COMPARE = {"EQU": "==", "NEQ": "!=", "LES": "<", "LEQ": "<=", "GRT": ">", "GEQ": ">="}


def labels_of(rungs: list[Rung]) -> dict[int, int]:
    out = {}
    for k, rung in enumerate(rungs):
        first = rung.elements[0] if rung.elements else None
        if isinstance(first, Instruction) and first.mnemonic == "LBL":
            out[first.operands[0].value] = k
    return out


@gc_paused
def compile_file(program: Program, number: int, table: DataTable, machine: Machine, jsr, zone: list,
                 module_instance=None) -> CompiledFile:
    pfile = program.files[number]
    fc = _FileCompiler(table, machine, number, labels_of(pfile.rungs), zone, module_instance)
    return fc.compile(pfile.rungs, jsr)
