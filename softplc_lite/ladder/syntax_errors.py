"""Lark's syntax errors in the words of the ladder language: where
(file:line:col, with lark's context line and caret) and what was expected,
token names turned into what a person calls them ("an address", "';'")."""

from __future__ import annotations

from typing import Iterable

from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from .ast import Pos
from .errors import LadderError

_FRIENDLY = {
    "_NL": "end of line", "$END": "end of file", "SEMICOLON": "';'", "COMMA": "','",
    "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'", "NAME": "an instruction or name",
    "ADDRESS": "an address", "SYMBOL_MEMBER": "a symbol", "INT": "a number", "FLOAT": "a number", "HEX": "a number",
    "STRING": "a quoted string", "COMMENT": "a comment", "BND": "BND", "NXB": "NXB",
    "BST": "BST", "EOR": "EOR", "SOR": "SOR", "MINUS": "'-'", "EQUAL": "'='",
    "COMPARE_OP": "a comparison", "ADD_OP": "'+' or '-'", "MUL_OP": "'*', '|' or MOD",
}


def _describe(names: Iterable[str]) -> str:
    shown = sorted({_FRIENDLY.get(n, n) for n in names})
    return ", ".join(shown) if shown else "nothing"


def syntax_error(e: UnexpectedInput, text: str, source: str, line_offset: int, column_offset: int) -> LadderError:
    line = getattr(e, "line", None) or 1
    column = getattr(e, "column", None) or 1
    if line == 1:
        column += column_offset
    pos = Pos(source, line + line_offset, column)
    try:
        context = e.get_context(text)
    except Exception:  # pragma: no cover - lark cannot always slice context at EOF
        context = None
    if isinstance(e, UnexpectedCharacters):
        ch = text[e.pos_in_stream] if e.pos_in_stream < len(text) else "end of file"
        message = f"unexpected character {ch!r}"
    elif isinstance(e, UnexpectedEOF):
        message = f"unexpected end of file; expected {_describe(e.expected)}"
    else:
        assert isinstance(e, UnexpectedToken)
        tok = e.token
        found = "end of file" if tok.type == "$END" else (
            "end of line" if tok.type == "_NL" else repr(str(tok)))
        message = f"unexpected {found}; expected {_describe(e.expected)}"
        if tok.type == "$END" and "SEMICOLON" in e.expected:
            message += " (a neutral-text rung must end with ';')"
        elif tok.type == "$END" and "EOR" in e.expected:
            message += " (SOR without EOR)"
    return LadderError(pos, message, context)
