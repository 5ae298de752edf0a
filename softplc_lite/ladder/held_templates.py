"""The compiler's templates on words held in locals (ladder/held_words.py):
contacts and coils, one-shots, word stores, TON, CTU/CTD and COP of direct
blocks. ``BIT_TEMPLATES`` (every operand a direct bit: ``fn(fc, ind,
*words)``, each word as (code, mask, held in a local)) and
``HELD_TEMPLATES`` (direct operands: ``fn(fc, ind, ins)``) join the table
templates in templates.TEMPLATES. The kernels of semantics.py are the
reference: the differential test holds these to them.
"""

from __future__ import annotations

from typing import Callable

from .ast import Instruction
from .blocks import RUNG_BOOL
from .held_words import _SIMPLE
from .semantics import BASE_MS, CD, CU, DN, EN, OV, STAMP, STAMP_MODULO, TT, UN

BIT_TEMPLATES: dict[str, Callable[..., None]] = {}
HELD_TEMPLATES: dict[str, Callable[..., None]] = {}


def _register(registry: dict):
    """Register ``bit_MNEMONIC`` or ``local_MNEMONIC`` under MNEMONIC."""
    def register(fn):
        registry[fn.__name__.split("_", 1)[1]] = fn
        return fn
    return register


def _written(fc, word: tuple) -> None:
    if word[2]:  # a local (a word in place needs nothing)
        fc.held.changed(word[0])


def store_in_local(fc, ind: int, dest, value_code: str, fallback: str, in_range: bool = False,
                   carry: str | None = None) -> None:
    """``value_code`` into the destination word (its local if held, else
    the table), with S:0 as the kernel sets it; out of range, the kernel
    (``fallback``, given the value as ``_v``) stores it and sets the
    overflow minor fault, and a held local reads it back. ``in_range``:
    the value is a word already (no range test)."""
    name = fc.inline_dest
    f, index, _ = fc.resolve(dest.address)
    target = name or f"{fc.array_name(f)}[{index!r}]"
    s0 = fc.inline_flags or "_s[0]"
    if in_range and _SIMPLE.match(value_code):
        v = value_code  # a local or a constant: no temporary
    else:
        v = "_v"
        fc.emit(ind, f"_v = {value_code}")
    if fc.inline_flags:
        # S:0 held: the flags are left pending until something reads S:0
        # (flags_exact); a later store replaces them.
        set_flags = f"_fz = {v}; _fc = {carry or 0}"
        fc.held.flags_pending = True
    else:
        flags = f"(4 if {v} == 0 else 8 if {v} < 0 else 0)"  # Z S:0/2, S S:0/3
        if carry is not None:
            flags = f"({carry}) | {flags}"
        set_flags = f"{s0} = ({s0} & -16) | {flags}"
    if in_range:
        fc.emit(ind, f"{target} = {v}")
        fc.emit(ind, set_flags)
        return
    fc.emit(ind, "if -32768 <= _v <= 32767:")
    fc.emit(ind + 1, f"{target} = _v")
    fc.emit(ind + 1, set_flags)
    fc.emit(ind, "else:")
    fc.emit(ind + 1, f"_m.rung = {fc.rung_index!r}")  # the minor fault names this rung
    if fc.inline_flags:  # the kernel sets S:0 in the table
        fc.held.flags_exact(ind + 1)
        fc.emit(ind + 1, f"_s[0] = {s0}")
    fc.emit(ind + 1, fallback.replace("_D_", f"{fc.array_name(f)}, {index!r}"))
    if name:
        fc.emit(ind + 1, f"{name} = f{f.number}[{index!r}]")
    if fc.inline_flags:
        fc.emit(ind + 1, f"{s0} = _s[0]")


# Bit instructions on words held in locals (or S words in place): each
# operand is (word code, mask, held in a local).
@_register(BIT_TEMPLATES)
def bit_XIC(fc, ind, w):
    fc.emit(ind, f"c = c and {w[0]} & {w[1]!r} != 0")


@_register(BIT_TEMPLATES)
def bit_XIO(fc, ind, w):
    fc.emit(ind, f"c = c and not {w[0]} & {w[1]!r}")


@_register(BIT_TEMPLATES)
def bit_OTE(fc, ind, w):
    fc.emit(ind, f"{w[0]} = ({w[0]} | {w[1]!r}) if c else ({w[0]} & {~w[1]!r})")
    _written(fc, w)


@_register(BIT_TEMPLATES)
def bit_OTL(fc, ind, w):
    fc.emit(ind, f"if c: {w[0]} |= {w[1]!r}")
    _written(fc, w)


@_register(BIT_TEMPLATES)
def bit_OTU(fc, ind, w):
    fc.emit(ind, f"if c: {w[0]} &= {~w[1]!r}")
    _written(fc, w)


