"""The typed syntax tree both rung syntaxes parse to.

Every node carries its source position (``pos``: file, line, column) for
error messages; positions take no part in equality, so the mnemonic and the
neutral-text forms of one rung compare equal and ``fmt`` round trips can be
checked with ``==``.

The nodes a program has one of per instruction (operands, instructions,
branches, rungs) are compact (the memory target: at most 300 bytes an instruction
after load): ``__slots__`` classes that keep their position as two slots
(source and line as one int shared by the nodes of a line, and the column)
and build the ``Pos`` when asked, not one Pos object per node. Operand
nodes are immutable and hashable (as frozen dataclasses were); instructions,
branches and rungs may be changed (the parser appends to them). A sequence
field (operands, elements, legs) may be a list (the parser's tree) or a
tuple (the validated tree, which keeps no spare list capacity); the two
compare equal item by item.
"""

from __future__ import annotations

import threading
from dataclasses import FrozenInstanceError, dataclass, field
from typing import Union

from ..datatable import Address
from ..errors import NOWHERE, Pos  # noqa: F401 (names of this module's too)




def _pos() -> Pos:
    return field(default=NOWHERE, compare=False, repr=False)


# A node keeps its source and line as one int, ``_where``: the source's
# number in _SOURCES (each source name is kept once per process) above
# _LINE_BITS bits of line. The int of the previous node is reused when the
# next is on the same line: nodes are built in source order, so a program
# keeps about one such int per line, not one per node.
_LINE_BITS = 32
_LINE_BIAS = 1 << (_LINE_BITS - 1)  # lines -2**31 .. 2**31-1 fit
_LINE_MASK = (1 << _LINE_BITS) - 1
_SOURCES: list[str] = []
_SOURCE_NUMBERS: dict[str, int] = {}
_registering = threading.Lock()
_last: tuple = (None, None, 0)  # (source, line, where) of the previous node


def _where_of(pos: Pos) -> int:
    global _last
    source, line = pos.source, pos.line
    last = _last
    if line == last[1] and source is last[0]:
        return last[2]
    number = _SOURCE_NUMBERS.get(source)
    if number is None:
        with _registering:
            number = _SOURCE_NUMBERS.setdefault(source, len(_SOURCES))
            if number == len(_SOURCES):
                _SOURCES.append(source)
    if not -_LINE_BIAS <= line < _LINE_BIAS:
        raise ValueError(f"line {line} out of range")
    where = number << _LINE_BITS | (line + _LINE_BIAS)
    _last = (source, line, where)
    return where


class _Node:
    """Position storage shared by the compact nodes."""

    __slots__ = ("_where", "_column")
    _fields: tuple[str, ...] = ()  # the fields that take part in equality and repr, in constructor order

    @property
    def pos(self) -> Pos:
        where = self._where
        return Pos(_SOURCES[where >> _LINE_BITS], (where & _LINE_MASK) - _LINE_BIAS, self._column)

    def __repr__(self) -> str:
        inner = ", ".join(f"{name}={getattr(self, name)!r}" for name in self._fields)
        return f"{type(self).__name__}({inner})"


# -- operands ------------------------------------------------------------------


class _Operand(_Node):
    """An immutable, hashable operand node (value semantics, position aside)."""

    __slots__ = ()

    def __setattr__(self, name, value):
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name):
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def _values(self) -> tuple:
        return tuple(getattr(self, name) for name in self._fields)

    def __eq__(self, other):
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._values() == other._values()

    def __hash__(self) -> int:
        return hash(self._values())

    def __reduce__(self):
        # Through the constructor: the slots refuse pickle's setattr.
        return _rebuild, (type(self), self._values(), self.pos, self._extra())

    def _extra(self) -> dict:
        return {}


def _rebuild(cls, values, pos, extra):
    return cls(*values, pos, **extra)


_set_where = _Node._where.__set__
_set_column = _Node._column.__set__


def _place(node: _Node, pos: Pos) -> None:
    """Store ``pos`` in an immutable node (its __setattr__ refuses)."""
    _set_where(node, _where_of(pos))
    _set_column(node, pos.column)


class Const(_Operand):
    """A number: an int (decimal or 0x hex) or a float. ``hex`` says it was
    written 0x...: a hex constant is a 16-bit pattern (0xFFFF is -1), a
    decimal one its value (docs/language.md); fmt prints it back in hex."""

    __slots__ = ("value", "hex")
    _fields = ("value",)
    __match_args__ = ("value",)

    def __init__(self, value: int | float, pos: Pos = NOWHERE, hex: bool = False) -> None:
        _set_const_value(self, value)
        _set_const_hex(self, hex)
        _place(self, pos)

    def _values(self) -> tuple:
        return (self.value,)

    def _extra(self) -> dict:
        return {"hex": self.hex} if self.hex else {}


