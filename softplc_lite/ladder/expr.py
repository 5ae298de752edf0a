"""Expressions of CPT and CMP: operators and functions, shared by the
compiler (which turns an expression tree into Python source) and the
reference interpreter (which walks the tree).

Operators (PLC-5 CPT/CMP): ``+ - *``, ``|`` (divide; ``/`` with spaces
around it is accepted too), ``MOD``, ``//`` (an integer quotient truncated
toward zero: Logix Structured Text's ``/`` of integers, never parsed from
PLC-5 text), ``**``, ``AND OR XOR NOT`` (16-bit
bitwise), unary ``-``, comparisons ``= <> < <= > >=`` (CMP only), and the
functions in :data:`FUNCTIONS`.
"""

from __future__ import annotations

import math
from typing import Callable

from .ast import AddressRef, BinOp, Call, Const, UnaryOp
from .rounding import round_half_even


def _int(v) -> int:
    """Bitwise operators (and TOD, FRD) work on integers: a float is rounded
    first, as a store into a word rounds it (rounding.round_half_even)."""
    if isinstance(v, float):
        if not math.isfinite(v):
            return 0
        return round_half_even(v)
    return v


# Integers from 2**1024 on have no float (float() raises OverflowError).
_FLOAT_RANGE = 2 ** 1024
_FLOAT_BITS = 1025  # the bit length of the largest integer _int() makes of a finite float


def _mul(a, b):
    """``*``: integer products are exact, but one past the float range (a
    product of many L or word operands) is taken as +-inf, the overflow it
    is on any PLC: mixed with a float, or stored, it would otherwise have no
    float value at all (OverflowError)."""
    r = a * b
    if r.__class__ is int and not -_FLOAT_RANGE < r < _FLOAT_RANGE:
        return math.inf if r > 0 else -math.inf
    return r


def int_bits(node) -> int:
    """An upper bound on the bit length of the integer ``node`` can give
    (0 for a float): the compiler multiplies inline, the fast way, unless a
    product could reach the float range (see _mul)."""
    if isinstance(node, Const):
        return abs(node.value).bit_length() + 1 if isinstance(node.value, int) else 0
    if isinstance(node, AddressRef):
        kind = node.address.kind.name
        return {"WORD": 16, "LONG": 32, "BIT": 1}.get(kind, 0)
    if isinstance(node, UnaryOp):
        inner = int_bits(node.operand)
        return (inner or _FLOAT_BITS) + 1 if node.op != "NEG" else inner + 1
    if isinstance(node, Call):
        return int_bits(node.arg) + 1 if node.func in ("ABS", "NEG") else 17 if node.func in ("FRD", "TOD") else 0
    op = node.op
    if op == "*":
        return int_bits(node.left) + int_bits(node.right)
    if op == "**":
        return 0  # Machine.power: always a float
    if op in PY_COMPARE:
        return 1
    left, right = int_bits(node.left), int_bits(node.right)
    if op in ("AND", "OR", "XOR"):  # a float operand is rounded to an integer (_int): up to 2**1024
        left, right = left or _FLOAT_BITS, right or _FLOAT_BITS
    return max(left, right) + 1  # + - | MOD AND OR XOR


def _safe(fn: Callable[[float], float]) -> Callable[[float], float]:
    def wrapped(v):
        try:
            return fn(float(v))
        except (ValueError, OverflowError):
            return math.nan
    return wrapped


def _frd(v) -> int | float:
    """BCD to integer (4 digits). A nibble above 9 is no BCD value: NaN,
    which the store turns into overflow (S:0/1 and the minor fault), as the
    FRD instruction does (ladder/instr/convert.py, docs/instructions.md)."""
    if isinstance(v, float) and not math.isfinite(v):
        return math.nan  # no word at all, so no BCD digits
    v = _int(v) & 0xFFFF
    digits = [(v >> s) & 0xF for s in (12, 8, 4, 0)]
    if any(d > 9 for d in digits):
        return math.nan
    return int("".join(map(str, digits)))


def _tod(v) -> int | float:
    """Integer 0..9999 to BCD, as the signed 16-bit word that holds the
    pattern (9760 gives 0x9760, -26784). Outside 0..9999 there is no 4-digit
    BCD value: NaN, stored as overflow (PLC-5 TOD sets V for a negative
    source or one above 9999). An infinite or NaN float is outside too
    (``_int`` would make it 0)."""
    if isinstance(v, float) and not math.isfinite(v):
        return math.nan
    v = _int(v)
    if not 0 <= v <= 9999:
        return math.nan
    out = 0
    for ch in f"{v:04d}":
        out = (out << 4) | int(ch)
    return out - 0x10000 if out & 0x8000 else out


