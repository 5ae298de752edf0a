"""Logix neutral rung text (``XIC(Start)[XIO(Stop),XIC(Jog)]OTE(Motor);``)
read into its parts: instructions with their operand texts, branches with
their legs, each with its column in the rung text. Operands stay text here
(tag paths, numbers, ``?``, expressions, strings): what an operand means
depends on the instruction, which rungs.py knows.

The syntax is what Studio 5000 exports (1756-RM084, "Neutral text"): a
mnemonic, its operands in parentheses separated by commas, branches in
``[...]`` with legs separated by commas, spaces anywhere between tokens
(Studio writes ``[XIC(A) ,XIC(B) ]``), empty legs (``[,]``), a rung ending
with ``;``.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class NInstruction:
    mnemonic: str
    operands: list[tuple[str, int]]  # (text, column of its first character), columns 0-based
    column: int


@dataclass
class NBranch:
    legs: list[list] = field(default_factory=list)
    column: int = 0


# Instructions without operands, taken without their "()" too (Studio writes NOP(); some exports NOP;).
BARE = frozenset({"NOP", "AFI", "TND", "MCR", "RET", "SBR", "EOT", "UID", "UIE", "NXT", "BRK"})


class NeutralError(Exception):
    def __init__(self, message: str, column: int) -> None:
        super().__init__(message)
        self.column = column


def split_operands(text: str, start: int) -> tuple[list[tuple[str, int]], int]:
    """The operands of ``MNEM(`` whose ``(`` is at ``start - 1``: (operand
    texts with their columns, the index after the closing ``)``)."""
    depth, i, begin = 0, start, start
    out: list[tuple[str, int]] = []
    quote = None
    while i < len(text):
        ch = text[i]
        if quote:
            if ch == "$" and i + 1 < len(text):
                i += 2
                continue
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch in "([":
            depth += 1
        elif ch in ")]":
            if depth == 0:
                if ch == "]":
                    raise NeutralError("expected ) to close the operands, found ]", i)
                piece = text[begin:i]
                if out or piece.strip():
                    out.append(_trimmed(piece, begin))
                return out, i + 1
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(_trimmed(text[begin:i], begin))
            begin = i + 1
        i += 1
    raise NeutralError("expected ) to close the operands", start - 1)


def _trimmed(piece: str, begin: int) -> tuple[str, int]:
    stripped = piece.lstrip()
    return stripped.rstrip(), begin + len(piece) - len(stripped)


def parse_rung(text: str) -> list:
    """The elements of one rung (NInstruction and NBranch), in order."""
    pos = 0
    n = len(text)

    def skip(i: int) -> int:
        while i < n and text[i] in " \t\r\n":
            i += 1
        return i

    def series(i: int, in_branch: bool) -> tuple[list, int]:
        elements: list = []
        while True:
            i = skip(i)
            if i >= n:
                if in_branch:
                    raise NeutralError("expected ] to close the branch", n)
                return elements, i
            ch = text[i]
            if ch == ";":
                if in_branch:
                    raise NeutralError("expected ] to close the branch before ;", i)
                return elements, i
            if ch in ",]":
                if not in_branch:
                    raise NeutralError(f"unexpected {ch!r} outside a branch", i)
                return elements, i
            if ch == "[":
                branch = NBranch(column=i)
                i += 1
                while True:
                    leg, i = series(i, True)
                    branch.legs.append(leg)
                    if text[i] == "]":
                        i += 1
                        break
                    i += 1  # the comma
                elements.append(branch)
                continue
            j = i
            while j < n and (text[j].isalnum() or text[j] == "_"):
                j += 1
            if j == i:
                raise NeutralError(f"expected an instruction, found {ch!r}", i)
            mnemonic = text[i:j]
            k = skip(j)
            if (k >= n or text[k] != "(") and mnemonic.upper() in BARE:
                elements.append(NInstruction(mnemonic.upper(), [], i))  # NOP; as some exports write it
                i = k
                continue
            if k >= n or text[k] != "(":
                raise NeutralError(f"expected ( after {mnemonic}", k)
            operands, end = split_operands(text, k + 1)
            elements.append(NInstruction(mnemonic.upper(), operands, i))
            i = end
        return elements, i

    elements, pos = series(pos, False)
    pos = skip(pos)
    if pos < n and text[pos] == ";":
        pos = skip(pos + 1)
    if pos < n:
        raise NeutralError(f"unexpected text after the rung's end: {text[pos:pos + 20]!r}", pos)
    return elements


def instructions_in(elements):
    """Every instruction of a rung's parts (NInstruction), branches opened,
    in scan order (ladder/ast.py's ``walk`` for the ladder's tree)."""
    for el in elements:
        if isinstance(el, NBranch):
            for leg in el.legs:
                yield from instructions_in(leg)
        else:
            yield el
