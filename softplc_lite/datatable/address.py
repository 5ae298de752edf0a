"""Data table addresses: one parser, one canonical text form.

Forms accepted (see docs/datatable.md for the full table)::

    N7:0   N7:0/3   B3/17   B3:1/1   O:0/0   I:012/17   S:1/15   L9:0   D10:0   A11:0
    L9:0/31   SI12:0/7   LI13:0/63 (bits by the item's width)
    I:1.0/3  O:2.1 (SLC slot.word/bit: word 32*slot + word of the I/O file)
    T4:0.ACC  T4:0/DN  T4:0.DN  C5:0/OV  R6:0.LEN  ST9:0  ST9:0.LEN  F8:2
    #N7:0 (indexed by S:24)   N7:[N7:1]   N[N7:2]:0   N7:0/[N7:3] (indirect)

``parse_address(text)`` returns an :class:`Address`; ``str(address)`` prints
the canonical form, and ``parse_address(str(a)) == a`` for every address.
Canonical choices: type letters and member names upper case; ``O:``/``I:``/
``S:`` for the fixed files; I/O word and bit numbers in octal without leading
zeros; status bits of T/C/R by name (``T4:0/DN``); direct B-file bits in the
bit-number-across-file form (``B3/17``), as RSLogix 5 shows them; an I/O
address written in SLC form (``I:1.0/3``) prints back in SLC form.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from enum import Enum
from functools import cached_property, lru_cache
from typing import Union

from .errors import AddressError
from .filetypes import (
    FILE_TYPES,
    MAX_ELEMENTS,
    MAX_FILE_NUMBER,
    OTHER_INTEGERS,
    WORD_BITS,
    FileType,
)


class ValueKind(Enum):
    """What an address holds, as instruction operands care about it."""

    BIT = "bit"
    WORD = "word"  # a 16-bit signed integer word
    FLOAT = "float"
    # A signed integer element that is not a 16-bit word: L (32-bit), SI
    # (8-bit), LI (64-bit); its width and range are its file's storage.
    LONG = "long"
    STRING = "string"  # a whole ST element
    TIMER = "timer"  # a whole T element
    COUNTER = "counter"
    CONTROL = "control"


#: SLC I/O addresses I:e.s/b: slot e (0..30) word s (0..31) is word
#: SLC_SLOT_WORDS * e + s of the I/O file (softplc choice, docs/datatable.md).
SLC_SLOT_WORDS = 32
SLC_MAX_SLOT = 30
SLC_WORDS = (SLC_MAX_SLOT + 1) * SLC_SLOT_WORDS  # I/O words an SLC address can name: I:0.0 to I:30.31

_STRUCT_KINDS = {"T": ValueKind.TIMER, "C": ValueKind.COUNTER, "R": ValueKind.CONTROL}

Part = Union[int, "Address"]


@dataclass(frozen=True)
class Address:
    """A parsed data table address.

    ``file``, ``element`` and ``bit`` are numbers, or an ``Address`` of the
    word that holds the number (indirect addressing). ``element`` is None only
    for a B-file bit addressed across the file with an indirect bit number
    (``B3/[N7:0]``). ``bit`` is a bit of the element's word (or of the member
    word): status bits like DN are bits of word 0 and print by name.
    """

    type_letter: str
    file: Part
    element: Part | None
    member: str | None = None  # word member: PRE ACC LEN POS
    bit: Part | None = None
    indexed: bool = False
    # Written as an SLC slot.word address (I:1.0/3): only how it prints. The
    # same word in PLC-5 form is the same address (equal, same hash).
    slc: bool = field(default=False, compare=False)

    # -- what it is -------------------------------------------------------
    @property
    def ftype(self) -> FileType:
        return FILE_TYPES[self.type_letter]

    @cached_property  # asked for every operand at load; an Address never changes
    def is_direct(self) -> bool:
        """True when no part comes from another word or the index register."""
        return not self.indexed and not any(
            isinstance(p, Address) for p in (self.file, self.element, self.bit)
        )

    @cached_property
    def kind(self) -> ValueKind:
        ftype = self.ftype
        if self.bit is not None:
            return ValueKind.BIT
        if self.member is not None:
            return ValueKind.WORD
        if ftype.is_string:
            return ValueKind.STRING
        if ftype.letter in _STRUCT_KINDS:
            return _STRUCT_KINDS[ftype.letter]
        if ftype.letter == "F":
            return ValueKind.FLOAT
        if ftype.storage in OTHER_INTEGERS:
            return ValueKind.LONG
        return ValueKind.WORD

    def file_name(self) -> str:
        """``N7`` for a direct file number; ``N[N7:2]`` for an indirect one."""
        if isinstance(self.file, Address):
            return f"{self.type_letter}[{self.file}]"
        return f"{self.type_letter}{self.file}"

    def with_element(self, element: int) -> "Address":
        """The same address at another element (used for blocks and files)."""
        return Address(self.type_letter, self.file, element, self.member, self.bit, self.indexed, self.slc)

    # -- canonical text -----------------------------------------------------
    def __str__(self) -> str:
        ftype = self.ftype
        out = ["#"] if self.indexed else []
        if isinstance(self.file, Address):
            out.append(f"{self.type_letter}[{self.file}]")
        elif ftype.fixed_number is not None:
            out.append(self.type_letter)
        else:
            out.append(f"{self.type_letter}{self.file}")
        if (
            ftype.bits_across_file
            and isinstance(self.element, int)
            and isinstance(self.bit, int)
        ):
            out.append(f"/{self.element * WORD_BITS + self.bit}")
            return "".join(out)
        # An SLC address stepped past the last slot (a block, a symbol's offset)
        # prints in the PLC-5 form, the same word: I:31.0 would not parse back.
        if self.slc and isinstance(self.element, int) and self.element < SLC_WORDS:
            slot, word = divmod(self.element, SLC_SLOT_WORDS)
            out.append(f":{slot}.{word}")
            if isinstance(self.bit, int):
                out.append(f"/{self.bit}")
            return "".join(out)
        if self.element is not None:
            out.append(":" + _number_text(self.element, ftype.octal))
        if self.member is not None:
            out.append("." + self.member)
        if self.bit is not None:
            name = None
            if isinstance(self.bit, int) and self.member is None:
                name = ftype.bit_name(self.bit)
            out.append("/" + (name or _number_text(self.bit, ftype.octal)))
        return "".join(out)

    def __repr__(self) -> str:
        return f"Address({str(self)!r})"


def _number_text(part: Part, octal: bool) -> str:
    if isinstance(part, Address):
        return f"[{part}]"
    return format(part, "o") if octal else str(part)


# ---------------------------------------------------------------------------
# Parser: a small recursive-descent scanner over the text; every error names
# the offending position and what was expected there.


class _Scanner:
    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0

    def peek(self, n: int = 1) -> str:
        return self.text[self.pos:self.pos + n]

    def at_end(self) -> bool:
        return self.pos >= len(self.text)

    def error(self, reason: str, pos: int | None = None) -> AddressError:
        return AddressError(self.text, self.pos if pos is None else pos, reason)

    def found(self) -> str:
        return f"'{self.text[self.pos]}'" if not self.at_end() else "the end"

    def take(self, ch: str) -> bool:
        if self.text.startswith(ch, self.pos):
            self.pos += len(ch)
            return True
        return False

    # One regex match a run, not a Python step a character: a 10,000-rung
    # program names thousands of distinct addresses, each parsed at load.
    # ASCII only, as str.isascii() with isdigit()/isalpha() accept.
    def digits(self) -> str:
        run = _DIGITS(self.text, self.pos).group()
        self.pos += len(run)
        return run

    def name(self) -> str:
        run = _LETTERS(self.text, self.pos).group()
        self.pos += len(run)
        return run


_DIGITS = re.compile("[0-9]*").match
_LETTERS = re.compile("[A-Za-z]*").match


def parse_address(text: str) -> Address:
    """Parse address text; raise :class:`AddressError` saying what is wrong."""
    if not isinstance(text, str):
        raise TypeError(f"address text must be str, not {type(text).__name__}")
    return _parse_cached(text)


@lru_cache(maxsize=4096)
def _parse_cached(text: str) -> Address:
    sc = _Scanner(text)
    if not text:
        raise sc.error("empty address; expected something like N7:0")
    addr = _parse(sc, nested=False)
    if not sc.at_end():
        raise sc.error(f"unexpected {sc.found()} after a complete address '{text[:sc.pos]}'")
    return addr


def _parse(sc: _Scanner, nested: bool) -> Address:
    indexed = sc.take("#")
    if indexed and nested:
        raise sc.error("an indirect reference cannot be indexed", sc.pos - 1)
    type_pos = sc.pos
    letters = sc.name().upper()
    ftype, rest = _file_type(letters)
    if ftype is None:
        raise sc.error(
            f"unknown file type '{letters or sc.peek()}' (expected one of "
            f"{' '.join(FILE_TYPES)})",
            type_pos,
        )
    # A name like "N7" is split by name(); "ST" + digits likewise. Anything
    # glued on after the type letters (e.g. "NX7") is not a file type.
    if rest:
        raise sc.error(
            f"unknown file type '{letters}' (expected one of {' '.join(FILE_TYPES)})", type_pos
        )
    file_part = _file_number(sc, ftype)

    element: Part | None = None
    member: str | None = None
    bit: Part | None = None

    if sc.take(":"):
        slot_word = _slc_slot_word(sc, ftype)
        if slot_word is not None:
            if sc.take("/"):
                bit = _number(sc, "bit number", False, WORD_BITS - 1)
            addr = Address(ftype.letter, file_part, slot_word, None, bit, indexed, slc=True)
            return _checked_nested(sc, addr, nested, type_pos)
        element = _element_number(sc, ftype)
        if sc.take("."):
            member, bit = _member(sc, ftype)
        if sc.peek() == "/":
            if bit is not None:
                raise sc.error(f"'{ftype.letter}' element already names a status bit")
            sc.take("/")
            bit = _bit(sc, ftype, member)
    elif sc.peek() == "/" and ftype.bits_across_file:
        sc.take("/")
        bit = _bit_across_file(sc)
        if isinstance(bit, int):
            element, bit = divmod(bit, WORD_BITS)
    else:
        example = "B3/17 or B3:1/1" if ftype.bits_across_file else f"{_example(ftype)}"
        raise sc.error(f"expected ':' and an element number after the file, as in {example}")

    addr = Address(ftype.letter, file_part, element, member, bit, indexed)
    return _checked_nested(sc, addr, nested, type_pos)


def _checked_nested(sc: _Scanner, addr: Address, nested: bool, type_pos: int) -> Address:
    if nested and addr.kind is not ValueKind.WORD:
        raise AddressError(
            sc.text, type_pos,
            f"an indirect reference must be a word address such as N7:1, not "
            f"'{addr}' ({addr.kind.value})",
        )
    if nested and not addr.is_direct:
        raise AddressError(sc.text, type_pos, "an indirect reference cannot itself be indirect")
    return addr


def _slc_slot_word(sc: _Scanner, ftype: FileType) -> int | None:
    """``1.0`` after ``I:``: an SLC slot and word (both decimal), as the I/O
    file's word SLC_SLOT_WORDS * slot + word; None (nothing taken) when the
    element is not written that way (PLC-5's octal ``I:012``)."""
    if not ftype.octal:
        return None
    start = sc.pos
    digits = sc.digits()
    if not digits or sc.peek() != ".":
        sc.pos = start
        return None
    slot = _to_int(digits)
    if slot > SLC_MAX_SLOT:
        raise sc.error(f"slot {_shown(digits)} out of range 0..{SLC_MAX_SLOT} (SLC I/O address "
                       f"{ftype.letter}:slot.word/bit)", start)
    sc.take(".")
    word = _number(sc, "word number", False, SLC_SLOT_WORDS - 1)
    return slot * SLC_SLOT_WORDS + word


def _example(ftype: FileType) -> str:
    if ftype.fixed_number is not None:
        return f"{ftype.letter}:0"
    return f"{ftype.letter}{ftype.default_number or 10}:0"


def _file_type(letters: str) -> tuple[FileType | None, str]:
    if letters in FILE_TYPES:
        return FILE_TYPES[letters], ""
    if letters[:2] in FILE_TYPES:
        return FILE_TYPES[letters[:2]], letters[2:]
    if letters[:1] in FILE_TYPES:
        return FILE_TYPES[letters[:1]], letters[1:]
    return None, letters


def _file_number(sc: _Scanner, ftype: FileType) -> Part:
    pos = sc.pos
    if sc.peek() == "[":
        if ftype.fixed_number is not None:
            raise sc.error(f"the {ftype.title} file is always {ftype.letter}{ftype.fixed_number}")
        return _indirect(sc)
    digits = sc.digits()
    if not digits:
        if ftype.fixed_number is not None:
            return ftype.fixed_number
        raise sc.error(
            f"{ftype.title} ({ftype.letter}) files need a file number 3..{MAX_FILE_NUMBER}, "
            f"as in {_example(ftype)}"
        )
    number = _to_int(digits)
    if ftype.fixed_number is not None:
        if number != ftype.fixed_number:
            raise sc.error(
                f"the {ftype.title} file is {ftype.letter}{ftype.fixed_number}, not "
                f"{ftype.letter}{_shown(digits)}", pos,
            )
        return number
    if number < 3 or number > MAX_FILE_NUMBER:
        raise sc.error(
            f"file number {_shown(digits)} out of range: {ftype.letter} files are numbered "
            f"3..{MAX_FILE_NUMBER} (0, 1, 2 are O, I and S)", pos,
        )
    return number


# No address number needs more digits than this; a longer run of digits is
# out of range without being converted (Python refuses to convert more than
# 4,300 digits, and converting is quadratic in the digits).
_MAX_DIGITS = 9


def _to_int(digits: str, base: int = 10) -> int:
    """``digits`` as an int, or a value past every limit when too long."""
    return int(digits, base) if len(digits) <= _MAX_DIGITS else 10 ** _MAX_DIGITS


def _shown(digits: str) -> str:
    """A number as a message quotes it: never thousands of characters."""
    return digits if len(digits) <= 20 else f"{digits[:8]}...({len(digits)} digits)"


def _indirect(sc: _Scanner) -> "Address":
    open_pos = sc.pos
    sc.take("[")
    inner = _parse(sc, nested=True)
    if not sc.take("]"):
        raise sc.error(f"expected ']' to close the indirect reference opened at column {open_pos + 1}")
    return inner


def _number(sc: _Scanner, what: str, octal: bool, limit: int) -> int:
    """A decimal (or, for I/O, octal) number; ``what`` is a noun like
    "element number"."""
    pos = sc.pos
    article = "an" if what[0] in "aeiou" else "a"
    if sc.peek() == "-":
        raise sc.error(f"{article} {what} cannot be negative")
    digits = sc.digits()
    if not digits:
        raise sc.error(f"expected {article} {what} but found {sc.found()}")
    if octal:
        bad = next((d for d in digits if d in "89"), None)
        if bad:
            hint = " (an SLC address names the slot and word, decimal: I:1.0/8)" if what == "bit number" else ""
            raise sc.error(f"I/O {what}s are octal; '{bad}' is not an octal digit in '{digits}'{hint}", pos)
        value = _to_int(digits, 8)
    else:
        value = _to_int(digits)
    if value > limit:
        shown = f"{digits} (octal, = {value})" if octal and len(digits) <= _MAX_DIGITS else _shown(digits)
        top = format(limit, "o") if octal else str(limit)
        raise sc.error(f"{what} {shown} out of range 0..{top}", pos)
    return value


def _element_number(sc: _Scanner, ftype: FileType) -> Part:
    if sc.peek() == "[":
        return _indirect(sc)
    return _number(sc, "element number", ftype.octal, MAX_ELEMENTS - 1)


def _member(sc: _Scanner, ftype: FileType) -> tuple[str | None, Part | None]:
    pos = sc.pos
    name = sc.name().upper()
    if not ftype.is_structure:
        raise sc.error(f"{ftype.title} ({ftype.letter}) elements have no members", pos - 1)
    if not name:
        raise sc.error(f"expected a member name ({ftype.member_names()}) after '.'")
    if ftype.is_string and name == "DATA":  # ST9:0.DATA3: code unit 3
        name += sc.digits()
    member = ftype.members_by_name.get(name)
    if member is None:
        chars = f" DATA0..DATA{ftype.chars - 1}" if ftype.is_string else ""
        raise sc.error(
            f"'{name}' is not a member of a {ftype.title} ({ftype.letter}) element; "
            f"members are {ftype.member_names()}{chars}", pos,
        )
    if hasattr(member, "bit"):
        return None, member.bit  # T4:0.DN is T4:0/DN
    return member.name, None


def _bit(sc: _Scanner, ftype: FileType, member: str | None) -> Part:
    pos = sc.pos
    if not ftype.has_bits:
        raise sc.error(f"{ftype.title} ({ftype.letter}) elements have no bits", pos - 1)
    if sc.peek() == "[":
        return _indirect(sc)
    if sc.peek().isalpha():
        name = sc.name().upper()
        m = ftype.members_by_name.get(name)
        if member is None and m is not None and hasattr(m, "bit"):
            return m.bit
        named = " ".join(b.name for b in ftype.bit_members)
        hint = f"; status bits are {named}" if named and member is None else ""
        raise sc.error(f"'{name}' is not a bit of {ftype.title} ({ftype.letter}) elements{hint}", pos)
    # A member (T4:0.ACC/3) is a 16-bit word; an element's bits are its item's.
    top = (WORD_BITS if member is not None else ftype.element_bits) - 1
    return _number(sc, "bit number", ftype.octal, top)


def _bit_across_file(sc: _Scanner) -> Part:
    if sc.peek() == "[":
        return _indirect(sc)
    return _number(sc, "bit number", False, MAX_ELEMENTS * WORD_BITS - 1)
