"""Data-table words held in locals of a block function (issue 17).

The part of the file compiler (compiler.py) that keeps the words a block's
instructions address directly in Python locals, and the instructions that
work on them: contacts and coils, one-shots, word stores, TON, CTU/CTD and
COP of direct blocks. The rules (when words are loaded, written back and
forgotten) are in docs/engine.md, "Compiled code"; the differential test
holds this code to the reference interpreter.
"""

from __future__ import annotations

import re

from ..datatable import bit_mask
from ..datatable.filetypes import Storage
from .ast import AddressRef, BinOp, Const, Instruction, UnaryOp, address_refs, instructions_of
from .blocks import RUNG_BOOL
from .semantics import BASE_MS, CD, CU, DN, EN, OV, STAMP, STAMP_MODULO, TT, UN


class HeldWords:
    """Mixin of _FileCompiler: words in locals, and the code shapes on them."""

    # -- words held in locals ---------------------------------------------------------------
    def word_local(self, ind: int, ref: AddressRef) -> tuple[str, int | None] | None:
        """(local, mask or None) for a direct address whose word a block
        holds in a local (a 16-bit word file other than S, whose words kernels
        and the engine write behind the block's back, S:0 excepted; and a word
        the block uses more than once), loading it at its first use (at rung
        level: every path after it has it); None for any other address."""
        a = ref.address
        if not a.is_direct:
            return None
        f, index, bit = self.resolve(a)
        name = self.word_at(ind, f, index)
        if name is None:
            return None
        return name, (bit_mask(bit) if bit is not None else None)

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
            self.local_names.add(name)
            if key == _FLAGS:
                self.emit(ind, f"{name} = {self.array_name(f)}[{index!r}]; _fz = None")  # no store pending yet
                self.flags_pending = False
            else:
                self.emit(ind, f"{name} = {self.array_name(f)}[{index!r}]")
        elif key == _FLAGS and not for_store:
            self.flags_exact(ind)
        return name

    def rung_words(self, k: int) -> list[tuple[int, int]]:
        """The words rung ``k`` addresses directly that a local could hold,
        once per use (a TON's or counter's element words as _ELEMENT_USES
        says; a word store adds S:0)."""
        out: list[tuple[int, int]] = []
        keys = self._word_keys
        for ins in instructions_of(self.rungs[k].elements):
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
        f, index, _ = self.resolve(a)
        return (f.number, index) if _may_hold(f, index) else None

    def flags_exact(self, ind: int) -> None:
        """S:0's local made exact before anything reads it: a word store
        held in a block leaves its flags pending, as its value (_fz) and
        carry (_fc), and they are set here (only the last store's count:
        each sets all four of C V Z S)."""
        if self.flags_pending and _FLAGS in self.words:
            name = self.words[_FLAGS]
            self.emit(ind, f"if _fz is not None: {name} = ({name} & -16) | _fc | "
                           f"(4 if _fz == 0 else 8 if _fz < 0 else 0); _fz = None")  # Z S:0/2, S S:0/3

    def flush_lines(self, ind: int) -> None:
        """Write back every local a rung may have changed."""
        self.flags_exact(ind)
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
        forget = []
        if dest is not None:
            if _word_store(ins) and self.holdable(dest):
                # A 16-bit result into a word: stored inline (i_MOV, i_CPT, _math2),
                # into its local if held, else into the table; S:0 likewise.
                f, index, _ = self.resolve(dest.address)
                self.inline_dest = self.words.get((f.number, index), "")
                self.inline_flags = self.word_at(ind, self.status_file, 0, for_store=True) or ""
                self.dispatch(ind, ins)
                for name in (self.inline_dest, self.inline_flags):
                    if name:
                        self.dirty.add(name)
                self.inline_dest = self.inline_flags = None
                return
            self.mark_rung(ind)  # a store may set a minor fault (overflow)
            # Its kernel writes the destination and S:0 in the table: held, they
            # are written back first and forgotten after.
            f, index, _ = self.resolve(dest.address)
            self.flags_exact(ind)
            for key in ((f.number, index), _FLAGS):
                name = self.words.get(key)
                if name is not None:
                    if name in self.dirty:
                        self.emit(ind, f"f{key[0]}[{key[1]!r}] = {name}")
                    forget.append((key, name))
        self.dispatch(ind, ins)
        for key, name in forget:
            self.words.pop(key, None)
            self.dirty.discard(name)

    def holdable(self, ref: AddressRef) -> bool:
        f = self.resolve(ref.address).file
        return f.ftype.storage is Storage.WORD and f.ftype.letter != "S"

    @property
    def status_file(self):
        return self.table.file(_FLAGS[0])

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
        s0 = self.inline_flags or "_s[0]"
        if in_range and _SIMPLE.match(value_code):
            v = value_code  # a local or a constant: no temporary
        else:
            v = "_v"
            self.emit(ind, f"_v = {value_code}")
        if self.inline_flags:
            # S:0 held: the flags are left pending until something reads S:0
            # (flags_exact); a later store replaces them.
            set_flags = f"_fz = {v}; _fc = {carry or 0}"
            self.flags_pending = True
        else:
            flags = f"(4 if {v} == 0 else 8 if {v} < 0 else 0)"  # Z S:0/2, S S:0/3
            if carry is not None:
                flags = f"({carry}) | {flags}"
            set_flags = f"{s0} = ({s0} & -16) | {flags}"
        if in_range:
            self.emit(ind, f"{target} = {v}")
            self.emit(ind, set_flags)
            return
        self.emit(ind, "if -32768 <= _v <= 32767:")
        self.emit(ind + 1, f"{target} = _v")
        self.emit(ind + 1, set_flags)
        self.emit(ind, "else:")
        self.emit(ind + 1, f"_m.rung = {self.rung_index!r}")  # the minor fault names this rung
        if self.inline_flags:  # the kernel sets S:0 in the table
            self.flags_exact(ind + 1)
            self.emit(ind + 1, f"_s[0] = {s0}")
        self.emit(ind + 1, fallback.replace("_D_", f"{self.array_name(f)}, {index!r}"))
        if name:
            self.emit(ind + 1, f"{name} = f{f.number}[{index!r}]")
        if self.inline_flags:
            self.emit(ind + 1, f"{s0} = _s[0]")

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

    # -- timers, counters and COP on held words ------------------------------------------------------
    def element_words(self, ind: int, ref: AddressRef, force=(True, True, True)) -> list[str]:
        """Code for a timer or counter element's three words (control, PRE,
        ACC): each its local, or (where ``force`` is False and the block uses
        the word only here) the table in place."""
        f, index, _ = self.resolve(ref.address)
        out = []
        for k in range(3):
            name = self.word_at(ind, f, index + k, force=force[k])
            out.append(name if name is not None else f"{self.array_name(f)}[{index + k!r}]")
        return out

    def held(self, *codes: str) -> None:
        """Mark the locals among ``codes`` changed (words in place need nothing)."""
        self.dirty.update(c for c in codes if c.startswith("w"))

    def local_TON(self, ind: int, ins: Instruction) -> None:
        """Semantics.ton written out on the element's locals (the kernel is
        the reference: the differential test holds them equal). The time is
        the engine's clock of this scan, _m.now_ms."""
        base = BASE_MS[ins.operands[1].value]
        self.uses_now = True
        f, index, _ = self.resolve(ins.operands[0].address)
        keys = [(f.number, index + k) for k in range(3)]
        if not any(key in self.words or self.uses.get(key, 0) > 1 for key in keys):
            self._ton_in_place(ind, ins, f, index, base)
            return
        wc, wp, wa = self.element_words(ind, ins.operands[0])
        self.emit(ind, f"if ({wp} | {wa}) < 0:")  # either negative: the kernel raises the fault, on an exact table
        self.flush_lines(ind + 1)
        d, i, _ = self.location(ind + 1, ins.operands[0])
        self.emit(ind + 1, f"{self.bind('_ton', self.machine.ton)}({d}, {i}, {RUNG_BOOL}, {base!r})")
        # EN, TT, DN and the stamp are every bit of the control word, so each
        # outcome sets the whole word: done is EN|DN and the stamp of now
        # (_ton_done, made once a block), enabled this scan EN|TT and now
        # (_ton_timing), still timing EN|TT and the stamp its time counts from.
        assert EN | TT | DN | STAMP == -1
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if {wa} < {wp}:")  # not done (DN is ACC >= PRE, tested each scan)
        self.emit(ind + 2, f"if {wc} & {EN!r}:")
        self.emit(ind + 3, f"_r = (_now - ({wc} & {STAMP!r})) % {STAMP_MODULO!r}")  # ms since its last update
        self.emit(ind + 3, f"_t = _r // {base!r}")
        self.emit(ind + 3, f"{wa} += _t")
        self.emit(ind + 3, f"if {wa} >= {wp}: {wa} = {wp}; {wc} = _ton_done")
        self.emit(ind + 3, f"else: {wc} = ((_now - _r + _t * {base!r}) & {STAMP!r}) | {EN | TT!r}")
        self.emit(ind + 2, "else:")
        self.emit(ind + 3, f"{wc} = _ton_timing")  # the evaluation that enables it starts it
        self.emit(ind + 1, "else:")
        self.emit(ind + 2, f"{wc} = _ton_done")
        self.emit(ind, "else:")
        self.emit(ind + 1, f"{wc} = 0")
        self.emit(ind + 1, f"{wa} = 0")
        self.dirty.update((wc, wa))

    def _ton_in_place(self, ind: int, ins: Instruction, f, index: int, base: int) -> None:
        """A TON whose element no other instruction of the block uses: its
        words read into temporaries and each written in place when it
        changes (a done timer: two reads and one write, where locals held
        for the block cost three reads and two write-backs)."""
        d = self.array_name(f)
        control, pre, acc = (f"{d}[{index + k!r}]" for k in range(3))
        self.emit(ind, f"_tp = {pre}; _ta = {acc}")
        self.emit(ind, "if (_tp | _ta) < 0:")  # either negative: the kernel raises the fault, on an exact table
        self.flush_lines(ind + 1)
        self.emit(ind + 1, f"{self.bind('_ton', self.machine.ton)}({d}, {index!r}, {RUNG_BOOL}, {base!r})")
        self.emit(ind, "if c:")
        self.emit(ind + 1, "if _ta < _tp:")
        self.emit(ind + 2, f"_tw = {control}")
        self.emit(ind + 2, f"if _tw & {EN!r}:")
        self.emit(ind + 3, f"_r = (_now - (_tw & {STAMP!r})) % {STAMP_MODULO!r}")
        self.emit(ind + 3, f"_t = _r // {base!r}")
        self.emit(ind + 3, "if _t:")
        self.emit(ind + 4, "_ta += _t")
        self.emit(ind + 4, f"if _ta >= _tp: {acc} = _tp; {control} = _ton_done")
        self.emit(ind + 4, f"else: {acc} = _ta; {control} = ((_now - _r + _t * {base!r}) & {STAMP!r}) | {EN | TT!r}")
        # no whole tick yet: ACC and the stamp stay (now - elapsed is the stamp)
        self.emit(ind + 3, f"else: {control} = (_tw & {STAMP!r}) | {EN | TT!r}")
        self.emit(ind + 2, f"else: {control} = _ton_timing")
        self.emit(ind + 1, f"else: {control} = _ton_done")
        self.emit(ind, "else:")
        self.emit(ind + 1, f"{control} = 0")
        self.emit(ind + 1, f"if _ta: {acc} = 0")

    def _local_count(self, ind: int, ins: Instruction, up: bool) -> None:
        """Semantics.ctu / ctd written out on the element's words: the
        control word in a local; PRE and ACC in place unless the block uses
        them elsewhere (a counting edge, which writes ACC, is rare). A control
        word nothing else in the block uses is a temporary, written back at
        the end of the rung: the same read and write, one local less held."""
        f, index, _ = self.resolve(ins.operands[0].address)
        key = (f.number, index)
        alone = key not in self.words and self.uses.get(key, 0) <= 1
        wc, wp, wa = self.element_words(ind, ins.operands[0], force=(not alone, False, False))
        if alone:
            control, wc = wc, "_tw"
            self.emit(ind, f"_tw = _tw_was = {control}")
        edge, limit, wrapped, flag, other = (CU, 32767, -32768, OV, UN) if up else (CD, -32768, 32767, UN, OV)
        self.emit(ind, "if c:")
        self.emit(ind + 1, f"if not {wc} & {edge!r}:")
        self.emit(ind + 2, f"if {wa} == {limit!r}:")
        self.emit(ind + 3, f"{wa} = {wrapped!r}")
        self.emit(ind + 3, f"{wc} = ({wc} | {flag!r}) if not {wc} & {other!r} else ({wc} & {~other!r})")
        self.emit(ind + 2, f"else: {wa} {'+' if up else '-'}= 1")
        self.emit(ind + 1, f"{wc} |= {edge!r}")
        self.emit(ind, f"else: {wc} &= {~edge!r}")
        if alone:
            self.emit(ind, f"{wc} = ({wc} | {DN!r}) if {wa} >= {wp} else ({wc} & {~DN!r})")
            self.emit(ind, f"if _tw != _tw_was: {control} = _tw")  # steady counters write nothing
        else:
            self.emit(ind, f"{wc} = ({wc} | {DN!r}) if {wa} >= {wp} else ({wc} & {~DN!r})")
        self.held(wc, wa)

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
        if any(key == _FLAGS for key, _ in held):
            self.flags_exact(ind)
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
