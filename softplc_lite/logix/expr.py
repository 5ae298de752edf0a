"""Logix operand text (a tag path, a number, an expression of CPT or CMP)
parsed into the ladder's expression nodes (ladder/ast.py), so both executors
evaluate it as they evaluate PLC-5 expressions.

Numbers take Logix's forms (1756-RM003, "Specify constants"; 1756-PM007,
"Constants"): ``123``, ``-5``, ``1.5``, ``2.5e3``, ``16#FF``, ``8#17``,
``2#1010_0101``, digits grouped by ``_``. Operator precedence follows the
CPT/CMP table of 1756-RM003 ("Valid operators", "Order of operation"): a
function, then ``**``, then unary ``-`` and ``NOT``, then ``* / MOD``, then
``+ -``, then ``AND``, ``XOR``, ``OR``; the comparisons of CMP bind below
``+ -`` and above ``AND``, as in Structured Text (1756-PM007, a softplc
choice where RM003's table is silent).
"""

from __future__ import annotations

import re
from typing import Callable

from ..ladder.ast import AddressRef, BinOp, Call, Const, Pos, UnaryOp
from ..ladder.expr import FUNCTIONS

_TOKEN = re.compile(r"""
    \s*(?:
      (?P<radix>(?:16\#[0-9A-Fa-f_]+|8\#[0-7_]+|2\#[01_]+))
    | (?P<float>(?:[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?|[0-9][0-9_]*[eE][-+]?[0-9]+|\.[0-9]+))
    | (?P<int>[0-9][0-9_]*)
    | (?P<path>[A-Za-z_][A-Za-z0-9_]*(?::[A-Za-z0-9_]+)*(?:\s*(?:\.\s*(?:[A-Za-z_][A-Za-z0-9_]*|[0-9]+)|\[[^\]]*\]))*)
    | (?P<op>\*\*|<=|>=|<>|[-+*/()<>=&])
    )""", re.VERBOSE)

_WORD_OPS = {"MOD": "MOD", "AND": "AND", "OR": "OR", "XOR": "XOR", "NOT": "NOT"}
_BINARY = {  # operator -> (binding power, the ladder node's op)
    "OR": (1, "OR"), "XOR": (2, "XOR"), "AND": (3, "AND"), "&": (3, "AND"),
    "=": (4, "="), "<>": (4, "<>"), "<": (4, "<"), "<=": (4, "<="), ">": (4, ">"), ">=": (4, ">="),
    "+": (5, "+"), "-": (5, "-"),
    "*": (6, "*"), "/": (6, "|"), "MOD": (6, "MOD"),
    "**": (8, "**"),
}
UNARY_POWER = 7
LOGIX_FUNCTIONS = {name for name in FUNCTIONS if name != "NEG"}


class ExprError(Exception):
    def __init__(self, message: str, offset: int) -> None:
        super().__init__(message)
        self.offset = offset


def number(text: str) -> int | float | None:
    """A Logix numeric constant's value, or None if ``text`` is not one."""
    t = text.strip().replace("_", "")
    sign = -1 if t.startswith("-") else 1
    t = t.lstrip("+-")
    try:
        if "#" in t:
            base, digits = t.split("#", 1)
            return sign * int(digits, int(base))
        if re.fullmatch(r"[0-9]+", t):
            return sign * int(t)
        if re.fullmatch(r"[0-9]*\.?[0-9]*([eE][-+]?[0-9]+)?", t) and any(c.isdigit() for c in t):
            return sign * float(t)
    except ValueError:
        return None
    return None


def _tokens(text: str) -> list[tuple[str, str, int]]:
    out = []
    i = 0
    while i < len(text):
        if text[i:].strip() == "":
            break
        m = _TOKEN.match(text, i)
        if not m or m.end() == i:
            j = len(text) - len(text[i:].lstrip())
            raise ExprError(f"unexpected {text[j]!r}: expected a number, a tag or an operator", j)
        kind = m.lastgroup
        value = m.group(kind)
        start = m.start(kind)
        if kind == "path" and value.upper() in _WORD_OPS and not re.search(r"[.\[:]", value):
            kind, value = "op", value.upper()
        elif kind == "path" and value.upper() in LOGIX_FUNCTIONS and text[m.end():].lstrip().startswith("("):
            kind, value = "func", value.upper()
        out.append((kind, value, start))
        i = m.end()
    return out


def parse_expression(text: str, pos: Pos, resolve: Callable[[str, int], AddressRef]) -> object:
    """The expression ``text`` as ladder nodes. ``resolve(path, offset)``
    gives the AddressRef of a tag path (raising ExprError for a bad one);
    ``pos`` is where ``text`` starts (nodes carry their own columns)."""
    tokens = _tokens(text)
    at = [0]

    def where(offset: int) -> Pos:
        return Pos(pos.source, pos.line, pos.column + offset)

    def peek():
        return tokens[at[0]] if at[0] < len(tokens) else None

    def take():
        t = peek()
        at[0] += 1
        return t

    def primary():
        t = take()
        if t is None:
            raise ExprError("expected a value", len(text))
        kind, value, start = t
        if kind in ("int", "radix", "float"):
            return Const(number(value), where(start))
        if kind == "path":
            return resolve(value, start)
        if kind == "func":
            if (take() or ("", "", 0))[1] != "(":
                raise ExprError(f"expected ( after {value}", start)
            arg = expression(0)
            if (take() or ("", "", len(text)))[1] != ")":
                raise ExprError(f"expected ) to close {value}(", start)
            return Call(value, arg, where(start))
        if value == "(":
            inner = expression(0)
            if (take() or ("", "", len(text)))[1] != ")":
                raise ExprError("expected )", start)
            return inner
        if value == "-":
            operand = expression(UNARY_POWER)
            if isinstance(operand, Const):
                return Const(-operand.value, where(start))
            return UnaryOp("NEG", operand, where(start))
        if value == "NOT":
            return UnaryOp("NOT", expression(UNARY_POWER), where(start))
        raise ExprError(f"expected a value, found {value!r}", start)

    def expression(min_power: int):
        left = primary()
        while True:
            t = peek()
            if t is None or t[0] != "op" or t[1] not in _BINARY:
                return left
            power, op = _BINARY[t[1]]
            if power < min_power:
                return left
            take()
            right = expression(power + 1)  # equal order: left to right (1756-RM003)
            left = BinOp(op, left, right, where(t[2]))

    node = expression(0)
    rest = peek()
    if rest is not None:
        raise ExprError(f"unexpected {rest[1]!r} after the expression", rest[2])
    return node