@_register(BIT_TEMPLATES)
def bit_ONS(fc, ind, w):
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, f"if {w[0]} & {w[1]!r}: c = False")
    fc.emit(ind + 1, f"else: {w[0]} |= {w[1]!r}")
    fc.emit(ind, f"else: {w[0]} &= {~w[1]!r}")
    _written(fc, w)


def _bit_one_shot(fc, ind, storage, output, rising: bool):
    stored = f"{storage[0]} & {storage[1]!r}"
    fire = f"c and not {stored}" if rising else f"not c and {stored}"
    o, om = output[0], output[1]
    fc.emit(ind, f"{o} = ({o} | {om!r}) if ({fire}) else ({o} & {~om!r})")
    fc.emit(ind, f"{storage[0]} = ({storage[0]} | {storage[1]!r}) if c else ({storage[0]} & {~storage[1]!r})")
    _written(fc, storage)
    _written(fc, output)


@_register(BIT_TEMPLATES)
def bit_OSR(fc, ind, storage, output):
    _bit_one_shot(fc, ind, storage, output, True)


@_register(BIT_TEMPLATES)
def bit_OSF(fc, ind, storage, output):
    _bit_one_shot(fc, ind, storage, output, False)


# -- timers, counters and COP on held words
@_register(HELD_TEMPLATES)
def local_TON(fc, ind: int, ins: Instruction) -> None:
    """Semantics.ton written out on the element's locals (the kernel is
    the reference: the differential test holds them equal). The time is
    the engine's clock of this scan, _m.now_ms."""
    base = BASE_MS[ins.operands[1].value]
    fc.uses_now = True
    f, index, _ = fc.resolve(ins.operands[0].address)
    keys = [(f.number, index + k) for k in range(3)]
    if not any(key in fc.held.words or fc.held.uses.get(key, 0) > 1 for key in keys):
        _ton_in_place(fc, ind, ins, f, index, base)
        return
    wc, wp, wa = fc.held.element_words(ind, ins.operands[0])
    fc.emit(ind, f"if ({wp} | {wa}) < 0:")  # either negative: the kernel raises the fault, on an exact table
    fc.held.flush(ind + 1)
    d, i, _ = fc.location(ind + 1, ins.operands[0])
    fc.emit(ind + 1, f"{fc.bind('_ton', fc.machine.ton)}({d}, {i}, {RUNG_BOOL}, {base!r})")
    # EN, TT, DN and the stamp are every bit of the control word, so each
    # outcome sets the whole word: done is EN|DN and the stamp of now
    # (_ton_done, made once a block), enabled this scan EN|TT and now
    # (_ton_timing), still timing EN|TT and the stamp its time counts from.
    assert EN | TT | DN | STAMP == -1
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, f"if {wa} < {wp}:")  # not done (DN is ACC >= PRE, tested each scan)
    fc.emit(ind + 2, f"if {wc} & {EN!r}:")
    fc.emit(ind + 3, f"_r = (_now - ({wc} & {STAMP!r})) % {STAMP_MODULO!r}")  # ms since its last update
    fc.emit(ind + 3, f"_t = _r // {base!r}")
    fc.emit(ind + 3, f"{wa} += _t")
    fc.emit(ind + 3, f"if {wa} >= {wp}: {wa} = {wp}; {wc} = _ton_done")
    fc.emit(ind + 3, f"else: {wc} = ((_now - _r + _t * {base!r}) & {STAMP!r}) | {EN | TT!r}")
    fc.emit(ind + 2, "else:")
    fc.emit(ind + 3, f"{wc} = _ton_timing")  # the evaluation that enables it starts it
    fc.emit(ind + 1, "else:")
    fc.emit(ind + 2, f"{wc} = _ton_done")
    fc.emit(ind, "else:")
    fc.emit(ind + 1, f"{wc} = 0")
    fc.emit(ind + 1, f"{wa} = 0")
    fc.held.dirty.update((wc, wa))


