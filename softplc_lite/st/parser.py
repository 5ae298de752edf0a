"""Parse a Logix Structured Text routine into the typed tree of ``ast``.

``parse_routine(lines, source, first_line)`` takes a routine as the export
reader gives it (its ``Line`` objects, whose positions are the export's),
as ``(number, text)`` pairs, or as one text; it returns the statements or
raises ``StErrors`` listing every syntax error, each an ``StError`` at
file:line:column with what was expected. Pass ``errors=[]`` to get the
errors in that list and the statements that did parse instead.

How it goes on after an error (a choice of ours): the routine is lexed
first, a bad character reported and skipped; the tokens are fed to lark's
interactive LALR parser, which is copied (its stacks, not the subtrees on
them, which no later step changes) at each point a statement may
start (after ";", THEN, ELSE, DO, REPEAT, a CASE label's ":"). At an error
the parser goes back to the last copy and skips to the next ";". An error
on the first token after such a skip is the first error's echo (an END_IF
whose IF was skipped) and is not reported again. An error in a block's head
(``IF a = THEN``) is passed over to the head's THEN, DO or OF with a
stand-in head, so the block's body and its END_IF still parse as such. The
statements returned beside errors are for a look only (a stand-in head's
tag is named "_"): a routine with errors does not go on to be compiled.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedToken, VisitError

from ..errors import LocatedError
from . import ast as A
from .ast import Pos

MAX_ERRORS = 100  # a binary file given as ST stops here, not at its millionth byte


class StError(LocatedError):
    """A syntax error in an ST routine: ``file:line:col: message``, and the
    line with a caret under the place (``report``)."""

    def __init__(self, pos: Pos, message: str, context: str | None = None) -> None:
        self.pos = pos
        super().__init__(message, pos.source, pos.line, pos.column)
        self.context = context  # after: str(e) is the located message alone

    def report(self) -> str:
        text = super().report()
        return text + "\n" + self.context if getattr(self, "context", None) else text


class StErrors(Exception):
    """Every syntax error of a routine, in the order of the text."""

    def __init__(self, errors: list[StError]) -> None:
        self.errors = errors
        super().__init__("\n".join(e.report() for e in errors))


@lru_cache(maxsize=None)
def _parser() -> Lark:
    grammar = (Path(__file__).with_name("grammar.lark")).read_text()
    return Lark(grammar, parser="lalr", lexer="basic", propagate_positions=True, maybe_placeholders=True)


_FRIENDLY = {
    "SEMICOLON": "';'", "COMMA": "','", "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'",
    "DOT": "'.'", "COLON": "':'", "DOTDOT": "'..'", "ASSIGN": "':='", "HOLD_ASSIGN": "'[:=]'",
    "MINUS": "'-'", "PLUS": "'+'", "STAR": "'*'", "SLASH": "'/'", "POW": "'**'", "AMP": "'&'",
    "EQ": "'='", "NE": "'<>'", "LT": "'<'", "LE": "'<='", "GT": "'>'", "GE": "'>='",
    "NAME": "a name", "MODULE": "a module tag", "ENUM": "an enumeration word (%ofMaximum)", "INT": "a number", "BASED": "a number",
    "FLOAT": "a number", "DOTNUM": "a number", "STRING": "a string", "$END": "end of routine",
}
_OPERATORS = {"MINUS", "PLUS", "STAR", "SLASH", "POW", "AMP", "EQ", "NE", "LT", "LE", "GT", "GE",
              "AND", "OR", "XOR", "MOD"}
# After these a statement may start: the parser is copied there.
_RESUME_AFTER = {"SEMICOLON", "THEN", "ELSE", "DO", "REPEAT", "COLON"}


def _expected(names) -> str:
    names = set(names)
    if "DOT" in names:  # ".5" after a tag is a "." then a bit number
        names.discard("DOTNUM")
    if len(names & _OPERATORS) > 3:  # "an operator" rather than fifteen of them
        names = (names - _OPERATORS) | {"OPERATOR"}
    shown = sorted({_FRIENDLY.get(n, "an operator" if n == "OPERATOR" else n) for n in names})
    if len(shown) > 1:
        return ", ".join(shown[:-1]) + " or " + shown[-1]
    return shown[0] if shown else "nothing"


class SourceLines:
    """A routine's text as lines, each with where it starts in the export
    (``starts``, ``texts``): the parser reads their joined text and places
    a (line, column) of it back (``pos``); the ST translation lists the
    same lines for the tools (logix/st_routine.py)."""

    def __init__(self, lines, source: str, first_line: int) -> None:
        self.texts: list[str] = []
        self.starts: list[Pos] = []
        if isinstance(lines, str):
            for i, text in enumerate(lines.split("\n")):
                self.texts.append(text)
                self.starts.append(Pos(source, first_line + i, 1))
            return
        for item in lines:
            if isinstance(item, tuple):
                number, text = item[0], item[1]
                pos = Pos(source, number, 1)
            else:  # a logix.model.Line
                text, pos = item.text, item.pos
                if pos.line == 0:
                    pos = Pos(source, first_line + item.number, 1)
            # A line's own newlines (an L5K line holds none; be safe) each start a line.
            for k, part in enumerate(text.split("\n")):
                self.texts.append(part)
                self.starts.append(pos if k == 0 else Pos(pos.source, pos.line + k, 1))

    @property
    def text(self) -> str:
        return "\n".join(self.texts)

    def pos(self, line: int, column: int) -> Pos:
        if not self.starts:
            return Pos("<st>", 1, 1)
        index = min(max(line - 1, 0), len(self.starts) - 1)
        start = self.starts[index]
        return Pos(start.source, start.line, start.column + column - 1)

    def context(self, line: int, column: int) -> str:
        index = min(max(line - 1, 0), len(self.texts) - 1)
        text = self.texts[index].expandtabs(1) if self.texts else ""
        return f"{text}\n{' ' * (column - 1)}^"


def parse_routine(lines: Sequence | str | SourceLines, source: str = "<st>", first_line: int = 1,
                  errors: list[StError] | None = None) -> list[A.Statement]:
    where = lines if isinstance(lines, SourceLines) else SourceLines(lines, source, first_line)
    found: list[StError] = []
    tree = _parse_tree(where, found)
    try:
        statements = _Build(where).transform(tree) if tree is not None else []
    except (RecursionError, VisitError) as e:
        if not isinstance(e, RecursionError) and not isinstance(e.orig_exc, RecursionError):
            raise
        # Thousands of terms in one expression, or blocks hundreds deep: a
        # generated file, not a person's, and past Python's recursion.
        found.append(_error(where, 1, 1, "an expression or block nested too deeply to read"))
        statements = []
    if errors is not None:
        found.sort(key=lambda e: (e.pos.line, e.pos.column))
        errors.extend(found)
        return statements
    found.sort(key=lambda e: (e.pos.line, e.pos.column))
    if found:
        raise StErrors(found)
    return statements


def _error(where: SourceLines, line: int, column: int, message: str) -> StError:
    return StError(where.pos(line, column), message, where.context(line, column))


def _tokens(where: SourceLines, text: str, found: list[StError], blanked: list[int]) -> list[Token]:
    parser = _parser()
    while True:
        try:
            tokens = list(parser.lex(text))
            for k in range(len(tokens) - 1):
                a, b = tokens[k], tokens[k + 1]
                if a.type in ("LPAR", "SLASH") and b.type == "STAR" and b.start_pos == a.end_pos:
                    found.append(_error(where, a.line, a.column, f"comment {a + b!r} is never closed"))
                    return tokens[:k]
            return tokens
        except UnexpectedCharacters as e:
            found.append(_error(where, e.line, e.column, f"unexpected character {text[e.pos_in_stream]!r}"))
            if len(found) >= MAX_ERRORS:
                return []
            # Blank it (same length, so every position stays) and lex again.
            blanked.append(e.pos_in_stream)
            text = text[:e.pos_in_stream] + " " + text[e.pos_in_stream + 1:]


def _parse_tree(where: SourceLines, found: list[StError]):
    blanked: list[int] = []
    tokens = _tokens(where, where.text, found, blanked)
    ip = _parser().parse_interactive("")
    checkpoint, since = ip.copy(deepcopy_values=False), 0
    i, resumed = 0, False
    while i <= len(tokens) and len(found) < MAX_ERRORS:
        try:
            if i == len(tokens):
                return ip.feed_eof(tokens[-1] if tokens else None)
            tok = tokens[i]
            ip.feed_token(tok)
        except UnexpectedToken as e:
            tok = e.token
            if not resumed and not _after_blank(where.text, blanked, tok):
                found.append(_token_error(where, e, tokens, _accepted(checkpoint, tokens[since:i])))
            if i >= len(tokens):
                return None
            header = _header_recovery(checkpoint, tokens, since, i)
            if header is not None:  # a bad IF/ELSIF/WHILE/FOR/CASE head: go on in its body
                ip, i = header
                checkpoint, since, resumed = ip.copy(deepcopy_values=False), i, False
                continue
            ip, resumed = checkpoint.copy(deepcopy_values=False), True
            while i < len(tokens) and tokens[i].type != "SEMICOLON":
                i += 1
            i += 1
            since = i
            continue
        resumed = False
        if tok.type in _RESUME_AFTER:
            checkpoint, since = ip.copy(deepcopy_values=False), i + 1
        i += 1
    return None


# A block's head, as a stand-in for one that did not parse: its opening
# keyword, the tokens of a valid head, and the keyword that ends the head.
_HEADS = {
    "IF": (("IF", "IF"), ("NAME", "_"), ("THEN", "THEN")),
    "ELSIF": (("ELSIF", "ELSIF"), ("NAME", "_"), ("THEN", "THEN")),
    "WHILE": (("WHILE", "WHILE"), ("NAME", "_"), ("DO", "DO")),
    "FOR": (("FOR", "FOR"), ("NAME", "_"), ("ASSIGN", ":="), ("INT", "0"), ("TO", "TO"), ("INT", "0"), ("DO", "DO")),
    "CASE": (("CASE", "CASE"), ("NAME", "_"), ("OF", "OF")),
}


def _header_recovery(checkpoint, tokens: list[Token], since: int, i: int):
    """When the error is in a block's head (IF a = THEN), the parser as if
    the head had parsed and the index of the token after it, so the body is
    still read as the body and its END_IF is not a second error; None
    otherwise."""
    if since >= len(tokens) or tokens[since].type not in _HEADS:
        return None
    head = _HEADS[tokens[since].type]
    end = head[-1][0]
    j = i
    while j < len(tokens) and tokens[j].type not in (end, "SEMICOLON"):
        j += 1
    if j >= len(tokens) or tokens[j].type != end:
        return None
    ip = checkpoint.copy(deepcopy_values=False)
    try:
        for kind, value in head:
            ip.feed_token(Token.new_borrow_pos(kind, value, tokens[since]))
    except UnexpectedToken:  # ELSIF outside an IF: no stand-in fits
        return None
    return ip, j + 1


def _after_blank(text: str, blanked: list[int], tok: Token) -> bool:
    """Whether ``tok`` comes right after a bad character already reported
    (its error is that one's echo)."""
    start = getattr(tok, "start_pos", None)
    if start is None:
        return False
    return any(p < start and not text[p + 1:start].strip() for p in blanked)


def _accepted(checkpoint, fed: list[Token]) -> set[str]:
    """The tokens the parser takes after ``fed``: lark's error lists every
    token of the LALR state, some of which another context would take."""
    ip = checkpoint.copy(deepcopy_values=False)
    for tok in fed:
        ip.feed_token(tok)
    return ip.accepts()


def _token_error(where: SourceLines, e: UnexpectedToken, tokens: list[Token], accepted: set[str]) -> StError:
    tok = e.token
    if tok.type == "$END":
        last = tokens[-1] if tokens else None
        line = last.end_line if last is not None else 1
        column = last.end_column if last is not None else 1
        return _error(where, line, column, f"unexpected end of routine; expected {_expected(accepted)}")
    shown = str(tok) if len(str(tok)) <= 40 else str(tok)[:37] + "..."
    return _error(where, tok.line, tok.column, f"unexpected {shown!r}; expected {_expected(accepted)}")


_SPACE = re.compile(r"\s+|\(\*[\s\S]*?\*\)|/\*[\s\S]*?\*/|//[^\n]*")


@v_args(meta=True)
class _Build(Transformer):
    """The lark tree to the typed tree, every node at its place in the export."""

    def __init__(self, where: SourceLines) -> None:
        super().__init__()
        self.where = where
        self.text = where.text

    def _pos(self, meta) -> Pos:
        return self.where.pos(meta.line, meta.column) if not meta.empty else self.where.pos(1, 1)

    # -- statements
    def start(self, meta, children):
        return list(children[0]) if children and children[0] is not None else []

    def stmts(self, meta, children):
        return [c for c in children if c is not None]

    def _body(self, stmts) -> tuple:
        return tuple(stmts) if stmts else ()

    def empty_stmt(self, meta, children):
        return None

    def assign(self, meta, children):
        target, op, value = children
        return A.Assign(target, value, op.type == "ASSIGN", self._pos(meta))

    def call_stmt(self, meta, children):
        name, args = children
        return A.Call(str(name), tuple(args) if args != [None] else (), self._pos(meta))

    def call_args(self, meta, children):
        return list(children)

    def args(self, meta, children):
        return list(children)

    def if_stmt(self, meta, children):
        _, cond, _, body, *rest = children
        branches = [(cond, self._body(body))]
        else_ = None
        for item in rest:
            if isinstance(item, tuple):
                branches.append(item)
        if len(rest) >= 3 and isinstance(rest[-3], Token) and rest[-3].type == "ELSE":
            else_ = self._body(rest[-2])
        return A.If(tuple(branches), else_, self._pos(meta))

    def elsif(self, meta, children):
        _, cond, _, body = children
        return (cond, self._body(body))

    def case_stmt(self, meta, children):
        selector = children[1]
        arms = tuple(c for c in children if isinstance(c, A.CaseArm))
        else_ = None
        if isinstance(children[-3], Token) and children[-3].type == "ELSE":
            else_ = self._body(children[-2])
        return A.Case(selector, arms, else_, self._pos(meta))

    def case_arm(self, meta, children):
        labels = tuple(c for c in children[:-2])
        return A.CaseArm(labels, self._body(children[-1]), self._pos(meta))

    def case_label(self, meta, children):
        return children[0]

    def case_range(self, meta, children):
        return A.CaseRange(children[0], children[2], self._pos(meta))

    def for_stmt(self, meta, children):
        _, var, _, start, _, stop, _by, step, _, body, _ = children
        return A.For(var, start, stop, step, self._body(body), self._pos(meta))

    def while_stmt(self, meta, children):
        _, cond, _, body, _ = children
        return A.While(cond, self._body(body), self._pos(meta))

    def repeat_stmt(self, meta, children):
        _, body, _, until, _ = children
        return A.Repeat(self._body(body), until, self._pos(meta))

    def exit_stmt(self, meta, children):
        return A.Exit(self._pos(meta))

    def return_stmt(self, meta, children):
        return A.Return(self._pos(meta))

    # -- expressions
    def binop(self, meta, children):
        left, op, right = children
        name = "AND" if op.type == "AMP" else str(op).upper()
        return A.BinOp(name, left, right, self._pos(meta))

    def binop_neg(self, meta, children):
        left, op, minus, right = children
        return A.BinOp("**", left, A.UnaryOp("-", right, self.where.pos(minus.line, minus.column)), self._pos(meta))

    def neg(self, meta, children):
        return A.UnaryOp("-", children[1], self._pos(meta))

    def neg_number(self, meta, children):
        return A.Const(-children[1].value, children[1].kind, self._pos(meta))

    def not_(self, meta, children):
        return A.UnaryOp("NOT", children[1], self._pos(meta))

    def function_call(self, meta, children):
        name, args = children
        return A.FunctionCall(str(name), tuple(args or ()), self._pos(meta))

    def int_const(self, meta, children):
        return A.Const(int(str(children[0]).replace("_", "")), "INT", self._pos(meta))

    def based_const(self, meta, children):
        base, digits = str(children[0]).split("#")
        return A.Const(int(digits.replace("_", ""), int(base)), "INT", self._pos(meta))

    def float_const(self, meta, children):
        text = str(children[0]).replace("_", "")
        return A.Const(float("0" + text if text.startswith(".") else text), "REAL", self._pos(meta))

    def string(self, meta, children):
        return A.Const(str(children[0])[1:-1], "STRING", self._pos(meta))

    def enum_word(self, meta, children):
        return A.TagRef(str(children[0]), str(children[0]), (), self._pos(meta))

    def tag(self, meta, children):
        text = _SPACE.sub("", self.text_between(meta))
        return A.TagRef(text, str(children[0]), tuple(children[1:]), self._pos(meta))

    def text_between(self, meta) -> str:
        return self.text[meta.start_pos:meta.end_pos]

    def member(self, meta, children):
        return A.Member(str(children[0]))

    def bit(self, meta, children):
        return A.Bit(int(str(children[0]).lstrip(".").replace("_", "")))

    def bit_index(self, meta, children):
        return A.BitIndex(children[0])

    def index(self, meta, children):
        return A.Index(tuple(children))
