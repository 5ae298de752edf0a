"""Power flow: which elements of a rung are energized on the data table's
current values, as an online ladder editor highlights them.

Read only: nothing is written (no one-shot storage, no status flags, no
minor faults), so the view can ask as often as it redraws. The rules:

* the rung starts true; a series is an AND (an element gets the power the
  element before it passes on), a branch an OR of its legs (each leg gets
  the branch's input; the branch passes on power when any leg does);
* condition instructions pass power when it reaches them and their test
  holds on the current values, exactly as the interpreter tests them:
  XIC XIO, EQU NEQ LES LEQ GRT GEQ LIM MEQ, CMP (a division by zero gives
  the infinity an overflow stores, without the minor fault), ASR; AFI never;
* the one-shots ONS OSR OSF pass their input through: their pulse lasts one
  scan, which a view redrawn a few times a second would all but never show
  (the values they drive, a counter's ACC, show that they fired);
* every other instruction (coils, timers, counters, math, moves, program
  control, the instructions of plug-in modules) passes its input through:
  an output "is energized" when power reaches it;
* an instruction with an address that does not resolve (an indirect or
  indexed address pointing outside the table) is a fault: it passes no
  power and its ``fault`` says why. Nothing raises.

What the ladder does not show is not modelled: an MCR zone, a JMP that
skips the rung, or a subroutine that is not called leave the picture as
the rung's own logic gives it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..datatable import DataTable, DataTableError
from ..ladder.ast import (
    AddressRef,
    Branch,
    Const,
    Element,
    Instruction,
    Rung,
    address_refs,
)
from ..ladder.expr import evaluate
from ..ladder.semantics import Machine, lim


@dataclass(frozen=True)
class ElementPower:
    """One element's state: power at its input, power passed on, and (for
    conditions) whether its own test holds whatever reaches it; outputs and
    boxes are "true" when energized. A branch lists each leg's power out."""

    power_in: bool
    power_out: bool
    is_true: bool
    fault: str | None = None
    legs: tuple[bool, ...] = ()


class Power:
    """The power flow of one rung: ``out`` is the rung-out condition;
    ``power[element]`` the state of an element (an Instruction or Branch of
    that rung, looked up by identity)."""

    __slots__ = ("_states", "out", "rung")

    def __init__(self, rung: Rung, out: bool, states: dict[int, ElementPower]) -> None:
        self.rung = rung  # keeps the elements (and so their ids) alive
        self.out = out
        self._states = states

    def __getitem__(self, element: Element) -> ElementPower:
        return self._states[id(element)]

    def get(self, element: Element) -> ElementPower | None:
        return self._states.get(id(element))

    def faults(self) -> list[str]:
        return [s.fault for s in self._states.values() if s.fault]


def rung_power(rung: Rung, table: DataTable) -> Power:
    """Evaluate ``rung`` on ``table``'s current values, without side effects."""
    states: dict[int, ElementPower] = {}
    out = _series(rung.elements, True, table, states)
    return Power(rung, out, states)


def _series(elements: list[Element], c: bool, table: DataTable, states: dict[int, ElementPower]) -> bool:
    """The power out of a series entered with ``c``; every element's state
    into ``states``. A stack, not recursion: nesting has no depth limit here."""
    # per open branch: (branch, its power in, its legs' power out so far, the series it is in, where it goes on)
    open_branches: list[tuple[Branch, bool, list[bool], list[Element], int]] = []
    series, i = elements, 0
    while True:
        if i < len(series):
            el = series[i]
            i += 1
            if not isinstance(el, Branch):
                state = states[id(el)] = _instruction(el, c, table)
                c = state.power_out
            elif el.legs:
                open_branches.append((el, c, [], series, i))
                series, i = el.legs[0], 0
            else:
                states[id(el)] = ElementPower(c, False, False, legs=())
                c = False
            continue
        if not open_branches:
            return c
        branch, c_in, outs, parent, after = open_branches[-1]
        outs.append(c)
        if len(outs) < len(branch.legs):
            series, i, c = branch.legs[len(outs)], 0, c_in
            continue
        open_branches.pop()
        legs = tuple(outs)
        out = any(legs)
        states[id(branch)] = ElementPower(c_in, out, out, legs=legs)
        series, i, c = parent, after, out


# What a failed read raises: an address outside the table, a value of the
# wrong kind (a program loaded against another table), bad arithmetic.
READ_FAILURES = (DataTableError, LookupError, TypeError, ValueError, ArithmeticError)


def _instruction(ins: Instruction, c: bool, table: DataTable) -> ElementPower:
    try:
        test = _test(ins, table)
    except READ_FAILURES as e:
        return ElementPower(c, False, False, fault=str(e) or type(e).__name__)
    if test is None:
        return ElementPower(c, c, c)
    return ElementPower(c, c and test, test)


_COMPARE = {
    "EQU": lambda a, b: a == b, "NEQ": lambda a, b: a != b, "LES": lambda a, b: a < b,
    "LEQ": lambda a, b: a <= b, "GRT": lambda a, b: a > b, "GEQ": lambda a, b: a >= b,
}


def _test(ins: Instruction, table: DataTable) -> bool | None:
    """A condition's test on current values; None for an instruction that
    passes its input through (after checking its addresses resolve)."""
    m, ops = ins.mnemonic, ins.operands
    if m == "XIC":
        return bool(table.read(ops[0].address))
    if m == "XIO":
        return not table.read(ops[0].address)
    if m in _COMPARE:
        return _COMPARE[m](read_operand(table, ops[0]), read_operand(table, ops[1]))
    if m == "LIM":
        return lim(*(read_operand(table, o) for o in ops))
    if m == "MEQ":
        s, mask, compare = (read_operand(table, o) for o in ops)
        return (s & mask) == (compare & mask)
    if m == "CMP":
        return bool(evaluate(ops[0], lambda ref: table.read(ref.address), _VIEW_MATH))
    if m == "ASR":
        return table.read(ops[0].address) == table.read(ops[1].address)
    if m == "AFI":
        return False
    for op in ops:
        for ref in address_refs(op):
            table.resolve(ref.address)
    return None


def read_operand(table: DataTable, operand) -> int | float:
    """A constant's value, or what an address holds now (typed as
    ``DataTable.read`` gives it)."""
    if isinstance(operand, Const):
        return operand.value
    if isinstance(operand, AddressRef):
        return table.read(operand.address)
    raise TypeError(f"not a value operand: {operand!r}")


class _ViewMath:
    """CMP's arithmetic without the machine's side effects: a division by
    zero gives the overflow result and sets no status bit."""

    divide = Machine.divide
    modulo = Machine.modulo
    power = Machine.power

    @staticmethod
    def div_zero(a):
        return math.copysign(math.inf, a) if a != 0 else math.inf


_VIEW_MATH = _ViewMath()
