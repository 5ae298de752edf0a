"""The documented limits of the ladder language (docs/language.md, "Limits").

Every stage after the parser (validate, compile, the reference interpreter,
fmt, the watch view) walks rungs and expressions recursively; the parser
refuses anything deeper than these limits, with the file, line and column,
so no later stage can reach Python's recursion limit or CPython's own limits
on generated code (200 nested parentheses). The figures are softplc's
choices, far above what real ladder uses; tests/test_hardening.py runs
every stage at exactly these depths.

Sizes are bounded too, because one rung is compiled into one Python
function (and a quoted string is kept whole): MAX_RUNG_ELEMENTS and
MAX_LITERAL_CHARS are checked while the text is parsed, and the parse of a
rung stops at its limit, so refusing a huge rung costs about what its
first 10,000 elements do (tests/test_language_limits_size.py).
"""

from __future__ import annotations

import re

from .ast import BinOp, Branch, Call, Instruction, UnaryOp

MAX_BRANCH_DEPTH = 32  # branches inside branches
MAX_EXPRESSION_DEPTH = 64  # operators and functions applied to each other's results
MAX_CONSTANT = 3.4028234663852886e38  # the largest F element; no element holds a larger value
MAX_NUMBER_DIGITS = 40  # a literal with more digits is out of range before it is converted
# The elements of one rung (or DATA line): each instruction, operand, branch
# start, leg or end, and operator or function of an expression counts one.
# A rung is one compiled function, whose cost grows faster than its size;
# 10,000 is 5,000 one-operand instructions, far past a readable rung.
MAX_RUNG_ELEMENTS = 10_000
# The characters between the quotes of a quoted string (a DATA string, a
# CPT/CMP expression in mnemonic form): an ST element holds 82, and the
# longest expression the depth limit lets through is well under 4,096.
MAX_LITERAL_CHARS = 4096
# Parentheses and brackets open at once, and signs (or NOTs) in a row: what
# the parser holds on its stack before any rule is reduced, so a rung of
# millions of "(" or "-" would cost gigabytes before MAX_RUNG_ELEMENTS or
# the depth limits could look at it. Checked on the text first
# (nesting_problem). Redundant parentheses add no expression level, hence
# the generous figure; a run of signs always does.
MAX_NESTING = 5000
MAX_SIGNS = 100

_EXPRESSION_NODES = (BinOp, UnaryOp, Call)


def expression_depth(node) -> int:
    """Operator levels in an expression tree (an address or constant is 0);
    iterative, so any depth is measured safely."""
    deepest = 0
    stack = [(node, 0)]
    while stack:
        node, depth = stack.pop()
        if not isinstance(node, _EXPRESSION_NODES):
            continue
        depth += 1
        deepest = max(deepest, depth)
        if isinstance(node, BinOp):
            stack.append((node.left, depth))
            stack.append((node.right, depth))
        elif isinstance(node, UnaryOp):
            stack.append((node.operand, depth))
        else:
            stack.append((node.arg, depth))
    return deepest


_STRING = r'"[^"\\\n]*+(?:\\.[^"\\\n]*+)*+"'
_SKIPPED = rf"{_STRING}|//[^\n]*+"  # strings and comments: no nesting counts inside them
_SIGN_RUN_TEXT = rf"(?:[-+][ \t]*+){{{MAX_SIGNS},}}+"
_NOT_RUN_TEXT = rf"(?i:(?:\bNOT\b[ \t]*+){{{MAX_SIGNS},}}+)"
_NESTING_SCAN = re.compile(rf"{_SKIPPED}|[(\[\])]|{_SIGN_RUN_TEXT}|{_NOT_RUN_TEXT}")
_SIGN_RUN = re.compile(_SIGN_RUN_TEXT)
_NOT_RUN = re.compile(_NOT_RUN_TEXT)


def _maybe_sign_run(text: str) -> bool:
    """Whether the text may hold MAX_SIGNS signs or NOTs in a row (strings
    and comments included); the counts spare most texts the regex."""
    if text.count("-") + text.count("+") >= MAX_SIGNS and _SIGN_RUN.search(text):
        return True
    return text.upper().count("NOT") >= MAX_SIGNS and _NOT_RUN.search(text) is not None


_STRINGS_AND_COMMENTS = re.compile(_SKIPPED)
_NOT_BRACKETS = re.compile(r"[^()\[\]]++")
_ONE_KIND = str.maketrans("[]", "()")
# Passes of the bracket filter below before it leaves the text to the exact
# scan: real ladder nests a few levels, a hostile text thousands.
_FILTER_PASSES = 64


