"""Structured Text expressions as the ladder's expression nodes (the CPT and
CMP trees both executors evaluate), each with its Logix type.

Rules (1756-PM007, Logix 5000 Controllers Structured Text, "Expressions"
and "Operators"; the arithmetic is the ladder side's, docs/logix.md):

- Precedence is the parser's (st/grammar.lark): ``**``, unary ``-`` and
  ``NOT``, ``* / MOD``, ``+ -``, comparisons, ``AND``/``&``, ``XOR``,
  ``OR``; equal operators left to right.
- ``AND``, ``OR``, ``XOR`` and ``NOT`` are logical on BOOL operands and bit
  by bit on integers ("Bitwise operators" and "Logical operators": one
  spelling, chosen by the operands' type). A BOOL is 0 or 1 in the ladder,
  so its AND, OR and XOR are the bitwise ones; its NOT is ``XOR 1``.
- A comparison is a BOOL. An integer constant is a DINT (a LINT when it
  does not fit); ``1.5`` a REAL.
- Integers and REALs mix as in CPT: a REAL operand makes the result REAL;
  ``/`` of integers truncates and ``MOD`` takes the dividend's sign, as
  Logix's DIV and MOD do.
- The functions: ABS, SQRT, LN, LOG, SIN, COS, TAN, ASIN, ACOS, ATAN, DEG,
  RAD, TRUNC, and the conversions FRD and TOD ("Numeric functions"), each
  the ladder's function of the same rule.
- ``TRUE`` and ``FALSE`` are the BOOL constants 1 and 0 (a softplc choice:
  Studio 5000 takes them in ST; no tag may be named so).
- A tag whose index is an expression (``Tanks[i+1].Level``) is read
  through the hidden index an LIDX computes and checks before the statement
  (logix/rungs.py), so a subscript out of range is major fault type 4,
  code 20, as in ladder.
"""

from __future__ import annotations

from ..errors import Pos
from ..ladder.ast import AddressRef, BinOp, Call, Const, UnaryOp
from ..st import ast as A
from .expr import ExprError
from .rungs import _resolve
from .tags import NotRun, PathError, Resolved

INTEGERS = ("SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT")
NUMBERS = INTEGERS + ("REAL", "LREAL")
# ST's function names -> the ladder's (ladder/expr.py FUNCTIONS)
FUNCTIONS = {"ABS": "ABS", "SQRT": "SQR", "LN": "LN", "LOG": "LOG", "SIN": "SIN", "COS": "COS", "TAN": "TAN",
             "ASIN": "ASN", "ACOS": "ACS", "ATAN": "ATN", "DEG": "DEG", "RAD": "RAD", "TRUNC": "TRN",
             "FRD": "FRD", "TOD": "TOD"}
_BINARY = {"**": "**", "*": "*", "/": "|", "MOD": "MOD", "+": "+", "-": "-", "<": "<", "<=": "<=", ">": ">",
           ">=": ">=", "=": "=", "<>": "<>", "AND": "AND", "XOR": "XOR", "OR": "OR"}
_COMPARES = ("<", "<=", ">", ">=", "=", "<>")
DINT_RANGE = (-(2 ** 31), 2 ** 31 - 1)


class StProblem(Exception):
    """Something in a statement that stops it: an error of the export, or
    (``not_run``) what softplc_lite does not run yet."""

    def __init__(self, pos: Pos, message: str, not_run: bool = False) -> None:
        super().__init__(message)
        self.pos = pos
        self.not_run = not_run


def at(pos: Pos, offset: int) -> Pos:
    return Pos(pos.source, pos.line, pos.column + offset)


def is_bool(r: Resolved) -> bool:
    return r.address is not None and (r.address.bit is not None or r.type.name == "BOOL")


