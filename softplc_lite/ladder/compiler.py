"""Stage 3 (fast path): validated AST -> Python functions, one per block
of rungs (ladder/blocks.py).

Each block is one generated function over up to CHUNK_RUNGS consecutive
rungs. The data-table words its contacts and coils use (direct bit
addresses in 16-bit word files other than S) live in locals of that
function: each is read into its local at its first use and written back
("flushed") at the block's end, before a JMP/RET/TND leaves it, and before
any instruction that is not block code runs (a kernel, a bound or module
instruction, a JSR, an indirect or indexed address); after such an
instruction the locals are read again at their next use. So every write a
rung makes is seen by the next rung, and the data table is exact whenever
anything else can look at it. docs/engine.md, "Compiled code".

Nothing from program text reaches the generated source except validated
tokens: file numbers, indexes, masks and constants are printed from ints
and floats with repr(), mnemonics select fixed templates, and expressions
are built from fixed operator tables (expr.to_python). A line table per
block maps each generated line back to its rung and instruction for fault
messages.
"""

from __future__ import annotations

import re

from ..gcpause import gc_paused
from ..datatable import DataTable, ValueKind, bit_mask
from ..datatable.filetypes import Storage
from . import status as S
from . import blocks
from .ast import AddressRef, BinOp, Branch, Const, Element, Instruction, Program, Rung, UnaryOp, address_refs, walk
from .blocks import BlockCode, CompiledFile
from .bound import BoundAccess
from .expr import namespace as expr_namespace
from .expr import to_python
from .instr import BOUND
from .resolvers import resolver
from .semantics import BASE_MS, CD, CU, DN, EN, OV, STAMP, STAMP_MODULO, TT, UN, Machine, MajorFault, lim, source_units

RET = -1
TND = -2


class EndScan(Exception):
    """TND: end this scan now. Control flow, not an error: it passes up
    through JSR calls (both executors) to the engine."""


def instructions_of(elements, out: list | None = None) -> list:
    """Every instruction of ``elements`` (branches opened), in scan order:
    ast.walk as a list, several times faster on a big program's load."""
    if out is None:
        out = []
    for el in elements:
        if el.__class__ is Instruction:
            out.append(el)
        else:
            for leg in el.legs:
                instructions_of(leg, out)
    return out


def describe(instr: Instruction) -> str:
    from .fmt import format_instruction

    return f"{format_instruction(instr, 'mnemonic')} at {instr.pos}"


