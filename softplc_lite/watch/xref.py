"""Find and cross-reference: every rung that reads or writes an address.

:class:`XrefIndex` walks a validated program once and lists each address
operand as a :class:`Use` (program file, rung, instruction in the rung,
operand, read or write). :meth:`XrefIndex.find` answers a query (an address
such as ``N7:0``, ``B3/5``, ``T4:0.DN``, a word such as ``B3:0`` that holds
bits, a file such as ``N7``, or a program symbol with its suffixes) with a
:class:`Finding`: the uses in scan order and a cursor that ``next`` and
``previous`` move from rung to rung. :class:`XrefPanel` draws a finding.

Whether an operand reads or writes is taken from the instruction's spec
(ladder/specs.py): its operand kind, and for the kinds that serve both ways
(a bit, a word, a string, a file) its name and whether the instruction is an
output. The few operands whose spec cannot say (a file shifted in place) are
listed in ``IN_PLACE``, and a test checks every entry against the specs.
Indirect and indexed addresses (``N7:[N7:1]``, ``#N7:0``) and blocks of
unknown length are *indirect* uses of their file: they may touch any word of
it. See docs/watch.md, "Find and cross-reference".
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum

from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import Address, AddressError, parse_address
from ..datatable.filetypes import FILE_TYPES, INDEX_REGISTER_WORD, WORD_BITS
from ..ladder.ast import AddressRef, Const, Program, address_refs, instructions_of
from ..ladder.instructions import BUILTIN, InstructionSet
from ..ladder.specs import InstructionSpec, K
from ..ladder.symbols import is_name, is_symbol_text, resolve_name


class Access(Enum):
    READ = "read"
    WRITE = "write"
    READ_WRITE = "read/write"


# Kinds that say it all.
_WRITE_KINDS = frozenset({K.DEST, K.INTEGER_DEST, K.PARAM_OUT, K.RESETTABLE})
_READ_WRITE_KINDS = frozenset({K.TIMER, K.COUNTER, K.CONTROL, K.ANY})  # ANY: a TLM's, it may do either
# Kinds a destination shares with sources: the operand's name decides.
_SHARED_KINDS = frozenset({K.BIT, K.WORD, K.STRING, K.FILE, K.WORD_FILE})
_WRITE_NAMES = frozenset({"dest", "result", "output", "control_output"})
_READ_WRITE_NAMES = frozenset({"storage", "control_block"})
# Operands of a shared kind whose name does not say what the instruction does
# with them: files worked on in place, and a TLM's output string. Checked
# against the specs by tests/test_watch_xref.py.
IN_PLACE: dict[tuple[str, str], Access] = {
    ("SWP", "source"): Access.READ_WRITE,  # swaps the bytes of the words in place
    ("BSL", "file"): Access.READ_WRITE,
    ("BSR", "file"): Access.READ_WRITE,
    ("FFL", "stack"): Access.WRITE,
    ("FFU", "stack"): Access.READ_WRITE,  # the unload shifts the stack up
    ("LFL", "stack"): Access.WRITE,
    ("LFU", "stack"): Access.READ,
    ("SQL", "file"): Access.WRITE,
    ("SRT", "file"): Access.READ_WRITE,
    ("MBR_GETFAULTMAP", "map"): Access.WRITE,
    ("STRPRINT", "string"): Access.WRITE,
}
_BLOCK_KINDS = frozenset({K.FILE, K.WORD_FILE, K.FILE_SOURCE})


def access_of(spec: InstructionSpec, index: int, operands=()) -> Access:
    """How operand ``index`` of an instruction of ``spec`` is used.
    ``operands``: the instruction's operands, for a JSR, whose parameters
    after its input count receive the subroutine's return values."""
    op = spec.operand_at(index)
    kind = op.kind
    if kind is K.SOURCE and index > 0:
        counts = [k for k, o in enumerate(spec.operands) if o.kind is K.PARAM_COUNT]
        if counts and counts[0] < index and len(operands) > counts[0]:
            count = operands[counts[0]]
            if isinstance(count, Const) and index > counts[0] + count.value:
                return Access.WRITE
    if kind in _WRITE_KINDS:
        return Access.WRITE
    if kind in _READ_WRITE_KINDS:
        return Access.READ_WRITE
    if kind in _SHARED_KINDS:
        special = IN_PLACE.get((spec.mnemonic, op.name))
        if special is not None:
            return special
        if op.name in _WRITE_NAMES:
            return Access.WRITE
        if op.name in _READ_WRITE_NAMES:
            return Access.READ_WRITE
        if kind is K.BIT and spec.output and len(spec.operands) == 1:
            return Access.WRITE  # OTE OTL OTU: the coil's bit
    return Access.READ


