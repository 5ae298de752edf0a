"""Sequencers: SQO (output), SQI (input), SQL (load), and SLC 500's SQC
(compare).

A sequencer file holds one word per step, from position 0 (the startup
step) to position LEN; the control (R) element keeps LEN and POS. On a
false-to-true transition SQO and SQL step POS on (LEN wraps to 1) and
act on the word at POS; while the rung stays true they act on it again
each scan without stepping (PLC-5 1785 user manual, "Sequencer
Instructions"). SQI compares without stepping: it usually shares its
control with an SQO. SQC (SLC 500) steps like SQO and sets FD when the
masked source matches the step word (1747-RM001 "Application Specific
Instructions").

A mask, source or destination written as a file (``#N7:30``) steps
through its own file with POS, as the sequencer file does; written as a
word address or a constant it is used as is (1747-RM001 "Application
Specific Instructions", sequencer TIP). ``#`` here marks a file, as it
does for the sequencer file; it is not S:24 indexing.

Length and Position are what a download writes into LEN and POS (see
shift.py); ER is set for LEN <= 0 or POS < 0 (for SQI also POS > LEN),
and then the instruction does nothing else.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

from ...datatable import Address
from ..ast import AddressRef, Instruction
from ..bound import LEN, POS, BoundInstruction, block, constant, control_words
from ..semantics import R_DN, R_EN, R_ER, R_FD, signed16
from ..specs import K, _spec


def _bad(n: int, pos: int) -> bool:
    """ER for SQO, SQL, SQC (1747-RM001; the 1756-RM003 flow charts): a
    position past LEN is not an error for them, the next step wraps it."""
    return n <= 0 or pos < 0


def _stepping(access, operand) -> Callable[[int, int], tuple]:
    """A getter ``(pos, n) -> (array, index)`` for an operand that steps
    with POS when written as a file (``#``), or stays on its word."""
    if isinstance(operand, AddressRef) and operand.address.indexed:
        get = access.location(AddressRef(replace(operand.address, indexed=False), operand.pos))
        what = str(operand.address)

        def at_step(pos: int, n: int):
            d, i, _ = get()
            block(d, i, n + 1, what)  # position 0 to LEN: LEN + 1 words
            return d, i + pos
        return at_step
    get = access.location(operand)

    def fixed(pos: int, n: int):
        d, i, _ = get()
        return d, i
    return fixed


def _stepping_value(access, operand) -> Callable[[int, int], int]:
    """As _stepping, for a read-only operand that may also be a constant."""
    if isinstance(operand, AddressRef):
        at = _stepping(access, operand)

        def read(pos: int, n: int) -> int:
            d, i = at(pos, n)
            return d[i]
        return read
    get = access.value(operand)
    return lambda pos, n: get()


def _step(d, i: int, w: int) -> tuple[int, int]:
    """A false-to-true transition: DN off, POS on by one (after LEN, back
    to 1), DN on at the last step. Returns (status word, position)."""
    n, pos = d[i + LEN], d[i + POS]
    pos = 1 if pos >= n else pos + 1
    d[i + POS] = pos
    w &= ~R_DN
    if pos == n:
        w |= R_DN
    return w, pos


def _stepper(get_control, act: Callable[[int, int, int], int]):
    """The run of SQO, SQL and SQC: EN remembers the rung; a false-to-true
    transition steps POS; on every true evaluation ``act(pos, n, status)``
    does the instruction's work and returns the status word."""
    def run(c: bool) -> bool:
        d, i, _ = get_control()
        w = d[i]
        if not c:
            d[i] = w & ~R_EN
            return c
        n, pos = d[i + LEN], d[i + POS]
        if _bad(n, pos):
            d[i] = w | R_EN | R_ER
            return c
        w &= ~R_ER
        if not w & R_EN:
            w, pos = _step(d, i, w)
        if pos <= n:  # a POS past LEN written while the rung stays true waits for the next step
            w = act(pos, n, w)
        d[i] = w | R_EN
        return c
    return run


def _bind_output(instr: Instruction, access):
    """SQO file mask dest control length position: dest = (dest AND NOT
    mask) OR (step word AND mask)."""
    file = _stepping(access, _as_file(instr.operands[0]))
    mask = _stepping_value(access, instr.operands[1])
    dest = _stepping(access, instr.operands[2])

    def act(pos: int, n: int, w: int) -> int:
        fd, fi = file(pos, n)
        m = mask(pos, n)
        dd, di = dest(pos, n)
        dd[di] = signed16((dd[di] & ~m) | (fd[fi] & m))
        return w
    return _stepper(access.location(instr.operands[3]), act)


def _bind_compare(instr: Instruction, access):
    """SQC file mask source control length position (SLC 500): steps like
    SQO; FD says whether the masked source equals the masked step word,
    assessed at each evaluation on a true rung."""
    file = _stepping(access, _as_file(instr.operands[0]))
    mask = _stepping_value(access, instr.operands[1])
    source = _stepping_value(access, instr.operands[2])

    def act(pos: int, n: int, w: int) -> int:
        fd, fi = file(pos, n)
        m = mask(pos, n)
        return w | R_FD if (source(pos, n) & m) == (fd[fi] & m) else w & ~R_FD
    return _stepper(access.location(instr.operands[3]), act)


def _bind_load(instr: Instruction, access):
    """SQL file source control length position: the source into the step
    word."""
    file = _stepping(access, _as_file(instr.operands[0]))
    source = _stepping_value(access, instr.operands[1])

    def act(pos: int, n: int, w: int) -> int:
        fd, fi = file(pos, n)
        fd[fi] = signed16(source(pos, n))
        return w
    return _stepper(access.location(instr.operands[2]), act)


def _bind_input(instr: Instruction, access):
    """SQI file mask source control length position: true when the masked
    source equals the masked step word at POS. ER (and false) when LEN <= 0,
    POS < 0 or POS > LEN (1756-RM003 SQI)."""
    file = _stepping(access, _as_file(instr.operands[0]))
    mask = _stepping_value(access, instr.operands[1])
    source = _stepping_value(access, instr.operands[2])
    get_control = access.location(instr.operands[3])

    def run(c: bool) -> bool:
        if not c:
            return False
        d, i, _ = get_control()
        n, pos = d[i + LEN], d[i + POS]
        if _bad(n, pos) or pos > n:
            d[i] |= R_ER
            return False
        d[i] &= ~R_ER
        fd, fi = file(pos, n)
        m = mask(pos, n)
        return (source(pos, n) & m) == (fd[fi] & m)
    return run


def _as_file(operand):
    """The sequencer file operand: the validator took its ``#`` off (a
    K.WORD_FILE operand); mark it again so it steps with POS."""
    if isinstance(operand, AddressRef) and not operand.address.indexed:
        return AddressRef(replace(operand.address, indexed=True), operand.pos)
    return operand


def _references(files: tuple[int, ...], length: int):
    """The last step word (LEN + 1 words from position 0) of the sequencer
    file and of every other operand written as a file."""
    def references(instr: Instruction) -> list[Address]:
        n = constant(instr, length)
        if n is None:
            return []
        out = []
        for k in files:
            op = instr.operands[k]
            if not isinstance(op, AddressRef) or (k != 0 and not op.address.indexed):
                continue
            a = replace(op.address, indexed=False)
            if a.is_direct and a.element is not None:
                out.append(a.with_element(a.element + n))
        return out
    return references


SQO = _spec("SQO", "sequencer output", True, ("file", K.WORD_FILE), ("mask", K.INT_SOURCE), ("dest", K.WORD),
            ("control", K.CONTROL), ("length", K.LENGTH), ("position", K.POSITION))
SQI = _spec("SQI", "sequencer input", False, ("file", K.WORD_FILE), ("mask", K.INT_SOURCE),
            ("source", K.INT_SOURCE), ("control", K.CONTROL), ("length", K.LENGTH), ("position", K.POSITION))
SQC = _spec("SQC", "sequencer compare", True, ("file", K.WORD_FILE), ("mask", K.INT_SOURCE),
            ("source", K.INT_SOURCE), ("control", K.CONTROL), ("length", K.LENGTH), ("position", K.POSITION))
SQL = _spec("SQL", "sequencer load", True, ("file", K.WORD_FILE), ("source", K.INT_SOURCE), ("control", K.CONTROL),
            ("length", K.LENGTH), ("position", K.POSITION))

INSTRUCTIONS = [
    BoundInstruction(SQO, _bind_output, _references((0, 1, 2), 4), lambda instr: control_words(instr, 3, 4, 5)),
    BoundInstruction(SQI, _bind_input, _references((0, 1, 2), 4), lambda instr: control_words(instr, 3, 4, 5)),
    BoundInstruction(SQC, _bind_compare, _references((0, 1, 2), 4), lambda instr: control_words(instr, 3, 4, 5)),
    BoundInstruction(SQL, _bind_load, _references((0, 1), 3), lambda instr: control_words(instr, 2, 3, 4)),
]
