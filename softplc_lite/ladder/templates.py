"""The compiler's instruction templates, and their registry.

A :class:`Template` says how the file compiler (compiler.py) emits one
instruction: ``table`` on the data table in place (after a barrier: every
held word written back, ladder/held_words.py), and, where an instruction
has them, ``bits`` on words held in locals and ``held`` on an element's
held words (ladder/held_templates.py). ``TEMPLATES`` maps each mnemonic to
its template; the bound instructions of ladder/instr/ and module
instructions have none (the compiler calls their objects). A table
template is ``fn(fc, ind, ops)``: the compiler, the indent, the operands.
Kernels with real logic are Machine methods (semantics.py), shared with
the reference interpreter.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from . import status as S
from .ast import AddressRef
from .blocks import RET, RUNG_BOOL, TND
from .held_templates import BIT_TEMPLATES, HELD_TEMPLATES, store_in_local
from .held_words import _SIMPLE, _is_word, _word_valued
from .semantics import BASE_MS, MajorFault, lim, source_units


@dataclass(frozen=True)
class Template:
    """How the compiler emits one instruction (see the module doc)."""

    table: Callable[..., None]  # fn(fc, ind, ops): on the table in place, after a barrier
    bits: Callable[..., None] | None = None  # fn(fc, ind, *words): every operand a direct bit, words held or in place
    held: Callable[..., None] | None = None  # fn(fc, ind, ins): direct operands, on the element's held words


_TABLE: dict[str, Callable[..., None]] = {}


def template(fn):
    """Register ``i_MNEMONIC`` as MNEMONIC's table template."""
    _TABLE[fn.__name__[2:]] = fn
    return fn


# Bit instructions on indirect or indexed addresses, on the table.
@template
def i_XIC(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, f"c = c and {d}[{i}] & {mk} != 0")


@template
def i_XIO(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, f"c = c and not {d}[{i}] & {mk}")


@template
def i_OTE(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, f"{d}[{i}] = ({d}[{i}] | {mk}) if c else ({d}[{i}] & ~{mk})")


@template
def i_OTL(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, f"if c: {d}[{i}] |= {mk}")


@template
def i_OTU(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, f"if c: {d}[{i}] &= ~{mk}")


@template
def i_ONS(fc, ind, ops):
    d, i, mk = fc.location(ind, ops[0])
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, f"if {d}[{i}] & {mk}: c = False")
    fc.emit(ind + 1, f"else: {d}[{i}] |= {mk}")
    fc.emit(ind, f"else: {d}[{i}] &= ~{mk}")


def _one_shot(fc, ind, ops, rising: bool):
    sd, si, sm = fc.location(ind, ops[0])
    od, oi, om = fc.location(ind, ops[1])
    stored = f"{sd}[{si}] & {sm}"
    fire = f"c and not {stored}" if rising else f"not c and {stored}"
    fc.emit(ind, f"{od}[{oi}] = ({od}[{oi}] | {om}) if ({fire}) else ({od}[{oi}] & ~{om})")
    fc.emit(ind, f"{sd}[{si}] = ({sd}[{si}] | {sm}) if c else ({sd}[{si}] & ~{sm})")


@template
def i_OSR(fc, ind, ops):
    _one_shot(fc, ind, ops, True)


@template
def i_OSF(fc, ind, ops):
    _one_shot(fc, ind, ops, False)


def _timer(fc, ind, ops, kernel: str):
    d, i, _ = fc.location(ind, ops[0])
    fn = fc.bind(f"_{kernel}", getattr(fc.machine, kernel))
    fc.emit(ind, f"{fn}({d}, {i}, {RUNG_BOOL}, {BASE_MS[ops[1].value]!r})")


@template
def i_TON(fc, ind, ops):
    _timer(fc, ind, ops, "ton")


@template
def i_TOF(fc, ind, ops):
    _timer(fc, ind, ops, "tof")


@template
def i_RTO(fc, ind, ops):
    _timer(fc, ind, ops, "rto")


def _counter(fc, ind, ops, kernel: str):
    d, i, _ = fc.location(ind, ops[0])
    fn = fc.bind(f"_{kernel}", getattr(fc.machine, kernel))
    fc.emit(ind, f"{fn}({d}, {i}, {RUNG_BOOL})")


@template
def i_CTU(fc, ind, ops):
    _counter(fc, ind, ops, "ctu")


