"""Reading MODBMAST.XML into a plain tree that remembers where things are.

The standard library's expat parser reads the bytes (honouring the file's
encoding declaration; UTF-8 without one). Every element becomes an
``XmlNode`` with its line and column (1-based) and those of each attribute,
so that every problem in the file can be reported at its place. A document
type declaration or an entity declaration is refused: a configuration file
needs neither, and refusing them keeps entity expansion (and its tricks) out.
The tree is built with an explicit stack, so nesting depth costs no Python
recursion; the configuration's own rules stop at five levels.
"""

from __future__ import annotations

import re
import xml.parsers.expat
from dataclasses import dataclass, field

MAX_BYTES = 16 * 1024 * 1024  # a scan list of 32 ports x 247 slaves fits in far less


@dataclass
class XmlNode:
    name: str
    attrs: dict[str, str]
    line: int
    column: int
    attr_pos: dict[str, tuple[int, int]] = field(default_factory=dict)
    children: list["XmlNode"] = field(default_factory=list)
    text: str = ""

    def where(self, attr: str | None = None) -> tuple[int, int]:
        """(line, column) of the element, or of one of its attributes."""
        if attr is not None and attr in self.attr_pos:
            return self.attr_pos[attr]
        return self.line, self.column


class XmlSyntaxError(ValueError):
    def __init__(self, message: str, line: int, column: int) -> None:
        super().__init__(message)
        self.message = message
        self.line = line
        self.column = column


_ATTR = re.compile(rb"([A-Za-z_][\w.\-:]*)\s*=\s*")


def _line_starts(data: bytes) -> list[int]:
    starts = [0]
    find = data.find
    i = find(b"\n")
    while i >= 0:
        starts.append(i + 1)
        i = find(b"\n", i + 1)
    return starts


def read_xml(data: bytes) -> XmlNode:
    """The document element of ``data``; XmlSyntaxError (with line and
    column) when it is not well-formed XML or declares a DTD or entities."""
    if len(data) > MAX_BYTES:
        raise XmlSyntaxError(f"the file has {len(data):,} bytes; a configuration file may have at most "
                             f"{MAX_BYTES:,}", 1, 1)
    parser = xml.parsers.expat.ParserCreate()
    stack: list[XmlNode] = []
    root: list[XmlNode] = []
    starts: list[int] | None = None
    refused: list[XmlSyntaxError] = []

    def position(offset: int) -> tuple[int, int]:
        nonlocal starts
        if starts is None:
            starts = _line_starts(data)
        lo, hi = 0, len(starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - starts[lo] + 1

    def start(name: str, attrs: dict[str, str]) -> None:
        node = XmlNode(name, dict(attrs), parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        if attrs:
            offset = parser.CurrentByteIndex
            end = data.find(b">", offset)
            for m in _ATTR.finditer(data, offset, end if end >= 0 else len(data)):
                key = m.group(1).decode("utf-8", "replace")
                if key in attrs and key not in node.attr_pos:
                    node.attr_pos[key] = position(m.start())
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def end(name: str) -> None:
        stack.pop()

    def text(chars: str) -> None:
        if stack:
            stack[-1].text += chars

    def refuse(what: str):
        def handler(*args) -> None:
            refused.append(XmlSyntaxError(f"{what} is not allowed in a configuration file",
                                          parser.CurrentLineNumber, parser.CurrentColumnNumber + 1))
            raise _Stop
        return handler

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    parser.StartDoctypeDeclHandler = refuse("a document type declaration (<!DOCTYPE ...>)")
    parser.EntityDeclHandler = refuse("an entity declaration")
    parser.UnparsedEntityDeclHandler = refuse("an entity declaration")
    try:
        parser.Parse(data, True)
    except _Stop:
        raise refused[0] from None
    except xml.parsers.expat.ExpatError as e:
        raise XmlSyntaxError(f"not well-formed XML: {xml.parsers.expat.ErrorString(e.code)}",
                             e.lineno, e.offset + 1) from None
    except (UnicodeError, ValueError, LookupError) as e:  # an unknown encoding declaration
        raise XmlSyntaxError(f"cannot read the file's characters: {e}", parser.CurrentLineNumber,
                             parser.CurrentColumnNumber + 1) from None
    return root[0]


class _Stop(Exception):
    pass