def nesting_within(text: str, limit: int = MAX_NESTING) -> bool:
    """True when the text certainly nests no deeper than ``limit``; False
    when it might (the exact scan then decides). Runs at C speed, so a
    10 MB rung of ordinary brackets is cleared in a fraction of the time
    the exact scan takes: strings, comments and everything but brackets
    are dropped, then each pass removes the innermost "()" pairs. After k
    passes the pairs left enclose any point at most k deep beyond what is
    left; once no pair is left, what is left is unmatched ")" then
    unmatched "(", and every "(" left can add one level."""
    if '"' in text or "//" in text:
        text = _STRINGS_AND_COMMENTS.sub("", text)
    brackets = _NOT_BRACKETS.sub("", text).translate(_ONE_KIND)
    too_deep_run = "(" * (limit + 1)
    for passes in range(_FILTER_PASSES):
        if too_deep_run in brackets:
            return False
        fewer = brackets.replace("()", "")
        if len(fewer) == len(brackets):
            return passes + fewer.count("(") <= limit
        brackets = fewer
    return False


def nesting_problem(text: str) -> tuple[int, str] | None:
    """(offset, what is wrong) for the first place a text nests
    parentheses and brackets deeper than MAX_NESTING or has MAX_SIGNS signs
    or NOTs in a row (outside strings and comments), else None. A text with
    fewer brackets than the limit and no such run is not scanned, nor one
    the bracket filter clears."""
    if not _maybe_sign_run(text) and (
            text.count("(") + text.count("[") <= MAX_NESTING or nesting_within(text)):
        return None
    depth = 0
    for m in _NESTING_SCAN.finditer(text):
        first = m.group()[0]
        if first in "([":
            depth += 1
            if depth > MAX_NESTING:
                return m.start(), f"parentheses and brackets nested more than {MAX_NESTING:,} deep"
        elif first in ")]":
            depth = max(0, depth - 1)
        elif first not in "\"/":
            run = m.group()
            signs = run.count("-") + run.count("+") + run.upper().count("NOT")
            return m.start(), (f"{signs:,} signs or NOTs in a row: an expression nested more than "
                               f"{MAX_EXPRESSION_DEPTH} levels deep")
    return None


def rung_size_message() -> str:
    return (f"more than {MAX_RUNG_ELEMENTS:,} elements (instructions, operands, branch parts, operators) "
            f"in one rung or DATA line; split it up")


def literal_problem(text: str) -> str | None:
    """What is wrong with a quoted string token (quotes included), or None."""
    length = len(text) - 2
    if length <= MAX_LITERAL_CHARS:
        return None
    return f"quoted string {short_quote(text[1:-1])} is longer than {MAX_LITERAL_CHARS:,} characters"


def short_quote(text: str, keep: int = 20) -> str:
    """``text`` quoted for a message: whole when short, else its first
    ``keep`` characters, '...' and its length."""
    if len(text) <= keep + 10:
        return f'"{text}"'
    return f'"{text[:keep]}..." ({len(text):,} characters)'


def expression_size(node) -> int:
    """The elements of an expression tree (operators, functions and
    operands: each node one); iterative."""
    count = 0
    stack = [node]
    while stack:
        node = stack.pop()
        count += 1
        if isinstance(node, BinOp):
            stack.append(node.left)
            stack.append(node.right)
        elif isinstance(node, UnaryOp):
            stack.append(node.operand)
        elif isinstance(node, Call):
            stack.append(node.arg)
    return count


def limit_problem(elements) -> tuple[object, str] | None:
    """The first element of a rung over a limit, and what is wrong; None
    when the rung is within every limit. Iterative."""
    stack = [(elements, 0)]
    while stack:
        series, depth = stack.pop()
        for el in series:
            if isinstance(el, Branch):
                if depth + 1 > MAX_BRANCH_DEPTH:
                    return el, (f"branches nested more than {MAX_BRANCH_DEPTH} levels deep "
                                f"(the limit is {MAX_BRANCH_DEPTH})")
                stack.extend((leg, depth + 1) for leg in el.legs)
            elif isinstance(el, Instruction):
                for op in el.operands:
                    if isinstance(op, _EXPRESSION_NODES):
                        levels = expression_depth(op)
                        if levels > MAX_EXPRESSION_DEPTH:
                            return op, (f"expression nested {levels} levels deep; the limit is "
                                        f"{MAX_EXPRESSION_DEPTH} (split it over several CPT instructions)")
    return None
