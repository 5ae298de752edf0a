"""Mutants of a program file made from Structured Text (its ladder/ast.py
``Listing``: logix/st_routine.py): the ST operators and constants changed
in the ladder expressions the text became, each described as the text
shows it (``line 12: Count > 5 -> Count >= 5``, the routine's own line
numbers, from 1, as the watch view and Studio 5000's editor number them)
and placed at its expression's line and column in the export.

The expressions the translation made up itself (the ``= 0`` of an IF's
test, a FOR's step and end test, a CASE's comparisons with its selector)
are not the text's, so they are not mutated: each ladder expression is
matched to the ST expression it came from (same place, same shape; the
ST text parsed again, st/parser.py) and only matched nodes are changed.
The operators (docs/testing.md, "Structured Text: statements, arms and
mutants"; a choice, after the classic arithmetic, relational and logical
operator replacements):

- ``+`` and ``-`` swapped, ``*`` as ``/`` and ``/`` as ``*``, ``MOD`` as
  ``/``, ``**`` as ``*`` (arithmetic);
- a comparison moved to its neighbour, as a ladder CMP's are (compare);
- ``AND`` as ``OR``, ``OR`` as ``AND``, ``XOR`` as ``OR`` (logic);
- a ``NOT`` removed (the ladder's ``XOR 1`` of a BOOL) (logic);
- a number one more and one less: integers and REALs in expressions and
  the labels of a CASE; 0 and 1 swapped where a BOOL is given a number
  (constant).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

from ..errors import Pos
from ..ladder.ast import BinOp, Branch, Call, Const, Instruction, Placeholder, ProgramFile, Rung, UnaryOp
from ..ladder.specs import K
from ..st import ast as A
from ..st.parser import parse_routine

ARITHMETIC, COMPARE, LOGIC, CONSTANT = "arithmetic", "compare", "logic", "constant"

# The ladder's operator an ST operator is made into (logix/st_expr.py: "/" is "|" for REALs and
# "//" for integers), and back.
_ST_OPS = {"/": ("|", "//")}
_SPELLING = {"|": "/", "//": "/"}
# Each ladder operator's replacement: (ladder operator, mutation operator).
_REPLACE = {"+": ("-", ARITHMETIC), "-": ("+", ARITHMETIC), "*": ("//", ARITHMETIC), "|": ("*", ARITHMETIC),
            "//": ("*", ARITHMETIC), "MOD": ("//", ARITHMETIC), "**": ("*", ARITHMETIC),
            "=": ("<>", COMPARE), "<>": ("=", COMPARE), ">": (">=", COMPARE), ">=": (">", COMPARE),
            "<": ("<=", COMPARE), "<=": ("<", COMPARE),
            "AND": ("OR", LOGIC), "OR": ("AND", LOGIC), "XOR": ("OR", LOGIC)}
# Binding strength, PM007's precedence as st/grammar.lark has it (higher binds tighter).
_LEVEL = {"OR": 1, "XOR": 2, "AND": 3, "=": 4, "<>": 4, "<": 5, "<=": 5, ">": 5, ">=": 5, "+": 6, "-": 6,
          "*": 7, "/": 7, "MOD": 7}
_UNARY, _POWER, _PRIMARY = 8, 9, 10
_FIXED_KINDS = {K.LABEL, K.PROGRAM_FILE, K.PARAM_COUNT, K.TIMEBASE}


@dataclass(frozen=True)
class Found:
    operator: str
    pos: Pos
    description: str
    rung: Rung


@dataclass
class _Root:
    """An expression of the text the translation took whole: its node,
    what a changed constant of it is shown in (the assignment), and
    whether it was matched already."""

    node: object
    show: object = None  # the A.Assign whose value this is, the A.CaseArm whose label, the A.For whose bound
    used: bool = False


class _Line:
    """A line of the listing as st/parser.py reads a logix.model.Line."""

    def __init__(self, number: int, text: str, pos: Pos) -> None:
        self.number, self.text, self.pos = number, text, pos


def st_mutants(pfile: ProgramFile, instructions) -> Iterator[tuple[int, Found]]:
    """(rung index, mutant) for each mutant of a Structured Text program file."""
    listing = pfile.listing
    roots = _roots(listing)
    line_of = {pos.line: k + 1 for k, (pos, _) in enumerate(listing.lines)}
    for index, rung in enumerate(pfile.rungs):
        elements = list(rung.elements)
        for i, el in enumerate(elements):
            if isinstance(el, Branch) or not isinstance(el, Instruction):
                continue  # a branch is the first-scan clears' rung: no expression of the text
            spec = instructions.lookup(el.mnemonic.upper())
            operands = list(el.operands)
            for k, operand in enumerate(operands):
                if spec is not None and k < spec.max_operands:
                    o = spec.operand_at(k)
                    if o.kind in _FIXED_KINDS:
                        continue
                flip = el.mnemonic.upper() == "LSTB" and k == 1  # a constant given to a BOOL: 0 and 1 swapped
                for operator, new, pos, old_text, new_text in _search(operand, roots, flip):
                    changed = Instruction(el.mnemonic, operands[:k] + [new] + operands[k + 1:], el.pos)
                    where = f"line {line_of.get(pos.line, 0)}: "
                    yield index, Found(operator, pos, f"{where}{old_text} -> {new_text}",
                                       Rung(elements[:i] + [changed] + elements[i + 1:], rung.comment, rung.pos))


# -- the text's expressions ------------------------------------------------------------------------


def _roots(listing) -> dict[tuple[int, int], list[_Root]]:
    """(line, column) -> the text's whole expressions that start there."""
    lines = [_Line(k, text, pos) for k, (pos, text) in enumerate(listing.lines)]
    if not lines:
        return {}
    first = lines[0].pos
    statements = parse_routine(lines, first.source, first.line, [])
    roots: dict[tuple[int, int], list[_Root]] = {}

    def add(node, show=None, at: Pos | None = None) -> None:
        if node is not None:
            p = at or node.pos
            roots.setdefault((p.line, p.column), []).append(_Root(node, show))

    def walk(body) -> None:
        for s in body or ():
            if isinstance(s, A.Assign):
                add(s.value, s)
            elif isinstance(s, A.Call):
                for a in s.args:
                    add(a)
            elif isinstance(s, A.If):
                for cond, inner in s.branches:
                    add(cond)
                    walk(inner)
                walk(s.else_)
            elif isinstance(s, A.Case):
                add(s.selector)
                for arm in s.arms:
                    for lab in arm.labels:
                        if isinstance(lab, A.CaseRange):  # the translation places both bounds at the range
                            add(lab.low, arm, lab.pos)
                            add(lab.high, arm, lab.pos)
                        else:
                            add(lab, arm)
                    walk(arm.body)
                walk(s.else_)
            elif isinstance(s, A.For):
                for e in (s.start, s.stop, s.step):
                    add(e, s)
                walk(s.body)
            elif isinstance(s, A.While):
                add(s.cond)
                walk(s.body)
            elif isinstance(s, A.Repeat):
                walk(s.body)
                add(s.until)
    walk(statements)
    return roots