def _trn(v) -> int | float:
    """TRN: the fraction cut off, toward zero, a REAL staying a REAL (Logix,
    1756-RM003 "Truncate (TRN)"; PLC-5 text has no TRN: parse_actions._CALLS
    leaves it out). An infinite or NaN REAL is as it is."""
    if isinstance(v, float) and math.isfinite(v):
        return float(math.trunc(v))
    return v


FUNCTIONS: dict[str, Callable] = {
    "SQR": _safe(lambda v: math.sqrt(abs(v))),
    "ABS": abs,
    "NEG": lambda v: -v,
    "FRD": _frd,
    "TOD": _tod,
    "LN": _safe(math.log),
    "LOG": _safe(math.log10),
    "SIN": _safe(math.sin),
    "COS": _safe(math.cos),
    "TAN": _safe(math.tan),
    "ASN": _safe(math.asin),
    "ACS": _safe(math.acos),
    "ATN": _safe(math.atan),
    "DEG": _safe(math.degrees),
    "RAD": _safe(math.radians),
    "TRN": _trn,
}

PY_COMPARE = {"=": "==", "<>": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}


def to_python(node, operand_code: Callable[[AddressRef], str]) -> str:
    """Python source for an expression. Names used: ``_x_mul``, ``_x_div``, ``_x_mod``,
    ``_x_pow``, ``_int``, ``_fn_<NAME>``; ``operand_code`` gives the source of
    each address read. Only validated tokens reach the text: numbers are
    printed by repr(), operators come from fixed tables."""
    if isinstance(node, Const):
        return repr(node.value)
    if isinstance(node, AddressRef):
        return operand_code(node)
    if isinstance(node, UnaryOp):
        inner = to_python(node.operand, operand_code)
        return f"(-{inner})" if node.op == "NEG" else f"(~_int({inner}))"
    if isinstance(node, Call):
        assert node.func in FUNCTIONS
        return f"_fn_{node.func}({to_python(node.arg, operand_code)})"
    assert isinstance(node, BinOp)
    a, b = to_python(node.left, operand_code), to_python(node.right, operand_code)
    op = node.op
    if op in ("+", "-"):
        return f"({a} {op} {b})"
    if op == "*":
        # inline unless the product could pass the float range (a product of dozens of words)
        return f"_x_mul({a}, {b})" if int_bits(node) >= 1000 else f"({a} * {b})"
    if op == "|":
        return f"_x_div({a}, {b})"
    if op == "//":
        return f"_x_tdiv({a}, {b})"
    if op == "MOD":
        return f"_x_mod({a}, {b})"
    if op == "**":
        return f"_x_pow({a}, {b})"
    if op in ("AND", "OR", "XOR"):
        sym = {"AND": "&", "OR": "|", "XOR": "^"}[op]
        return f"(_int({a}) {sym} _int({b}))"
    if op in PY_COMPARE:
        return f"({a} {PY_COMPARE[op]} {b})"
    raise ValueError(f"unknown operator {op!r}")  # the grammar has no others


def evaluate(node, read: Callable[[AddressRef], int | float], machine):
    """Walk an expression tree (the reference interpreter's way)."""
    if isinstance(node, Const):
        return node.value
    if isinstance(node, AddressRef):
        return read(node)
    if isinstance(node, UnaryOp):
        v = evaluate(node.operand, read, machine)
        return -v if node.op == "NEG" else ~_int(v)
    if isinstance(node, Call):
        return FUNCTIONS[node.func](evaluate(node.arg, read, machine))
    a = evaluate(node.left, read, machine)
    b = evaluate(node.right, read, machine)
    op = node.op
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return _mul(a, b)
    if op == "|":
        return machine.divide(a, b)
    if op == "//":
        return machine.divide_truncated(a, b)
    if op == "MOD":
        return machine.modulo(a, b)
    if op == "**":
        return machine.power(a, b)
    if op == "AND":
        return _int(a) & _int(b)
    if op == "OR":
        return _int(a) | _int(b)
    if op == "XOR":
        return _int(a) ^ _int(b)
    return {"=": a == b, "<>": a != b, "<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b}[op]


def namespace(machine) -> dict[str, object]:
    """The helper names compiled expressions use."""
    ns: dict[str, object] = {"_x_mul": _mul, "_x_div": machine.divide, "_x_tdiv": machine.divide_truncated,
                               "_x_mod": machine.modulo, "_x_pow": machine.power, "_int": _int}
    for name, fn in FUNCTIONS.items():
        ns[f"_fn_{name}"] = fn
    return ns
