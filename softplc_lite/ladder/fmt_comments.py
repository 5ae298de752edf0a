"""Where each comment of a .lad text goes when ``softplc fmt`` reprints it.

The parser keeps only rung comments (the comment lines just above a rung
and the one at the end of its line) because nothing after it needs the
others; ``fmt`` must keep every one. So comments are found here, from the
text, only when formatting: the 10,000-rung parse the engine does on every
load pays nothing for them.

Every comment is attached to one statement (SYMBOL, DATA, FILE header,
rung) or to the file:

* the file's header: own-line comments before the first statement that
  are not the first rung's comment (printed first);
* a statement's leading comments: own-line comments after the previous
  statement and before this one (they travel with it when fmt puts SYMBOL
  and DATA first); a rung's own comment is the run just above it;
* a statement's trailing comment: at the end of its (last) line;
* a multi-line rung's inner comments (inside SOR ... EOR, or between a
  neutral-text rung's first "(" or "[" and its ";"), each with the number
  of top-level elements before it, so it is printed between the same two;
* the file's footer: own-line comments after the last statement.

A comment's text is kept as written (from ``//`` to the end of the line,
trailing blanks dropped).
"""

from __future__ import annotations

import re
from bisect import bisect_right
from dataclasses import dataclass, field

from .ast import Program, Rung


@dataclass
class SourceComment:
    line: int
    column: int
    text: str  # from "//", trailing blanks dropped
    own_line: bool  # nothing but blanks before it on its line


@dataclass
class Block:
    """Consecutive own-line comments, and whether a blank line separated
    them from what came before and from what follows."""

    lines: list[str]
    blank_before: bool
    blank_after: bool


@dataclass
class Comments:
    """Every comment of one file, attached (see the module docstring);
    statements are keyed by ``id()`` of their AST object."""

    header: list[Block] = field(default_factory=list)
    footer: list[Block] = field(default_factory=list)
    leading: dict[int, list[Block]] = field(default_factory=dict)
    above: dict[int, list[str]] = field(default_factory=dict)  # a rung's own comment lines
    trailing: dict[int, str] = field(default_factory=dict)
    inner: dict[int, list[tuple[int, SourceComment]]] = field(default_factory=dict)  # (elements before, comment)


def scan_comments(text: str) -> tuple[list[SourceComment], list[str]]:
    """Every ``//`` comment outside a string, and each line's code (the line
    without its comment and with string contents blanked)."""
    found: list[SourceComment] = []
    code_lines: list[str] = []
    for number, line in enumerate(text.splitlines(), 1):
        code = []
        i, quoted, n = 0, False, len(line)
        while i < n:
            ch = line[i]
            if quoted:
                if ch == "\\":
                    code.append("  ")
                    i += 2
                    continue
                if ch == '"':
                    quoted = False
                code.append(ch if ch == '"' else " ")
            elif ch == '"':
                quoted = True
                code.append(ch)
            elif ch == "/" and line.startswith("//", i):
                found.append(SourceComment(number, i + 1, line[i:].rstrip(), not line[:i].strip()))
                break
            else:
                code.append(ch)
            i += 1
        code_lines.append("".join(code))
    return found, code_lines


_SOR = re.compile(r"\s*SOR\b", re.IGNORECASE)
_EOR = re.compile(r"\bEOR\b", re.IGNORECASE)
_SEMICOLON = re.compile(";")
_NEUTRAL = re.compile(r"\s*(\[|[A-Za-z_][A-Za-z0-9_]*\s*\()")
_FILE = re.compile(r"\s*FILE\b", re.IGNORECASE)


def _rung_end(code: list[str], start: int, column: int) -> int:
    """The last line of the rung that starts at ``start`` (1-based)."""
    first = code[start - 1][column - 1:]
    if _SOR.match(first):
        closer, rest = _EOR, first.lstrip()[3:]
    elif _NEUTRAL.match(first):  # a mnemonic rung has "[" only in addresses (N7:[N9:0]), never "("
        closer, rest = _SEMICOLON, first
    else:
        return start
    for number in range(start, len(code) + 1):
        line = rest if number == start else code[number - 1]
        if closer.search(line):
            return number
    return len(code)


def attach_comments(program: Program, text: str) -> Comments:
    """The comments of ``text`` (one file, parsed into ``program``)."""
    found, code = scan_comments(text)
    out = Comments()
    # (start line, start column, end line, object) of every statement written in the text
    statements: list[tuple[int, int, int, object]] = []
    for decl in program.symbols.values():
        statements.append((decl.pos.line, decl.pos.column, decl.pos.line, decl))
    for decl in program.data:
        statements.append((decl.pos.line, decl.pos.column, decl.pos.line, decl))
    for pfile in program.files.values():
        line = pfile.pos.line
        if 1 <= line <= len(code) and _FILE.match(code[line - 1][pfile.pos.column - 1:]):
            statements.append((line, pfile.pos.column, line, pfile))
        for rung in pfile.rungs:
            pos = rung.pos
            statements.append((pos.line, pos.column, _rung_end(code, pos.line, pos.column), rung))
    statements.sort(key=lambda s: (s[0], s[1]))
    first_lines = [s[0] for s in statements]
    commented = {c.line for c in found}
    blank = {n for n, line in enumerate(code, 1) if not line.strip() and n not in commented}

    def spanning(line: int):
        """The statement whose lines include ``line`` (the last one to start on it)."""
        k = bisect_right(first_lines, line)
        return statements[k - 1] if k and statements[k - 1][2] >= line else None

    pending: list[SourceComment] = []  # own-line comments between statements
    for c in found:
        s = spanning(c.line)
        if s is None or (c.own_line and s[0] == s[2]):
            pending.append(c)
            continue
        start, _, end, obj = s
        if isinstance(obj, Rung) and c.line < end:  # inside a multi-line rung
            before = sum(1 for el in obj.elements if (el.pos.line, el.pos.column) < (c.line, c.column))
            out.inner.setdefault(id(obj), []).append((before, c))
        else:
            out.trailing[id(obj)] = c.text
    # Own-line comments between statements: group them into blocks, each
    # going to the statement after it (or to the footer).
    blocks: list[tuple[int, int, list[str]]] = []  # first line, last line, texts
    for c in pending:
        if blocks and blocks[-1][1] == c.line - 1:
            blocks[-1][2].append(c.text)
            blocks[-1] = (blocks[-1][0], c.line, blocks[-1][2])
        else:
            blocks.append((c.line, c.line, [c.text]))
    for first, last, texts in blocks:
        k = bisect_right(first_lines, last)
        after = statements[k] if k < len(statements) else None
        block = Block(texts, blank_before=first - 1 in blank, blank_after=last + 1 in blank)
        if after is None:
            out.footer.append(block)
            continue
        obj = after[3]
        if isinstance(obj, Rung) and after[0] == last + 1:
            out.above[id(obj)] = texts  # the rung's own comment
        elif statements and after is statements[0]:
            out.header.append(block)
        else:
            out.leading.setdefault(id(obj), []).append(block)
    return out
