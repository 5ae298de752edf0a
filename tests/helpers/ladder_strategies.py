"""Hypothesis strategies for random, valid ladder programs (as AST).

``programs()`` draws a :class:`~softplc_lite.ladder.ast.Program` that
``validate`` accepts and that ``fmt`` can print: a main file 2 and optionally
subroutine files 3.. with SBR/RET/JSR, forward JMPs to labels, nested
branches (parallel outputs too), symbols and a ``DATA N9`` declaration.

The address space is small on purpose, so rungs interact: B3:0..3, I:0,
O:0, N7:0..9, F8:0..3, T4:0..3, C5:0..3. Indirect addresses take their
element, bit or file number from N9:0..4 (``N7:[N9:1]``, ``B3/[N9:0]``,
``N[N9:4]:2``), which the program never writes: ``DATA N9`` gives them
values that are mostly in range and sometimes not, so some programs fault
(and both executors must then fault the same way). A few use ``N7:[N7:k]``,
whose index the program itself changes.

The AST is built the way the parser builds it (negative constants as
``Const(-5)``, never ``UnaryOp('NEG', Const(5))``; CPT/CMP expressions as
trees), so ``parse_program(format_program(p, style)) == p`` can be checked.
"""

from __future__ import annotations

import functools
import random

from hypothesis import strategies as st

from softplc_lite.datatable import parse_address
from softplc_lite.ladder.ast import (
    AddressRef,
    BinOp,
    Branch,
    Call,
    Const,
    DataDecl,
    Instruction,
    Program,
    ProgramFile,
    Rung,
    SymbolDecl,
    SymbolRef,
    UnaryOp,
)

INDEX_FILE = "N9"
INDEX_WORDS = 5  # N9:0..3 element/bit numbers, N9:4 a file number
FILE_SELECTOR = 4

# -- addresses ---------------------------------------------------------------------


def ref(text: str) -> AddressRef:
    return AddressRef(parse_address(text))


N7_WORDS = [f"N7:{k}" for k in range(10)]
F8_FLOATS = [f"F8:{k}" for k in range(4)]
TIMERS = [f"T4:{k}" for k in range(4)]
COUNTERS = [f"C5:{k}" for k in range(4)]
B3_BITS = [f"B3:{e}/{b}" for e in range(4) for b in range(16)]
OUT_BITS = [f"O:0/{b:o}" for b in range(16)]
IN_BITS = [f"I:0/{b:o}" for b in range(16)]
N7_BITS = [f"N7:{e}/{b}" for e in range(10) for b in (0, 1, 2, 7, 15)]
TIMER_BITS = [f"T4:{k}/{b}" for k in range(4) for b in ("EN", "TT", "DN")]
COUNTER_BITS = [f"C5:{k}/{b}" for k in range(4) for b in ("CU", "CD", "DN", "OV", "UN")]
# The arithmetic flags (carry, overflow, zero, sign), which math sets and the
# compiled code may hold in a local.
STATUS_BITS = [f"S:0/{b}" for b in range(4)]
STRUCT_WORDS = [f"T4:{k}.{m}" for k in range(4) for m in ("PRE", "ACC")] + [
    f"C5:{k}.{m}" for k in range(4) for m in ("PRE", "ACC")]
B3_WORDS = [f"B3:{k}" for k in range(4)]
IDX = [f"N9:{k}" for k in range(4)]  # index words (N9:4 is the file selector)
# The last element of each file: the test references these so that every
# file holds the whole address space (indirect addresses do not grow files).
ADDRESS_SPACE = ["B3:3", "N7:9", "F8:3", "T4:3", "C5:3", "N9:4"]


# Strategies made once: hypothesis validates each new strategy object and
# works out its properties, which cost more than the draw itself when a
# program takes a thousand draws.
@functools.cache
def _integers(lo: int, hi: int) -> st.SearchStrategy[int]:
    return st.integers(lo, hi)


@functools.cache
def _indexes(n: int) -> st.SearchStrategy[int]:
    return st.sampled_from(range(n))


