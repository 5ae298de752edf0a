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
from collections import Counter
from functools import cached_property

from ..gcpause import gc_paused
from ..datatable import DataTable, ValueKind, data_bit_mask
from ..datatable.filetypes import Storage
from . import blocks
from .ast import AddressRef, Branch, Const, Element, Instruction, Program, Rung, address_refs, instructions_of, walk
from .blocks import RET, RUNG_BOOL, TND, BlockCode, CompiledFile  # noqa: F401 (RET, TND: the block protocol, imported from here)
from .held_words import _FLAGS, _LOCAL_SAFE, _NO_BARRIER, HeldWords, _cannot_fault, _may_hold, _word_store
from .templates import _COMPARE, TEMPLATES
from .bound import BoundAccess
from .expr import namespace as expr_namespace
from .expr import to_python
from .instr import BOUND
from .resolvers import resolver
from .semantics import DN, EN, STAMP, TT, Machine


class EndScan(Exception):
    """TND: end this scan now. Control flow, not an error: it passes up
    through JSR calls (both executors) to the engine."""


def describe(instr: Instruction) -> str:
    from .fmt import format_instruction

    return f"{format_instruction(instr, 'mnemonic')} at {instr.pos}"


class _FileCompiler:
    """Compiles one program file into block functions (CompiledFile).

    It holds a locals allocator (``held``: ladder/held_words.HeldWords) and
    emits each instruction through its template (``TEMPLATES``:
    ladder/templates.py, ladder/held_templates.py). Templates are functions
    of this compiler, and use of it: ``emit``, ``location``, ``value``,
    ``expression``, ``bind``, ``bind_once``, ``resolve``, ``array_name``,
    ``barrier``, ``mark_rung``, ``dispatch``, and the state below."""

    def __init__(self, table: DataTable, machine: Machine, number: int, rungs: list[Rung], zone: list, jsr,
                 module_instance=None) -> None:
        self.table = table
        self.machine = machine
        self.number = number
        self.rungs = rungs
        self.labels = labels_of(rungs)
        self.module_instance = module_instance  # module instructions: (Instruction, Access) -> callable(c) -> c
        self.access = BoundAccess(table, machine)  # how bound and module instructions reach operands
        self.env: dict[str, object] = {"_jsr": jsr, "_zone": zone, "_m": machine, **expr_namespace(machine)}
        self.named: dict[tuple, str] = {}  # per-instruction objects, made once (a block compiled again reuses them)
        self.rung_elements: list = []
        self.current: Instruction | None = None
        self.inline_dest: str | None = None  # the local a word store writes (in_place)
        self.inline_flags: str | None = None  # the local holding S:0, if held, for that store
        self.first_contact = (None, None)  # a rung's first element and its contact expression
        self._locations: dict[int, object] = {}  # id(Address) -> Location, for direct addresses
        self._bits: dict[int, tuple] = {}  # id(Address) -> what bit() needs of a direct bit address
        self.held = HeldWords(self)  # the words the block being compiled holds in locals
        # The block being compiled (begin_block): its lines, and per line its
        # instruction and rung; a counter for temporaries; the rung being
        # compiled and the last one named to _m.rung; whether it reads the clock.
        self.lines: list[str] = []
        self.line_instr: list = []
        self.line_rung: list[int] = []
        self.temp = 0
        self.rung_index = 0
        self.rung_marked: int | None = None
        self.uses_now = False
        self.rung_in: str | None = None  # a rung's pending rung-in (start_rung)

    @cached_property
    def has_mcr(self) -> bool:
        """Whether an MCR zone may be open: every rung then takes ``z``."""
        return any(ins.mnemonic == "MCR" for r in self.rungs for ins in instructions_of(r.elements))

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

    # -- operands ----------------------------------------------------------------------------
    def location(self, ind: int, ref: AddressRef) -> tuple[str, str, str | None]:
        """Code for (array, index, mask) of an address operand; emits a
        resolver call first for indirect/indexed addresses. Only after a
        barrier: the table is exact."""
        a = ref.address
        if a.is_direct:
            f, index, bit = self.resolve(a)
            return self.array_name(f), repr(index), (repr(data_bit_mask(f.data, bit)) if bit is not None else None)
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
            name = self.held.held((f.number, index))
            if name is not None:  # held in a local (loaded at rung level before this instruction)
                if (f.number, index) == _FLAGS:
                    self.held.flags_exact(ind)
                return name if bit is None else f"(1 if {name} & {data_bit_mask(f.data, bit)!r} else 0)"
        d, i, m = self.location(ind, operand)
        if m is not None:
            return f"(1 if {d}[{i}] & {m} else 0)"
        return f"{d}[{i}]"

    def expression(self, ind: int, node) -> str:
        return to_python(node, lambda ref: self.value(ind, ref))

    def bit(self, ind: int, ref: AddressRef) -> tuple[str, int, bool] | None:
        """A bit instruction's word as (code of the word, mask, held in a
        local): a local, or an S word read in place; None: not direct."""
        a = ref.address
        # What does not change within a compile, looked up once per Address
        # (the parser makes one per address text; contacts are most of a
        # program): the word's key if a local may hold it, its mask, and
        # its code in place.
        known = self._bits.get(id(a))
        if known is None:
            if not a.is_direct:
                return None
            f, index, bit = self.resolve(a)
            known = self._bits[id(a)] = (
                (f.number, index) if _may_hold(f, index) else None, f, index,
                data_bit_mask(f.data, bit) if bit is not None else None, f"{self.array_name(f)}[{index!r}]")
        key, f, index, mask, in_place = known
        if key is not None:
            held = self.held
            name = held.held(key)
            if name is None and held.uses.get(key, 0) >= 2:
                name = held.word_at(ind, f, index)  # loaded now, at rung level
            elif name is not None and key == _FLAGS:
                held.flags_exact(ind)
            if name is not None:
                return name, mask, True
        return in_place, mask, False

    # -- rungs -------------------------------------------------------------------------------
    def rung(self, index: int, rung: Rung) -> None:
        self.rung_index = index
        self.rung_elements = rung.elements
        self.current = None
        self.rung_in = "z" if self.has_mcr else "True"
        first = rung.elements[0] if rung.elements else None
        start = len(self.lines)
        expr = self.contact_expression(first) if first is not None else None
        if expr is None:
            self.start_rung()
        self.first_contact = (first, expr)  # series takes it as computed, not twice
        self.series(2, rung.elements)
        self.fold_condition(start)

    def fold_condition(self, start: int) -> None:
        """``c = EXPR`` whose one use, later in the rung, is ``if c:`` or
        ``... if c else ...`` at rung level: EXPR goes there and the line
        goes (a store and a load of c less a rung; ``if True:`` compiles
        to nothing). Every rung sets c before it reads it, so no later
        rung needs this one's."""
        lines = self.lines
        for k in range(start, len(lines)):
            if lines[k].startswith(_RUNG_C):
                break
        else:
            return
        use = None
        for j in range(k + 1, len(lines)):
            found = _C_NAME.findall(lines[j])
            if found:
                if use is not None or len(found) > 1:
                    return
                use = j
        if use is None or not all(_LOAD.match(lines[j]) for j in range(k + 1, use)):
            return  # (only loads between: EXPR reads the same data later)
        line = lines[use]
        expr = lines[k][len(_RUNG_C):]
        if line.startswith(_RUNG_IF):
            lines[use] = f"{_RUNG_IF[:-2]}{expr}:{line[len(_RUNG_IF):]}"
        elif line.startswith("        ") and line[8] != " " and " if c else " in line:
            lines[use] = line.replace(" if c else ", f" if ({expr}) else ", 1)
        else:
            return
        del lines[k], self.line_instr[k], self.line_rung[k]

    def start_rung(self) -> None:
        """Give ``c`` its rung-in (left pending while a rung's first contacts
        can assign it in one line)."""
        if self.rung_in is not None:
            self.emit(2, f"c = {self.rung_in}")
            self.rung_in = None

    def series(self, ind: int, elements) -> None:
        run: list[tuple[Element, str]] = []  # contacts waiting to be emitted as one expression
        for el in elements:
            if el is self.first_contact[0]:
                expr = self.first_contact[1]
                self.first_contact = (None, None)
            else:
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
        if el.__class__ is Instruction:
            m = el.mnemonic
            if m == "XIC" or m == "XIO":  # most of a program: first
                held = self.bit(2, el.operands[0])
                if held is None:
                    return None
                return f"{held[0]} & {held[1]!r}" if m == "XIC" else f"not {held[0]} & {held[1]!r}"
            if m in _COMPARE and all(isinstance(op, Const) or op.address.is_direct for op in el.operands):
                # A compare of direct words reads and writes nothing else: a contact too.
                for op in el.operands:
                    if isinstance(op, AddressRef):
                        self.held.local(2, op)
                a, b = (self.value(2, op) for op in el.operands)
                return f"{a} {_COMPARE[m]} {b}"
            return None
        legs = []  # a branch
        for leg in el.legs:
            terms = [self.contact_expression(e) for e in leg]
            if None in terms:
                return None
            legs.append("True" if not terms else terms[0] if len(terms) == 1 else f"({' and '.join(terms)})")
        return f"({' or '.join(legs)})"

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
        template = TEMPLATES.get(m)
        if template is not None:
            if template.bits is not None:
                words = [self.bit(ind, op) for op in ops]
                if None not in words:
                    template.bits(self, ind, *words)
                    return
            if template.held is not None and all(isinstance(op, Const) or op.address.is_direct for op in ops) and \
                    self.resolve(ops[0].address).file.ftype.storage is Storage.WORD:
                template.held(self, ind, ins)  # on the element's words held in locals
                return
        dest = self.local_safe(ins)
        if dest is not False:
            self.in_place(ind, ins, dest)
            return
        if m not in _NO_BARRIER:
            self.barrier(ind)
        self.dispatch(ind, ins)

    def dispatch(self, ind: int, ins: Instruction) -> None:
        """The instruction's code on the table in place: its template, or a
        call of its bound (ladder/instr/) or module object."""
        m = ins.mnemonic
        template = TEMPLATES.get(m)
        if template is not None:
            template.table(self, ind, ins.operands)
            return
        bound = BOUND.get(m)
        if bound is not None:
            # A bound instruction (ladder/instr/): one object per instruction.
            name = self.bind_once((id(ins), "bi"), "_bi", lambda: bound.bind(ins, self.access))
            self.emit(ind, f"c = {name}({RUNG_BOOL})")
            return
        key = (id(ins), "tli")
        if key not in self.named:
            instance = self.module_instance(ins, self.access) if self.module_instance is not None else None
            if instance is None:
                raise NotImplementedError(f"no compiler template for {m}")  # validated programs never get here
            self.bind_once(key, "_tli", lambda: instance)
        # A module instruction: its instance takes the rung-in and gives the rung-out.
        self.emit(ind, f"c = {self.named[key]}({RUNG_BOOL})")

    def barrier(self, ind: int) -> None:
        """Before code that is not block code: the table made exact, the
        locals forgotten (that code may write any word), and the rung
        recorded for a minor fault it may set."""
        self.held.flush(ind)
        self.held.forget_all()
        self.mark_rung(ind)

    def mark_rung(self, ind: int) -> None:
        """``_m.rung``: the rung being scanned, for what is not block code."""
        if self.rung_marked != self.rung_index:
            self.rung_marked = self.rung_index
            self.emit(ind, f"_m.rung = {self.rung_index!r}")

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
        held = self.held
        for op in ins.operands:
            if op is not dest:
                for ref in address_refs(op):
                    held.local(ind, ref)
        forget = []
        if dest is not None:
            if _word_store(ins) and held.holdable(dest):
                # A 16-bit result into a word: stored inline (i_MOV, i_CPT, _math2),
                # into its local if held, else into the table; S:0 likewise.
                f, index, _ = self.resolve(dest.address)
                self.inline_dest = held.held((f.number, index)) or ""
                self.inline_flags = held.flags_local(ind) or ""
                self.dispatch(ind, ins)
                held.changed(self.inline_dest, self.inline_flags)
                self.inline_dest = self.inline_flags = None
                return
            self.mark_rung(ind)  # a store may set a minor fault (overflow)
            # Its kernel writes the destination and S:0 in the table: held, they
            # are written back first and forgotten after.
            f, index, _ = self.resolve(dest.address)
            forget = held.write_back(ind, ((f.number, index), _FLAGS))
        self.dispatch(ind, ins)
        held.forget(forget)

    # -- blocks -----------------------------------------------------------------------------------
    def block(self, first: int, end: int, words=None) -> BlockCode:
        """The code of one block function over rungs first..end-1
        (``words``: each rung's rung_words, when known)."""
        self.begin_block(first)
        self.held.begin(Counter(key for k in range(first, end)
                                for key in (words[k] if words is not None else self.held.rung_words(self.rungs[k]))))
        for k in range(first, end):
            self.rung(k, self.rungs[k])
        return self.end_block(end)

    def begin_block(self, first: int) -> None:
        self.lines, self.line_instr, self.line_rung = [], [], []
        self.temp = 0
        self.rung_index = first
        self.rung_marked = None
        self.uses_now = False
        self.current = None
        self.emit(1, "def _block(z):")

    def end_block(self, end: int) -> BlockCode:
        self.current = None
        self.held.flush(2)
        if self.uses_now:  # the engine's clock of this scan, read once per block (TON)
            self.lines.insert(1, f"        _now = _m.now_ms; _ton_done = (_now & {STAMP!r}) | {EN | DN!r}; "
                                 f"_ton_timing = (_now & {STAMP!r}) | {EN | TT!r}")
            self.line_instr.insert(1, None)
            self.line_rung.insert(1, self.line_rung[0])
        if len(self.lines) == 1:
            self.emit(2, "pass")
        return BlockCode(self.line_rung[0], end, self.lines, self.line_instr, self.line_rung)

    def compile(self) -> CompiledFile:
        # A block starts at every label (a JMP lands at a block's start) and
        # holds at most CHUNK_RUNGS rungs, about LOCALS_BUDGET word locals and
        # about INSTRUCTIONS_BUDGET instructions:
        # CPython's compile() slows down more than linearly with the number of
        # locals of one function, and a call's frame is made and cleared
        # local by local.
        labels = set(self.labels.values())
        count = len(self.rungs)
        words = [self.held.rung_words(rung) for rung in self.rungs]
        self.has_mcr = self.held.saw_mcr  # (the pass just made saw every instruction)
        cf = CompiledFile(self.number, len(self.rungs), self.has_mcr, self)
        k = 0
        while k < count:
            first = k
            distinct = set(words[k])
            size = len(instructions_of(self.rungs[k].elements))
            k += 1
            while k < count and k not in labels and k - first < blocks.CHUNK_RUNGS and \
                    len(distinct) < blocks.LOCALS_BUDGET and size < blocks.INSTRUCTIONS_BUDGET:
                distinct.update(words[k])
                size += len(instructions_of(self.rungs[k].elements))
                k += 1
            cf.add(self.block(first, k, words))
        # The code is compiled: keep no text, and no caches a later isolate() can rebuild.
        self.lines = self.line_instr = self.line_rung = None
        self._locations, self._bits = {}, {}
        self.held.done()
        return cf


# fold_condition: the rung-level assignment of c, its rung-level "if c:", and
# c as a name (not part of one: _fc, _calls).
_RUNG_C = "        c = "
_RUNG_IF = "        if c:"
_C_NAME = re.compile(r"(?<![\w.])c(?!\w)")
_LOAD = re.compile(r"^        (?:\w+ = )+f\d+\[\d+\](?:; (?:\w+ = )+(?:f\d+\[\d+\]|None))*$")  # w3_0 = f3[0]

# Outputs: they leave the rung condition as they found it.
_PASS_THROUGH = frozenset({"OTE", "OTL", "OTU"})

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