@template
def i_CTD(fc, ind, ops):
    _counter(fc, ind, ops, "ctd")


@template
def i_RES(fc, ind, ops):
    fc.emit(ind, "if c:")
    d, i, _ = fc.location(ind + 1, ops[0])
    fc.emit(ind + 1, f"{fc.bind('_res', fc.machine.res)}({d}, {i})")


@template
def i_LIM(fc, ind, ops):
    lo, t, hi = (fc.value(ind, o) for o in ops)
    fc.emit(ind, f"c = c and {fc.bind('_lim', lim)}({lo}, {t}, {hi})")


@template
def i_MEQ(fc, ind, ops):
    src, mask, cmp_ = (fc.value(ind, o) for o in ops)
    fc.emit(ind, f"c = c and ({src} & {mask}) == ({cmp_} & {mask})")


@template
def i_CMP(fc, ind, ops):
    fc.emit(ind, "if c:")
    fc.emit(ind + 1, f"c = bool({fc.expression(ind + 1, ops[0])})")


def _store(fc, ind, dest, value_code: str, kernel: str = "store", value=None):
    if fc.inline_dest is not None:  # MOV/CPT of a word value into a held word (in_place)
        fc.bind("_s", fc.machine.s)
        fn = fc.bind("_store", fc.machine.store)
        store_in_local(fc, ind + 1, dest, value_code, f"{fn}(_v, _D_)", in_range=_is_word(value))
        return
    d, i, _ = fc.location(ind + 1, dest)
    if kernel == "store" and value is not None and _is_word(dest) and _word_valued(value):
        kernel = "store_word"
    fn = fc.bind(f"_{kernel}", getattr(fc.machine, kernel))
    fc.emit(ind + 1, f"{fn}({value_code}, {d}, {i})")


def _math2(fc, ind, ops, kernel: str):
    fc.emit(ind, "if c:")
    a, b = fc.value(ind + 1, ops[0]), fc.value(ind + 1, ops[1])
    if fc.inline_dest is not None:  # ADD/SUB of words into a held word (in_place)
        # Operands read in place are read once (the sum, the carry and a fallback use them);
        # an operand that is the destination's local too (SUB N7:4 1 N7:4) is copied, as the
        # carry is worked out after the store.
        if not _SIMPLE.match(a) or a == fc.inline_dest:
            fc.emit(ind + 1, f"_a = {a}")
            a = "_a"
        if not _SIMPLE.match(b) or b == fc.inline_dest:
            fc.emit(ind + 1, f"_b = {b}")
            b = "_b"
        fc.bind("_s", fc.machine.s)
        fn = fc.bind(f"_{kernel}", getattr(fc.machine, kernel))
        a16, b16 = (repr(int(x) & 65535) if x.lstrip("-").isdigit() else f"({x} & 65535)" for x in (a, b))
        symbol, carry = ("+", f"{a16} + {b16} > 65535") if kernel == "add" else ("-", f"{a16} < {b16}")
        store_in_local(fc, ind + 1, ops[2], f"{a} {symbol} {b}", f"{fn}({a}, {b}, _D_)", carry=carry)
        return
    d, i, _ = fc.location(ind + 1, ops[2])
    if kernel in ("add", "sub") and all(_is_word(op) for op in ops):
        kernel += "_words"
    fn = fc.bind(f"_{kernel}", getattr(fc.machine, kernel))
    fc.emit(ind + 1, f"{fn}({a}, {b}, {d}, {i})")


@template
def i_ADD(fc, ind, ops):
    _math2(fc, ind, ops, "add")


@template
def i_SUB(fc, ind, ops):
    _math2(fc, ind, ops, "sub")


@template
def i_DIV(fc, ind, ops):
    _math2(fc, ind, ops, "div")


@template
def i_MOD(fc, ind, ops):
    _math2(fc, ind, ops, "mod")


@template
def i_MUL(fc, ind, ops):
    fc.emit(ind, "if c:")
    a, b = fc.value(ind + 1, ops[0]), fc.value(ind + 1, ops[1])
    _store(fc, ind, ops[2], f"{a} * {b}")


@template
def i_NEG(fc, ind, ops):
    fc.emit(ind, "if c:")
    v = fc.value(ind + 1, ops[0])
    d, i, _ = fc.location(ind + 1, ops[1])
    fc.emit(ind + 1, f"{fc.bind('_neg', fc.machine.neg)}({v}, {d}, {i})")