class Gen:
    """Draws one program procedurally: every choice is one small hypothesis
    draw, so generation is cheap and shrinks well (towards the first
    option of each choice, the smallest number, fewer elements)."""

    def __init__(self, draw, symbols: dict[str, str]) -> None:
        self._draw = draw
        self.symbols: dict[str, list[str]] = {}
        for name, text in symbols.items():
            self.symbols.setdefault(parse_address(text).kind.value, []).append(name)

    # -- primitive choices ------------------------------------------------------------
    def int(self, lo: int, hi: int) -> int:
        return self._draw(_integers(lo, hi))

    def kind(self, n: int) -> int:
        """One of n cases, 0..n-1, uniformly."""
        return self.pick(range(n))

    def chance(self, one_in: int) -> bool:
        return self.kind(one_in) == 0

    def pick(self, options: list):
        # sampled_from is uniform (integers() favours the ends of its range);
        # an index into the options, so that one strategy serves every
        # choice of that many options
        return options[self._draw(_indexes(len(options)))]

    def weighted(self, *pairs):
        """pairs of (weight, value); returns a value."""
        return self.pick([v for w, v in pairs for _ in range(w)])

    # -- operands ------------------------------------------------------------------------
    def _operand(self, kind: str, direct: list[str], indirect):
        """A direct address (mostly), an indirect one (sometimes), a symbol (rarely)."""
        names = self.symbols.get(kind)
        how = self.weighted((8, "direct"), (2 if indirect else 0, "indirect"), (1 if names else 0, "symbol"))
        if how == "symbol":
            return SymbolRef(self.pick(names))
        if how == "indirect":
            return ref(indirect())
        return ref(self.pick(direct))

    def _idx(self) -> str:
        return self.pick(IDX)

    def _indirect_bit(self) -> str:
        k = self.kind(5 + self.chance(2))
        if k == 0:
            return f"B3/[{self._idx()}]"
        if k == 1:
            return f"B3:[{self._idx()}]/{self.int(0, 15)}"
        if k == 2:
            return f"N7:{self.int(0, 9)}/[{self._idx()}]"
        if k == 3:
            return f"T4:[{self._idx()}]/{self.pick(['DN', 'EN', 'TT'])}"
        return f"N7:[N7:{self.int(0, 3)}]/{self.int(0, 15)}"

    def _indirect_word(self) -> str:
        k = self.kind(6)
        if k <= 1:
            return f"N7:[{self._idx()}]"
        if k == 2:
            return f"N[N9:{FILE_SELECTOR}]:{self.int(0, 3)}"
        if k == 3:
            return f"T4:[{self._idx()}].ACC"
        if k == 4:
            return f"#N7:{self.int(0, 3)}"  # indexed by S:24 (0 unless written)
        # The program itself changes N7:0..3, so these often leave the file.
        return f"N7:[N7:{self.int(0, 3)}]" if self.chance(2) else f"N7:[{self._idx()}]"

    def bit_read(self):
        pool = self.pick([B3_BITS, IN_BITS, OUT_BITS, N7_BITS, TIMER_BITS, COUNTER_BITS, STATUS_BITS])
        return self._operand("bit", pool, self._indirect_bit)

    def bit_write(self):
        pool = self.pick([B3_BITS, B3_BITS, OUT_BITS, N7_BITS])
        return self._operand("bit", pool, self._indirect_bit)

    def word(self):
        pool = self.pick([N7_WORDS, N7_WORDS, N7_WORDS, STRUCT_WORDS, B3_WORDS])
        return self._operand("word", pool, self._indirect_word)

    def float(self):
        return self._operand("float", F8_FLOATS, lambda: f"F8:[{self._idx()}]")

    def numeric_dest(self):
        return self.float() if self.chance(3) else self.word()

    def constant(self) -> Const:
        k = self.kind(7)
        if k == 6:
            return Const(self.pick([0, 0.0]))  # divisors, MOD operands
        if k <= 2:
            return Const(self.int(-10, 40))
        if k == 3:
            return Const(self.int(-32768, 32767))
        if k == 4:
            return Const(self.pick([0.0, 0.5, 1.5, -2.25, 100.0, 1e-05, 3.0e10, -7.75]))
        return Const(self._draw(st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, width=32)))

    def source(self):
        return self.weighted((4, self.word), (2, self.float), (3, self.constant))()

    def int_source(self):
        return Const(self.int(-32768, 32767)) if self.chance(3) else self.word()

    def timer(self):
        return self._operand("timer", TIMERS, lambda: f"T4:[{self._idx()}]")

    def counter(self):
        return self._operand("counter", COUNTERS, lambda: f"C5:[{self._idx()}]")

    # -- expressions (CPT, CMP) ---------------------------------------------------------
    def expression(self, depth: int = 3):
        k = self.kind(7) if depth > 0 else self.kind(2)
        if k == 0:
            return self.weighted((3, self.word), (1, self.float))()
        if k == 1:
            return self.constant()
        if k in (2, 3):
            return BinOp(self.pick(ARITH_OPS), self.expression(depth - 1), self.expression(depth - 1))
        if k == 4:
            operand = self.expression(depth - 1)
            # The parser folds "-5" into Const(-5); NEG wraps only non-constants.
            return Const(-operand.value) if isinstance(operand, Const) else UnaryOp("NEG", operand)
        if k == 5:
            return UnaryOp("NOT", self.expression(depth - 1))
        return Call(self.pick(FUNCS), self.expression(depth - 1))

    def comparison(self):
        return BinOp(self.pick(COMPARE_OPS), self.expression(2), self.expression(2))

    # -- instructions ----------------------------------------------------------------------
    def file_instruction(self) -> Instruction:
        """COP or FLL on N7 or F8 blocks (source and destination of one type)."""
        letter = self.pick(["N7", "N7", "F8"])
        size = 10 if letter == "N7" else 4
        length = Const(self.int(1, 4))

        def block():
            if self.chance(10):
                return ref(f"#{letter}:[{self._idx()}]")
            return ref(f"#{letter}:{self.int(0, size - 1)}")

        dest = block()
        if self.chance(2):
            return I("COP", block(), dest, length)
        value = block() if self.chance(4) else self.source()
        return I("FLL", value, dest, length)

    def condition(self) -> Instruction:
        k = self.kind(9)
        if k <= 1:
            return I("XIC", self.bit_read())
        if k <= 3:
            return I("XIO", self.bit_read())
        if k == 4:
            return I("ONS", self.bit_write())
        if k == 5:
            return I(self.pick(["EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ"]), self.source(), self.source())
        if k == 6:
            return I("LIM", self.source(), self.source(), self.source())
        if k == 7:
            return I("MEQ", self.int_source(), self.int_source(), self.int_source())
        return I("CMP", self.comparison())

    def _preset(self) -> Const:
        # A negative timer preset or accumulator faults the processor (code 34).
        return Const(self.weighted((40, lambda: self.int(0, 30)), (10, lambda: self.int(0, 32767)),
                                   (1, lambda: self.int(-3, -1)))())

    def _accum(self) -> Const:
        return Const(self.weighted((40, lambda: 0), (10, lambda: self.int(0, 40)), (1, lambda: -1))())

    def output(self, jumps: list[int], jsrs: list[int], in_sub: bool) -> Instruction:
        """An output instruction. ``jumps``: labels a JMP here may go to (all
        in later rungs); ``jsrs``: files a JSR here may call."""
        if self.kind(40) == 39:
            return I("TND")  # rare: it ends the scan and hides the rest
        k = self.kind(20 + bool(jumps) + bool(jsrs) + in_sub)
        if k <= 2:
            return I("OTE", self.bit_write())
        if k == 3:
            return I("OTL", self.bit_write())
        if k == 4:
            return I("OTU", self.bit_write())
        if k == 5:
            return I(self.pick(["OSR", "OSF"]), self.bit_write(), self.bit_write())
        if k in (6, 7):
            base = Const(self.pick([0.01, 0.01, 1.0]))
            return I(self.pick(["TON", "TOF", "RTO"]), self.timer(), base, self._preset(), self._accum())
        if k == 8:
            # Counters start near the ends of their range now and then, to wrap (OV, UN).
            acc = self.weighted((3, self._accum), (1, lambda: Const(self.pick([32767, 32767, -32768, 32765]))))()
            return I(self.pick(["CTU", "CTD"]), self.counter(), self._preset(), acc)
        if k == 9:
            return I("RES", self.timer() if self.chance(2) else self.counter())
        if k == 10:
            return I(self.pick(["ADD", "SUB", "MUL", "DIV", "MOD"]), self.source(), self.source(), self.numeric_dest())
        if k == 11:
            return I(self.pick(["NEG", "ABS", "SQR", "MOV", "MOV"]), self.source(), self.numeric_dest())
        if k == 12:
            return I("CPT", self.numeric_dest(), self.expression())
        if k == 13:
            return I("CLR", self.numeric_dest())
        if k == 14:
            return I(self.pick(["AND", "OR", "XOR"]), self.int_source(), self.int_source(), self.word())
        if k == 15:
            return I("NOT", self.int_source(), self.word())
        if k == 16:
            return I("MVM", self.int_source(), self.int_source(), self.word())
        if k == 17:
            return self.file_instruction()
        if k == 18:
            return I("BTD", self.int_source(), Const(self.int(0, 15)), self.word(), Const(self.int(0, 15)),
                     Const(self.int(1, 16)))
        if k == 19:
            return I("MOV", self.source(), self.numeric_dest())
        extra = ([("JMP", jumps)] if jumps else []) + ([("JSR", jsrs)] if jsrs else []) + (
            [("RET", None)] if in_sub else [])
        mnemonic, targets = extra[k - 20]
        return I(mnemonic, Const(self.pick(targets))) if targets else I(mnemonic)

    # -- rungs ----------------------------------------------------------------------------------
    def conditions(self, depth: int, min_size: int = 0) -> list:
        """A series of input instructions and input branches."""
        out = []
        for _ in range(self.int(min_size, 3 if depth >= 2 else 2)):
            if depth > 0 and self.chance(4):
                out.append(Branch([self.conditions(depth - 1, 1) for _ in range(self.int(2, 3))]))
            else:
                out.append(self.condition())
        return out

    def outputs(self, depth: int, jumps, jsrs, in_sub) -> list:
        """One output, or a branch of parallel output legs (each leg: optional
        conditions, then outputs); sometimes two outputs in series."""
        k = self.kind(10)
        if k < 6 or depth <= 0:
            return [self.output(jumps, jsrs, in_sub)]
        if k < 8:
            return [self.output(jumps, jsrs, in_sub), self.output(jumps, jsrs, in_sub)]
        legs = [self.conditions(depth - 1) + self.outputs(depth - 1, jumps, jsrs, in_sub)
                for _ in range(self.int(2, 3))]
        return [Branch(legs)]

    def comment(self) -> str | None:
        if not self.chance(5):
            return None
        lines = [self._draw(COMMENT_TEXT) for _ in range(self.int(1, 3))]
        return "\n".join(lines) or None  # "" prints as no comment at all

    def rung(self, label: int | None, jumps, jsrs, in_sub) -> Rung:
        elements = [I("LBL", Const(label))] if label is not None else []
        shape = self.kind(20)
        if shape == 0:  # an MCR zone edge: conditional start or unconditional end
            if not elements and self.chance(2):
                elements.append(I("MCR"))
            else:
                elements += self.conditions(1, 1) + [I("MCR")]
        elif shape == 1:  # AFI blocks the rest
            elements += self.conditions(0) + [I("AFI")] + self.outputs(0, jumps, jsrs, in_sub)
        elif shape == 2:  # outputs in the middle of a series
            elements += self.outputs(0, jumps, jsrs, in_sub) + self.conditions(1, 1) + self.outputs(1, jumps, jsrs, in_sub)
        else:
            elements += self.conditions(2) + self.outputs(2, jumps, jsrs, in_sub)
        return Rung(elements, self.comment())

    def program_file(self, number: int, jsrs: list[int], max_rungs: int) -> ProgramFile:
        in_sub = number != 2
        count = self.int(1, max_rungs)
        # Labels on some rungs after the first; a JMP goes only forward, to a later rung.
        labels: dict[int, int] = {}
        for _ in range(self.int(0, 2) if count > 1 else 0):
            at, n = self.int(1, count - 1), self.int(0, 999)
            if at not in labels and n not in labels.values():
                labels[at] = n
        rungs = [Rung([I("SBR")], None)] if in_sub and self.chance(2) else []
        for k in range(count):
            jumps = [n for at, n in labels.items() if at > k]
            rungs.append(self.rung(labels.get(k), jumps, jsrs, in_sub))
        name = None
        if self.chance(3):
            name = self.pick(["Main", "Sub", "Scale", "Alarms_2"])
        return ProgramFile(number, name, rungs)


