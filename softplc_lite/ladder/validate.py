"""Stage 2: check a parsed program and resolve names.

Finds every problem it can (``softplc check`` lists them all), each with
file:line:col: unknown instructions (with a did-you-mean), wrong operand
counts and kinds, unknown symbols, JMPs to missing labels, JSRs to missing
files, bad data declarations. Symbols are replaced by their addresses and
quoted CPT/CMP expressions are parsed, so later stages see only addresses,
constants and expression trees.
"""

from __future__ import annotations

import operator
from dataclasses import replace

from ..gcpause import gc_paused
from ..datatable import FILE_TYPES, MAX_ELEMENTS, Address, AddressError, ValueKind, parse_address
from ..datatable.errors import DataTableError
from ..datatable.filetypes import OTHER_INTEGERS, int_range, split_file_name
from ..datatable.table import word_from_text
from .ast import (
    MAIN_FILE,
    AddressRef,
    BinOp,
    Branch,
    Call,
    Const,
    Element,
    Instruction,
    Operand,
    Placeholder,
    Pos,
    Program,
    Rung,
    SymbolRef,
    Text,
    UnaryOp,
    leaves,
)
from .errors import LadderError, ProgramErrors
from .instructions import BUILTIN, MAX_PARAMETERS, InstructionSet, K
from .limits import MAX_BRANCH_DEPTH, MAX_EXPRESSION_DEPTH, expression_depth, limit_problem
from .parser import parse_expression
from .subroutine_check import SubroutineChecks, describe as _describe, pos_of as _pos
from .symbols import SymbolIndex, resolve_name, symbol_base

_NUMERIC = (ValueKind.WORD, ValueKind.FLOAT, ValueKind.LONG)  # LONG: SLC/MicroLogix L elements
COMPARISONS = ("=", "<>", "<", "<=", ">", ">=")


# Operand kinds that must be constants, and the value kinds each address
# operand kind accepts (built once: validate() asks for every operand).
_CONSTANT_KINDS = frozenset({K.TIMEBASE, K.PRESET, K.LABEL, K.PROGRAM_FILE, K.LENGTH, K.BIT_NUMBER,
                             K.BIT_LENGTH, K.POSITION, K.PARAM_COUNT})
_WANT = {
    K.BIT: (ValueKind.BIT,), K.SOURCE: _NUMERIC, K.DEST: _NUMERIC, K.FILE: _NUMERIC,
    K.FILE_SOURCE: _NUMERIC, K.INT_SOURCE: (ValueKind.WORD,), K.WORD: (ValueKind.WORD,),
    K.TIMER: (ValueKind.TIMER,), K.COUNTER: (ValueKind.COUNTER,), K.CONTROL: (ValueKind.CONTROL,),
    K.RESETTABLE: (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL),
    K.STRING: (ValueKind.STRING,),
    K.PORT: (ValueKind.WORD,), K.FORMAT: (ValueKind.WORD,), K.WORD_FILE: (ValueKind.WORD,),
    K.INTEGER_SOURCE: (ValueKind.WORD, ValueKind.LONG), K.INTEGER_DEST: (ValueKind.WORD, ValueKind.LONG),
    K.PARAM: (ValueKind.WORD, ValueKind.FLOAT, ValueKind.STRING),
    K.PARAM_OUT: (ValueKind.WORD, ValueKind.FLOAT, ValueKind.STRING),
}
_FILE_KINDS = (K.FILE, K.FILE_SOURCE, K.WORD_FILE)  # '#' marks a file operand here, not indexing
# Integer constants allowed where an operand may be a constant or a word.
_CONSTANT_RANGE = {K.PORT: (0, 35), K.FORMAT: (0, 32000)}

_UNPLANNED = object()
_EXPRESSIONS = (BinOp, UnaryOp, Call)


class _OverLimit(Exception):
    """A rung past a limit of the language (limits.py), found while validating it."""


