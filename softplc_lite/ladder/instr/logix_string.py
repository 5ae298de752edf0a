"""Logix's string instructions, bound objects run by both executors. A Logix
string is an ST element here (its LEN, then its characters: logix/tags.py);
each instruction that writes one is given the capacity of the
destination's string type (82 for STRING, less for a string type of the
export), as a constant after its operands.

Rules (1756-RM003, Logix 5000 Controllers General Instructions, chapters
"ASCII String Instructions", "ASCII Conversion Instructions" and "Compare"):

- CONCAT: A's characters then B's. MID: ``Qty`` characters from the 1-based
  ``Start``. INSERT: B put into A before character ``Start``. DELETE:
  ``Qty`` characters removed from ``Start``. FIND: the 1-based position of
  Search in Source from ``Start``, 0 when it is not there. UPPER, LOWER:
  the letters a-z (A-Z) changed, nothing else.
- A result longer than the destination's string type: minor fault type 4,
  code 51 ("The sum length ... is greater than the DATA size"); softplc_lite
  stores the characters that fit (a softplc choice, as Logix controllers are
  reported to truncate).
- A Start below 1 or past the source's end, or a Qty reaching past it:
  minor fault type 4, code 56 ("The Start or Quantity value is invalid");
  the destination is not written (a softplc choice).
- DTOS, RTOS: the number's characters (RTOS: the shortest decimal form that
  reads back as the same REAL, with a decimal point: a softplc choice, the
  manual does not give Logix's format); longer than the destination: type 4
  code 52.
- STOD, STOR: characters before the first digit (or sign, or point for
  STOR) are skipped; the number runs to the first character that is not
  part of it; no number is 0 (a softplc choice for the last two, RM003 says
  "converts up to the first non-numeric character"). A value past a DINT is
  type 4 code 53; softplc_lite stores it as a MOV stores (low 32 bits, S:V).
- Compares (EQU, NEQ, LES, GRT, LEQ, GEQ on strings): character by
  character by their codes, a string that is the start of a longer one
  the smaller ("Compare" instructions on strings: "the hexadecimal values
  of the characters").

Every string minor fault is the ladder's string error (the minor fault bit
and code instructions.md gives for ACN, AEX, ASC): a softplc choice of place
for Logix's codes 51 to 56.
"""

from __future__ import annotations

import re
import struct

from ...datatable.table import read_string, store_text
from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec


def _spec(mnemonic: str, title: str, *names: str) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, K.ANY) for n in names), True)


SPECS = [
    _spec("LCONCAT", "Logix string concatenate", "source A", "source B", "dest", "capacity"),
    _spec("LMID", "Logix middle string", "source", "quantity", "start", "dest", "capacity"),
    _spec("LINSERT", "Logix insert string", "source A", "source B", "start", "dest", "capacity"),
    _spec("LDELETE", "Logix delete string", "source", "quantity", "start", "dest", "capacity"),
    _spec("LFIND", "Logix find string", "source", "search", "start", "result"),
    _spec("LUPPER", "Logix upper case", "source", "dest", "capacity"),
    _spec("LLOWER", "Logix lower case", "source", "dest", "capacity"),
    _spec("LDTOS", "Logix DINT to string", "source", "dest", "capacity"),
    _spec("LRTOS", "Logix REAL to string", "source", "dest", "capacity"),
    _spec("LSTOD", "Logix string to DINT", "source", "dest"),
    _spec("LSTOR", "Logix string to REAL", "source", "dest"),
    _spec("LSCMP", "Logix string compare", "source A", "source B", "comparison"),
]
LOGIX_NAMES = {s.mnemonic: s.mnemonic[1:] for s in SPECS}
LOGIX_NAMES["LSCMP"] = "CMP"
COMPARISONS = ("EQU", "NEQ", "LES", "GRT", "LEQ", "GEQ")  # LSCMP's comparison operand: the index here
_TESTS = (str.__eq__, str.__ne__, str.__lt__, str.__gt__, str.__le__, str.__ge__)
_UPPER = str.maketrans("abcdefghijklmnopqrstuvwxyz", "ABCDEFGHIJKLMNOPQRSTUVWXYZ")
_LOWER = str.maketrans("ABCDEFGHIJKLMNOPQRSTUVWXYZ", "abcdefghijklmnopqrstuvwxyz")
_INTEGER = re.compile(r"[+-]?[0-9]+")
_REAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _text(access, operand):
    get = access.location(operand)
    size = operand.address.ftype.chars  # ST 82, SL more

    def read() -> str:
        d, i, _ = get()
        return read_string(d, i, size)
    return read