@dataclass(frozen=True)
class Use:
    """One operand that names (or may name) an address."""

    file: int  # program file
    rung: int
    instruction: int  # in the rung, in scan order (branches opened), from 0
    mnemonic: str
    operand: int  # from 0
    access: Access
    address: Address
    indirect: bool = False  # may touch the file: the word is chosen at run time, or the block's length is
    span: int = 1  # elements from the address on (a block of known length)

    def describe(self, naming=None) -> str:
        """One line: where (instruction and operand numbered from 1, as the
        rung shows them left to right), what and how. ``naming``: the view's
        (naming.py), which names a Logix app's routines, instructions and
        operands its way."""
        where, mnemonic, address = self._parts(naming)
        line = self._line(naming)
        if line is not None:
            return f"{where} line {line}  {address}  {self.how}"
        return (f"{where} rung {self.rung}  instruction {self.instruction + 1} {mnemonic}  "
                f"operand {self.operand + 1} {address}  {self.how}")

    def _parts(self, naming) -> tuple[str, str, str]:
        if naming is None:
            return f"file {self.file}", self.mnemonic, str(self.address)
        names = naming.for_file(self.file)
        address = (names.name(self.address) if names.replaces_address else None) or str(self.address)
        return naming.where(self.file), names.mnemonic(self.mnemonic), address

    @property
    def how(self) -> str:
        """``read``, ``write``, ``read/write``, or one of them ``indirect``."""
        return "indirect " + self.access.value if self.indirect else self.access.value

    def brief(self, naming=None) -> str:
        """Where, short, for a narrow list (the how goes first there):
        ``file 2 rung 3  OTL B3/0``."""
        where, mnemonic, address = self._parts(naming)
        line = self._line(naming)
        if line is not None:
            return f"{where} line {line}  {address}"
        return f"{where} rung {self.rung}  {mnemonic} {address}"

    def _line(self, naming) -> int | None:
        """The line (from 1) of a Structured Text routine the use is on: its
        rungs and instructions are the translation's, its lines the user's."""
        pfile = naming.app.program.files.get(self.file) if naming is not None else None
        listing = getattr(pfile, "listing", None)
        if listing is None or not 0 <= self.rung < len(listing.rung_lines):
            return None
        return listing.rung_lines[self.rung] + 1


class _Target:
    """What a query names, as parts of the data table: a file, an element, a
    word of an element (a member), a bit; None = all of it."""

    def __init__(self, letter: str, file: int, element: int | None, word: int | None, bit: int | None) -> None:
        self.letter, self.file, self.element, self.word, self.bit = letter, file, element, word, bit

    @classmethod
    def of(cls, a: Address) -> _Target:
        return cls(a.type_letter, a.file, a.element, *_word_and_bit(a))

    def matches(self, use: Use) -> bool:
        a = use.address
        if a.type_letter != self.letter:
            return False
        if use.indirect and (isinstance(a.file, Address) or a.file == self.file):
            return True  # it may touch this file
        if a.file != self.file:
            return False
        if self.element is None:
            return True
        if not isinstance(a.element, int) or not a.element <= self.element < a.element + use.span:
            return False
        if use.span > 1:
            return True  # a block: the whole element
        word, bit = _word_and_bit(a)
        return (self.word is None or word is None or word == self.word) and \
            (self.bit is None or bit is None or bit == self.bit)