class _FileCompiler:
    def __init__(self, table: DataTable, machine: Machine, number: int, rungs: list[Rung], zone: list, jsr,
                 module_instance=None) -> None:
        self.table = table
        self.machine = machine
        self.number = number
        self.rungs = rungs
        self.labels = labels_of(rungs)
        self.module_instance = module_instance  # TLM instructions: Instruction -> callable(c) -> c
        self.has_mcr = any(ins.mnemonic == "MCR" for r in rungs for ins in instructions_of(r.elements))
        self.env: dict[str, object] = {"_jsr": jsr, "_zone": zone, "_m": machine, **expr_namespace(machine)}
        self.named: dict[tuple, str] = {}  # per-instruction objects, made once (a block compiled again reuses them)
        self.rung_elements: list = []
        self.current: Instruction | None = None
        self.inline_dest: str | None = None  # the local a word store writes (in_place)
        self._locations: dict[int, object] = {}  # id(Address) -> Location, for direct addresses

    # -- emitting ------------------------------------------------------------------------
    def emit(self, indent: int, text: str) -> None:
        self.lines.append("    " * indent + text)
        self.line_instr.append(self.current)
        self.line_rung.append(self.rung_index)

    def resolve(self, a):
        """``table.resolve`` of a direct address, once per Address object
        (the parser makes one per address text): load time."""
        loc = self._locations.get(id(a))
        if loc is None:
            loc = self._locations[id(a)] = self.table.resolve(a)
        return loc

    def bind(self, name: str, value: object) -> str:
        self.env[name] = value
        return name

    def bind_once(self, key: tuple, prefix: str, make) -> str:
        """A name for an object made once per instruction (or operand):
        compiling a block again must not make a second one."""
        name = self.named.get(key)
        if name is None:
            name = self.named[key] = f"{prefix}{len(self.named)}"
            self.env[name] = make()
        return name

    def array_name(self, file) -> str:
        return self.bind(f"f{file.number}", file.data)

    # -- words held in locals ---------------------------------------------------------------
    def word_local(self, ind: int, ref: AddressRef) -> tuple[str, int | None] | None:
        """(local, mask or None) for a direct address whose word a block may
        hold in a local (a 16-bit word file other than S: S words are written
        by kernels and the engine behind the block's back), loading it at its
        first use (at rung level: every path after it has it); None for any
        other address."""
        a = ref.address
        if not a.is_direct:
            return None
        f, index, bit = self.resolve(a)
        name = self.word_at(ind, f, index)
        if name is None:
            return None
        return name, (bit_mask(bit) if bit is not None else None)

    def word_at(self, ind: int, f, index: int) -> str | None:
        """The local holding word ``index`` of file ``f`` (loaded now if not
        held), or None if no local may hold that file's words."""
        if f.ftype.storage is not Storage.WORD or f.ftype.letter == "S":
            return None
        key = (f.number, index)
        name = self.words.get(key)
        if name is None:
            name = self.words[key] = f"w{f.number}_{index}"
            self.local_names.add(name)
            self.emit(ind, f"{name} = {self.array_name(f)}[{index!r}]")
        return name

    def mark_written(self, key_name: str) -> None:
        self.dirty.add(key_name)

    def flush_lines(self, ind: int) -> None:
        """Write back every local a rung may have changed."""
        for (number, index), name in self.words.items():
            if name in self.dirty:
                self.emit(ind, f"f{number}[{index!r}] = {name}")

    def barrier(self, ind: int) -> None:
        """Before code that is not block code: the table made exact, the
        locals forgotten (that code may write any word), and the rung
        recorded for a minor fault it may set."""
        self.flush_lines(ind)
        self.words.clear()
        self.dirty.clear()
        self.mark_rung(ind)

    def mark_rung(self, ind: int) -> None:
        """``_m.rung``: the rung being scanned, for what is not block code."""
        if self.rung_marked != self.rung_index:
            self.rung_marked = self.rung_index
            self.emit(ind, f"_m.rung = {self.rung_index!r}")

    # -- operands ----------------------------------------------------------------------------
    def location(self, ind: int, ref: AddressRef) -> tuple[str, str, str | None]:
        """Code for (array, index, mask) of an address operand; emits a
        resolver call first for indirect/indexed addresses. Only after a
        barrier: the table is exact."""
        a = ref.address
        if a.is_direct:
            f, index, bit = self.resolve(a)
            return self.array_name(f), repr(index), (repr(bit_mask(bit)) if bit is not None else None)
        k = self.temp
        self.temp += 1
        name = self.bind_once((id(ref), "loc"), "_loc", lambda: resolver(self.table, a))
        self.emit(ind, f"_d{k}, _i{k}, _m{k} = {name}()")
        return f"_d{k}", f"_i{k}", (f"_m{k}" if a.kind is ValueKind.BIT else None)

    def value(self, ind: int, operand) -> str:
        if isinstance(operand, Const):
            return repr(operand.value)
        a = operand.address
        if a.is_direct:
            f, index, bit = self.resolve(a)
            name = self.words.get((f.number, index))
            if name is not None:  # held in a local (loaded at rung level before this instruction)
                return name if bit is None else f"(1 if {name} & {bit_mask(bit)!r} else 0)"
        d, i, m = self.location(ind, operand)
        if m is not None:
            return f"(1 if {d}[{i}] & {m} else 0)"
        return f"{d}[{i}]"

    def expression(self, ind: int, node) -> str:
        return to_python(node, lambda ref: self.value(ind, ref))

    def bit(self, ind: int, ref: AddressRef) -> tuple[str, int, bool] | None:
        """A bit instruction's word as (code of the word, mask, held in a
        local): a local, or an S word read in place; None: not direct."""
        held = self.word_local(ind, ref)
        if held is not None:
            return held[0], held[1], True
        a = ref.address
        if not a.is_direct:
            return None
        f, index, bit = self.resolve(a)
        return f"{self.array_name(f)}[{index!r}]", bit_mask(bit), False

    # -- rungs -------------------------------------------------------------------------------
    def rung(self, index: int, rung: Rung) -> None:
        self.rung_index = index
        self.rung_elements = rung.elements
        self.current = None
        self.rung_in = "z" if self.has_mcr else "True"
        first = rung.elements[0] if rung.elements else None
        if first is None or self.contact_expression(first) is None:
            self.start_rung()
        self.series(2, rung.elements)

    def start_rung(self) -> None:
        """Give ``c`` its rung-in (left pending while a rung's first contacts
        can assign it in one line)."""
        if self.rung_in is not None:
            self.emit(2, f"c = {self.rung_in}")
            self.rung_in = None

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
        """Emit a run of contacts as one short-circuit line."""
        if not run:
            return
        first = run[0][0]
        self.current = first if isinstance(first, Instruction) else next(walk([first]))
        terms = " and ".join(expr for _, expr in run)
        if self.rung_in is not None:  # the rung's first contacts
            self.emit(ind, f"c = {terms}" if self.rung_in == "True" else f"c = z and {terms}")
            self.rung_in = None
        else:
            self.emit(ind, "c = c and " + terms)
        self.current = None
        run.clear()

    def contact_expression(self, el) -> str | None:
        """A Python boolean for an XIC/XIO on a direct address, or a branch
        whose legs hold only such contacts; None for anything else. These
        read one bit and write nothing, so they can short-circuit as one
        expression: the result is the same whatever order, or whether, they
        are evaluated. (Their words are loaded into locals first.)"""
        if isinstance(el, Branch):
            legs = []
            for leg in el.legs:
                terms = [self.contact_expression(e) for e in leg]
                if None in terms:
                    return None
                legs.append("True" if not terms else terms[0] if len(terms) == 1 else f"({' and '.join(terms)})")
            return f"({' or '.join(legs)})"
        if el.mnemonic in _COMPARE and all(isinstance(op, Const) or op.address.is_direct for op in el.operands):
            # A compare of direct words reads and writes nothing else: a contact too.
            for op in el.operands:
                if isinstance(op, AddressRef):
                    self.word_local(2, op)
            a, b = (self.value(2, op) for op in el.operands)
            return f"{a} {_COMPARE[el.mnemonic]} {b}"
        if el.mnemonic not in ("XIC", "XIO"):
            return None
        held = self.bit(2, el.operands[0])
        if held is None:
            return None
        word, mk, _ = held
        return f"{word} & {mk!r} != 0" if el.mnemonic == "XIC" else f"not {word} & {mk!r}"

    def branch(self, ind: int, branch: Branch) -> None:
        self.start_rung()
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
        self.start_rung()
        if m in _BIT_OPS and all(self.bit(ind, op) is not None for op in ops):
            getattr(self, f"bit_{m}")(ind, *(self.bit(ind, op) for op in ops))
            return
        inline = getattr(self, f"local_{m}", None)
        if inline is not None and all(isinstance(op, Const) or op.address.is_direct for op in ops) and \
                self.resolve(ops[0].address).file.ftype.storage is Storage.WORD:
            inline(ind, ins)  # on the element's words held in locals
            return
        dest = self.local_safe(ins)
        if dest is not False:
            self.in_place(ind, ins, dest)
            return
        if m not in _NO_BARRIER:
            self.barrier(ind)
        self.dispatch(ind, ins)

    def local_safe(self, ins: Instruction):
        """For an instruction that reads and writes only its operands (and
        S:0, minor fault words) and cannot fault, on direct addresses: its
        destination operand (None: none). False for any other instruction:
        it runs after a barrier."""
        m = ins.mnemonic
        where = _LOCAL_SAFE.get(m)
        if where is None:
            return False
        for op in ins.operands:
            for ref in address_refs(op):
                if not ref.address.is_direct:
                    return False
            if m == "CPT" and not isinstance(op, (AddressRef, Const)) and not _cannot_fault(op):
                return False
        return ins.operands[where] if where >= 0 else None

    def in_place(self, ind: int, ins: Instruction, dest) -> None:
        """A safe instruction beside the locals: the words it reads are
        loaded (at rung level), its destination word is written back first
        if held and changed, and forgotten after (its kernel writes the
        table)."""
        for op in ins.operands:
            if op is not dest:
                for ref in address_refs(op):
                    self.word_local(ind, ref)
        name = None
        if dest is not None:
            if _word_store(ins) and self.holdable(dest):
                # A 16-bit result into a word: stored inline (i_MOV, i_CPT, _math2),
                # into its local if held, else into the table.
                f, index, _ = self.resolve(dest.address)
                self.inline_dest = self.words.get((f.number, index), "")
                self.dispatch(ind, ins)
                if self.inline_dest:
                    self.dirty.add(self.inline_dest)
                self.inline_dest = None
                return
            self.mark_rung(ind)  # a store may set a minor fault (overflow)
            f, index, _ = self.resolve(dest.address)
            key = (f.number, index)
            name = self.words.get(key)
            if name is not None and name in self.dirty:
                self.emit(ind, f"f{f.number}[{index!r}] = {name}")
        self.dispatch(ind, ins)
        if name is not None:
            del self.words[key]
            self.dirty.discard(name)

    def holdable(self, ref: AddressRef) -> bool:
        f = self.resolve(ref.address).file
        return f.ftype.storage is Storage.WORD and f.ftype.letter != "S"

    def store_in_local(self, ind: int, dest, value_code: str, fallback: str, in_range: bool = False,
                       carry: str | None = None) -> None:
        """``value_code`` into the destination word (its local if held, else
        the table), with S:0 as the kernel sets it; out of range, the kernel
        (``fallback``, given the value as ``_v``) stores it and sets the
        overflow minor fault, and a held local reads it back. ``in_range``:
        the value is a word already (no range test)."""
        name = self.inline_dest
        f, index, _ = self.resolve(dest.address)
        target = name or f"{self.array_name(f)}[{index!r}]"
        if in_range and _SIMPLE.match(value_code):
            v = value_code  # a local or a constant: no temporary
        else:
            v = "_v"
            self.emit(ind, f"_v = {value_code}")
        flags = f"(({v} == 0) << 2) | (({v} < 0) << 3)"
        if carry is not None:
            flags = f"({carry}) | {flags}"
        if in_range:
            self.emit(ind, f"{target} = {v}")
            self.emit(ind, f"_s[0] = (_s[0] & -16) | {flags}")
            return
        self.emit(ind, "if -32768 <= _v <= 32767:")
        self.emit(ind + 1, f"{target} = _v")
        self.emit(ind + 1, f"_s[0] = (_s[0] & -16) | {flags}")
        self.emit(ind, "else:")
        self.emit(ind + 1, f"_m.rung = {self.rung_index!r}")  # the minor fault names this rung
        self.emit(ind + 1, fallback.replace("_D_", f"{self.array_name(f)}, {index!r}"))
        if name:
            self.emit(ind + 1, f"{name} = f{f.number}[{index!r}]")

    def dispatch(self, ind: int, ins: Instruction) -> None:
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
            name = self.bind_once((id(ins), "bi"), "_bi", lambda: bound.bind(ins, BoundAccess(self.table, self.machine)))
            self.emit(ind, f"c = {name}(c)")
            return
        key = (id(ins), "tli")
        if key not in self.named:
            instance = self.module_instance(ins) if self.module_instance is not None else None
            if instance is None:
                raise NotImplementedError(f"no compiler template for {m}")  # validated programs never get here
            self.bind_once(key, "_tli", lambda: instance)
        # A module (TLM) instruction: its instance takes the rung-in and gives the rung-out.
        self.emit(ind, f"c = {self.named[key]}(c)")

    # Bit instructions on words held in locals (or S words in place): each
    # operand is (word code, mask, held in a local).
    def written(self, word: tuple) -> None:
        if word[2]:
            self.dirty.add(word[0])

    def bit_XIC(self, ind, w):
        self.emit(ind, f"c = c and {w[0]} & {w[1]!r} != 0")

    def bit_XIO(self, ind, w):
        self.emit(ind, f"c = c and not {w[0]} & {w[1]!r}")

    def bit_OTE(self, ind, w):
        self.emit(ind, f"{w[0]} = ({w[0]} | {w[1]!r}) if c else ({w[0]} & {~w[1]!r})")
        self.written(w)

    def bit_OTL(self, ind, w):
        self.emit(ind, f"if c: {w[0]} |= {w[1]!r}")
        self.written(w)

    def bit_OTU(self, ind, w):
        self.emit(ind, f"if c: {w[0]} &= {~w[1]!r}")
        self.written(w)

    def bit_ONS(self, ind, w):
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if {w[0]} & {w[1]!r}: c = False")
        self.emit(ind + 1, f"else: {w[0]} |= {w[1]!r}")
        self.emit(ind, f"else: {w[0]} &= {~w[1]!r}")
        self.written(w)

    def _bit_one_shot(self, ind, storage, output, rising: bool):
        stored = f"{storage[0]} & {storage[1]!r}"
        fire = f"c and not {stored}" if rising else f"not c and {stored}"
        o, om = output[0], output[1]
        self.emit(ind, f"{o} = ({o} | {om!r}) if ({fire}) else ({o} & {~om!r})")
        self.emit(ind, f"{storage[0]} = ({storage[0]} | {storage[1]!r}) if c else ({storage[0]} & {~storage[1]!r})")
        self.written(storage)
        self.written(output)

    def bit_OSR(self, ind, storage, output):
        self._bit_one_shot(ind, storage, output, True)

    def bit_OSF(self, ind, storage, output):
        self._bit_one_shot(ind, storage, output, False)

    # The same on indirect or indexed addresses, on the table (after a barrier).
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
        if self.inline_dest is not None:  # MOV/CPT of a word value into a held word (in_place)
            self.bind("_s", self.machine.s)
            fn = self.bind("_store", self.machine.store)
            self.store_in_local(ind + 1, dest, value_code, f"{fn}(_v, _D_)", in_range=_is_word(value))
            return
        d, i, _ = self.location(ind + 1, dest)
        if kernel == "store" and value is not None and _is_word(dest) and _word_valued(value):
            kernel = "store_word"
        fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
        self.emit(ind + 1, f"{fn}({value_code}, {d}, {i})")

    def _math2(self, ind, ops, kernel: str):
        self.emit(ind, "if c:")
        a, b = self.value(ind + 1, ops[0]), self.value(ind + 1, ops[1])
        if self.inline_dest is not None:  # ADD/SUB of words into a held word (in_place)
            self.bind("_s", self.machine.s)
            fn = self.bind(f"_{kernel}", getattr(self.machine, kernel))
            symbol, carry = ("+", f"({a} & 65535) + ({b} & 65535) > 65535") if kernel == "add" else \
                ("-", f"({a} & 65535) < ({b} & 65535)")
            self.store_in_local(ind + 1, ops[2], f"{a} {symbol} {b}", f"{fn}({a}, {b}, _D_)", carry=carry)
            return
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

    # program control: leaving the block writes its locals back first
    def leave(self, ind: int, value: str) -> None:
        self.emit(ind, "if c:")
        self.flush_lines(ind + 1)
        self.emit(ind + 1, f"return {value}")

    def i_JMP(self, ind, ops):
        self.leave(ind, repr(self.labels[ops[0].value]))

    def i_LBL(self, ind, ops):
        pass

    def i_SBR(self, ind, ops):
        pass  # its parameters are written by the engine when a JSR enters the file (Engine.run_file)

    def _call(self) -> str:
        """``_calls[k]``: the instruction being compiled, for the engine to
        move its parameters (JSR inputs and returns, RET values)."""
        calls = self.env.setdefault("_calls", [])
        key = (id(self.current), "call")
        if key not in self.named:
            self.named[key] = f"_calls[{len(calls)}]"
            calls.append(self.current)
        return self.named[key]

    def i_JSR(self, ind, ops):
        if len(ops) > 1:
            self.emit(ind, f"if c: _jsr({ops[0].value!r}, {self._call()})")
        else:
            self.emit(ind, f"if c: _jsr({ops[0].value!r})")

    def i_RET(self, ind, ops):
        # A RET with values returns itself: run_file reads them (a fault there names this rung), the JSR stores them.
        if ops:
            self.mark_rung(ind)
        self.leave(ind, self._call() if ops else repr(RET))

    def i_TND(self, ind, ops):
        self.leave(ind, repr(TND))

    def i_MCR(self, ind, ops):
        # An MCR alone on its rung ends the zone; with conditions before it, it starts one.
        conditional = self.rung_elements[0] is not self.current
        self.emit(ind, f"z = {'c' if conditional else 'True'}")
        self.emit(ind, "_zone[0] = z")

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

    # -- timers, counters and COP on held words ------------------------------------------------------
    def element_words(self, ind: int, ref: AddressRef) -> list[str]:
        """The locals of a timer or counter element's three words (control, PRE, ACC)."""
        f, index, _ = self.resolve(ref.address)
        return [self.word_at(ind, f, index + k) for k in range(3)]

    def local_TON(self, ind: int, ins: Instruction) -> None:
        """Semantics.ton written out on the element's locals (the kernel is
        the reference: the differential test holds them equal). The time is
        the engine's clock of this scan, _m.now_ms."""
        wc, wp, wa = self.element_words(ind, ins.operands[0])
        base = BASE_MS[ins.operands[1].value]
        self.uses_now = True
        self.emit(ind, f"if {wp} < 0 or {wa} < 0:")  # the kernel raises the fault, on an exact table
        self.flush_lines(ind + 1)
        d, i, _ = self.location(ind + 1, ins.operands[0])
        self.emit(ind + 1, f"{self.bind('_ton', self.machine.ton)}({d}, {i}, c, {base!r})")
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if {wc} & {EN!r} and {wa} < {wp}:")
        self.emit(ind + 2, f"_t, _r = divmod((_now - ({wc} & {STAMP!r})) % {STAMP_MODULO!r}, {base!r})")
        self.emit(ind + 2, f"{wa} += _t")
        self.emit(ind + 2, f"if {wa} >= {wp}: {wa} = {wp}; _r = 0")
        self.emit(ind + 2, f"{wc} = ({wc} & {~STAMP!r}) | ((_now - _r) & {STAMP!r}) | {EN!r}")
        self.emit(ind + 1, "else:")
        self.emit(ind + 2, f"{wc} = ({wc} & {~STAMP!r}) | (_now & {STAMP!r}) | {EN!r}")
        self.emit(ind + 1, f"if {wa} >= {wp}: {wc} = ((({wc} | {DN!r}) & {~STAMP!r}) | (_now & {STAMP!r})) & {~TT!r}")
        self.emit(ind + 1, f"else: {wc} = ({wc} | {TT!r}) & {~DN!r}")
        assert EN | TT | DN | STAMP == -1
        self.emit(ind, "else:")
        self.emit(ind + 1, f"{wc} = 0")  # EN TT DN and the stamp are every bit of the word
        self.emit(ind + 1, f"{wa} = 0")
        self.dirty.update((wc, wa))

    def _local_count(self, ind: int, ins: Instruction, up: bool) -> None:
        """Semantics.ctu / ctd written out on the element's locals."""
        wc, wp, wa = self.element_words(ind, ins.operands[0])
        edge, limit, wrapped, flag, other = (CU, 32767, -32768, OV, UN) if up else (CD, -32768, 32767, UN, OV)
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if not {wc} & {edge!r}:")
        self.emit(ind + 2, f"if {wa} == {limit!r}:")
        self.emit(ind + 3, f"{wa} = {wrapped!r}")
        self.emit(ind + 3, f"{wc} = ({wc} | {flag!r}) if not {wc} & {other!r} else ({wc} & {~other!r})")
        self.emit(ind + 2, f"else: {wa} {'+' if up else '-'}= 1")
        self.emit(ind + 1, f"{wc} |= {edge!r}")
        self.emit(ind, f"else: {wc} &= {~edge!r}")
        self.emit(ind, f"{wc} = ({wc} | {DN!r}) if {wa} >= {wp} else ({wc} & {~DN!r})")
        self.dirty.update((wc, wa))

    def local_COP(self, ind: int, ins: Instruction) -> None:
        """COP between direct blocks of one storage, whose ranges fit their
        files (known at load: the table's files do not change size while a
        program runs): a slice assignment. Held words of both blocks are
        written back first; those of the destination are forgotten after.
        Anything else runs the kernel after a barrier."""
        src, dest, length = ins.operands
        sf, si, _ = self.resolve(src.address)
        df, di, _ = self.resolve(dest.address)
        n = length.value * dest.address.ftype.words_per_element
        if sf.data.typecode != df.data.typecode or si + n > len(sf.data) or di + n > len(df.data):
            self.barrier(ind)
            self.dispatch(ind, ins)
            return
        held = [(key, name) for key, name in self.words.items()
                if (key[0] == sf.number and si <= key[1] < si + n) or (key[0] == df.number and di <= key[1] < di + n)]
        for (number, index), name in held:
            if name in self.dirty:
                self.emit(ind, f"f{number}[{index!r}] = {name}")
        self.emit(ind, f"if c: {self.array_name(df)}[{di!r}:{di + n!r}] = {self.array_name(sf)}[{si!r}:{si + n!r}]")
        for key, name in held:
            if key[0] == df.number:
                del self.words[key]
                self.dirty.discard(name)

    def local_CTU(self, ind: int, ins: Instruction) -> None:
        self._local_count(ind, ins, True)

    def local_CTD(self, ind: int, ins: Instruction) -> None:
        self._local_count(ind, ins, False)

    # -- blocks -----------------------------------------------------------------------------------
    def block(self, first: int, end: int) -> BlockCode:
        """The code of one block function over rungs first..end-1."""
        self.begin_block(first)
        for k in range(first, end):
            self.rung(k, self.rungs[k])
        return self.end_block(end)

    def begin_block(self, first: int) -> None:
        self.lines, self.line_instr, self.line_rung = [], [], []
        self.words: dict[tuple[int, int], str] = {}  # (file, word) -> the local holding it
        self.local_names: set[str] = set()  # every word local of the block, held now or not
        self.dirty: set[str] = set()  # locals a rung may have changed since the last write-back
        self.temp = 0
        self.rung_index = first
        self.rung_marked = None
        self.uses_now = False
        self.current = None
        self.emit(1, "def _block(z):")

    def end_block(self, end: int) -> BlockCode:
        self.current = None
        self.flush_lines(2)
        if self.uses_now:  # the engine's clock of this scan, read once per block (TON)
            self.lines.insert(1, "        _now = _m.now_ms")
            self.line_instr.insert(1, None)
            self.line_rung.insert(1, self.line_rung[0])
        if len(self.lines) == 1:
            self.emit(2, "pass")
        return BlockCode(self.line_rung[0], end, self.lines, self.line_instr, self.line_rung)

    def compile(self) -> CompiledFile:
        cf = CompiledFile(self.number, len(self.rungs), self.has_mcr, self)
        # A block starts at every label (a JMP lands at a block's start) and
        # holds at most CHUNK_RUNGS rungs and about LOCALS_BUDGET word locals:
        # CPython's compile() slows down more than linearly with the number of
        # locals of one function, and a call's frame is made and cleared
        # local by local.
        labels = set(self.labels.values())
        count = len(self.rungs)
        k = 0
        while k < count:
            first = k
            self.begin_block(first)
            self.rung(k, self.rungs[k])
            k += 1
            while k < count and k not in labels and k - first < blocks.CHUNK_RUNGS and \
                    len(self.local_names) < blocks.LOCALS_BUDGET:
                self.rung(k, self.rungs[k])
                k += 1
            cf.add(self.end_block(k))
        self.lines = self.line_instr = self.line_rung = None  # the code is compiled: keep no text
        return cf


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

