"""The value syntax Studio 5000 exports share: radix-prefixed numbers
(``16#00ff``, ``2#0101_1010``, ``8#17``), REALs in float and exponential
form with Logix's non-numbers (``1.#QNAN``, ``1.#INF``, ``1.$``), strings
with ``$`` escapes (``'$00'``, ``$'``, ``$$``, ``$N``, ``$0D``), and the
positional L5K form of a whole value (``[5,'READY',[1,2]]``), as the L5K
file and an L5X's ``Format="L5K"`` data write them (Logix 5000 Controllers
Import/Export, 1756-RM084, "L5K data" and "Decorated data").

Every function raises ``ValueSyntax`` (with an offset into the text it was
given and what was expected) for text it cannot read; the readers turn it
into a located ``Problem``.
"""

from __future__ import annotations

import math
import re

_RADIX = {"2#": 2, "8#": 8, "16#": 16}

# Logix writes a REAL that is not a number in the Microsoft C runtime's
# spelling; "1.$" is the same value in the form some decorated data uses.
_SPECIAL_REALS = {
    "1.#QNAN": math.nan,
    "-1.#QNAN": math.nan,
    "1.#SNAN": math.nan,
    "-1.#SNAN": math.nan,
    "1.#IND": math.nan,
    "-1.#IND": math.nan,
    "1.$": math.nan,
    "-1.$": math.nan,
    "1.#INF": math.inf,
    "-1.#INF": -math.inf,
}

# $-escapes of Logix string literals (1756-RM084, "String data"): the
# letter forms, and $hh for any character by two hex digits.
_ESCAPES = {"'": "'", '"': '"', "$": "$", "N": "\n", "L": "\n", "P": "\f", "R": "\r", "T": "\t"}


# Deeper nesting than any Logix type allows (a structure's members nest
# a few levels): a bound so that no input can exhaust Python's stack.
MAX_DEPTH = 64


class ValueSyntax(Exception):
    """Text that is not a value: ``offset`` into the text, ``message``
    what was expected."""

    def __init__(self, offset: int, message: str) -> None:
        super().__init__(message)
        self.offset = offset
        self.message = message


def parse_number(text: str, offset: int = 0) -> int | float:
    """One number as Logix writes it: decimal, radix-prefixed with
    ``_`` separators, float or exponential, or a Logix non-number."""
    t = text.strip()
    if t.upper() in _SPECIAL_REALS:
        return _SPECIAL_REALS[t.upper()]
    sign = 1
    body = t
    if body[:1] in "+-" and body[1:2]:
        sign = -1 if body[0] == "-" else 1
        body = body[1:]
    for prefix, base in _RADIX.items():
        if body.startswith(prefix):
            digits = body[len(prefix):].replace("_", "")
            try:
                return sign * int(digits, base)
            except ValueError:
                raise ValueSyntax(offset, f"expected base-{base} digits after {prefix}, found {t!r}") from None
    try:
        return int(t.replace("_", ""), 10)
    except ValueError:
        pass
    try:
        if t and t[0] in "+-.0123456789" and t.lower() not in ("nan", "inf", "-inf", "+inf"):
            return float(t)
    except ValueError:
        pass
    raise ValueSyntax(offset, f"expected a number, found {t!r}" if t else "expected a number")


def unescape(body: str, offset: int = 0) -> str:
    """The text of a string literal's body (without its quotes)."""
    out = []
    i = 0
    n = len(body)
    while i < n:
        c = body[i]
        if c != "$":
            out.append(c)
            i += 1
            continue
        nxt = body[i + 1:i + 2]
        if nxt.upper() in _ESCAPES and nxt:
            out.append(_ESCAPES[nxt.upper()])
            i += 2
            continue
        hh = body[i + 1:i + 3]
        if len(hh) == 2 and all(ch in "0123456789abcdefABCDEF" for ch in hh):
            out.append(chr(int(hh, 16)))
            i += 3
            continue
        raise ValueSyntax(offset + i, f"expected an escape after $ ($$, $', $N, $R, $T, $L, $P or two hex digits), found {body[i:i + 3]!r}")
    return "".join(out)


def parse_quoted(text: str, offset: int = 0) -> str:
    """A whole quoted literal, ``'text'`` or ``"text"``."""
    t = text.strip()
    if len(t) < 2 or t[0] not in "'\"" or t[-1] != t[0]:
        raise ValueSyntax(offset, f"expected a quoted string, found {t!r}")
    return unescape(t[1:-1], offset + 1)