def _word_and_bit(a: Address) -> tuple[int | None, int | None]:
    """The word inside the element (None: the whole element) and the bit (None: the whole word)."""
    ftype = a.ftype
    bit = a.bit if isinstance(a.bit, int) else None
    if a.member is not None:
        return ftype.members_by_name[a.member].offset, bit
    if ftype.is_structure and bit is not None:
        return 0, bit  # status bits are bits of word 0
    return None, bit


_FILE_NAME = re.compile(r"(ST|[A-Z])([0-9]+)?", re.IGNORECASE)


@dataclass
class Finding:
    """The uses of one query, in scan order (program file, rung, instruction),
    and which of them is current (-1 before the first ``next``)."""

    query: str
    title: str  # what the query names: "N7:0", "Start (N7:0)", "file N7"
    uses: list[Use]
    current: int = -1

    @property
    def writers(self) -> list[Use]:
        return [u for u in self.uses if u.access is not Access.READ]

    def next(self) -> tuple[int, int] | None:
        """The (program file, rung) of the next use, wrapping after the last."""
        if not self.uses:
            return None
        self.current = (self.current + 1) % len(self.uses)
        return self.where

    def previous(self) -> tuple[int, int] | None:
        if not self.uses:
            return None
        self.current = (self.current - 1) % len(self.uses) if self.current >= 0 else len(self.uses) - 1
        return self.where

    def start_at(self, file: int | None, rung: int) -> None:
        """Make ``next`` go to the first use at or after rung ``rung`` of
        program file ``file`` (the selected rung), as a find from the cursor does."""
        if file is None:
            return
        after = [k for k, u in enumerate(self.uses) if (u.file, u.rung) >= (file, rung)]
        self.current = (after[0] if after else 0) - 1

    @property
    def where(self) -> tuple[int, int] | None:
        if not 0 <= self.current < len(self.uses):
            return None
        use = self.uses[self.current]
        return use.file, use.rung


class XrefIndex:
    """Every address operand of a validated program, built once."""

    def __init__(self, program: Program, instructions: InstructionSet | None = None) -> None:
        self.program = program
        self.instructions = instructions or BUILTIN
        self.uses: list[Use] = []
        for number in sorted(program.files):
            for r, rung in enumerate(program.files[number].rungs):
                for k, ins in enumerate(instructions_of(rung.elements)):
                    self._add(number, r, k, ins)

    def _add(self, file: int, rung: int, k: int, ins) -> None:
        spec = self.instructions.lookup(ins.mnemonic)
        operands = ins.operands
        for n, operand in enumerate(operands):
            if spec is None or not spec.operands:
                access = Access.READ_WRITE  # unknown to this set: say it may do either
            else:
                access = access_of(spec, n, operands)
            if isinstance(operand, AddressRef):
                kind = spec.operand_at(n).kind if spec is not None and spec.operands else None
                span, known = _block_span(spec, operands, kind) if kind in _BLOCK_KINDS else (1, True)
                self._address(file, rung, k, ins.mnemonic, n, access, operand.address, span, known)
            else:  # an expression: everything in it is read
                for ref in address_refs(operand):
                    self._address(file, rung, k, ins.mnemonic, n, Access.READ, ref.address, 1, True)

    def _address(self, file, rung, k, mnemonic, n, access, a: Address, span: int, known: bool) -> None:
        add = self.uses.append
        add(Use(file, rung, k, mnemonic, n, access, a, indirect=not a.is_direct or not known, span=span))
        for part in (a.file, a.element, a.bit):  # the words an indirect address reads to find its word
            if isinstance(part, Address):
                self._address(file, rung, k, mnemonic, n, Access.READ, part, 1, True)
        if a.indexed:  # the index register S:24 offsets it
            add(Use(file, rung, k, mnemonic, n, Access.READ, Address("S", 2, INDEX_REGISTER_WORD)))

    def target(self, text: str) -> tuple[_Target, str]:
        """What ``text`` names, and its title; AddressError when it names nothing."""
        text = text.strip()
        if not text:
            raise AddressError(text, 0, "expected an address (N7:0, B3/5, T4:0.DN), a file (N7) or a symbol")
        symbols = self.program.symbols
        m = _FILE_NAME.fullmatch(text)
        if m and not any(name.upper() == text.upper() for name in symbols):
            letter = m.group(1).upper()
            ftype = FILE_TYPES.get(letter)
            number = int(m.group(2)) if m.group(2) else (ftype.fixed_number if ftype else None)
            if ftype is not None and number is not None:
                return _Target(letter, number, None, None, None), f"file {letter}{number}"
        if is_symbol_text(text) or is_name(text, symbols):  # a symbol, or a Logix app's tag path (Tanks[1].Level)
            address = resolve_name(text, symbols)
            return _Target.of(address), f"{text} ({address})"
        address = parse_address(text)
        if not address.is_direct:
            raise AddressError(text, 0, "expected a direct address to find (N7:0, not N7:[N7:1] or #N7:0)")
        return _Target.of(address), str(address)

    def find(self, text: str) -> Finding:
        """The uses of what ``text`` names (see the module docstring)."""
        target, title = self.target(text)
        return Finding(text.strip(), title, [u for u in self.uses if target.matches(u)])