def _search(node, roots, flip: bool = False) -> Iterator[tuple[str, object, Pos, str, str]]:
    """Each mutant of a ladder operand: where a node is an expression of the
    text (a root not matched before), its changes; elsewhere, the changes
    of its parts. (operator, the new operand, place, old text, new text)."""
    pos = getattr(node, "pos", None)
    if pos is not None:
        for root in roots.get((pos.line, pos.column), ()):
            if not root.used and _same(node, root.node):
                root.used = True
                yield from _mutate(node, root.node, root, flip)
                return
    for child, rebuild in _children(node):
        for operator, new, p, old, text in _search(child, roots):
            yield operator, rebuild(new), p, old, text


def _children(node):
    """(child, a function making the node with that child replaced)."""
    if isinstance(node, BinOp):
        return [(node.left, lambda n: BinOp(node.op, n, node.right, node.pos)),
                (node.right, lambda n: BinOp(node.op, node.left, n, node.pos))]
    if isinstance(node, UnaryOp):
        return [(node.operand, lambda n: UnaryOp(node.op, n, node.pos))]
    if isinstance(node, Call):
        return [(node.arg, lambda n: Call(node.func, n, node.pos))]
    return []


def _is_not(node, st) -> bool:
    """A BOOL's NOT: the ladder's ``x XOR 1``."""
    return (isinstance(st, A.UnaryOp) and st.op == "NOT" and isinstance(node, BinOp) and node.op == "XOR"
            and isinstance(node.right, Const) and node.right.value == 1)