_set_const_value = Const.value.__set__
_set_const_hex = Const.hex.__set__


class Placeholder(Const):
    """Stands in for an operand the parser refused (a bad address, an
    unknown function) while it goes on to list every problem: that problem
    is already reported, so the validator says nothing more about it."""

    __slots__ = ()


class AddressRef(_Operand):
    __slots__ = ("address",)
    _fields = ("address",)
    __match_args__ = ("address",)

    def __init__(self, address: Address, pos: Pos = NOWHERE) -> None:
        _set_address(self, address)
        _place(self, pos)

    def _values(self) -> tuple:
        return (self.address,)


_set_address = AddressRef.address.__set__


class SymbolRef(_Operand):
    """A name: a declared symbol, resolved to an address by the validator."""

    __slots__ = ("name",)
    _fields = ("name",)
    __match_args__ = ("name",)

    def __init__(self, name: str, pos: Pos = NOWHERE) -> None:
        SymbolRef.name.__set__(self, name)
        _place(self, pos)


class Text(_Operand):
    """A quoted string operand in mnemonic form (kept for TLMs)."""

    __slots__ = ("value",)
    _fields = ("value",)
    __match_args__ = ("value",)

    def __init__(self, value: str, pos: Pos = NOWHERE) -> None:
        Text.value.__set__(self, value)
        _place(self, pos)


class BinOp(_Operand):
    __slots__ = ("op", "left", "right")  # op: + - * | MOD ** AND OR XOR = <> < <= > >=
    _fields = ("op", "left", "right")
    __match_args__ = _fields

    def __init__(self, op: str, left: "Expr", right: "Expr", pos: Pos = NOWHERE) -> None:
        BinOp.op.__set__(self, op)
        BinOp.left.__set__(self, left)
        BinOp.right.__set__(self, right)
        _place(self, pos)


class UnaryOp(_Operand):
    __slots__ = ("op", "operand")  # op: NEG NOT
    _fields = ("op", "operand")
    __match_args__ = _fields

    def __init__(self, op: str, operand: "Expr", pos: Pos = NOWHERE) -> None:
        UnaryOp.op.__set__(self, op)
        UnaryOp.operand.__set__(self, operand)
        _place(self, pos)


class Call(_Operand):
    __slots__ = ("func", "arg")  # func: SQR ABS ...
    _fields = ("func", "arg")
    __match_args__ = _fields

    def __init__(self, func: str, arg: "Expr", pos: Pos = NOWHERE) -> None:
        Call.func.__set__(self, func)
        Call.arg.__set__(self, arg)
        _place(self, pos)


Expr = Union[Const, AddressRef, SymbolRef, BinOp, UnaryOp, Call]
Operand = Union[Const, AddressRef, SymbolRef, Text, BinOp, UnaryOp, Call]


# -- rungs -----------------------------------------------------------------------


def _same_items(a, b) -> bool:
    """Sequence fields compare item by item, list or tuple alike."""
    if type(a) is type(b):
        return a == b
    return len(a) == len(b) and all(x == y for x, y in zip(a, b))


class _Mutable(_Node):
    """A node the parser builds up and a library user may change in place
    (instructions, branches, rungs): unhashable, as mutable dataclasses are."""

    __slots__ = ()
    __hash__ = None  # type: ignore[assignment]

    @_Node.pos.setter
    def pos(self, pos: Pos) -> None:
        self._where, self._column = _where_of(pos), pos.column

    def __reduce__(self):
        return _rebuild, (type(self), tuple(getattr(self, name) for name in self._fields), self.pos, {})