class _Plan:
    """One instruction's operand checks, worked out from its spec once per
    validation rather than for every instruction (validate asks for each):
    the kind of each operand, the value kinds an address there may have
    (None: not a plain address operand), and whether a '#' there marks a
    file operand rather than indexing. ``mnemonic`` is the spec's string
    when spelt the same, so every validated instruction shares it."""

    __slots__ = ("spec", "mnemonic", "min_operands", "max_operands", "kinds", "wants", "unindexed")

    def __init__(self, spec, mnemonic: str) -> None:
        self.spec = spec
        self.mnemonic = spec.mnemonic if spec.mnemonic == mnemonic else mnemonic
        self.min_operands, self.max_operands = spec.min_operands, spec.max_operands
        self.kinds = tuple(o.kind for o in spec.operands)
        self.wants = tuple(_WANT.get(kind) for kind in self.kinds)
        self.unindexed = tuple(kind in _FILE_KINDS for kind in self.kinds)


class _Checker(SubroutineChecks):
    def __init__(self, program: Program, instructions: InstructionSet = BUILTIN) -> None:
        self.program = program
        self.instructions = instructions
        self.errors: list[LadderError] = []
        self.symbols = SymbolIndex(program.symbols)
        self._shapes: dict[int, tuple] = {}  # subroutine_shape, per program file
        self._plans: dict[str, _Plan | None] = {}  # plan, per mnemonic as written
        self.bits_are_values = False  # in the file being checked: a Structured Text routine's rungs

    def error(self, pos, message: str) -> None:
        self.errors.append(LadderError(pos, message))

    # -- operands -------------------------------------------------------------------
    def resolve(self, operand: Operand, wants: str | None = None) -> Operand | None:
        """Symbols -> addresses, recursively through expressions; ``wants``
        says what the operand takes, for an unknown symbol's message."""
        if isinstance(operand, SymbolRef):
            return self.symbol(operand, wants)
        if isinstance(operand, BinOp):
            left, right = self.resolve(operand.left, wants), self.resolve(operand.right, wants)
            if left is None or right is None:
                return None
            if left is operand.left and right is operand.right:
                return operand  # nothing to resolve: keep the parsed node
            return BinOp(operand.op, left, right, operand.pos)
        if isinstance(operand, UnaryOp):
            inner = self.resolve(operand.operand, wants)
            if inner is None:
                return None
            return operand if inner is operand.operand else UnaryOp(operand.op, inner, operand.pos)
        if isinstance(operand, Call):
            inner = self.resolve(operand.arg, wants)
            if inner is None:
                return None
            return operand if inner is operand.arg else Call(operand.func, inner, operand.pos)
        return operand

    def symbol(self, ref: SymbolRef, wants: str | None = None) -> AddressRef | None:
        """A symbol, with its offset, member or bit (PollTimer/DN), as an
        address (symbols.py); an unknown name suggests the nearest declared
        symbol, else says what the operand takes (``wants``). It never
        suggests an instruction: a name in an operand's place is an operand
        (a misspelt mnemonic in mnemonic text is found as an operand too
        many, validate.instruction)."""
        name = symbol_base(ref.name) or ref.name
        if self.symbols.get(name) is None:
            near = self.symbols.nearest(name)
            extra = f" (did you mean {near}?)" if near else f": {wants}" if wants else ""
            self.error(ref.pos, f"unknown symbol {name!r}{extra}")
            return None
        try:
            return AddressRef(resolve_name(ref.name, self.symbols), ref.pos)
        except AddressError as e:
            reason = e.reason
            bit = ref.name.rpartition("/")[2]
            if "/" in ref.name and self.symbols.get(bit) is not None:
                reason += f" ({ref.name} reads as a bit of {name}; to divide, write {name} / {bit} or {name} | {bit})"
            self.error(Pos(ref.pos.source, ref.pos.line, ref.pos.column + e.position), reason)
            return None

    def expression(self, operand: Operand, mnemonic: str, where=None) -> Operand | None:
        if isinstance(operand, Text):
            try:
                operand = parse_expression(operand.value, operand.pos)
            except LadderError as e:
                self.errors.append(e)
                return None
        wants = None if where is None else f"{where()} takes numbers, word and float addresses and declared symbols"
        operand = self.resolve(operand, wants)
        if operand is None:
            return None
        ok = True
        for leaf in leaves(operand):
            # A BOOL is 0 or 1 in a Structured Text expression (1756-PM007, "Expressions"); the
            # executors read a bit leaf so. Ladder text keeps PLC-5's rule: words, floats, numbers.
            if isinstance(leaf, AddressRef) and leaf.address.kind not in _NUMERIC \
                    and not (self.bits_are_values and leaf.address.kind is ValueKind.BIT):
                self.error(leaf.pos, f"{leaf.address} is a {leaf.address.kind.value}; expressions "
                           "take words, floats and numbers")
                ok = False
        top_is_compare = isinstance(operand, BinOp) and operand.op in COMPARISONS
        if mnemonic in ("CMP", "FSC") and not top_is_compare:
            self.error(_pos(operand), f"{mnemonic} needs a comparison (=, <>, <, <=, >, >=) at the top of its expression")
            ok = False
        if mnemonic not in ("CMP", "FSC") and _has_compare(operand) and not self.bits_are_values:
            self.error(_pos(operand), f"{mnemonic} computes a value; comparisons belong in CMP")
            ok = False
        return operand if ok else None

    def operand(self, instr: Instruction, index: int, kind: K, operand: Operand) -> Operand | None:
        if kind is K.FILE_MODE:
            return self.file_mode(instr, index, operand)
        def where() -> str:
            name = self.instructions.lookup(instr.mnemonic).operand_at(index).name
            return f"{instr.mnemonic} operand {index + 1} ({name})"

        if kind is K.EXPRESSION:
            return self.expression(operand, instr.mnemonic, where)
        wants = None
        if isinstance(operand, SymbolRef) and self.symbols.declaration(operand.name) is None:
            wants = f"{where()} takes {_a(kind.value)}" + ("" if kind in _CONSTANT_KINDS else
                                                           f", and no SYMBOL line declares {operand.name}")
        if kind is K.ANY:
            return self.resolve(operand, wants)
        resolved = self.resolve(operand, wants)
        if resolved is None:
            return None

        def bad(expected: str) -> None:
            self.error(_pos(resolved), f"{where()} must be {expected}, not {_describe(resolved)}")

        if kind in _CONSTANT_KINDS:
            if not isinstance(resolved, Const):
                bad(f"a constant ({kind.value})")
                return None
            v = resolved.value
            if kind is K.TIMEBASE:
                if v not in (1.0, 0.01, 0.001):
                    bad("the time base 1.0, 0.01 or 0.001")
                    return None
                return resolved
            if isinstance(v, float):
                bad(f"an integer ({kind.value})")
                return None
            lo, hi = {K.PRESET: (-32768, 32767), K.LABEL: (0, 999), K.PROGRAM_FILE: (3, 999),
                      K.LENGTH: (1, 1000), K.BIT_NUMBER: (0, 15),
                      K.BIT_LENGTH: (1, 16000), K.POSITION: (0, 1000), K.PARAM_COUNT: (0, MAX_PARAMETERS)}[kind]
            if kind is K.BIT_NUMBER and instr.mnemonic == "BTD" and index == 4:
                lo, hi = 1, 16
            if not lo <= v <= hi:
                bad(f"in {lo}..{hi}")
                return None
            return resolved
        if isinstance(resolved, Const):
            if kind in _CONSTANT_RANGE:
                lo, hi = _CONSTANT_RANGE[kind]
                if isinstance(resolved.value, int) and lo <= resolved.value <= hi:
                    return resolved
                bad(f"a {kind.value.split(' or ')[0]} in {lo}..{hi}, or a word address")
                return None
            if kind is K.PARAM:
                return self._int_constant(resolved, where()) if isinstance(resolved.value, int) else resolved
            if kind in (K.SOURCE, K.FILE_SOURCE):
                return _word_constant(resolved) if isinstance(resolved.value, int) else resolved
            if kind in (K.INT_SOURCE, K.INTEGER_SOURCE) and isinstance(resolved.value, int):
                return self._int_constant(resolved, where())
            bad(kind.value)
            return None
        if not isinstance(resolved, AddressRef):
            bad(kind.value)
            return None
        a = resolved.address
        want = _WANT[kind]
        if a.kind not in want:
            bad(kind.value)
            return None
        if kind is K.STRING and a.ftype.letter != "ST":  # ACN, AEX ...: 82 characters (PLC-5, SLC)
            bad("an ST string (an SL file's long strings go to the Logix string instructions)")
            return None
        if kind in _FILE_KINDS and a.indexed:
            # '#' marks a file operand here (PLC-5 file instructions), not indexing.
            return AddressRef(replace(a, indexed=False), resolved.pos)  # keeps an SLC address's form
        return resolved

    def file_mode(self, instr: Instruction, index: int, operand: Operand) -> Operand | None:
        """FAL/FSC mode: ALL or INC (words of the instruction, never looked up
        as symbols) or a number of elements per scan, 1..the length."""
        if isinstance(operand, SymbolRef) and operand.name.upper() in ("ALL", "INC"):
            return operand
        spec = self.instructions.lookup(instr.mnemonic)
        length = next((o.value for o, s in zip(instr.operands, spec.operands)
                       if s.kind is K.LENGTH and isinstance(o, Const) and isinstance(o.value, int)), 1000)
        if isinstance(operand, Const) and isinstance(operand.value, int) and 1 <= operand.value <= length:
            return operand
        what = operand.name if isinstance(operand, SymbolRef) else _describe(operand)
        self.error(_pos(operand), f"{instr.mnemonic} operand {index + 1} (mode) must be ALL, INC or a number "
                   f"of elements per scan 1..{length}, not {what}")
        return None

    def _int_constant(self, const: Const, where: str) -> Const | None:
        """Where only a 16-bit word can go: a decimal constant in
        -32768..32767, or a hex bit pattern up to 0xFFFF."""
        v = const.value
        if -32768 <= v <= 32767 or const.hex and 0 <= v <= 0xFFFF:
            return _word_constant(const)
        self.error(const.pos, f"{where}: {_word_range_problem(v)}")
        return None

    # -- instructions and rungs ---------------------------------------------------------
    def plan(self, mnemonic: str) -> _Plan | None:
        """How to check the operands of ``mnemonic`` (None: no such
        instruction), worked out once per mnemonic as written."""
        plan = self._plans.get(mnemonic, _UNPLANNED)
        if plan is _UNPLANNED:
            spec = self.instructions.lookup(mnemonic)
            plan = self._plans[mnemonic] = None if spec is None else _Plan(spec, mnemonic)
        return plan

    def instruction(self, instr: Instruction, file_number: int, labels: set[int], first: bool,
                    at_end: bool | None = None) -> Instruction:
        """``instr`` validated; ``first``: it opens its rung; ``at_end``: it
        stands where an output does, nothing after it in series (None: not
        known), which a did-you-mean for a misspelt mnemonic follows."""
        given = instr.operands  # once: a property (ast.Instruction)
        for op in given:
            if isinstance(op, _EXPRESSIONS) and expression_depth(op) > MAX_EXPRESSION_DEPTH:
                raise _OverLimit  # before anything walks it recursively
        plan = self.plan(instr.mnemonic)
        if plan is None:
            hint = self.instructions.hint(instr.mnemonic, at_end)
            self.error(instr.pos, f"unknown instruction {instr.mnemonic!r}{hint}")
            return instr
        spec = plan.spec
        n = len(given)
        if not plan.min_operands <= n <= plan.max_operands:
            extras = given[spec.max_operands:]
            strays = [o for o in extras if isinstance(o, SymbolRef) and self.symbols.declaration(o.name) is None]
            if strays:
                # In mnemonic text a misspelt mnemonic reads as an operand of the instruction before it:
                # it stands where an output does if that instruction does and no other misspelt one follows.
                stray = strays[0]
                output = at_end and len(strays) == 1
                self.error(stray.pos, f"unknown instruction {stray.name!r}{self.instructions.hint(stray.name, output)}")
                return instr
            want = (f"{spec.min_operands}..{spec.max_operands}" if spec.optional else str(spec.max_operands))
            plural = "" if want == "1" else "s"
            # CPT N7:0 N7:1+5: the mnemonic form splits an unquoted expression into operands
            quote = (' (in mnemonic text an expression with operators is quoted: "N7:1 + 5")'
                     if n > spec.max_operands and any(o.kind is K.EXPRESSION for o in spec.operands) else "")
            self.error(instr.pos, f"{spec.mnemonic} takes {want} operand{plural} ({spec.signature()}), got {n}{quote}")
            return instr
        kinds, wants, unindexed = plan.kinds, plan.wants, plan.unindexed
        last = len(kinds) - 1  # a repeated last operand covers every position from its own on
        checked_operands = []
        refused = changed = False
        for i, op in enumerate(given):
            j = i if i < last else last
            if op.__class__ is AddressRef:
                # The common case, answered here: an address of a kind the operand takes.
                want, address = wants[j], op.address
                if (want is not None and address.kind in want and not (address.indexed and unindexed[j])
                        and (kinds[j] is not K.STRING or address.type_letter == "ST")):
                    checked_operands.append(op)
                    continue
            elif _refused(op):
                # An operand the parser refused (and reported) is a Placeholder: not checked again.
                refused = True
                checked_operands.append(op)
                continue
            checked = self.operand(instr, i, kinds[j], op)
            if checked is None or checked is op:
                checked_operands.append(op)
            else:
                checked_operands.append(checked)
                changed = True
        operands = tuple(checked_operands)  # no spare capacity: the validated tree is kept
        if refused:
            return instr.copy_with(plan.mnemonic, operands)
        if spec.mnemonic == "LBL" and not first:
            self.error(instr.pos, "LBL must be the first instruction of its rung")
        if spec.mnemonic == "JSR" and operands and isinstance(operands[0], Const):
            target = operands[0].value
            if target not in self.program.files:
                self.error(_pos(operands[0]), f"JSR to program file {target}, which does not exist"
                           f" (files: {', '.join(map(str, sorted(self.program.files)))})")
            else:
                self.jsr_parameters(instr, operands, target)
        if spec.mnemonic == "SBR" and operands:
            rungs = self.program.files[file_number].rungs
            if file_number == MAIN_FILE or not (rungs and rungs[0].elements and rungs[0].elements[0] is instr):
                self.error(instr.pos, "an SBR with parameters must be the first instruction of the first rung "
                           "of a subroutine file (3..999): a JSR passes its inputs there")
        if spec.mnemonic == "JMP" and operands and isinstance(operands[0], Const):
            if operands[0].value not in labels:
                self.error(_pos(operands[0]), f"JMP to label {operands[0].value}, which is not in program file {file_number}")
        if not changed and instr.mnemonic is plan.mnemonic and type(given) is tuple:
            return instr  # already in validated form, the spec's mnemonic string included: kept
        return instr.copy_with(plan.mnemonic, operands)

    def series(self, elements: list[Element], file_number: int, labels: set[int], first: bool,
               depth: int = 0, tail: bool = True) -> tuple[Element, ...]:
        """The validated series (``depth``: branches around it). Raises
        _OverLimit past the language's limits (limits.py), checked on the
        way rather than by a walk of every rung beforehand. A part already
        in validated form (tuples, nothing to resolve) is shared, not copied.
        ``tail``: the series ends at the right rail (nothing follows it), so
        its last element stands where an output does."""
        out: list[Element] = []
        end = len(elements) - 1
        for el in elements:
            if isinstance(el, Branch):
                if depth >= MAX_BRANCH_DEPTH:
                    raise _OverLimit
                if len(el.legs) < 2:
                    self.error(el.pos, "a branch needs at least two legs (BST ... NXB ... BND)")
                at_end = tail and len(out) == end
                legs = tuple([self.series(leg, file_number, labels, False, depth + 1, at_end) for leg in el.legs])
                for leg in el.legs:
                    if not leg:
                        self.error(el.pos, "empty branch leg")
                out.append(el if _same(legs, el.legs) else el.copy_with(legs))
            else:
                out.append(self.instruction(el, file_number, labels, first and not out, tail and len(out) == end))
        return elements if _same(out, elements) else tuple(out)  # a tuple: no spare capacity

    def run(self) -> Program:
        prog = self.program
        spelt: dict[str, str] = {}
        for name, decl in prog.symbols.items():
            if self.instructions.lookup(name) is not None:
                self.error(decl.pos, f"symbol {name} has the name of an instruction")
            first = spelt.setdefault(name.upper(), name)
            if first != name:  # a program built as a tree (the parser refuses this itself)
                self.error(decl.pos, f"symbol {name} is declared twice (first as {first}; symbols compare "
                           "without regard to case)")
        for decl in prog.data:
            self.data(decl)
        if prog.files and MAIN_FILE not in prog.files:
            first = min(prog.files.values(), key=lambda f: f.number)
            self.error(first.pos, "the program has no main file 2 (rungs before any FILE header go there)")
        resolved = Program(data=prog.data, symbols=prog.symbols)
        for number, pfile in prog.files.items():
            self.bits_are_values = pfile.listing is not None
            labels: dict[int, Rung] = {}
            for rung in pfile.rungs:
                if rung.elements and isinstance(rung.elements[0], Instruction) and rung.elements[0].mnemonic == "LBL":
                    ops = rung.elements[0].operands
                    if len(ops) == 1 and isinstance(ops[0], Const) and not isinstance(ops[0], Placeholder) \
                            and isinstance(ops[0].value, int):
                        if ops[0].value in labels:
                            self.error(rung.pos, f"label {ops[0].value} is defined twice in file {number} "
                                       f"(first at {labels[ops[0].value].pos})")
                        labels[ops[0].value] = rung
            rungs = []
            label_numbers = set(labels)
            for rung in pfile.rungs:
                if not rung.elements:
                    self.error(rung.pos, "empty rung")
                reported = len(self.errors)
                try:
                    elements = self.series(rung.elements, number, label_numbers, True)
                    rungs.append(rung if elements is rung.elements else rung.copy_with(elements))
                except _OverLimit:
                    # A tree built through the library, not the parser (which refuses it):
                    # the problems found on the way are dropped, the rung is reported once.
                    del self.errors[reported:]
                    over = limit_problem(rung.elements)
                    self.error(over[0].pos, over[1])
                    rungs.append(rung)
            resolved.files[number] = replace(pfile, rungs=rungs)
        return resolved

    def data(self, decl) -> None:
        text = decl.file
        ftype, digits = split_file_name(text)
        if ftype is None or not digits.isdigit():
            self.error(decl.pos, f"DATA {text}: expected a data file name such as N10, F11 or ST12")
            return
        try:
            parse_address(f"{text}:0")
        except AddressError as e:
            self.error(decl.pos, f"DATA {text}: {e.reason}")
            return
        if not 1 <= decl.size <= MAX_ELEMENTS:
            self.error(decl.pos, f"DATA {text}: size {decl.size} out of range 1..{MAX_ELEMENTS}")
        if len(decl.values) > decl.size:
            self.error(decl.pos, f"DATA {text}: {len(decl.values)} values for {decl.size} elements")
        for v in decl.values:
            if ftype.is_string:
                if not isinstance(v, str) or len(v) > ftype.chars:
                    self.error(decl.pos, f"DATA {text}: string files take quoted strings of at most {ftype.chars} characters")
                    return
            elif ftype.letter == "F":
                if isinstance(v, str):
                    self.error(decl.pos, f"DATA {text}: float files take numbers")
                    return
            elif ftype.storage in OTHER_INTEGERS:  # L, SI, LI
                lo, hi = int_range(ftype.item_bits)
                if not isinstance(v, int) or not lo <= v <= hi:
                    article = "an" if ftype.item_bits == 8 else "a"
                    self.error(decl.pos, f"DATA {text}: {v!r} does not fit {article} {ftype.item_bits}-bit "
                                         f"{ftype.title} ({lo}..{hi})")
                    return
            elif ftype.radix != "decimal" and isinstance(v, str):  # D "1234" (BCD digits), A "AB"
                try:
                    word_from_text(v, ftype, f"{text}")
                except DataTableError as e:
                    self.error(decl.pos, f"DATA {text}: {e}")
                    return
            elif ftype.letter in ("N", "B", "O", "I", "S", "D", "A"):
                # The parser has made hex bit patterns (0xFFFF) negative already.
                if not isinstance(v, int) or not -32768 <= v <= 32767:
                    problem = _word_range_problem(v) if isinstance(v, int) else f"{v!r} does not fit a 16-bit word"
                    self.error(decl.pos, f"DATA {text}: {problem}")
                    return
            else:
                self.error(decl.pos, f"DATA {text}: initial values are for N, B, F, ST, L, D and A files")
                return