def _same(node, st) -> bool:
    """Whether ladder ``node`` is the translation of ST expression ``st``."""
    if isinstance(st, A.BinOp):
        return (isinstance(node, BinOp) and node.op in _ST_OPS.get(st.op, (st.op,))
                and _same(node.left, st.left) and _same(node.right, st.right))
    if isinstance(st, A.UnaryOp):
        if _is_not(node, st):
            return _same(node.left, st.operand)
        if isinstance(node, UnaryOp):
            return node.op == ("NOT" if st.op == "NOT" else "NEG") and _same(node.operand, st.operand)
        return st.op == "-" and isinstance(node, Const) and isinstance(st.operand, A.Const) \
            and node.value == -st.operand.value
    if isinstance(st, A.Const):
        return isinstance(node, Const) and not isinstance(node, Placeholder) and node.value == st.value
    if isinstance(st, A.FunctionCall):
        return isinstance(node, Call) and len(st.args) == 1 and _same(node.arg, st.args[0])
    if isinstance(st, A.TagRef):  # a tag, or TRUE/FALSE made a constant
        return not isinstance(node, (BinOp, UnaryOp, Call))
    return False


def _mutate(node, st, root: _Root, flip: bool) -> Iterator[tuple[str, object, Pos, str, str]]:
    """The changes of a matched ladder node and of its matched parts; the
    texts are of the ST node a change is in, or for a constant of the
    expression it is an operand of (its assignment, its CASE arm)."""
    if flip and isinstance(node, Const) and node.value in (0, 1):
        new_st = A.Const(1 - node.value, "INT", st.pos)
        yield CONSTANT, Const(1 - node.value, node.pos), st.pos, *_shown(st, new_st, root)
        return
    for operator, new, new_st, p, shown in _changes(node, st, None, root):
        yield operator, new, p, shown[0], shown[1]


