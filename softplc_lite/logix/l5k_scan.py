"""The text-level scanning of an L5K export: positions, blanks and
``(* comments *)``, words, statements up to ``;``, attribute lists
``(Name := value, ...)`` and blocks up to their END_ word. The L5K reader
(l5k.py) builds on it; every problem is collected, located, in
``problems``."""

from __future__ import annotations

import bisect
import re

from ..ladder.ast import Pos
from .model import Problem
from .values import ValueSyntax, unescape

IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class Scanner:
    def __init__(self, text: str, source: str) -> None:
        self.t = text
        self.n = len(text)
        self.i = 0
        self.source = source
        self.problems: list[Problem] = []
        self.lines = [0] + [m.end() for m in re.finditer(r"\n", text)]

    def pos(self, i: int) -> Pos:
        line = bisect.bisect_right(self.lines, i)
        return Pos(self.source, line, i - self.lines[line - 1] + 1)

    def problem(self, i: int, message: str) -> None:
        self.problems.append(Problem(self.pos(i), message))

    def skip(self) -> None:
        """Whitespace and (* comments *)."""
        t = self.t
        while self.i < self.n:
            c = t[self.i]
            if c in " \t\r\n":
                self.i += 1
            elif t.startswith("(*", self.i):
                end = t.find("*)", self.i + 2)
                if end < 0:
                    self.problem(self.i, "expected *) to close this comment")
                    self.i = self.n
                else:
                    self.i = end + 2
            else:
                break

    def word(self) -> tuple[str, int] | None:
        self.skip()
        m = IDENT.match(self.t, self.i)
        if not m:
            return None
        self.i = m.end()
        return m.group(), m.start()

    def peek_word(self) -> str | None:
        self.skip()
        m = IDENT.match(self.t, self.i)
        return m.group() if m else None

    def skip_line(self) -> None:
        end = self.t.find("\n", self.i)
        self.i = self.n if end < 0 else end + 1

    def statement(self) -> tuple[str, int, bool]:
        """Text up to the next ``;`` outside quotes (consumed, not
        returned), its start, and whether the ``;`` was found: a line that
        starts with an END_ word ends the search, so one missing ``;`` does
        not swallow the blocks after it."""
        t = self.t
        start = i = self.i
        quote = None
        while i < self.n:
            c = t[i]
            if quote:
                if c == "$":
                    i += 2
                    continue
                if c == quote:
                    quote = None
            elif c in "'\"":
                quote = c
            elif c == ";":
                self.i = i + 1
                return t[start:i], start, True
            elif c == "\n" and re.match(r"[ \t]*END_", t[i + 1:i + 40]):
                break
            i += 1
        self.i = i
        return t[start:i], start, False

    def attrs_at(self, text: str, offset: int) -> tuple[dict, int]:
        """``(Name := value, ...)`` at the start of ``text`` (after blanks):
        the attributes by lower-cased name, and the length read."""
        j = len(text) - len(text.lstrip())
        if text[j:j + 1] != "(":
            return {}, 0
        depth, quote, k = 0, None, j
        while k < len(text):
            c = text[k]
            if quote:
                if c == "$":
                    k += 2
                    continue
                if c == quote:
                    quote = None
            elif c in "'\"":
                quote = c
            elif c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
                if depth == 0:
                    break
            k += 1
        if k >= len(text):
            self.problem(offset + j, "expected ) to close these attributes")
            return {}, len(text)
        return self.attr_list(text[j + 1:k], offset + j + 1), k + 1

    def attr_list(self, body: str, offset: int) -> dict:
        out: dict = {}
        for part, at in split_commas(body):
            if not part.strip():
                continue
            key, sep, value = part.partition(":=")
            if not sep:
                self.problem(offset + at + len(part) - len(part.lstrip()), f"expected Name := value, found {part.strip()!r}")
                continue
            v = value.strip()
            if len(v) >= 2 and v[0] == '"' and v[-1] == '"':
                try:
                    v = unescape(v[1:-1])
                except ValueSyntax as e:
                    self.problem(offset + at, f"bad string in attribute {key.strip()}: {e.message}")
            out[key.strip().lower()] = v
        return out

    def block_header(self, kind: str) -> tuple[str, int, dict]:
        """``KIND name (attributes)``: the keyword is read already."""
        w = self.word()
        if w is None:
            self.problem(self.i, f"expected a name after {kind}")
            return "", self.i, {}
        name, at = w
        rest_start = self.i
        line_end = self.t.find("\n", rest_start)
        probe = self.t[rest_start:self.n if line_end < 0 else line_end]
        if probe.strip().startswith("("):
            attrs, used = self.attrs_at(self.t[rest_start:], rest_start)
            self.i = rest_start + used
        else:
            attrs = {}
        return name, at, attrs

    def attrs_here(self) -> dict:
        self.skip()
        attrs, used = self.attrs_at(self.t[self.i:], self.i)
        self.i += used
        return attrs

    def end_of(self, kind: str, name: str, at: int) -> bool:
        """True (and the END_ word read) when the block's END_ word is
        next; at the end of the file, the unterminated block's problem."""
        self.skip()
        if self.i >= self.n:
            self.problem(at, f"expected END_{kind} to close {kind} {name} (opened here) before the end of the file")
            return True
        m = IDENT.match(self.t, self.i)
        if m and m.group() == f"END_{kind}":
            self.i = m.end()
            if self.t[self.i:self.i + 1] == ";":
                self.i += 1
            return True
        return False

    def skip_block(self, kind: str, name: str, at: int) -> None:
        m = re.compile(rf"\bEND_{kind}\b").search(self.t, self.i)
        if m is None:
            opened = f"{kind} {name}" if name else kind
            self.problem(at, f"expected END_{kind} to close {opened} (opened here) before the end of the file")
            self.i = self.n
        else:
            self.i = m.end()

    def unexpected(self, where: str) -> None:
        self.problem(self.i, f"expected {where}, found {self.t[self.i:self.i + 20].split(chr(10))[0]!r}")
        self.skip_line()


def split_commas(body: str):
    """Top-level comma-separated parts of an attribute list, with their
    offsets (commas inside quotes and brackets do not split)."""
    depth, quote, start, k = 0, None, 0, 0
    while k < len(body):
        c = body[k]
        if quote:
            if c == "$":
                k += 2
                continue
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == "," and depth == 0:
            yield body[start:k], start
            start = k + 1
        k += 1
    yield body[start:], start


def split_attrs(text: str) -> tuple[str, str]:
    """A member or alias declaration split at its attribute list's ``(``."""
    k = text.find("(")
    return (text, "") if k < 0 else (text[:k], text[k:])