def _same(checked, given) -> bool:
    """Is ``given`` a tuple holding exactly the ``checked`` parts (so it can
    be kept as it is)?"""
    return type(given) is tuple and len(checked) == len(given) and all(map(operator.is_, checked, given))


def _refused(operand: Operand) -> bool:
    """Does the operand hold a Placeholder (a part the parser refused)?
    Plain operands answer without walking a tree: validate asks for each."""
    if isinstance(operand, (AddressRef, Const, SymbolRef, Text)):
        return isinstance(operand, Placeholder)  # a Const subclass
    return any(isinstance(leaf, Placeholder) for leaf in leaves(operand))


def _word_constant(const: Const) -> Const:
    """Hex constants 0x8000..0xFFFF are bit patterns: 0xFFFF is -1. A
    decimal constant is its value (MOV 40000 N7:0 overflows, as 70000)."""
    v = const.value
    if const.hex and isinstance(v, int) and 0x8000 <= v <= 0xFFFF:
        return Const(v - 0x10000, const.pos, hex=True)
    return const


def _word_range_problem(v: int) -> str:
    """Why a decimal integer cannot be a 16-bit word, with the hex spelling
    of its bit pattern when it has one."""
    hint = f"; for the 16-bit pattern write 0x{v:X}" if 0x8000 <= v <= 0xFFFF else ""
    return f"{v} does not fit a 16-bit word (decimal -32768..32767){hint}"


