"""Shift registers, FIFO and LIFO: BSL, BSR, FFL, FFU, LFL, LFU.

All six act on a false-to-true transition of their rung and keep their
state in a control (R) element: word 0 the status bits, word 1 LEN, word 2
POS. The enable bit is the memory of the rung state (EN for BSL, BSR, FFL,
LFL; EU for FFU and LFU, so that a load and an unload instruction can share
one control, as AB pairs them).

The Length and Position operands are what a download writes into LEN and
POS (``initial``: bound.control_words, as RSLogix writes a timer's preset
into PRE); at run time the instructions work from the control's words, so
a program may change them, and a bad value sets ER instead of being
refused at load.
docs/instructions.md cites the AB section for each rule:

- BSL/BSR: 1747-NP002 (the SLC 500 hand-held terminal manual) ch. 23
  "Bit Shift, FIFO, and LIFO" (operation, UL, wraparound), 1747-RM001
  (control element); a false rung clearing EN, DN and ER is our choice.
- FFL/FFU/LFL/LFU: 1747-RM001 "FIFO and LIFO Instructions" and 1747-NP002
  ch. 23 (loading, unloading, DN full, EM empty, S:24).
"""

from __future__ import annotations

from ...datatable import Address
from ..ast import Instruction
from ..bound import LEN, POS, BoundInstruction, block, constant, control_words, file_references
from ..semantics import R_DN, R_EM, R_EN, R_ER, R_EU, R_UL, signed16
from ..specs import K, _spec
from .. import status as S


# -- BSL, BSR --------------------------------------------------------------------------


def _shift_bits(d, i: int, n: int, bit_in: int, left: bool) -> int:
    """Shift the ``n``-bit array from word ``i`` by one; return the bit out.
    Bits past ``n`` in the last word are left as they are (AB: do not use
    them)."""
    words = (n + 15) // 16
    value = 0
    for k in range(words):
        value |= (d[i + k] & 0xFFFF) << (16 * k)
    full = (1 << n) - 1
    bits = value & full
    if left:
        out = (bits >> (n - 1)) & 1
        bits = ((bits << 1) | bit_in) & full
    else:
        out = bits & 1
        bits = (bits >> 1) | (bit_in << (n - 1))
    value = (value & ~full) | bits
    for k in range(words):
        d[i + k] = signed16(value >> (16 * k))
    return out