# Bit instructions that work on words held in locals, when their operands are direct.
_BIT_OPS = frozenset({"XIC", "XIO", "OTE", "OTL", "OTU", "ONS", "OSR", "OSF"})
# Instructions that read their operands, write only their destination (and
# S:0 and the minor fault words, which no local holds) and cannot raise a
# major fault: run beside the locals (in_place). The number is the index of
# the destination operand (-1: none). DIV, MOD and SQR... fault or may: not here.
_LOCAL_SAFE = {
    "EQU": -1, "NEQ": -1, "LES": -1, "LEQ": -1, "GRT": -1, "GEQ": -1, "LIM": -1, "MEQ": -1,
    "MOV": 1, "ADD": 2, "SUB": 2, "MUL": 2, "NEG": 1, "ABS": 1, "CLR": 0,
    "AND": 2, "OR": 2, "XOR": 2, "NOT": 1, "MVM": 2, "CPT": 0,
}


_SIMPLE = re.compile(r"^(w\d+_\d+|-?\d+)$")


def _word_store(ins: Instruction) -> bool:
    """A MOV or CPT of a word value, or an ADD/SUB of words, into a word:
    compiled to store into the destination's local (in_place)."""
    m, ops = ins.mnemonic, ins.operands
    if m in ("MOV", "CPT"):
        dest, value = (ops[1], ops[0]) if m == "MOV" else (ops[0], ops[1])
        return _is_word(dest) and _word_valued(value)
    return m in ("ADD", "SUB") and all(_is_word(op) for op in ops)


def _cannot_fault(node) -> bool:
    """An expression of + - * and bitwise operators only: no division by
    zero, no function that can fault."""
    if isinstance(node, (AddressRef, Const)):
        return True
    if isinstance(node, BinOp):
        return node.op in ("+", "-", "*", "AND", "OR", "XOR") and _cannot_fault(node.left) and _cannot_fault(node.right)
    if isinstance(node, UnaryOp):
        return _cannot_fault(node.operand)
    return False


# Instructions that touch no data-table word (or only leave the block,
# writing back first): no barrier before them.
_NO_BARRIER = frozenset({"JMP", "LBL", "RET", "TND", "MCR", "AFI", "SBR"})


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
    fc = _FileCompiler(table, machine, number, program.files[number].rungs, zone, jsr, module_instance)
    return fc.compile()