def _ton_in_place(fc, ind: int, ins: Instruction, f, index: int, base: int) -> None:
    """A TON whose element no other instruction of the block uses: its
    words read into temporaries and each written in place when it
    changes (a done timer: two reads and one write, where locals held
    for the block cost three reads and two write-backs)."""
    d = fc.array_name(f)
    control, pre, acc = (f"{d}[{index + k!r}]" for k in range(3))
    fc.emit(ind, f"_tp = {pre}; _ta = {acc}")
    fc.emit(ind, "if (_tp | _ta) < 0:")  # either negative: the kernel raises the fault, on an exact table
    fc.held.flush(ind + 1)
    fc.emit(ind + 1, f"{fc.bind('_ton', fc.machine.ton)}({d}, {index!r}, {RUNG_BOOL}, {base!r})")
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, "if _ta < _tp:")
    fc.emit(ind + 2, f"_tw = {control}")
    fc.emit(ind + 2, f"if _tw & {EN!r}:")
    fc.emit(ind + 3, f"_r = (_now - (_tw & {STAMP!r})) % {STAMP_MODULO!r}")
    fc.emit(ind + 3, f"_t = _r // {base!r}")
    fc.emit(ind + 3, "if _t:")
    fc.emit(ind + 4, "_ta += _t")
    fc.emit(ind + 4, f"if _ta >= _tp: {acc} = _tp; {control} = _ton_done")
    fc.emit(ind + 4, f"else: {acc} = _ta; {control} = ((_now - _r + _t * {base!r}) & {STAMP!r}) | {EN | TT!r}")
    # no whole tick yet: ACC and the stamp stay (now - elapsed is the stamp)
    fc.emit(ind + 3, f"else: {control} = (_tw & {STAMP!r}) | {EN | TT!r}")
    fc.emit(ind + 2, f"else: {control} = _ton_timing")
    fc.emit(ind + 1, f"else: {control} = _ton_done")
    fc.emit(ind, "else:")
    fc.emit(ind + 1, f"{control} = 0")
    fc.emit(ind + 1, f"if _ta: {acc} = 0")


def _local_count(fc, ind: int, ins: Instruction, up: bool) -> None:
    """Semantics.ctu / ctd written out on the element's words: the
    control word in a local; PRE and ACC in place unless the block uses
    them elsewhere (a counting edge, which writes ACC, is rare). A control
    word nothing else in the block uses is a temporary, written back at
    the end of the rung: the same read and write, one local less held."""
    f, index, _ = fc.resolve(ins.operands[0].address)
    key = (f.number, index)
    alone = key not in fc.held.words and fc.held.uses.get(key, 0) <= 1
    wc, wp, wa = fc.held.element_words(ind, ins.operands[0], force=(not alone, False, False))
    if alone:
        control, wc = wc, "_tw"
        fc.emit(ind, f"_tw = _tw_was = {control}")
    edge, limit, wrapped, flag, other = (CU, 32767, -32768, OV, UN) if up else (CD, -32768, 32767, UN, OV)
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, f"if not {wc} & {edge!r}:")
    fc.emit(ind + 2, f"if {wa} == {limit!r}:")
    fc.emit(ind + 3, f"{wa} = {wrapped!r}")
    fc.emit(ind + 3, f"{wc} = ({wc} | {flag!r}) if not {wc} & {other!r} else ({wc} & {~other!r})")
    fc.emit(ind + 2, f"else: {wa} {'+' if up else '-'}= 1")
    fc.emit(ind + 1, f"{wc} |= {edge!r}")
    fc.emit(ind, f"else: {wc} &= {~edge!r}")
    if alone:
        fc.emit(ind, f"{wc} = ({wc} | {DN!r}) if {wa} >= {wp} else ({wc} & {~DN!r})")
        fc.emit(ind, f"if _tw != _tw_was: {control} = _tw")  # steady counters write nothing
    else:
        fc.emit(ind, f"{wc} = ({wc} | {DN!r}) if {wa} >= {wp} else ({wc} & {~DN!r})")
    fc.held.changed(wc, wa)


@_register(HELD_TEMPLATES)
def local_COP(fc, ind: int, ins: Instruction) -> None:
    """COP between direct blocks of one storage, whose ranges fit their
    files (known at load: the table's files do not change size while a
    program runs): a slice assignment. Held words of both blocks are
    written back first; those of the destination are forgotten after.
    Anything else runs the kernel after a barrier."""
    src, dest, length = ins.operands
    sf, si, _ = fc.resolve(src.address)
    df, di, _ = fc.resolve(dest.address)
    n = length.value * dest.address.ftype.words_per_element
    if sf.data.typecode != df.data.typecode or si + n > len(sf.data) or di + n > len(df.data):
        fc.barrier(ind)
        fc.dispatch(ind, ins)
        return
    in_blocks = [key for key in fc.held.words
                 if (key[0] == sf.number and si <= key[1] < si + n) or (key[0] == df.number and di <= key[1] < di + n)]
    held = fc.held.write_back(ind, in_blocks)
    fc.emit(ind, f"if c: {fc.array_name(df)}[{di!r}:{di + n!r}] = {fc.array_name(sf)}[{si!r}:{si + n!r}]")
    fc.held.forget([(key, name) for key, name in held if key[0] == df.number])


@_register(HELD_TEMPLATES)
def local_CTU(fc, ind: int, ins: Instruction) -> None:
    _local_count(fc, ind, ins, True)


@_register(HELD_TEMPLATES)
def local_CTD(fc, ind: int, ins: Instruction) -> None:
    _local_count(fc, ind, ins, False)
