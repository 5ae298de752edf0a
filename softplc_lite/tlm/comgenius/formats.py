"""Parsing the conversion specifications of a COMGENIUS format string.

Printing (COMPRINT, STRPRINT) and scanning (COMSCAN, STRSCAN) read their
format strings with slightly different grammars (manual 4.3.4 and 4.3.5):

    print:  %[flags][width][.precision][l|L|h]conv
            flags - + space 0 #; width and precision digits or *
            (h with c or C: one byte a word, softplc's addition)
            conv  b d i o u x X s c C f e E g G % S R
    scan:   %[*|#][width][.precision][l|L|h|H]conv
            width digits; precision digits, or * for c and C (softplc's
            addition: the count from the next integer Param); h or H with
            c or C: one character a word (softplc's addition)
            conv  b d i o u x X c C e E f g G s S R n, %%, and % followed
            by a whitespace character (matches that one character)

A format string is parsed once into ``Spec`` objects and literal text; a
bad one raises ``FormatError`` with the character offset of the problem, so
``softplc check`` can point at it and the instructions can set ER.
"""

from __future__ import annotations

from dataclasses import dataclass

PRINT_CONVERSIONS = "bdiouxXscCfeEgG%SR"
SCAN_CONVERSIONS = "bdiouxXcCeEfgGsSRn"
WHITESPACE = " \t\n\r\v\f"  # the manual's definition (1.2)
STAR = -1  # width or precision taken from the next integer Param

INTEGER_CONVERSIONS = "bdiouxX"
FLOAT_CONVERSIONS = "feEgG"


class FormatError(Exception):
    """An illegal format string: ``offset`` is the character index in it."""

    def __init__(self, offset: int, message: str) -> None:
        super().__init__(f"at character {offset}: {message}")
        self.offset = offset
        self.message = message


@dataclass(frozen=True)
class Spec:
    """One conversion specification, as written."""

    conv: str
    flags: str = ""  # print: any of "-+ 0#"; scan: "*" and/or "#"
    width: int | None = None  # None: not given; STAR: from a Param
    precision: int | None = None  # None: no '.'; '.' alone is 0
    length: str = ""  # "l"/"L" (32-bit), "h"/"H" (one-byte sum; c/C: one byte a word)
    offset: int = 0  # of the '%' in the format string
    text: str = ""  # the spec as written, for messages

    @property
    def long(self) -> bool:
        return self.length in ("l", "L")

    @property
    def byte_per_word(self) -> bool:
        """%hc / %hC: one byte in the low half of each word (softplc's addition)."""
        return self.length in ("h", "H") and self.conv in "cC"

    @property
    def suppressed(self) -> bool:  # scan only
        return "*" in self.flags

    def kind(self) -> str | None:
        """The Param kind this conversion requires (manual tables), or None
        when it consumes no Param."""
        c = self.conv
        if c in INTEGER_CONVERSIONS or c in "cCn":
            return "integer"
        if c in FLOAT_CONVERSIONS:
            return "float"
        if c == "s":
            return "STRING"
        return None


# The largest width or precision a format may write: what a ``*`` can take
# from a 16-bit word. A larger one could only ask for more output than any
# STRING (82 characters) or transmit buffer holds, at the cost of building it.
MAX_FIELD = 32767


def _digits(fmt: str, i: int, start: int) -> tuple[int | None, int]:
    j = i
    while j < len(fmt) and "0" <= fmt[j] <= "9":
        j += 1
    if j - i > 5 or (j > i and int(fmt[i:j]) > MAX_FIELD):
        raise FormatError(start, f"{fmt[start:j][:20]!r}: a width or precision is at most {MAX_FIELD}")
    return (int(fmt[i:j]) if j > i else None), j


def _length_and_conversion(fmt: str, start: int, i: int, lengths: str, conversions: str,
                           listing: str) -> tuple[str, str, int]:
    """The optional length modifier and the conversion character that end
    the specification begun at ``start``; both parsers share this tail."""
    n = len(fmt)
    length = ""
    if i < n and fmt[i] in lengths:
        length = fmt[i]
        i += 1
    if i >= n:
        raise FormatError(start, f"the format ends inside the conversion {fmt[start:]!r}")
    conv = fmt[i]
    i += 1
    if conv not in conversions:
        raise FormatError(start, f"{fmt[start:i]!r} has no conversion character {conv!r} ({listing})")
    return length, conv, i


