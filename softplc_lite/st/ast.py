"""The typed syntax tree of a Logix Structured Text routine.

Every node carries its place in the export (``pos``: file, line, column);
positions take no part in equality, as in the ladder's tree, so two parses
of one text compare equal wherever the text sits. Nodes are frozen
dataclasses: an ST routine has few nodes beside a ladder program's, so the
ladder's compact slot classes would buy nothing here. Sequences are tuples.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from ..errors import NOWHERE, Pos  # noqa: F401 (names of this module's too)




def _pos() -> Pos:
    return field(default=NOWHERE, compare=False, repr=False)


# -- expressions ---------------------------------------------------------------


@dataclass(frozen=True)
class Const:
    """A number or a string as written: ``kind`` is "INT" (16#FF, 2#1010 and
    decimal alike), "REAL" or "STRING" (``value`` without quotes, $ escapes
    kept as written: their meaning is the next stage's)."""

    value: int | float | str
    kind: str
    pos: Pos = _pos()


@dataclass(frozen=True)
class Member:
    name: str


@dataclass(frozen=True)
class Bit:
    """``.5``: a bit of an integer."""

    number: int


@dataclass(frozen=True)
class BitIndex:
    """``.[expr]``: the bit an expression picks."""

    index: "Expression"


@dataclass(frozen=True)
class Index:
    """``[i]`` or ``[i, j]``: an element of an array."""

    indices: tuple["Expression", ...]


Selector = Union[Member, Bit, BitIndex, Index]


@dataclass(frozen=True)
class TagRef:
    """A tag: ``text`` as written (spaces and comments left out), ``base``
    its name (a module tag's whole ``Local:1:I``) and the selectors after it."""

    text: str
    base: str
    selectors: tuple[Selector, ...] = ()
    pos: Pos = _pos()


@dataclass(frozen=True)
class BinOp:
    """``op`` spelt in capitals: "**", "*", "/", "MOD", "+", "-", "<", "<=",
    ">", ">=", "=", "<>", "AND" (for & too: PM007 gives them one meaning),
    "XOR", "OR"."""

    op: str
    left: "Expression"
    right: "Expression"
    pos: Pos = _pos()


@dataclass(frozen=True)
class UnaryOp:
    op: str  # "-" or "NOT"
    operand: "Expression"
    pos: Pos = _pos()


@dataclass(frozen=True)
class FunctionCall:
    """A function in an expression: ``ABS(x)``, ``SIN(a)``."""

    name: str
    args: tuple["Expression", ...]
    pos: Pos = _pos()


Expression = Union[Const, TagRef, BinOp, UnaryOp, FunctionCall]


# -- statements ----------------------------------------------------------------


@dataclass(frozen=True)
class Assign:
    """``target := value`` (retentive) or ``target [:=] value``."""

    target: TagRef
    value: Expression
    retentive: bool = True
    pos: Pos = _pos()


@dataclass(frozen=True)
class Call:
    """An instruction as a statement: ``TONR(MyTimer);``, ``JSR(Sub, 0);``,
    an Add-On Instruction ``MyAoi(Inst, a, b);``. An operand left empty
    (``GSV(WallClockTime, , LocalDateTime, d[0]);``) is None."""

    name: str
    args: tuple[Expression | None, ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class If:
    """IF/ELSIF as ``branches`` of (condition, body); ``else_`` None when
    there is no ELSE."""

    branches: tuple[tuple[Expression, tuple["Statement", ...]], ...]
    else_: tuple["Statement", ...] | None = None
    pos: Pos = _pos()


@dataclass(frozen=True)
class CaseRange:
    """``low..high`` in a CASE arm."""

    low: Const
    high: Const
    pos: Pos = _pos()


@dataclass(frozen=True)
class CaseArm:
    labels: tuple[Const | CaseRange, ...]
    body: tuple["Statement", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Case:
    selector: Expression
    arms: tuple[CaseArm, ...]
    else_: tuple["Statement", ...] | None = None
    pos: Pos = _pos()


@dataclass(frozen=True)
class For:
    var: TagRef
    start: Expression
    stop: Expression
    step: Expression | None
    body: tuple["Statement", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class While:
    cond: Expression
    body: tuple["Statement", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Repeat:
    body: tuple["Statement", ...]
    until: Expression
    pos: Pos = _pos()


@dataclass(frozen=True)
class Exit:
    pos: Pos = _pos()


@dataclass(frozen=True)
class Return:
    pos: Pos = _pos()


Statement = Union[Assign, Call, If, Case, For, While, Repeat, Exit, Return]