def I(mnemonic: str, *operands) -> Instruction:  # noqa: E743 - a short builder
    return Instruction(mnemonic, list(operands))


ARITH_OPS = ["+", "-", "*", "|", "MOD", "**", "AND", "OR", "XOR"]
COMPARE_OPS = ["=", "<>", "<", "<=", ">", ">="]
FUNCS = ["SQR", "ABS", "NEG", "FRD", "TOD", "LN", "LOG", "SIN", "COS", "TAN", "ASN", "ACS", "ATN", "DEG", "RAD"]

COMMENT_TEXT = st.text(
    alphabet=st.characters(min_codepoint=32, max_codepoint=126) | st.sampled_from("éµ°"), max_size=20
).map(str.strip)


SYMBOL_NAMES = ["Start", "StopOk", "Motor", "Level", "Count_1", "Temp", "Speed", "Pump3", "Valve_a"]
SYMBOL_TARGETS = ["B3/5", "I:0/0", "O:0/3", "N7:4", "N7:8/2", "F8:1", "T4:1", "C5:2", "T4:0/DN", "N7:[N9:2]"]


@st.composite
def programs(draw, max_rungs: int = 6, subroutines: bool = True, symbols: bool = True) -> Program:
    """A random valid program."""
    decls: dict[str, SymbolDecl] = {}
    if symbols and draw(st.booleans()):
        names = draw(st.lists(st.sampled_from(SYMBOL_NAMES), unique=True, max_size=4))
        for name in names:
            decls[name] = SymbolDecl(name, parse_address(draw(st.sampled_from(SYMBOL_TARGETS))))
    g = Gen(draw, {n: str(d.address) for n, d in decls.items()})

    # N9:0..3 index words: mostly 0..3 (in range for every indirect use),
    # sometimes past the end of a file or negative. N9:4: a file number, mostly 7.
    index = [g.int(0, 3) if not g.chance(16) else g.pick([5, 9, 12, 17, 70, -1]) for _ in range(4)]
    index.append(7 if not g.chance(12) else g.pick([9, 3, 8, 40]))
    data = [DataDecl(INDEX_FILE, INDEX_WORDS, index)]
    if g.chance(4):  # declarations the rungs do not use: for fmt and the loader
        floats = [g._draw(st.floats(-1e6, 1e6, allow_nan=False, width=32)) for _ in range(g.int(0, 3))]
        data.append(DataDecl("F10", 3, floats))
    if g.chance(4):
        texts = [g._draw(st.text(alphabet='ab Z\\"/é', max_size=8)) for _ in range(g.int(0, 2))]
        data.append(DataDecl("ST11", 2, texts))

    subs = list(range(3, 3 + g.int(0, 2))) if subroutines else []
    files = {2: g.program_file(2, subs, max_rungs)}
    for number in subs:
        # Calls go to higher-numbered files only (no unbounded recursion)...
        files[number] = g.program_file(number, [n for n in subs if n > number], max(2, max_rungs // 2))
    if subs and g.chance(10):
        # ...except, rarely, one rung that calls its own file: it nests until
        # the JSR depth limit faults (linear, since it is the only self-call).
        rec = subs[-1]
        files[rec].rungs.append(Rung([I("XIC", ref("B3/0")), I("JSR", Const(rec))], None))
    return Program(files=files, data=data, symbols=decls)


def input_words(seed: int, scans: int) -> list[tuple[int, int]]:
    """Per-scan raw words for I:0 and B3:0 (the test's input image), from a
    seeded sequence: a failing example shows one number, not 100 words."""
    rng = random.Random(seed)
    return [(rng.getrandbits(16), rng.getrandbits(16)) for _ in range(scans)]


input_seeds = st.integers(0, 2**32 - 1)
