"""The locals allocator of the file compiler: which data-table words a
block function holds in Python locals, when they are loaded, written back
and forgotten.

A block's instructions that address a word directly (a 16-bit word file
other than S, S:0 excepted) and use it more than once read it into a local
at its first use and write it back before anything that is not block code
can look at the table. The rules are in docs/engine.md, "Compiled code";
the differential test holds the code built on them to the reference
interpreter. The templates that work on held words are in
held_templates.py; the file compiler (compiler.py) holds one allocator.
"""

from __future__ import annotations

import re
from collections import Counter
from typing import Protocol

from ..datatable import data_bit_mask
from ..datatable.filetypes import Storage
from .ast import AddressRef, BinOp, Const, Instruction, UnaryOp, address_refs, instructions_of


class Emitter(Protocol):
    """What the allocator needs of its compiler: emitting a line, and the
    (load-time) location and array name of a direct address's word."""

    table: object

    def emit(self, indent: int, text: str) -> None: ...

    def resolve(self, address): ...

    def array_name(self, file) -> str: ...


class HeldWords:
    """The words one block holds in locals (``begin`` starts a block).

    A local is named ``wFILE_WORD``; ``words`` maps (file, word) to the
    local holding it now, ``dirty`` holds the locals changed since their
    last write-back. S:0 (``_FLAGS``) is held like a data word, but a word
    store leaves its flags pending (``_fz``, ``_fc``) until something reads
    it (``flags_exact``)."""

    def __init__(self, out: Emitter) -> None:
        self.out = out
        self.words: dict[tuple[int, int], str] = {}  # (file, word) -> the local holding it
        self.dirty: set[str] = set()  # locals a rung may have changed since the last write-back
        self.flags_pending = False  # a word store may have left S:0's flags pending (flags_exact)
        self.uses: Counter = Counter()  # how often the block being compiled addresses each word
        self.saw_mcr = False  # set by rung_words: the compiler learns has_mcr in its first pass
        self._word_keys: dict[int, tuple | None] = {}  # id(Address) -> (file, word) a local could hold, or None

    def begin(self, uses: Counter) -> None:
        """A new block, whose rungs address each word ``uses[key]`` times."""
        self.words = {}
        self.dirty = set()
        self.flags_pending = False
        self.uses = uses

    def done(self) -> None:
        """The file is compiled: drop what a later compile can rebuild."""
        self.uses, self._word_keys = Counter(), {}

    def held(self, key: tuple[int, int]) -> str | None:
        """The local holding word ``key`` now, or None."""
        return self.words.get(key)

    def holdable(self, ref: AddressRef) -> bool:
        """A direct address in a 16-bit word file other than S."""
        f = self.out.resolve(ref.address).file
        return f.ftype.storage is Storage.WORD and f.ftype.letter != "S"

    # -- loading ---------------------------------------------------------------------------
    def local(self, ind: int, ref: AddressRef) -> tuple[str, int | None] | None:
        """(local, mask or None) for a direct address whose word a block
        holds in a local (a 16-bit word file other than S, whose words kernels
        and the engine write behind the block's back, S:0 excepted; and a word
        the block uses more than once), loading it at its first use (at rung
        level: every path after it has it); None for any other address."""
        a = ref.address
        if not a.is_direct:
            return None
        f, index, bit = self.out.resolve(a)
        name = self.word_at(ind, f, index)
        if name is None:
            return None
        return name, (data_bit_mask(f.data, bit) if bit is not None else None)

    def word_at(self, ind: int, f, index: int, force: bool = False, for_store: bool = False) -> str | None:
        """The local holding word ``index`` of file ``f`` (loaded now if not
        held), or None if no local may hold that file's words, or (unless
        ``force``) the block uses the word only once: a local would cost a
        load and a write-back for one use, the table in place costs neither."""
        if not _may_hold(f, index):
            return None
        key = (f.number, index)
        name = self.words.get(key)
        if name is None:
            if not force and self.uses.get(key, 0) < 2:
                return None
            name = self.words[key] = f"w{f.number}_{index}"
            if key == _FLAGS:
                self.out.emit(ind, f"{name} = {self.out.array_name(f)}[{index!r}]; _fz = None")  # no store pending yet
                self.flags_pending = False
            else:
                self.out.emit(ind, f"{name} = {self.out.array_name(f)}[{index!r}]")
        elif key == _FLAGS and not for_store:
            self.flags_exact(ind)
        return name

    def flags_local(self, ind: int) -> str | None:
        """S:0's local for a word store to set the flags in (loaded now if
        the block uses S:0 more than once), else None."""
        return self.word_at(ind, self.out.table.file(_FLAGS[0]), 0, for_store=True)

    def element_words(self, ind: int, ref: AddressRef, force=(True, True, True)) -> list[str]:
        """Code for a timer or counter element's three words (control, PRE,
        ACC): each its local, or (where ``force`` is False and the block uses
        the word only here) the table in place."""
        f, index, _ = self.out.resolve(ref.address)
        out = []
        for k in range(3):
            name = self.word_at(ind, f, index + k, force=force[k])
            out.append(name if name is not None else f"{self.out.array_name(f)}[{index + k!r}]")
        return out

    def rung_words(self, rung) -> list[tuple[int, int]]:
        """The words ``rung`` addresses directly that a local could hold,
        once per use (a TON's or counter's element words as _ELEMENT_USES
        says; a word store adds S:0)."""
        out: list[tuple[int, int]] = []
        keys = self._word_keys
        for ins in instructions_of(rung.elements):
            m = ins.mnemonic
            if m == "MCR":
                self.saw_mcr = True
            element = _ELEMENT_USES.get(m)
            for op in ins.operands:
                for ref in ((op,) if op.__class__ is AddressRef else () if op.__class__ is Const else address_refs(op)):
                    a = ref.address
                    key = keys.get(id(a), 0)
                    if key == 0:  # not looked at yet (None: not a word a local could hold)
                        key = keys[id(a)] = self._word_key(a)
                    if key is None:
                        continue
                    if element:
                        out += [(key[0], key[1] + j) for j in element]
                    else:
                        out.append(key)
            if m in _STORES and _word_store(ins):
                out.append(_FLAGS)  # it sets S:0's arithmetic flags
        return out

    def _word_key(self, a) -> tuple[int, int] | None:
        if not a.is_direct:
            return None
        f, index, _ = self.out.resolve(a)
        return (f.number, index) if _may_hold(f, index) else None

    # -- changing, writing back, forgetting ---------------------------------------------------
    def changed(self, *codes: str) -> None:
        """Mark the locals among ``codes`` changed (words in place need nothing)."""
        self.dirty.update(c for c in codes if c.startswith("w"))

    def flags_exact(self, ind: int) -> None:
        """S:0's local made exact before anything reads it: a word store
        held in a block leaves its flags pending, as its value (_fz) and
        carry (_fc), and they are set here (only the last store's count:
        each sets all four of C V Z S)."""
        if self.flags_pending and _FLAGS in self.words:
            name = self.words[_FLAGS]
            self.out.emit(ind, f"if _fz is not None: {name} = ({name} & -16) | _fc | "
                               f"(4 if _fz == 0 else 8 if _fz < 0 else 0); _fz = None")  # Z S:0/2, S S:0/3

    def flush(self, ind: int) -> None:
        """Write back every local a rung may have changed."""
        self.flags_exact(ind)
        for (number, index), name in self.words.items():
            if name in self.dirty:
                self.out.emit(ind, f"f{number}[{index!r}] = {name}")

    def forget_all(self) -> None:
        """After code that may write any word: each is read again at its next use."""
        self.words.clear()
        self.dirty.clear()

    def write_back(self, ind: int, keys) -> list[tuple[tuple[int, int], str]]:
        """Write back those of the words ``keys`` that are held and changed,
        before code that is not block code reads or writes them; returns the
        held ones as (key, local), for ``forget``."""
        held = [(key, self.words[key]) for key in keys if key in self.words]
        if any(key == _FLAGS for key, _ in held):
            self.flags_exact(ind)
        for (number, index), name in held:
            if name in self.dirty:
                self.out.emit(ind, f"f{number}[{index!r}] = {name}")
        return held

    def forget(self, held) -> None:
        """Forget these (key, local) pairs: read again at their next use."""
        for key, name in held:
            self.words.pop(key, None)
            self.dirty.discard(name)


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


# How often a TON's or counter's code uses each word of its element
# (control, PRE, ACC), for the block's count of uses: each once, so a TON
# or counter whose element nothing else in the block uses works on
# temporaries, not locals held for the block (_ton_in_place, _local_count).
_ELEMENT_USES = {"TON": (0, 1, 2), "CTU": (0, 1, 2), "CTD": (0, 1, 2)}

_STORES = frozenset({"MOV", "CPT", "ADD", "SUB"})  # the instructions _word_store may accept

def _may_hold(f, index: int) -> bool:
    """Whether a local may hold word ``index`` of file ``f``: a 16-bit word
    file's, not an S word (kernels and the engine write those behind the
    block's back) but S:0, the math flags (held like a data word, below)."""
    return f.ftype.storage is Storage.WORD and (f.ftype.letter != "S" or index == 0)


# S:0, the arithmetic flags word: held in a local like a data word (the
# kernels that set it are called with it written back, and read it after).
_FLAGS = (2, 0)

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
