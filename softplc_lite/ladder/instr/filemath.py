"""File arithmetic and search: FAL and FSC, and the file statistics AVE,
STD and SRT (PLC-5 Instruction Set Reference 1785-6.1; Logix 1756-RM003
chapter "Array (File)/Misc. Instructions" where the PLC-5 text was not at
hand). docs/instructions.md, "File arithmetic and search instructions",
has the rules and says which are softplc choices.

FAL and FSC step a position (the control's POS) through ``Length``
elements. At each element S:24 is set to the position, so the ``#``
(indexed) addresses of the destination and of the expression name the
element at that offset: ``#N7:10`` is N7:10 at position 0, N7:13 at
position 3. How many elements a scan does is the mode:

- ``ALL``: the whole file in the scan of the rung's false-to-true
  transition;
- ``INC``: one element per false-to-true transition;
- a number N: N elements a scan from the transition on, on every scan
  until the file is done, whatever the rung does meanwhile.

The Length and Position operands are what a download writes into the
control's LEN and POS (``initial``, as for shift registers); at run time the
instructions work from the control's words, so a program may change them.

Control bits: EN follows the rung; EU is set while an operation is under
way (started, not done); DN when the last element is done; ER when a
FAL store overflows (the operation stops at that element). FSC sets FD
and IN on a true comparison and stops there; the program clears IN to go
on. A false rung resets a finished or stopped operation (DN, ER, FD, IN
cleared, POS 0); one under way (EU) is left to go on. A new operation
starts at POS: 0 after that reset, or what the download or the program
wrote.
"""

from __future__ import annotations

import math

from ...datatable import Address
from ..ast import Instruction, SymbolRef, address_refs
from ..bound import LEN, POS, BoundInstruction, block, constant, control_words, file_references
from ..semantics import R_DN, R_EN, R_ER, R_EU, R_FD, R_IN
from ..specs import K, _spec
from .. import status as S

ALL, INC = "ALL", "INC"
FILE_MODES = (ALL, INC)
_OVERFLOW = 1 << S.OVERFLOW  # S:0/1
_FINISHED = R_DN | R_ER | R_FD | R_IN


def file_mode(operand) -> str | int:
    """A validated mode operand: "ALL", "INC" or elements per scan."""
    if isinstance(operand, SymbolRef):
        return operand.name.upper()
    return operand.value


def _stepper(instr: Instruction, access, step, on_stop: int, clears_stop: bool):
    """The ALL / INC / numeric engine FAL and FSC share.

    ``step(p)`` handles the element at position ``p`` and returns True to
    stop there. ``on_stop`` is the bits set when it does (FAL: ER, FSC: FD
    and IN); ``clears_stop`` says whether a stop ends the operation (FAL's
    ER does; FSC's find only pauses it until the program clears IN)."""
    control = access.location(instr.operands[0])
    mode = file_mode(instr.operands[3])
    per_scan = None if mode == ALL else 1 if mode == INC else mode
    incremental, numeric = mode == INC, isinstance(mode, int)
    s = access.machine.s

    def work(d, i: int, w: int) -> int:
        p, length = d[i + POS], d[i + LEN]
        if w & R_FD:  # FSC resuming after a find: the found element is behind it
            w &= ~R_FD
            p += 1
        budget = per_scan
        while p < length and budget != 0:
            if p < 0:
                break
            d[i + POS] = p
            s[S.INDEX_REGISTER] = p
            if step(p):
                w |= on_stop
                if clears_stop:
                    w &= ~R_EU
                return w
            p += 1
            if budget is not None:
                budget -= 1
        if p < 0 or p > length:
            # A length or position the program wrote outside the file (softplc choice: ER, nothing done).
            return (w | R_ER) & ~R_EU
        d[i + POS] = p
        if p == length:
            w = (w | R_DN) & ~R_EU
        return w

    def run(c: bool) -> bool:
        d, i, _ = control()
        w = d[i]
        if c:
            first = not w & R_EN
            w |= R_EN
            if first and not w & R_EU:
                # A new operation, from POS, with the last one's bits cleared.
                w = (w & ~_FINISHED) | R_EU
            busy = w & R_EU and not w & (R_IN | R_ER)
            if busy and (first or not incremental):
                w = work(d, i, w)
        else:
            w &= ~R_EN
            if w & R_EU:
                if numeric and not w & (R_IN | R_ER):
                    w = work(d, i, w)  # numeric mode goes on whatever the rung does
            elif w & _FINISHED:
                w &= ~_FINISHED
                d[i + POS] = 0
        d[i] = w
        return c

    return run


def _bind_fal(instr: Instruction, access):
    dest = access.location(instr.operands[4])
    expression = access.expression(instr.operands[5])
    machine = access.machine
    s = machine.s

    def step(p: int) -> bool:
        value = expression()
        d, i, _ = dest()
        machine.store(value, d, i)
        return bool(s[S.ARITH_FLAGS] & _OVERFLOW)

    return _stepper(instr, access, step, R_ER, True)


def _bind_fsc(instr: Instruction, access):
    expression = access.expression(instr.operands[4])
    return _stepper(instr, access, lambda p: bool(expression()), R_FD | R_IN, False)