def _block_span(spec, operands, kind) -> tuple[int, bool]:
    """(elements, known) a block operand covers: its instruction's constant
    length (words for a bit length); unknown without one, or when a position
    walks the block (a sequencer's or a stack's, which may hold one more)."""
    if kind is K.FILE_SOURCE:
        return 1, True  # FLL's source: one word (or a number), copied into the destination
    for k, op in enumerate(spec.operands):
        if op.kind in (K.LENGTH, K.BIT_LENGTH) and k < len(operands) and isinstance(operands[k], Const):
            length = int(operands[k].value)
            if any(o.kind is K.POSITION for o in spec.operands):
                return length + 1, False
            return ((length + WORD_BITS - 1) // WORD_BITS if op.kind is K.BIT_LENGTH else length), True
    return 1, False


class XrefPanel:
    """A finding as a list: what was searched, how many uses and writers,
    then one line a use, the current one marked; as many as fit
    ``height`` lines, the current one kept in view."""

    def __init__(self, finding: Finding, height: int | None = None, naming=None) -> None:
        self.finding = finding
        self.height = height
        self.naming = naming  # the view's names (naming.py); None: addresses and file numbers

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        f = self.finding
        uses = f.uses
        head = Text(no_wrap=True, overflow="ellipsis")
        head.append(f"find {f.title}: ", style="bold")
        if not uses:
            head.append("not used in any rung", style="yellow")
            yield head
            return
        counts = f"{len(uses)} use{'s' if len(uses) != 1 else ''}, {len(f.writers)} writing"
        where = f"  ({f.current + 1} of {len(uses)}; x next, X previous)" if f.current >= 0 else ""
        if where and head.cell_len + len(counts) + len(where) > options.max_width:
            where = f"  ({f.current + 1} of {len(uses)})"  # the keys are on the ? list
            if head.cell_len + len(counts) + len(where) > options.max_width:  # the side panel: shorter still
                counts, where = f"use {f.current + 1} of {len(uses)}, {len(f.writers)} writing", ""
        head.append(counts)
        head.append(where, style="dim")
        yield head
        height = self.height or options.height or len(uses) + 1
        rows = max(1, height - 1)
        first = 0
        if len(uses) > rows:
            first = min(max(0, f.current - rows // 2), len(uses) - rows)
        shown = uses[first:first + rows]
        # Where a whole line does not fit (the 46-column side panel), read or write goes first, in a
        # column of its own, and the line says where more briefly: what was cut is never the access.
        brief = any(2 + len(use.describe(self.naming)) > options.max_width for use in shown)
        how_w = max(len(use.how) for use in shown)
        for k, use in enumerate(shown, first):
            line = Text(no_wrap=True, overflow="ellipsis")
            mark = k == f.current
            line.append("▶ " if mark else "  ", style="bold")
            text = f"{use.how.ljust(how_w)}  {use.brief(self.naming)}" if brief else use.describe(self.naming)
            line.append(text, style="reverse" if mark else "red" if use.access is not Access.READ else None)
            yield line
