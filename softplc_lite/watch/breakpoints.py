"""Breakpoints: stop running at a rung, or when a condition becomes true.

- **Rung breakpoint** (``b`` on the selected rung): running stops after a
  scan in which that rung was scanned with its rung condition true (it
  was executed, not skipped by a JMP or an uncalled subroutine, and power
  reached its end). The check is made as the rung runs, by wrapping that
  one rung's callable, so rungs without a breakpoint cost nothing; the
  rung condition is evaluated on the values the rung reads, just before
  it runs (a self-resetting timer, ``XIO T4:0/DN TON T4:0``, is true in
  the scan its DN goes on and false in the next). In a Structured Text
  routine (its rungs are its statements, st_view.py) the breakpoint is on
  a line's first rung and stops when that rung runs at all: a statement
  has no rung condition (an IF's test rung is false when the IF is taken).
- **Condition breakpoint** (``--break-when "N7:0 > 100"``, ``--break-when
  R6:0/ER``): a CMP-style expression, or a bit address, checked after each
  scan; running stops when it goes from false to true.

A stop is reported as a :class:`Hit`: which scan, and which rung or
condition.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..datatable import DataTable, DataTableError, ValueKind
from ..ladder.ast import AddressRef, Pos, SymbolRef, address_refs
from ..ladder.errors import LadderError
from ..ladder.expr import evaluate
from ..ladder.parser import parse_expression
from ..ladder.symbols import resolve_name


def quoted(text: str, limit: int = 60) -> str:
    """``text`` quoted for a message, its middle left out past ``limit``
    characters (a command-line argument can be a megabyte long)."""
    if len(text) > limit:
        text = f"{text[:limit // 2]}...{text[-(limit // 3):]}"
    return repr(text)


@dataclass(frozen=True)
class Hit:
    scan: int
    file: int | None = None
    rung: int | None = None
    condition: str | None = None

    def __str__(self) -> str:
        if self.condition is not None:
            return f"break: {self.condition} became true at scan {self.scan}"
        return f"break: file {self.file} rung {self.rung} energized at scan {self.scan}"


class _PureMath:
    """Expression arithmetic without the status-file side effects the
    engine's Machine has (a breakpoint must not set minor faults)."""

    @staticmethod
    def divide(a, b):
        return a / b if b else 0

    @staticmethod
    def modulo(a, b):
        return a % b if b else 0

    @staticmethod
    def power(a, b):
        try:
            return a ** b
        except (OverflowError, ZeroDivisionError, ValueError):
            return 0


_NUMBERS = (ValueKind.BIT, ValueKind.WORD, ValueKind.FLOAT, ValueKind.LONG)


class Condition:
    """A --break-when expression."""

    def __init__(self, text: str, symbols=None) -> None:
        self.text = text
        try:
            # a Logix app's symbols are an empty mapping that resolves tag paths: kept, not replaced
            node = parse_expression(text, Pos("--break-when", 1, 1))
            self.node = _resolve(node, symbols if symbols is not None else {})
        except LadderError as e:
            raise DataTableError(f"--break-when {quoted(text)}: {e.message if hasattr(e, 'message') else e}") from None
        for ref in address_refs(self.node):
            a = ref.address
            if a.kind is ValueKind.STRING:  # ST9:0 < 1 cannot be computed: say so now, not at a scan
                raise DataTableError(f"--break-when {quoted(text)}: {a} holds a string, not a number or a bit")
            if a.kind not in _NUMBERS:
                raise DataTableError(f"--break-when {quoted(text)}: {a} is a whole {a.kind.value}; compare one of "
                                     f"its words or bits ({a}.{a.ftype.word_members[-1].name}, ...)")
        self.was = False

    def value(self, table: DataTable) -> bool:
        try:
            return bool(evaluate(self.node, lambda ref: table.read(ref.address), _PureMath))
        except (DataTableError, ArithmeticError, TypeError, ValueError):
            return False  # an address past its file (or a value it cannot use) is "not true", not a crash

    def became_true(self, table: DataTable) -> bool:
        now = self.value(table)
        edge = now and not self.was
        self.was = now
        return edge


def _resolve(node, symbols):
    """Symbols in a --break-when expression become their addresses."""
    if isinstance(node, SymbolRef):
        try:
            return AddressRef(resolve_name(node.name, symbols), node.pos)
        except DataTableError as e:
            raise DataTableError(f"--break-when: {e}") from None
    for name in ("left", "right", "operand", "arg"):
        child = getattr(node, name, None)
        if child is not None:
            object.__setattr__(node, name, _resolve(child, symbols))
    return node


class Breakpoints:
    """Rung and condition breakpoints of one engine."""

    def __init__(self, engine, rung_power: Callable | None = None) -> None:
        self.engine = engine
        self.rung_power = rung_power  # (rung, table) -> power with .out; None: any execution counts
        self.rungs: set[tuple[int, int]] = set()
        self.conditions: list[Condition] = []
        self.hits: list[Hit] = []
        self._original: dict[tuple[int, int], Callable] = {}

    # -- rungs ----------------------------------------------------------------------------
    def toggle(self, file: int, rung: int) -> bool:
        """Set or clear a rung breakpoint; True when it is now set."""
        key = (file, rung)
        compiled = self.engine.files[file][0]
        if key in self.rungs:
            self.rungs.discard(key)
            compiled.blocks[compiled.block_index(rung)] = self._original.pop(key)
            return False
        self.rungs.add(key)
        # The rung alone in its block: the table is exact when it starts.
        k = compiled.isolate(rung)
        original = compiled.blocks[k]
        self._original[key] = original
        pfile = self.engine.program.files[file]
        source = pfile.rungs[rung]
        table = self.engine.table
        power = self.rung_power if pfile.listing is None else None

        def watched(c, original=original, source=source, key=key):
            # the rung condition on the values the rung reads: before it runs, so a
            # rung that writes what it reads (XIO T4:0/DN TON T4:0) is judged as scanned
            energized = c and (power is None or bool(power(source, table).out))
            result = original(c)
            if energized:
                self.hits.append(Hit(self.engine.scans + 1, key[0], key[1]))
            return result

        compiled.blocks[k] = watched
        return True

    def program_replaced(self, changes) -> list[tuple[int, int]]:
        """After Engine.replace_program (an online edit): the old code and its
        watched blocks are gone, so every rung breakpoint is set again on the
        new code. A breakpoint on a rung whose text is unchanged moves to the
        rung's new number; the others are dropped and returned as (file, old
        rung). Condition breakpoints read the table, which is kept: they stay."""
        old = sorted(self.rungs)
        self.rungs.clear()
        self._original.clear()  # the old program's blocks: never to be put back in the new code
        self.hits.clear()
        dropped = []
        for file, rung in old:
            new = changes.new_rung(file, rung)
            if new is None:
                dropped.append((file, rung))
            else:
                self.toggle(file, new)
        return dropped

    # -- conditions -------------------------------------------------------------------------
    def add_condition(self, text: str, symbols=None) -> Condition:
        cond = Condition(text, symbols)
        cond.was = cond.value(self.engine.table)  # only a change from now on breaks
        self.conditions.append(cond)
        return cond

    def after_scan(self) -> Hit | None:
        """Call after each scan: the first hit of this scan, if any."""
        if not self.hits and not self.conditions:
            return None
        for cond in self.conditions:
            if cond.became_true(self.engine.table):
                self.hits.append(Hit(self.engine.scans, condition=cond.text))
        hit = self.hits[0] if self.hits else None
        self.hits.clear()
        return hit