def constant_fits(const: Const, dest: Address, overflow: str = "clamp") -> str | None:
    """For softplc check's warnings: None when ``const`` stored in ``dest``
    (MOV 40000 N7:0) keeps its value, else what the store will do. A hex
    0x8000..0xFFFF constant is a bit pattern and fits; ``overflow`` is the
    app setting (semantics.Settings.overflow)."""
    v = const.value
    if not isinstance(v, int) or dest.kind is not ValueKind.WORD or -32768 <= v <= 32767:
        return None
    if const.hex and 0 <= v <= 0xFFFF:
        return None
    if overflow == "clamp":
        stored = 32767 if v > 0 else -32768
    else:
        stored = (v & 0xFFFF) - 0x10000 if v & 0x8000 else v & 0xFFFF
    return f"{v} cannot fit {dest}, it will be stored as {stored} with overflow"


def _has_compare(expr) -> bool:
    if isinstance(expr, BinOp):
        return expr.op in COMPARISONS or _has_compare(expr.left) or _has_compare(expr.right)
    if isinstance(expr, UnaryOp):
        return _has_compare(expr.operand)
    if isinstance(expr, Call):
        return _has_compare(expr.arg)
    return False


def _a(kind: str) -> str:
    """An operand kind with its article: "a bit address", "an integer constant"."""
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def check(program: Program, instructions: InstructionSet = BUILTIN) -> tuple[Program, list[LadderError]]:
    """Validate; return the resolved program and every problem found."""
    checker = _Checker(program, instructions)
    resolved = checker.run()
    checker.errors.sort(key=lambda e: (e.pos.source, e.pos.line, e.pos.column))
    return resolved, checker.errors


@gc_paused
def validate(program: Program, instructions: InstructionSet = BUILTIN) -> Program:
    """Validate and resolve, raising ProgramErrors if anything is wrong."""
    resolved, errors = check(program, instructions)
    if errors:
        raise ProgramErrors(errors)
    return resolved