def _changes(node, st, parent, root):
    """(operator, new ladder node, new ST node, place, (old text, new text))."""
    if isinstance(st, A.BinOp):
        op = node.op
        if op in _REPLACE:
            new_op, operator = _REPLACE[op]
            changed = A.BinOp(_SPELLING.get(new_op, new_op), st.left, st.right, st.pos)
            yield operator, BinOp(new_op, node.left, node.right, node.pos), changed, st.pos, \
                (render(st), render(changed))
        for side, st_side in (("left", st.left), ("right", st.right)):
            for operator, new, new_st, p, shown in _changes(getattr(node, side), st_side, st, root):
                left, right = (new, node.right) if side == "left" else (node.left, new)
                st_left, st_right = (new_st, st.right) if side == "left" else (st.left, new_st)
                whole = A.BinOp(st.op, st_left, st_right, st.pos)
                yield operator, BinOp(node.op, left, right, node.pos), whole, p, \
                    shown if shown is not None else (render(st), render(whole))
    elif isinstance(st, A.UnaryOp) and _is_not(node, st):
        yield LOGIC, node.left, st.operand, st.pos, (render(st), render(st.operand))
        for operator, new, new_st, p, shown in _changes(node.left, st.operand, st, root):
            whole = A.UnaryOp("NOT", new_st, st.pos)
            yield operator, BinOp("XOR", new, node.right, node.pos), whole, p, \
                shown if shown is not None else (render(st), render(whole))
    elif isinstance(st, A.UnaryOp) and isinstance(node, UnaryOp):
        if st.op == "NOT":
            yield LOGIC, node.operand, st.operand, st.pos, (render(st), render(st.operand))
        for operator, new, new_st, p, shown in _changes(node.operand, st.operand, st, root):
            whole = A.UnaryOp(st.op, new_st, st.pos)
            yield operator, UnaryOp(node.op, new, node.pos), whole, p, \
                shown if shown is not None else (render(st), render(whole))
    elif isinstance(st, A.FunctionCall) and isinstance(node, Call):
        for operator, new, new_st, p, shown in _changes(node.arg, st.args[0], st, root):
            whole = A.FunctionCall(st.name, (new_st,), st.pos)
            yield operator, Call(node.func, new, node.pos), whole, p, \
                shown if shown is not None else (render(st), render(whole))
    elif isinstance(node, Const) and type(node.value) in (int, float) and not isinstance(node, Placeholder) and isinstance(st, (A.Const, A.UnaryOp)):
        for delta in (1, -1):
            value = node.value + (delta if isinstance(node.value, int) else float(delta))
            new_st = A.Const(value, "REAL" if isinstance(value, float) else "INT", st.pos)
            shown = None if parent is not None else _shown(st, new_st, root)
            yield CONSTANT, Const(value, node.pos, hex=node.hex), new_st, st.pos, shown


def _shown(st, new_st, root: _Root) -> tuple[str, str]:
    """A constant that is a whole expression, shown in what holds it."""
    if isinstance(root.show, A.Assign):
        target, op = root.show.target.text, ":=" if root.show.retentive else "[:=]"
        return f"{target} {op} {render(st)}", f"{target} {op} {render(new_st)}"
    if isinstance(root.show, A.For):
        return _for_head(root.show), _for_head(root.show, st, new_st)
    if isinstance(root.show, A.CaseArm):
        labels = root.show.labels
        return _labels(labels) + ":", _labels(labels, st, new_st) + ":"
    return render(st), render(new_st)


def _for_head(s: A.For, old=None, new=None) -> str:
    def one(e):
        return render(new) if e is old else render(e)
    by = f" BY {one(s.step)}" if s.step is not None else ""
    return f"FOR {s.var.text} := {one(s.start)} TO {one(s.stop)}{by}"


def _labels(labels, old=None, new=None) -> str:
    def one(c):
        return render(new) if c is old else render(c)
    return ", ".join(f"{one(x.low)}..{one(x.high)}" if isinstance(x, A.CaseRange) else one(x) for x in labels)


# -- ST text -----------------------------------------------------------------------------------------


def render(e, need: int = 0) -> str:
    """ST text of an expression, parenthesised only where PM007's precedence
    needs it (``need``: the binding strength the place it stands in needs)."""
    if isinstance(e, A.Const):
        if e.kind == "STRING":
            return f"'{e.value}'"
        return repr(e.value) if isinstance(e.value, float) else str(e.value)
    if isinstance(e, A.TagRef):
        return e.text
    if isinstance(e, A.FunctionCall):
        return f"{e.name}({', '.join(render(a) for a in e.args)})"
    if isinstance(e, A.UnaryOp):
        text = f"NOT {render(e.operand, _UNARY)}" if e.op == "NOT" else f"-{render(e.operand, _UNARY)}"
        level = _UNARY
    elif isinstance(e, A.BinOp):
        if e.op == "**":
            level = _POWER
            text = f"{render(e.left, _POWER)} ** {render(e.right, _PRIMARY)}"
        else:
            level = _LEVEL[e.op]
            text = f"{render(e.left, level)} {e.op} {render(e.right, level + 1)}"
    else:
        return str(e)
    return f"({text})" if level < need else text
