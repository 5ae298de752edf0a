"""Compiled program files as blocks of rungs (the compiler's output).

One generated Python function runs a block of consecutive rungs (at most
CHUNK_RUNGS, and a block starts at every LBL rung, so a JMP lands at the
start of one). Inside a block the data-table words its contacts and coils
use are held in locals: read once, written back before anything that is
not block code can look (docs/engine.md, "Compiled code"). One call per
block rather than one per rung: a call per rung costs about half of a
boolean scan.

A block function ``fn(z)`` takes the rung-in of its rungs (the file's MCR
zone) and returns None when its last rung is done, or what ended it early:
a rung index (JMP), RET, TND, or a RET instruction with values.

Faults name their rung and instruction through a line table per block: each
block is compiled under its own file name, ``<ladder file N rungs A-B>``.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass

# What a block function returns besides None (ran to its end) and a rung
# index (a JMP): the RET and TND of the file.
RET = -1
TND = -2

# Rungs per block (at most). Bigger blocks load a few more words than they
# use per rung; smaller ones pay the call more often. CPython compiles one
# huge function body several times slower than the same code in pieces.
CHUNK_RUNGS = 1000

# The rung condition ``c`` of block code is any value with the rung's truth
# (a contact is ``word & mask``, not ``word & mask != 0``: a compare less
# per contact to compile and to run). Where it leaves block code -- a kernel,
# a bound or module instruction, the MCR zone -- it is made a bool.
RUNG_BOOL = "not not c"
# Word locals per block (about: a block ends after the rung that passes it).
LOCALS_BUDGET = 300
# Instructions per block (about, as LOCALS_BUDGET): CPython's compile() of
# one function needs several KB an instruction at once, so a block of many
# large rungs is split, and a load's memory stays proportional to its
# biggest block (one rung at most limits.MAX_RUNG_ELEMENTS), not its program.
INSTRUCTIONS_BUDGET = 10_000

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_FEW_NAMES = 100  # up to this many names to bind, each is looked for in the text


@dataclass
class BlockCode:
    """What the file compiler emitted for one block: source lines, and for
    each line the instruction (or None) and rung it belongs to."""

    first: int  # first rung
    end: int  # one past the last rung
    lines: list[str]
    line_instr: list  # per line (0-based): Instruction or None
    line_rung: list[int]


def block_name(number: int, first: int, end: int) -> str:
    return f"<ladder file {number} rungs {first}-{end - 1}>"


def build_block(number: int, code: BlockCode, env: dict):
    """Compile one block: a factory binding the names the body uses, so the
    body reads them as closure cells (fast), and the block function."""
    body = "\n".join(code.lines)
    if len(env) <= _FEW_NAMES:
        # A name found as a substring may not be used after all (f3 in f30);
        # binding it anyway costs nothing. Cheaper than listing every
        # identifier of a large body (about 2% of a load).
        used = [n for n in sorted(env) if n in body]
    else:
        identifiers = set(IDENTIFIER.findall(body))
        used = [n for n in sorted(env) if n in identifiers]
    bindings = "; ".join(f"{n} = _env[{n!r}]" for n in used) or "pass"
    # The bindings come after the body so every body line keeps its number
    # (line k + 2 is code.lines[k]); the block reads them as closure cells,
    # filled before it first runs.
    text = f"def _factory(_env):\n{body}\n    {bindings}\n    return _block\n"
    name = block_name(number, code.first, code.end)
    module = compile(text, name, "exec")
    return run_block(module, env), name, module


def run_block(module, env: dict):
    """The block function of a compiled block module (compiled now, or
    read from the code cache)."""
    scope: dict[str, object] = {}
    exec(module, scope)  # noqa: S102 - source built only from validated tokens
    return scope["_factory"](env)


class CompiledFile:
    """A program file as block functions, with what maps faults back to
    rungs and instructions, and what the watch view's breakpoints need to
    run one rung alone."""

    def __init__(self, number: int, rung_count: int, has_mcr: bool, compiler) -> None:
        self.number = number
        self.rung_count = rung_count
        self.has_mcr = has_mcr
        self.blocks: list = []  # block functions, in rung order
        self.starts: list[int] = []  # first rung of each block
        # Block file name -> (first rung, end): a fault's line is mapped back by
        # compiling that block's text again (where): no line table is kept.
        self.tables: dict[str, tuple[int, int]] = {}
        self.modules: list = []  # each block's compiled module code (what the code cache keeps)
        self._compiler = compiler  # kept to compile a block again, split (isolate); may be a maker of one

    @property
    def compiler(self):
        if callable(self._compiler):  # loaded from the code cache: made when first needed
            self._compiler = self._compiler()
        return self._compiler

    def add(self, code: BlockCode) -> None:
        fn, name, module = build_block(self.number, code, self.compiler.env)
        self.add_compiled(fn, code.first, code.end, name, module)

    def add_compiled(self, fn, first: int, end: int, name: str, module) -> None:
        self.blocks.append(fn)
        self.starts.append(first)
        self.modules.append(module)
        self.tables[name] = (first, end)

    # -- the engine's view ----------------------------------------------------------------------
    def block_index(self, rung: int) -> int:
        """The block holding ``rung``."""
        return bisect.bisect_right(self.starts, rung) - 1

    def where(self, filename: str, lineno: int):
        """(rung, instruction) of a generated line, or (None, None). The
        block's code is emitted again (the same text, line for line: the
        compiler is deterministic) rather than a line table kept for every
        line of every block: faults are rare, memory is not."""
        span = self.tables.get(filename)
        if span is None:
            return None, None
        code = self.compiler.block(*span)
        k = lineno - 2  # line 1 is the factory's def
        if 0 <= k < len(code.lines):
            return code.line_rung[k], code.line_instr[k]
        return None, None

    # -- breakpoints -------------------------------------------------------------------------------
    def isolate(self, rung: int) -> int:
        """Make ``rung`` a block of its own (compiling its old block again in
        up to three parts) and return its block index: a breakpoint wraps it,
        and sees the data table exact when the rung starts."""
        k = self.block_index(rung)
        first = self.starts[k]
        end = self.starts[k + 1] if k + 1 < len(self.starts) else self.rung_count
        if first == rung and end == rung + 1:
            return k
        parts = [(a, b) for a, b in ((first, rung), (rung, rung + 1), (rung + 1, end)) if a < b]
        old = CompiledFile(self.number, self.rung_count, self.has_mcr, self.compiler)
        for a, b in parts:
            old.add(self.compiler.block(a, b))
        del self.tables[block_name(self.number, first, end)]
        self.blocks[k:k + 1] = old.blocks
        self.starts[k:k + 1] = old.starts
        self.modules[k:k + 1] = old.modules
        self.tables.update(old.tables)
        return self.block_index(rung)

    def split_rungs(self) -> None:
        """Make every rung a block of its own (each old block compiled again,
        rung by rung): the watch view wraps each to see which rungs ran. The
        file scans as before; a block call a rung is the cost, paid only
        by a file split so."""
        if len(self.blocks) == self.rung_count:
            return
        parts = CompiledFile(self.number, self.rung_count, self.has_mcr, self.compiler)
        for rung in range(self.rung_count):
            parts.add(self.compiler.block(rung, rung + 1))
        self.blocks[:] = parts.blocks
        self.starts[:] = parts.starts
        self.modules[:] = parts.modules
        self.tables = parts.tables

    # -- for people and tests ---------------------------------------------------------------------
    @property
    def source(self) -> str:
        """The generated code of every block, emitted again (not kept: it is
        as big as the program text)."""
        out = []
        bounds = self.starts + [self.rung_count]
        for a, b in zip(bounds, bounds[1:]):
            out += ["def _factory(_env):", *self.compiler.block(a, b).lines]
        return "\n".join(out) + "\n"

    @property
    def line_table(self) -> dict:
        """(block name, line) -> instruction, for every line that has one."""
        out = {}
        for name, span in self.tables.items():
            code = self.compiler.block(*span)
            for k, ins in enumerate(code.line_instr):
                if ins is not None:
                    out[(name, k + 2)] = ins
        return out