def parse_ascii(text: str, offset: int = 0) -> int:
    """An integer in ASCII radix (``'$00'``, ``'AB'``): its characters
    are the integer's bytes, most significant first."""
    value = 0
    for ch in parse_quoted(text, offset):
        value = (value << 8) | (ord(ch) & 0xFF)
    return value


def parse_scalar(text: str, offset: int = 0) -> int | float | str:
    t = text.strip()
    if t[:1] in ("'", '"'):
        return parse_quoted(t, offset)
    return parse_number(t, offset)


def parse_l5k_value(text: str) -> int | float | str | list:
    """A whole value in the positional L5K form: nested ``[...]`` of
    numbers and quoted strings."""
    p = _L5K(text)
    p.skip()
    value = p.value()
    p.skip()
    if p.i < len(text):
        raise ValueSyntax(p.i, f"expected the end of the value, found {text[p.i:p.i + 10]!r}")
    return value


class _L5K:
    def __init__(self, text: str) -> None:
        self.text = text
        self.i = 0

    def skip(self) -> None:
        t = self.text
        while self.i < len(t) and t[self.i] in " \t\r\n":
            self.i += 1

    def value(self, depth: int = 0) -> int | float | str | list:
        t = self.text
        if depth > MAX_DEPTH:
            raise ValueSyntax(self.i, f"expected at most {MAX_DEPTH} levels of nested [ ]")
        if self.i >= len(t):
            raise ValueSyntax(self.i, "expected a value (a number, a 'string' or [...])")
        c = t[self.i]
        if c == "[":
            start = self.i
            self.i += 1
            items: list = []
            self.skip()
            if self.i < len(t) and t[self.i] == "]":
                self.i += 1
                return items
            while True:
                self.skip()
                items.append(self.value(depth + 1))
                self.skip()
                if self.i >= len(t):
                    raise ValueSyntax(start, "expected ] to close this [")
                if t[self.i] == ",":
                    self.i += 1
                    continue
                if t[self.i] == "]":
                    self.i += 1
                    return items
                raise ValueSyntax(self.i, f"expected , or ] in a list, found {t[self.i]!r}")
        if c in "'\"":
            start = self.i
            j = self.i + 1
            while j < len(t) and t[j] != c:
                j += 2 if t[j] == "$" else 1
            if j >= len(t):
                raise ValueSyntax(start, f"expected {c} to close this string")
            self.i = j + 1
            return unescape(t[start + 1:j], start + 1)
        start = self.i
        while self.i < len(t) and t[self.i] not in ",] \t\r\n[":
            self.i += 1
        if start == self.i:
            raise ValueSyntax(start, f"expected a value, found {c!r}")
        return parse_number(t[start:self.i], start)


# Date, time and duration literals (DT#..., LDT#..., LT#..., T32#...) are
# kept as their text: no softplc instruction reads them yet.
_TIME_LITERAL = re.compile(r"^-?(DT|LDT|LT|T|T32|TIME|LTIME|TOD|LTOD|D|DATE)#", re.IGNORECASE)


def typed_scalar(text: str, data_type: str | None, radix: str | None, offset: int = 0) -> int | float | str:
    """A decorated ``Value`` attribute read by its DataType and Radix: a
    REAL or LREAL is a float, an ASCII radix a quoted string of bytes, a
    date or time literal its text, anything else an integer in its
    radix's form."""
    t = text.strip()
    dt = (data_type or "").upper()
    if _TIME_LITERAL.match(t):
        return t
    if (radix or "").upper() == "ASCII" or (t[:1] == "'" and dt not in ("STRING",)):
        return parse_ascii(t, offset)
    number = parse_number(t, offset)
    if dt in ("REAL", "LREAL"):
        return float(number)
    if isinstance(number, float) and dt:
        raise ValueSyntax(offset, f"expected an integer for a {data_type}, found {t!r}")
    return number


def flag(value: str | None, default: bool = False) -> bool:
    """An export's yes/no attribute (``Disabled="true"``, ``Hidden := 1``)."""
    if value is None:
        return default
    return value.strip().lower() in ("true", "1", "yes")


SCAN_MODES = {"EXECUTEPRESCAN": "PRESCAN", "EXECUTEPOSTSCAN": "POSTSCAN", "EXECUTEENABLEINFALSE": "ENABLEINFALSE"}


def scan_modes(attrs: dict) -> set[str] | None:
    """The scan-mode routines an AOI's header says to run
    (``ExecutePrescan="true"``, ``ExecuteEnableInFalse := Yes``), as routine
    names upper-cased; None when it names none of them."""
    said = {key.upper(): value for key, value in attrs.items() if key.upper() in SCAN_MODES}
    if not said:
        return None
    return {SCAN_MODES[key] for key, value in said.items() if flag(value)}