@template
def i_ABS(fc, ind, ops):
    fc.emit(ind, "if c:")
    _store(fc, ind, ops[1], f"abs({fc.value(ind + 1, ops[0])})")


@template
def i_SQR(fc, ind, ops):
    fc.emit(ind, "if c:")
    v = fc.value(ind + 1, ops[0])
    d, i, _ = fc.location(ind + 1, ops[1])
    fc.emit(ind + 1, f"{fc.bind('_sqr', fc.machine.sqr)}({v}, {d}, {i})")


@template
def i_MOV(fc, ind, ops):
    fc.emit(ind, "if c:")
    _store(fc, ind, ops[1], fc.value(ind + 1, ops[0]), value=ops[0])


@template
def i_CPT(fc, ind, ops):
    fc.emit(ind, "if c:")
    _store(fc, ind, ops[0], fc.expression(ind + 1, ops[1]), value=ops[1])


@template
def i_CLR(fc, ind, ops):
    fc.emit(ind, "if c:")
    d, i, _ = fc.location(ind + 1, ops[0])
    fc.emit(ind + 1, f"{fc.bind('_clear', fc.machine.clear)}({d}, {i})")


def _logic(fc, ind, ops, symbol: str):
    fc.emit(ind, "if c:")
    a, b = fc.value(ind + 1, ops[0]), fc.value(ind + 1, ops[1])
    _store(fc, ind, ops[2], f"{a} {symbol} {b}", "logic")


@template
def i_AND(fc, ind, ops):
    _logic(fc, ind, ops, "&")


@template
def i_OR(fc, ind, ops):
    _logic(fc, ind, ops, "|")


@template
def i_XOR(fc, ind, ops):
    _logic(fc, ind, ops, "^")


@template
def i_NOT(fc, ind, ops):
    fc.emit(ind, "if c:")
    _store(fc, ind, ops[1], f"~{fc.value(ind + 1, ops[0])}", "logic")


@template
def i_MVM(fc, ind, ops):
    fc.emit(ind, "if c:")
    src, mask = fc.value(ind + 1, ops[0]), fc.value(ind + 1, ops[1])
    d, i, _ = fc.location(ind + 1, ops[2])
    fc.emit(ind + 1, f"{fc.bind('_logic', fc.machine.logic)}(({d}[{i}] & ~{mask}) | ({src} & {mask}), {d}, {i})")


def _block(fc, ind, ref: AddressRef, length: int, dest_ref: AddressRef) -> tuple[str, str, str]:
    """A block operand of a file instruction: array, start, word count.
    The element count comes from the destination's element size; a COP
    source of another storage (F vs words) spans the same bytes."""
    wpe = dest_ref.address.ftype.words_per_element
    needed = source_units(length * wpe, ref.address.ftype, dest_ref.address.ftype)
    d, i, _ = fc.location(ind, ref)
    check = fc.bind("_block_check", _block_check)
    fc.emit(ind, f"{check}({d}, {i}, {needed!r}, {str(ref.address)!r})")
    return d, i, repr(length * wpe)


@template
def i_COP(fc, ind, ops):
    fc.emit(ind, "if c:")
    n = ops[2].value
    sd, si, count = _block(fc, ind + 1, ops[0], n, ops[1])
    dd, di, _ = _block(fc, ind + 1, ops[1], n, ops[1])
    fc.emit(ind + 1, f"{fc.bind('_cop', fc.machine.cop)}({sd}, {si}, {dd}, {di}, {count})")


@template
def i_FLL(fc, ind, ops):
    fc.emit(ind, "if c:")
    v = fc.value(ind + 1, ops[0])
    dd, di, count = _block(fc, ind + 1, ops[1], ops[2].value, ops[1])
    fc.emit(ind + 1, f"{fc.bind('_fll', fc.machine.fll)}({v}, {dd}, {di}, {count})")


@template
def i_BTD(fc, ind, ops):
    fc.emit(ind, "if c:")
    src = fc.value(ind + 1, ops[0])
    d, i, _ = fc.location(ind + 1, ops[2])
    fc.emit(ind + 1, f"{fc.bind('_btd', fc.machine.btd)}({src}, {ops[1].value!r}, {d}, {i}, "
            f"{ops[3].value!r}, {ops[4].value!r})")


# program control: leaving the block writes its locals back first
def leave(fc, ind: int, value: str) -> None:
    fc.emit(ind, "if c:")
    fc.held.flush(ind + 1)
    fc.emit(ind + 1, f"return {value}")