def _bind_bit_shift(left: bool):
    def bind(instr: Instruction, access):
        get_file = access.location(instr.operands[0])
        get_control = access.location(instr.operands[1])
        get_bit = access.value(instr.operands[2])
        what = str(instr.operands[0].address)

        def run(c: bool) -> bool:
            d, i, _ = get_control()
            w = d[i]
            if not c:
                d[i] = w & ~(R_EN | R_DN | R_ER)
                return c
            if w & R_EN:  # still true: one shift per false-to-true transition
                return c
            n = d[i + LEN]
            if n < 0:
                d[i] = (w | R_EN | R_ER) & ~R_DN
                return c
            if n > 0:
                fd, fi, _ = get_file()
                block(fd, fi, (n + 15) // 16, what)
                # Read the source bit before shifting: it may be in the array
                # or be the UL bit itself (AB's wraparound).
                bit_in = get_bit()
                w = d[i]
                w = w | R_UL if _shift_bits(fd, fi, n, bit_in, left) else w & ~R_UL
            d[i] = (w | R_EN | R_DN) & ~R_ER
            return c
        return run
    return bind


def _bit_shift_references(instr: Instruction) -> list[Address]:
    n = constant(instr, 3)
    return file_references(instr, 0, None if n is None else (n + 15) // 16)


def _bit_shift(mnemonic: str, title: str, left: bool) -> BoundInstruction:
    spec = _spec(mnemonic, title, True, ("file", K.WORD_FILE), ("control", K.CONTROL), ("bit", K.BIT),
                 ("length", K.BIT_LENGTH))
    return BoundInstruction(spec, _bind_bit_shift(left), _bit_shift_references,
                            lambda instr: control_words(instr, 1, 3))


# -- FFL, FFU, LFL, LFU ----------------------------------------------------------------


def stack_status(w: int, n: int, pos: int) -> int:
    """DN (full) and EM (empty) from LEN and POS, or ER when they are bad."""
    if n <= 0 or pos < 0 or pos > n:
        return w | R_ER
    w &= ~(R_ER | R_DN | R_EM)
    if pos >= n:
        w |= R_DN
    if pos == 0:
        w |= R_EM
    return w


def _bind_load(instr: Instruction, access):
    """FFL and LFL: one word into the stack at POS, then POS + 1."""
    get_source = access.value(instr.operands[0])
    get_stack = access.location(instr.operands[1])
    get_control = access.location(instr.operands[2])
    what = str(instr.operands[1].address)
    s = access.machine.s

    def run(c: bool) -> bool:
        d, i, _ = get_control()
        w, n, pos = d[i], d[i + LEN], d[i + POS]
        if not c:
            d[i] = stack_status(w & ~R_EN, n, pos)
            return c
        if not w & R_EN and 0 <= pos < n:
            sd, si, _ = get_stack()
            block(sd, si, n, what)
            s[S.INDEX_REGISTER] = pos  # SLC: the position at entry
            sd[si + pos] = signed16(get_source())
            pos += 1
            d[i + POS] = pos
        d[i] = stack_status(w | R_EN, n, pos)
        return c
    return run


def _bind_unload(fifo: bool):
    """FFU: the word at 0 out, the stack shifted down, the top zeroed.
    LFU: the word at POS - 1 out (and zeroed). Both then POS - 1."""
    def bind(instr: Instruction, access):
        get_stack = access.location(instr.operands[0])
        get_dest = access.location(instr.operands[1])
        get_control = access.location(instr.operands[2])
        what = str(instr.operands[0].address)
        s = access.machine.s

        def run(c: bool) -> bool:
            d, i, _ = get_control()
            w, n, pos = d[i], d[i + LEN], d[i + POS]
            if not c:
                d[i] = stack_status(w & ~R_EU, n, pos)
                return c
            if not w & R_EU and 0 < pos <= n:
                sd, si, _ = get_stack()
                block(sd, si, n, what)
                dd, di, _ = get_dest()
                if fifo:
                    out = sd[si]
                    sd[si:si + n - 1] = sd[si + 1:si + n]
                    sd[si + n - 1] = 0
                else:
                    out = sd[si + pos - 1]
                    sd[si + pos - 1] = 0
                dd[di] = out
                pos -= 1
                d[i + POS] = pos
                s[S.INDEX_REGISTER] = pos  # SLC: the position at exit
            d[i] = stack_status(w | R_EU, n, pos)
            return c
        return run
    return bind


def _stack_references(stack: int):
    return lambda instr: file_references(instr, stack, constant(instr, 3))


def _load(mnemonic: str, title: str) -> BoundInstruction:
    spec = _spec(mnemonic, title, True, ("source", K.INT_SOURCE), ("stack", K.WORD_FILE), ("control", K.CONTROL),
                 ("length", K.LENGTH), ("position", K.POSITION))
    return BoundInstruction(spec, _bind_load, _stack_references(1), lambda instr: control_words(instr, 2, 3, 4))


def _unload(mnemonic: str, title: str, fifo: bool) -> BoundInstruction:
    spec = _spec(mnemonic, title, True, ("stack", K.WORD_FILE), ("dest", K.WORD), ("control", K.CONTROL),
                 ("length", K.LENGTH), ("position", K.POSITION))
    return BoundInstruction(spec, _bind_unload(fifo), _stack_references(0),
                            lambda instr: control_words(instr, 2, 3, 4))


INSTRUCTIONS = [
    _bit_shift("BSL", "bit shift left", True),
    _bit_shift("BSR", "bit shift right", False),
    _load("FFL", "FIFO load"),
    _unload("FFU", "FIFO unload", True),
    _load("LFL", "LIFO load"),
    _unload("LFU", "LIFO unload", False),
]