def _writer(access, operand, capacity):
    get = access.location(operand)
    machine = access.machine
    cap = capacity.value
    size = operand.address.ftype.chars

    def write(text: str) -> None:
        if len(text) > cap:
            machine._string_error()
            text = text[:cap]
        d, i, _ = get()
        store_text(d, i, text, size)
        d[i] = len(text)
    return write


def _integer(value) -> int:
    return value if isinstance(value, int) else int(value)


def _real_text(x: float) -> str:
    x = struct.unpack("f", struct.pack("f", x))[0]
    if x != x:
        return "NaN"
    if x in (float("inf"), float("-inf")):
        return "Inf" if x > 0 else "-Inf"
    for digits in range(1, 10):
        text = f"{x:.{digits}g}"
        if struct.unpack("f", struct.pack("f", float(text)))[0] == x:
            break
    if "e" in text:
        mantissa, exponent = text.split("e")
        if "." not in mantissa:
            mantissa += ".0"
        return f"{mantissa}e{int(exponent):+03d}"
    return text if "." in text else text + ".0"


def _bind(instr, access):
    m, ops = instr.mnemonic, instr.operands
    machine = access.machine
    if m == "LSCMP":
        a, b, test = _text(access, ops[0]), _text(access, ops[1]), _TESTS[ops[2].value]
        return lambda c: c and test(a(), b())
    if m in ("LSTOD", "LSTOR"):
        source, dest = _text(access, ops[0]), access.location(ops[1])
        pattern = _INTEGER if m == "LSTOD" else _REAL

        def convert(c: bool) -> bool:
            if c:
                found = pattern.search(source())
                value = 0 if found is None else (int(found.group()) if m == "LSTOD" else float(found.group()))
                d, i, _ = dest()
                machine.store(value, d, i)
            return c
        return convert
    if m == "LFIND":
        source, search, start, result = (_text(access, ops[0]), _text(access, ops[1]), access.value(ops[2]),
                                         access.location(ops[3]))

        def find(c: bool) -> bool:
            if c:
                text, k = source(), _integer(start())
                if not 1 <= k <= len(text):
                    machine._string_error()
                    return c
                d, i, _ = result()
                machine.store(text.find(search(), k - 1) + 1, d, i)
            return c
        return find
    write = _writer(access, ops[-2], ops[-1])
    if m == "LCONCAT":
        a, b = _text(access, ops[0]), _text(access, ops[1])
        op = lambda: a() + b()  # noqa: E731
    elif m in ("LUPPER", "LLOWER"):
        a, table = _text(access, ops[0]), _UPPER if m == "LUPPER" else _LOWER
        op = lambda: a().translate(table)  # noqa: E731
    elif m == "LDTOS":
        v = access.value(ops[0])
        op = lambda: str(_integer(v()))  # noqa: E731
    elif m == "LRTOS":
        v = access.value(ops[0])
        op = lambda: _real_text(float(v()))  # noqa: E731
    else:
        return _edit(m, ops, access, write)

    def run(c: bool) -> bool:
        if c:
            write(op())
        return c
    return run


def _edit(m, ops, access, write):
    """MID, INSERT and DELETE: a Start (and a Qty) checked against the
    source; invalid, the string error and nothing written."""
    machine = access.machine
    a = _text(access, ops[0])
    if m == "LINSERT":
        b, start = _text(access, ops[1]), access.value(ops[2])
    else:
        qty, start = access.value(ops[1]), access.value(ops[2])

    def run(c: bool) -> bool:
        if c:
            text, k = a(), _integer(start())
            if m == "LINSERT":
                if not 1 <= k <= len(text) + 1:
                    machine._string_error()
                    return c
                write(text[:k - 1] + b() + text[k - 1:])
                return c
            n = _integer(qty())
            if not 1 <= k <= len(text) or n < 0 or k - 1 + n > len(text):
                machine._string_error()
                return c
            write(text[k - 1:k - 1 + n] if m == "LMID" else text[:k - 1] + text[k - 1 + n:])
        return c
    return run


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