@template
def i_JMP(fc, ind, ops):
    leave(fc, ind, repr(fc.labels[ops[0].value]))


@template
def i_LBL(fc, ind, ops):
    pass


@template
def i_SBR(fc, ind, ops):
    pass  # its parameters are written by the engine when a JSR enters the file (Engine.run_file)


def _call(fc) -> str:
    """``_calls[k]``: the instruction being compiled, for the engine to
    move its parameters (JSR inputs and returns, RET values)."""
    calls = fc.env.setdefault("_calls", [])
    key = (id(fc.current), "call")
    if key not in fc.named:
        fc.named[key] = f"_calls[{len(calls)}]"
        calls.append(fc.current)
    return fc.named[key]


@template
def i_JSR(fc, ind, ops):
    if len(ops) > 1:
        fc.emit(ind, f"if c: _jsr({ops[0].value!r}, {_call(fc)})")
    else:
        fc.emit(ind, f"if c: _jsr({ops[0].value!r})")


@template
def i_RET(fc, ind, ops):
    # A RET with values returns itself: run_file reads them (a fault there names this rung), the JSR stores them.
    if ops:
        fc.mark_rung(ind)
    leave(fc, ind, _call(fc) if ops else repr(RET))


@template
def i_TND(fc, ind, ops):
    leave(fc, ind, repr(TND))


@template
def i_MCR(fc, ind, ops):
    # An MCR alone on its rung ends the zone; with conditions before it, it starts one.
    conditional = fc.rung_elements[0] is not fc.current
    fc.emit(ind, f"z = {RUNG_BOOL if conditional else 'True'}")
    fc.emit(ind, "_zone[0] = z")


@template
def i_AFI(fc, ind, ops):
    fc.emit(ind, "c = False")


# strings
def _strings(fc, ind, kernel: str, ops, values=()):
    fc.emit(ind, "if c:")
    args = []
    for k, op in enumerate(ops):
        if k in values:
            args.append(fc.value(ind + 1, op))
        else:
            d, i, _ = fc.location(ind + 1, op)
            args += [d, i]
    fc.emit(ind + 1, f"{fc.bind('_' + kernel, getattr(fc.machine, kernel))}({', '.join(args)})")


@template
def i_ACI(fc, ind, ops):
    _strings(fc, ind, "aci", ops)


@template
def i_AIC(fc, ind, ops):
    _strings(fc, ind, "aic", ops, values=(0,))


@template
def i_ACN(fc, ind, ops):
    _strings(fc, ind, "acn", ops)


@template
def i_AEX(fc, ind, ops):
    _strings(fc, ind, "aex", ops, values=(1, 2))


@template
def i_ASC(fc, ind, ops):
    # operands in AB order, as the kernel takes them: source (sought), index, string search, result
    _strings(fc, ind, "asc", ops, values=(1,))


@template
def i_ASR(fc, ind, ops):
    fc.emit(ind, "if c:")
    (ad, ai, _), (bd, bi, _) = fc.location(ind + 1, ops[0]), fc.location(ind + 1, ops[1])
    fc.emit(ind + 1, f"c = {fc.bind('_asr', fc.machine.asr)}({ad}, {ai}, {bd}, {bi})")


def _block_check(d, i, n, text) -> None:
    if i + n > len(d):
        raise MajorFault(S.FAULT_BLOCK_RANGE, f"{n} words from {text} run past the end of the file ({len(d)} words)")


def _compare(symbol: str):
    def compare(fc, ind, ops):
        a, b = fc.value(ind, ops[0]), fc.value(ind, ops[1])
        fc.emit(ind, f"c = c and {a} {symbol} {b}")
    return compare


_COMPARE = {"EQU": "==", "NEQ": "!=", "LES": "<", "LEQ": "<=", "GRT": ">", "GEQ": ">="}
_TABLE.update((m, _compare(symbol)) for m, symbol in _COMPARE.items())

TEMPLATES: dict[str, Template] = {m: Template(fn) for m, fn in _TABLE.items()}
for _m, _fn in BIT_TEMPLATES.items():
    TEMPLATES[_m] = replace(TEMPLATES[_m], bits=_fn)
for _m, _fn in HELD_TEMPLATES.items():
    TEMPLATES[_m] = replace(TEMPLATES[_m], held=_fn)
