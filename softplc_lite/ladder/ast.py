"""The typed syntax tree both rung syntaxes parse to.

Every node carries its source position (``pos``: file, line, column) for
error messages; positions take no part in equality, so the mnemonic and the
neutral-text forms of one rung compare equal and ``fmt`` round trips can be
checked with ``==``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from ..datatable import Address


@dataclass(frozen=True)
class Pos:
    source: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.source}:{self.line}:{self.column}"


NOWHERE = Pos("<generated>", 0, 0)


def _pos() -> Pos:
    return field(default=NOWHERE, compare=False, repr=False)


# -- operands ------------------------------------------------------------------


@dataclass(frozen=True)
class Const:
    """A number: an int (decimal or 0x hex) or a float. ``hex`` says it was
    written 0x...: a hex constant is a 16-bit pattern (0xFFFF is -1), a
    decimal one its value (docs/language.md); fmt prints it back in hex."""

    value: int | float
    pos: Pos = _pos()
    hex: bool = field(default=False, compare=False, repr=False)


@dataclass(frozen=True)
class Placeholder(Const):
    """Stands in for an operand the parser refused (a bad address, an
    unknown function) while it goes on to list every problem: that problem
    is already reported, so the validator says nothing more about it."""


@dataclass(frozen=True)
class AddressRef:
    address: Address
    pos: Pos = _pos()


@dataclass(frozen=True)
class SymbolRef:
    """A name: a declared symbol, resolved to an address by the validator."""

    name: str
    pos: Pos = _pos()


@dataclass(frozen=True)
class Text:
    """A quoted string operand in mnemonic form (kept for TLMs)."""

    value: str
    pos: Pos = _pos()


@dataclass(frozen=True)
class BinOp:
    op: str  # + - * | MOD ** AND OR XOR = <> < <= > >=
    left: "Expr"
    right: "Expr"
    pos: Pos = _pos()


@dataclass(frozen=True)
class UnaryOp:
    op: str  # NEG NOT
    operand: "Expr"
    pos: Pos = _pos()


@dataclass(frozen=True)
class Call:
    func: str  # SQR ABS ...
    arg: "Expr"
    pos: Pos = _pos()


Expr = Union[Const, AddressRef, SymbolRef, BinOp, UnaryOp, Call]
Operand = Union[Const, AddressRef, SymbolRef, Text, BinOp, UnaryOp, Call]


# -- rungs -----------------------------------------------------------------------


@dataclass
class Instruction:
    mnemonic: str
    operands: list[Operand]
    pos: Pos = _pos()


@dataclass
class Branch:
    """Parallel legs; the branch passes power if any leg does."""

    legs: list[list["Element"]]
    pos: Pos = _pos()


Element = Union[Instruction, Branch]


@dataclass
class Rung:
    elements: list[Element]
    comment: str | None = None
    pos: Pos = _pos()


@dataclass
class ProgramFile:
    number: int
    name: str | None
    rungs: list[Rung]
    pos: Pos = _pos()


@dataclass
class DataDecl:
    """``DATA N10 20 = 1 2 3``: a data file, its size, initial values."""

    file: str
    size: int
    values: list[int | float | str]
    pos: Pos = _pos()


@dataclass
class SymbolDecl:
    name: str
    address: Address
    pos: Pos = _pos()


@dataclass
class Program:
    files: dict[int, ProgramFile] = field(default_factory=dict)
    data: list[DataDecl] = field(default_factory=list)
    symbols: dict[str, SymbolDecl] = field(default_factory=dict)

    @property
    def main(self) -> ProgramFile:
        return self.files[MAIN_FILE]


MAIN_FILE = 2


def walk(elements: list[Element]):
    """Every instruction in a series, branches included, in scan order."""
    for el in elements:
        if isinstance(el, Branch):
            for leg in el.legs:
                yield from walk(leg)
        else:
            yield el


def leaves(operand):
    """The leaves of an operand or expression (constants, addresses,
    symbols, text), left to right."""
    if isinstance(operand, BinOp):
        yield from leaves(operand.left)
        yield from leaves(operand.right)
    elif isinstance(operand, UnaryOp):
        yield from leaves(operand.operand)
    elif isinstance(operand, Call):
        yield from leaves(operand.arg)
    else:
        yield operand


def address_refs(operand):
    """The addresses an operand or expression reads, left to right."""
    return (leaf for leaf in leaves(operand) if isinstance(leaf, AddressRef))
