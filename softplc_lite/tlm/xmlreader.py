"""Reading a module's XML configuration file (MODBMAST.XML, MODBTCPS.XML) into a
plain tree that remembers where things are.

The standard library's expat parser reads the bytes (honouring the file's
encoding declaration; UTF-8 without one). Every element becomes an
``XmlNode`` with its line and column (1-based) and those of each attribute,
so that every problem in the file can be reported at its place. A document
type declaration or an entity declaration is refused: a configuration file
needs neither, and refusing them keeps entity expansion (and its tricks) out.
The tree is built with an explicit stack, so nesting depth costs no Python
recursion; the configurations themselves stop at five levels (MODBMAST.XML).
"""

from __future__ import annotations

import re
import xml.parsers.expat
from dataclasses import dataclass, field

MAX_BYTES = 16 * 1024 * 1024  # a scan list of 32 ports x 247 slaves (MODBMAST.XML) fits in far less


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


# An attribute with its quoted value (so that text inside a value is never
# taken for an attribute), or the end of the start tag.
_ATTR = re.compile(rb"""([^\s=<>/"']+)\s*=\s*(?:"[^"]*"|'[^']*')|>""")
_UTF16 = ((b"\xff\xfe", "utf-16"), (b"\xfe\xff", "utf-16"), (b"<\x00", "utf-16-le"), (b"\x00<", "utf-16-be"))
_DECLARED = re.compile(rb"(?:\xef\xbb\xbf)?<\?xml[^>]*\sencoding\s*=")


def _where(text: str) -> tuple[int, int]:
    """(line, column) just after ``text``."""
    lines = re.split(r"\r\n?|\n", text)
    return len(lines), len(lines[-1]) + 1


def _as_utf8(data: bytes) -> tuple[bytes, str | None]:
    """UTF-16 turned into UTF-8 (attribute positions are looked for in the
    bytes), and the encoding to tell expat; a file without an encoding
    declaration must be UTF-8 (XmlSyntaxError at the first byte that is not)."""
    for bom, codec in _UTF16:
        if data.startswith(bom):
            try:
                return data.decode(codec).encode("utf-8"), "utf-8"
            except UnicodeDecodeError as e:
                raise XmlSyntaxError(f"the file is UTF-16 but its bytes {e.start}..{e.end - 1} are not: {e.reason}",
                                     *_where(data[:e.start].decode(codec, "replace"))) from None
    if _DECLARED.match(data) is None:
        try:
            data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise XmlSyntaxError(f"byte 0x{data[e.start]:02X} is not UTF-8, and a file without an encoding "
                                 "declaration must be UTF-8: save it as UTF-8, or declare its encoding "
                                 "(<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>)",
                                 *_where(data[:e.start].decode("utf-8"))) from None
    return data, None


_BREAK = re.compile(rb"\r\n?|\n")


def _line_starts(data: bytes) -> list[int]:
    """Where each line starts: after LF, CR LF or a lone CR, as expat counts lines."""
    return [0, *(m.end() for m in _BREAK.finditer(data))]


def read_xml(data: bytes) -> XmlNode:
    """The document element of ``data``; XmlSyntaxError (with line and
    column) when it is not well-formed XML or declares a DTD or entities."""
    if len(data) > MAX_BYTES:
        raise XmlSyntaxError(f"the file has {len(data):,} bytes; a configuration file may have at most "
                             f"{MAX_BYTES:,}", 1, 1)
    data, encoding = _as_utf8(data)
    parser = xml.parsers.expat.ParserCreate(encoding)
    stack: list[XmlNode] = []
    texts: list[list[str]] = []  # the text pieces of each open element (joined once: += would be quadratic)
    root: list[XmlNode] = []
    starts: list[int] | None = None
    refused: list[XmlSyntaxError] = []
    last = [-1, 1]  # the last offset given a position, and its column

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
        # The column in characters, as expat counts them; offsets come in
        # increasing order, so count on from the last one on the same line.
        base, column = (last[0], last[1]) if last[0] >= starts[lo] and last[0] <= offset else (starts[lo], 1)
        column += len(data[base:offset].decode("utf-8", "replace"))
        last[:] = [offset, column]
        return lo + 1, column

    def start(name: str, attrs: dict[str, str]) -> None:
        node = XmlNode(name, dict(attrs), parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        if attrs:
            for m in _ATTR.finditer(data, parser.CurrentByteIndex):
                if m.group(1) is None:  # the end of the start tag
                    break
                key = m.group(1).decode("utf-8", "replace")
                if key in attrs and key not in node.attr_pos:
                    node.attr_pos[key] = position(m.start())
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)
        texts.append([])

    def end(name: str) -> None:
        stack.pop().text = "".join(texts.pop())

    def text(chars: str) -> None:
        if texts:
            texts[-1].append(chars)

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