def _indexed_references(instr: Instruction, operands: tuple[int, ...]) -> list[Address]:
    """The last element each ``#`` address of these operands reaches, so
    the data table holds the whole file at load (as for COP)."""
    length = constant(instr, 1)
    out = []
    if not isinstance(length, int) or length < 1:
        return out
    for k in operands:
        if k >= len(instr.operands):
            continue
        for ref in address_refs(instr.operands[k]):
            a = ref.address
            if a.indexed and isinstance(a.file, int) and isinstance(a.element, int) \
                    and not isinstance(a.bit, Address):
                out.append(a.with_element(a.element + length - 1))
    return out


# -- AVE, STD, SRT ---------------------------------------------------------------------------


def _statistic(compute):
    """AVE, STD and SRT: the whole file in the scan of the false-to-true
    transition (as 1756-RM003 says AVE does: a FAL in ALL mode); DN then
    until the rung goes false, which resets EN, DN, ER and POS."""

    def bind(instr: Instruction, access):
        source = access.location(instr.operands[0])
        control = access.location(instr.operands[-3])
        dest = access.location(instr.operands[1]) if len(instr.operands) == 5 else None
        machine = access.machine
        what = str(instr.operands[0].address)

        def run(c: bool) -> bool:
            d, i, _ = control()
            w, length = d[i], d[i + LEN]
            if not c:
                d[i] = w & ~(R_EN | R_DN | R_ER)
                d[i + POS] = 0
                return False
            if w & R_EN:
                return True  # done on the transition; nothing more while the rung stays true
            error = length < 1  # nothing to average or sort (softplc choice: ER)
            if not error:
                fd, fi, _ = source()
                block(fd, fi, length, what)
                error = compute(machine, fd, fi, length, dest)
                d[i + POS] = length
            d[i] = w | R_EN | (R_ER if error else R_DN)
            return True

        return run

    return bind


def _store_result(machine, value: float, dest) -> bool:
    d, i, _ = dest()
    machine.store(value, d, i)
    return bool(machine.s[S.ARITH_FLAGS] & _OVERFLOW)


def _sum(values) -> float:
    """The sum in double precision; a float file holding both infinities
    sums to NaN (math.fsum refuses them), which the store turns into
    overflow: V, the overflow minor fault and ER, as for any result the
    destination cannot hold."""
    try:
        return math.fsum(values)
    except (ValueError, OverflowError):
        return math.nan


def _average(machine, fd, fi, n, dest) -> bool:
    values = [fd[fi + k] for k in range(n)]
    if all(isinstance(v, int) for v in values):
        total = sum(values)  # exact: a word file cannot overflow the sum
        return _store_result(machine, total / n, dest)
    return _store_result(machine, _sum(values) / n, dest)


def _deviation(machine, fd, fi, n, dest) -> bool:
    if n < 2:
        return True  # the sample deviation divides by n - 1 (softplc choice: ER, dest unchanged)
    values = [float(fd[fi + k]) for k in range(n)]
    mean = _sum(values) / n
    variance = _sum([(v - mean) ** 2 for v in values]) / (n - 1)
    return _store_result(machine, math.sqrt(variance), dest)


def _sort(machine, fd, fi, n, dest) -> bool:
    # NaN (a float file can hold one) sorts last, so the order is total and both executors agree.
    fd[fi:fi + n] = type(fd)(fd.typecode, sorted(fd[fi:fi + n], key=lambda v: (v != v, v)))
    return False


def _file_references(instr: Instruction) -> list[Address]:
    length = constant(instr, len(instr.operands) - 2)
    return file_references(instr, 0, length if isinstance(length, int) else None)


_CONTROL = ("control", K.CONTROL)
_LENGTH = ("length", K.LENGTH)
_POSITION = ("position", K.POSITION)

INSTRUCTIONS = [
    BoundInstruction(
        _spec("FAL", "file arithmetic and logic", True, _CONTROL, _LENGTH, _POSITION, ("mode", K.FILE_MODE),
              ("dest", K.DEST), ("expression", K.EXPRESSION)),
        _bind_fal, lambda instr: _indexed_references(instr, (4, 5)), lambda instr: control_words(instr, 0, 1, 2)),
    BoundInstruction(
        _spec("FSC", "file search and compare", True, _CONTROL, _LENGTH, _POSITION, ("mode", K.FILE_MODE),
              ("expression", K.EXPRESSION)),
        _bind_fsc, lambda instr: _indexed_references(instr, (4,)), lambda instr: control_words(instr, 0, 1, 2)),
    BoundInstruction(
        _spec("AVE", "file average", True, ("file", K.FILE), ("dest", K.DEST), _CONTROL, _LENGTH, _POSITION),
        _statistic(_average), _file_references, lambda instr: control_words(instr, 2, 3, 4)),
    BoundInstruction(
        _spec("STD", "file standard deviation", True, ("file", K.FILE), ("dest", K.DEST), _CONTROL, _LENGTH,
              _POSITION),
        _statistic(_deviation), _file_references, lambda instr: control_words(instr, 2, 3, 4)),
    BoundInstruction(
        _spec("SRT", "file sort (ascending)", True, ("file", K.FILE), _CONTROL, _LENGTH, _POSITION),
        _statistic(_sort), _file_references, lambda instr: control_words(instr, 1, 2, 3)),
]
