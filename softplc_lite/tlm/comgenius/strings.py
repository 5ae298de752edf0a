"""The COMGENIUS string table: the format strings of ``[STRINGS]``.

Manual 3.2.3: string 0 is the empty string, supplied by COMGENIUS; yours are
numbered from 1, one a line. A line's string lies between its first and
last double quote; text outside the quotes is ignored (a comment); a line
with no quotes is the empty string and still takes its number. At most
32,000 strings of at most 255 characters. Escapes are translated once, at
load, each to one 16-bit character:

    \\a \\b \\f \\n \\r \\t \\v    7 8 12 10 13 9 11
    \\\\  \\"                 backslash, double quote
    \\ooo                   1 to 3 octal digits: an 8-bit value (at most \\377)
    \\xHH                   1 or 2 hex digits: an 8-bit value
    \\uHHHH                 1 to 4 hex digits: a 16-bit value

>>> decode_escapes(r'\\x02\\x03%.2C\\u124F\\0')
'\\x02\\x03%.2Cሏ\\x00'
"""

from __future__ import annotations

from dataclasses import dataclass, field

MAX_STRINGS = 32_000
MAX_LENGTH = 255

_SIMPLE = {"a": "\a", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v", "\\": "\\", '"': '"'}
_HEX = "0123456789abcdefABCDEF"


class EscapeError(ValueError):
    """A bad escape: ``offset`` is the index of its backslash in the text."""

    def __init__(self, offset: int, message: str) -> None:
        super().__init__(message)
        self.offset = offset
        self.message = message


def _run(text: str, i: int, allowed: str, most: int) -> int:
    j = i
    while j < len(text) and j - i < most and text[j] in allowed:
        j += 1
    return j


def decode_escapes(text: str) -> str:
    """The characters a quoted [STRINGS] text stands for."""
    if "\\" not in text:
        return text
    out: list[str] = []
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch != "\\":
            out.append(ch)
            i += 1
            continue
        if i + 1 >= n:
            raise EscapeError(i, "a backslash at the end of the string (write \\\\ for a backslash)")
        e = text[i + 1]
        if e in _SIMPLE:
            out.append(_SIMPLE[e])
            i += 2
        elif e in "01234567":
            j = _run(text, i + 1, "01234567", 3)
            value = int(text[i + 1:j], 8)
            if value > 0xFF:
                raise EscapeError(i, f"the octal escape \\{text[i + 1:j]} is {value}, more than 8 bits "
                                  "(use \\uHHHH for 16-bit characters)")
            out.append(chr(value))
            i = j
        elif e in "xu":
            most = 2 if e == "x" else 4
            j = _run(text, i + 2, _HEX, most)
            if j == i + 2:
                raise EscapeError(i, f"\\{e} needs 1 to {most} hex digits")
            out.append(chr(int(text[i + 2:j], 16)))
            i = j
        else:
            raise EscapeError(i, f"unknown escape \\{e} (escapes: \\a \\b \\f \\n \\r \\t \\v \\\\ \\\" "
                              "\\ooo \\xHH \\uHHHH)")
    return "".join(out)


@dataclass
class StringTable:
    """Format strings by index; index 0 is always the empty string."""

    strings: list[str] = field(default_factory=lambda: [""])
    lines: list[int] = field(default_factory=lambda: [0])  # config line of each string (0: built in)

    def __len__(self) -> int:
        return len(self.strings)

    def get(self, index: int) -> str | None:
        """The string, or None for an index outside the table."""
        if 0 <= index < len(self.strings):
            return self.strings[index]
        return None

    def add(self, text: str, line: int = 0) -> int:
        self.strings.append(text)
        self.lines.append(line)
        return len(self.strings) - 1

    @classmethod
    def of(cls, *strings: str) -> "StringTable":
        """A table holding ``strings`` as 1, 2, ... (tests, docs)."""
        table = cls()
        for s in strings:
            table.add(s)
        return table