class Instruction(_Mutable):
    """``operands`` is kept as given (the parser's list grows as it reads),
    except that a tuple of one operand node, the most common instruction
    (XIC B3/0) in a validated tree, is kept as that node alone: ``operands``
    gives it back as a 1-tuple (a tuple object less per instruction,
    for the memory target)."""

    __slots__ = ("mnemonic", "_operands")
    _fields = ("mnemonic", "operands")
    __match_args__ = _fields

    def __init__(self, mnemonic: str, operands: list[Operand] | tuple[Operand, ...], pos: Pos = NOWHERE) -> None:
        self.mnemonic = mnemonic
        self._operands = _kept(operands)
        self._where = _where_of(pos)
        self._column = pos.column

    @property
    def operands(self) -> list[Operand] | tuple[Operand, ...]:
        operands = self._operands
        return (operands,) if isinstance(operands, _Operand) else operands

    @operands.setter
    def operands(self, operands: list[Operand] | tuple[Operand, ...]) -> None:
        self._operands = _kept(operands)

    def __eq__(self, other):
        if other.__class__ is not Instruction:
            return NotImplemented
        return self.mnemonic == other.mnemonic and _same_items(self.operands, other.operands)

    def copy_with(self, mnemonic: str, operands) -> "Instruction":
        """This instruction, at its position, with other fields (the
        validator's resolved copy; no Pos built on the way)."""
        new = _new(Instruction)
        new.mnemonic, new._operands = mnemonic, _kept(operands)
        new._where, new._column = _shared_where(self._where, operands), self._column
        return new


def _shared_where(where: int, parts) -> int:
    """``where``, or the equal int its first part keeps: a parser that builds
    operands, instructions and rungs in separate passes over the text gives
    each pass an int per line; the validated copy keeps one."""
    first = parts[0] if parts else None
    if first is not None and getattr(first, "_where", None) == where:
        return first._where
    return where


def _kept(operands):
    """How an instruction keeps ``operands``: a 1-tuple of a node as the node."""
    if operands.__class__ is tuple and len(operands) == 1 and isinstance(operands[0], _Operand):
        return operands[0]
    return operands


class Branch(_Mutable):
    """Parallel legs; the branch passes power if any leg does."""

    __slots__ = ("legs",)
    _fields = ("legs",)
    __match_args__ = _fields

    def __init__(self, legs: list[list["Element"]], pos: Pos = NOWHERE) -> None:
        self.legs = legs
        self._where = _where_of(pos)
        self._column = pos.column

    def __eq__(self, other):
        if other.__class__ is not Branch:
            return NotImplemented
        mine, theirs = self.legs, other.legs
        return len(mine) == len(theirs) and all(_same_items(a, b) for a, b in zip(mine, theirs))

    def copy_with(self, legs) -> "Branch":
        new = _new(Branch)
        new.legs = legs
        new._where, new._column = _shared_where(self._where, legs[0] if legs else ()), self._column
        return new


Element = Union[Instruction, Branch]


class Rung(_Mutable):
    __slots__ = ("elements", "comment")
    _fields = ("elements", "comment")
    __match_args__ = _fields

    def __init__(self, elements: list[Element], comment: str | None = None, pos: Pos = NOWHERE) -> None:
        self.elements = elements
        self.comment = comment
        self._where = _where_of(pos)
        self._column = pos.column

    def __eq__(self, other):
        if other.__class__ is not Rung:
            return NotImplemented
        return self.comment == other.comment and _same_items(self.elements, other.elements)

    def copy_with(self, elements) -> "Rung":
        new = _new(Rung)
        new.elements, new.comment = elements, self.comment
        new._where, new._column = _shared_where(self._where, elements), self._column
        return new


_new = object.__new__


@dataclass
class ProgramFile:
    number: int
    name: str | None
    rungs: list[Rung]
    pos: Pos = _pos()
    listing: "Listing | None" = None  # a file made from text of another language (Structured Text)


@dataclass(frozen=True)
class Arm:
    """One way through an IF or CASE of a :class:`Listing`: taken when rung
    ``rung`` ran with the outcome ``taken_when`` (a condition's rung that
    did not jump), or, ``taken_when`` None, when it ran at all (a label an
    ELSE starts at)."""

    rung: int
    taken_when: bool | None
    label: str  # what the arm is in the text: "IF", "ELSIF", "ELSE", "CASE 1..3", "no arm"
    line: int  # its line in the listing, from 0


@dataclass
class Listing:
    """The text a program file was made from, when it was not ladder (a
    Logix Structured Text routine becomes rungs: logix/st_routine.py): the
    watch view shows the text, coverage counts its statements and arms.
    ``rung_lines[k]``: the line (from 0) rung k was made from;
    ``statements``: the rungs that begin a statement."""

    lines: list[tuple[Pos, str]]
    rung_lines: list[int]
    statements: list[int]
    arms: list[Arm]


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


def instructions_of(elements, out: list | None = None) -> list:
    """Every instruction of ``elements`` (branches opened), in scan order:
    ast.walk as a list, several times faster on a big program's load."""
    if out is None:
        out = []
    for el in elements:
        if el.__class__ is Instruction:
            out.append(el)
        else:
            for leg in el.legs:
                instructions_of(leg, out)
    return out
