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