class Expressions:
    """Translates the expressions of one routine (``ctx``: logix/rungs.py
    RoutineContext; the LIDXs an index needs go into ``ctx.before``)."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx

    def tag(self, ref: A.TagRef) -> Resolved:
        try:
            return _resolve(tag_text(ref), ref.pos, self.ctx)
        except NotRun as e:
            raise StProblem(at(ref.pos, e.offset), f"{ref.text}: {e}", not_run=True) from None
        except (PathError, ExprError) as e:
            raise StProblem(at(ref.pos, e.offset), f"{ref.text}: {e}") from None

    def value(self, e) -> tuple[object, str]:
        """(ladder node, Logix type name) of expression ``e``."""
        if isinstance(e, A.Const):
            if e.kind == "STRING":
                raise StProblem(e.pos, "a string constant in an expression: softplc_lite runs string constants "
                                       "only as instruction operands", not_run=True)
            if e.kind == "REAL":
                return Const(float(e.value), e.pos), "REAL"
            low, high = DINT_RANGE
            return Const(e.value, e.pos), "DINT" if low <= e.value <= high else "LINT"
        if isinstance(e, A.TagRef):
            if not e.selectors and e.base.upper() in ("TRUE", "FALSE"):
                return Const(1 if e.base.upper() == "TRUE" else 0, e.pos), "BOOL"
            r = self.tag(e)
            if r.address is None or r.type.kind == "string":
                kind = f"{r.type.name} array" if r.dims else r.type.name
                if r.type.kind == "string" and not r.dims:
                    raise StProblem(e.pos, f"{e.text} is a {kind}: softplc_lite runs strings in ST through "
                                           f"the string instructions, not in expressions", not_run=True)
                raise StProblem(e.pos, f"{e.text} is a {kind}: expected a single value (a number or a BOOL)")
            return AddressRef(r.address, e.pos), "BOOL" if is_bool(r) else r.type.name
        if isinstance(e, A.UnaryOp):
            node, t = self.value(e.operand)
            if e.op == "NOT":
                if t == "BOOL":
                    return BinOp("XOR", node, Const(1, e.pos), e.pos), "BOOL"
                self._number(t, e.pos, "NOT")
                return UnaryOp("NOT", node, e.pos), t
            self._number(t, e.pos, "-", bool_ok=True)
            if isinstance(node, Const):
                return Const(-node.value, e.pos), t
            return UnaryOp("NEG", node, e.pos), t
        if isinstance(e, A.BinOp):
            left, lt = self.value(e.left)
            right, rt = self.value(e.right)
            op = _BINARY[e.op]
            if op in _COMPARES:
                return BinOp(op, left, right, e.pos), "BOOL"
            if op in ("AND", "OR", "XOR"):
                if lt == rt == "BOOL":
                    return BinOp(op, left, right, e.pos), "BOOL"
                for t in (lt, rt):
                    if t in ("REAL", "LREAL"):
                        raise StProblem(e.pos, f"{e.op} of a REAL: expected BOOL or integer operands (1756-PM007, "
                                               f"\"Bitwise operators\")")
                return BinOp(op, left, right, e.pos), _wider(lt, rt)
            for t in (lt, rt):
                self._number(t, e.pos, e.op, bool_ok=True)
            result = "REAL" if "REAL" in (lt, rt) or op == "**" else _wider(lt, rt)
            if op == "|" and result != "REAL":  # integers: the quotient truncated, as Logix's DIV does
                op = "//"
            return BinOp(op, left, right, e.pos), result
        if isinstance(e, A.FunctionCall):
            name = e.name.upper()
            fn = FUNCTIONS.get(name)
            if fn is None:
                raise StProblem(e.pos, f"{e.name}: not a function of Structured Text (expected one of "
                                       f"{', '.join(sorted(FUNCTIONS))}); an instruction is a statement of its own")
            if len(e.args) != 1:
                raise StProblem(e.pos, f"{e.name} takes one argument, found {len(e.args)}")
            node, t = self.value(e.args[0])
            self._number(t, e.pos, e.name, bool_ok=True)
            kind = t if name in ("ABS", "TRUNC") else "DINT" if name in ("FRD", "TOD") else "REAL"
            return Call(fn, node, e.pos), kind
        raise StProblem(getattr(e, "pos", self.ctx_pos()), "expected an expression")

    def ctx_pos(self) -> Pos:
        return Pos(self.ctx.source, 0, 0)

    def condition(self, e) -> object:
        """A condition (IF, WHILE, UNTIL) as a ladder node that is not zero
        when it holds. Logix wants a BOOL there; a number is taken as true
        when it is not 0 (a softplc choice, the meaning an assignment of it
        to a BOOL has)."""
        node, _ = self.value(e)
        return node

    @staticmethod
    def _number(t: str, pos: Pos, op: str, bool_ok: bool = False) -> None:
        if t in NUMBERS or (bool_ok and t == "BOOL"):
            return
        raise StProblem(pos, f"{op} of a {t}: expected a number")


def _wider(a: str, b: str) -> str:
    if "REAL" in (a, b):
        return "REAL"
    return "LINT" if "LINT" in (a, b) else "DINT"


def render(e) -> str:
    """Logix operand text of an ST expression (an instruction's operand,
    read again by the ladder side's operand reader, logix/expr.py)."""
    if e is None:
        return ""
    if isinstance(e, A.Const):
        if e.kind == "STRING":
            return "'" + str(e.value) + "'"
        return repr(e.value) if isinstance(e.value, float) else str(e.value)
    if isinstance(e, A.TagRef):
        return tag_text(e)
    if isinstance(e, A.UnaryOp):
        return f"{'NOT ' if e.op == 'NOT' else '-'}({render(e.operand)})"
    if isinstance(e, A.BinOp):
        return f"({render(e.left)} {e.op} {render(e.right)})"
    if isinstance(e, A.FunctionCall):
        name = FUNCTIONS.get(e.name.upper(), e.name)
        return f"{name}({', '.join(render(a) for a in e.args)})"
    raise TypeError(e)


def tag_text(ref: A.TagRef) -> str:
    """A tag's path as the ladder side reads it (tags.py), its index
    expressions written out again (the parser's ``text`` drops spaces)."""
    out = [ref.base]
    for sel in ref.selectors:
        if isinstance(sel, A.Member):
            out.append("." + sel.name)
        elif isinstance(sel, A.Bit):
            out.append(f".{sel.number}")
        elif isinstance(sel, A.BitIndex):
            out.append(f".[{render(sel.index)}]")
        else:
            out.append("[" + ",".join(render(i) for i in sel.indices) + "]")
    return "".join(out)