def parse_print(fmt: str) -> list[str | Spec]:
    """Literal runs and Specs of a print format, in order."""
    items: list[str | Spec] = []
    literal: list[str] = []
    i, n = 0, len(fmt)
    while i < n:
        ch = fmt[i]
        if ch != "%":
            literal.append(ch)
            i += 1
            continue
        start = i
        i += 1
        flags = ""
        while i < n and fmt[i] in "-+ 0#":
            if fmt[i] not in flags:
                flags += fmt[i]
            i += 1
        if i < n and fmt[i] == "*":
            width: int | None = STAR
            i += 1
        else:
            width, i = _digits(fmt, i, start)
        precision: int | None = None
        if i < n and fmt[i] == ".":
            i += 1
            if i < n and fmt[i] == "*":
                precision = STAR
                i += 1
            else:
                precision, i = _digits(fmt, i, start)
                precision = precision or 0
        length, conv, i = _length_and_conversion(fmt, start, i, "lLh", PRINT_CONVERSIONS,
                                                 f"print conversions: {' '.join(PRINT_CONVERSIONS)}")
        if conv == "%" and i - start == 2:
            literal.append("%")
            continue
        if literal:
            items.append("".join(literal))
            literal = []
        items.append(Spec(conv, flags, width, precision, length, start, fmt[start:i]))
    if literal:
        items.append("".join(literal))
    return items


def parse_scan(fmt: str) -> list[str | Spec]:
    """Literal runs and Specs of a scan format. Whitespace runs in the
    format come back as a single " " literal item marked by ``Spec('ws')``."""
    items: list[str | Spec] = []
    i, n = 0, len(fmt)
    while i < n:
        ch = fmt[i]
        if ch in WHITESPACE:
            j = i
            while j < n and fmt[j] in WHITESPACE:
                j += 1
            items.append(Spec("ws", offset=i, text=fmt[i:j]))
            i = j
            continue
        if ch != "%":
            j = i
            while j < n and fmt[j] != "%" and fmt[j] not in WHITESPACE:
                j += 1
            items.append(fmt[i:j])
            i = j
            continue
        start = i
        i += 1
        if i < n and (fmt[i] == "%" or fmt[i] in WHITESPACE):
            # %% and "% " etc.: match that one character literally.
            items.append(Spec("char", offset=start, text=fmt[start:i + 1], flags=fmt[i]))
            i += 1
            continue
        flags = ""
        while i < n and fmt[i] in "*#":
            if fmt[i] not in flags:
                flags += fmt[i]
            i += 1
        width, i = _digits(fmt, i, start)
        if i < n and fmt[i] == "*":
            raise FormatError(i, "a scan width may not be '*'")
        precision: int | None = None
        star_at = None
        if i < n and fmt[i] == ".":
            i += 1
            if i < n and fmt[i] == "*":
                precision, star_at = STAR, i
                i += 1
            else:
                precision, i = _digits(fmt, i, start)
                precision = precision or 0
        length, conv, i = _length_and_conversion(
            fmt, start, i, "lLhH", SCAN_CONVERSIONS,
            f"scan conversions: {' '.join(SCAN_CONVERSIONS)}, %%, % and a space")
        if star_at is not None and conv not in "cC":
            # The manual forbids '*' in a scan precision; softplc allows it for
            # c and C only, where a byte count known at run time is what a
            # binary protocol needs (a frame whose length the line told).
            raise FormatError(star_at, f"a scan precision may be '*' only for %c and %C, not in {fmt[start:i]!r}")
        items.append(Spec(conv, flags, width, precision, length, start, fmt[start:i]))
    return items


def params_needed(items: list[str | Spec], scan: bool) -> list[tuple[Spec, str]]:
    """The Params a parsed format consumes, in order: (spec, kind), where
    kind is "integer", "float" or "STRING" ("integer" for a * width or
    precision)."""
    out: list[tuple[Spec, str]] = []
    for item in items:
        if not isinstance(item, Spec) or item.conv in ("ws", "char"):
            continue
        if scan:
            if item.precision == STAR:  # the byte count, even when suppressed
                out.append((item, "integer"))
            if item.suppressed:
                continue
        else:
            if item.width == STAR:
                out.append((item, "integer"))
            if item.precision == STAR:
                out.append((item, "integer"))
        kind = item.kind()
        if kind is not None:
            out.append((item, kind))
    return out
