"""Program symbols: one resolver for every place a name is taken.

A symbol names an address (``SYMBOL PollTimer T4:0``). Wherever an address
is taken (rung operands, CPT/CMP expressions, ``--set``, ``--print``,
``--watch``, ``--force``, ``--break-when``, a watch file, ``[display]``)
the text may be a symbol with a suffix:

- ``PollTimer.DN`` / ``PollTimer/DN``: a status bit of a T, C or R element
  (``.`` and ``/`` both name a status bit, as ``T4:0.DN`` and ``T4:0/DN`` do);
- ``PollTimer.ACC``: a word member (PRE ACC LEN POS);
- ``Flags/3``: bit 3 of a word symbol (``Flags.ACC/3`` of a member word);
- ``Levels[3]``: the element 3 further on (``Levels`` is N7:10, so N7:13),
  which may take a member or bit after it (``Timers[2].DN``).

Names compare without regard to case, as mnemonics and addresses do.
Text shaped like an address (one or two letters, optional digits, then
``:`` or ``/``, the ladder lexer's ADDRESS shape) is always an address:
``B3/0`` is never a symbol ``B3`` with a bit. See docs/language.md.
"""

from __future__ import annotations

import re
from typing import Mapping

from ..datatable import MAX_ELEMENTS, Address, AddressError, parse_address
from ..datatable.address import SLC_MAX_SLOT, SLC_SLOT_WORDS, SLC_WORDS
from ..datatable.errors import DataTableError
from ..datatable.filetypes import WORD_BITS
from .spelling import closest

# The ladder grammar's ADDRESS terminal, as far as it decides: text that
# starts this way is lexed as an address (ladder.lark), so here too.
_ADDRESS_SHAPE = re.compile(r"#?[A-Za-z]{1,2}[0-9]*(\[[^\]\s]*\])?[:/]")
# A symbol and its suffix: [offset] then .member then /bit (each optional).
_SYMBOL_TEXT = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[([0-9]+)\])?(?:\.([A-Za-z]+))?(?:/([A-Za-z]+|[0-9]+))?")


class SymbolError(AddressError):
    """A symbol that is not declared, or a suffix its element does not have.
    An AddressError, so every site that reports a bad address reports it;
    ``position`` is where in ``text`` the problem starts."""

    def __init__(self, text: str, position: int, reason: str) -> None:
        self.text = text
        self.position = max(0, min(position, len(text)))
        self.reason = reason
        DataTableError.__init__(self, f"{text!r}: {reason}")


class SymbolIndex:
    """Declared symbols by upper-cased name (declarations keep their spelling)."""

    def __init__(self, symbols: Mapping[str, object] | None) -> None:
        # A Logix app's symbols are its tags: ``resolve_path(text)`` gives a tag path's address.
        self.resolve_path = getattr(symbols, "resolve_path", None)
        self.by_upper = {name.upper(): decl for name, decl in (symbols or {}).items()}
        self.names = [getattr(d, "name", n) for n, d in (symbols or {}).items()]

    def get(self, name: str):
        return self.by_upper.get(name.upper())

    def declaration(self, text: str):
        """The declared symbol ``text`` names, suffix or not (``PollTimer.DN``
        names PollTimer), or None."""
        return self.get(symbol_base(text) or text)

    def nearest(self, name: str) -> str | None:
        """The declared symbol closest to ``name``, for "did you mean"
        (spelling.py: a swap of two letters is one edit, ``Strat`` is Start)."""
        return closest(name, self.names)


def index(symbols) -> SymbolIndex:
    return symbols if isinstance(symbols, SymbolIndex) else SymbolIndex(symbols)


def is_name(text: str, symbols=None) -> bool:
    """True when ``text`` names something by a name (a program symbol, or a
    tag path of a Logix app), not by its data table address: what labels
    show the name beside the address."""
    names = index(symbols)
    if names.resolve_path is not None:
        try:
            names.resolve_path(text)
            return True
        except AddressError:
            return False
    return is_symbol_text(text)


def is_symbol_text(text: str) -> bool:
    """True when ``text`` is taken as a symbol (with or without a suffix),
    not as an address."""
    return not _ADDRESS_SHAPE.match(text) and _SYMBOL_TEXT.fullmatch(text) is not None


def symbol_base(text: str) -> str | None:
    """The symbol name part of ``text`` (``PollTimer`` of ``PollTimer.DN``)."""
    m = _SYMBOL_TEXT.match(text)
    return m.group(1) if m else None


def resolve_name(text: str, symbols=None) -> Address:
    """The address ``text`` names: a data table address, or a declared symbol
    with an optional ``[offset]``, ``.member`` and ``/bit``. Raises
    AddressError (SymbolError for a symbol problem) saying what is wrong."""
    text = text.strip()
    resolve_path = index(symbols).resolve_path
    if resolve_path is not None:  # a tag path (Tank.Level, Arr[3].5), else an address of the table
        try:
            return resolve_path(text)
        except SymbolError:
            if not _ADDRESS_SHAPE.match(text):
                raise
    if not is_symbol_text(text):
        try:
            return parse_address(text)
        except AddressError as e:
            base = symbol_base(text)
            if base is None or index(symbols).get(base) is None:
                raise
            raise SymbolError(text, e.position, f"{e.reason} ({text} reads as an address: one or two letters "
                              f"and digits before '/' or ':' are one, in a rung too; give symbol {base} a "
                              "longer name to take its bits)") from None
    m = _SYMBOL_TEXT.fullmatch(text)
    name, offset, member, bit = m.groups()
    table = index(symbols)
    decl = table.get(name)
    if decl is None:
        near = table.nearest(name)
        hint = f" (did you mean {near}?)" if near else ""
        raise SymbolError(text, 0, f"{name} is neither an address nor a program symbol{hint}")
    return apply_suffix(text, getattr(decl, "name", name), decl.address, m)


def apply_suffix(text: str, name: str, address: Address, m: re.Match) -> Address:
    """``address`` (what symbol ``name`` stands for) with the offset, member
    and bit of the match ``m`` of ``text`` applied."""
    _, offset, member, bit = m.groups()
    a = address
    ftype = a.ftype
    what = _what(name, a)
    if offset is not None:
        if a.member is not None or a.bit is not None or not isinstance(a.element, int) or not a.is_direct:
            raise SymbolError(text, m.start(2) - 1, f"{what}: an [offset] applies to a symbol of a whole, "
                              "direct element (N7:10, T4:0), not to a bit, member or indirect address")
        element = a.element + int(offset)
        if element >= MAX_ELEMENTS:
            raise SymbolError(text, m.start(2), f"{what}: {name}[{offset}] is element {element}, past the "
                              f"last element {MAX_ELEMENTS - 1}")
        if a.slc and element >= SLC_WORDS:
            raise SymbolError(text, m.start(2), f"{what}: {name}[{offset}] is word {element} of the I/O file, "
                              f"past the last SLC slot {SLC_MAX_SLOT} (I:{SLC_MAX_SLOT}.{SLC_SLOT_WORDS - 1})")
        a = a.with_element(element)
    if member is not None:
        if a.member is not None or a.bit is not None:
            raise SymbolError(text, m.start(3) - 1, f"{what}: it has no members")
        found = ftype.members_by_name.get(member.upper())
        if found is None:
            raise SymbolError(text, m.start(3), f"{what}: {_members(ftype)}")
        if hasattr(found, "bit"):
            a = Address(a.type_letter, a.file, a.element, None, found.bit, a.indexed)
        else:
            a = Address(a.type_letter, a.file, a.element, found.name, None, a.indexed)
    if bit is not None:
        at = m.start(4)
        if a.bit is not None:
            raise SymbolError(text, at - 1, f"{what}: it has no bits of its own")
        if not ftype.has_bits:
            raise SymbolError(text, at - 1, f"{what}: {ftype.title} elements have no bits")
        if bit.isdigit():
            # octal for a PLC-5 I/O address (I:12/17); an SLC one (I:1.0/8) numbers its bits in decimal
            base = 8 if ftype.octal and not a.slc else 10
            # An element's bits are its item's (L: 0..31, SI 0..7, LI 0..63); a member word's 0..15.
            width = WORD_BITS if a.member is not None else ftype.element_bits
            try:
                number = int(bit, base)
            except ValueError:
                number = width  # an 8 or 9 in an octal bit number
            if number >= width:
                top = "17 (octal)" if base == 8 else str(width - 1)
                raise SymbolError(text, at, f"{what}: bit {bit} is past bit {top}")
        else:
            found = ftype.members_by_name.get(bit.upper())
            if found is None or not hasattr(found, "bit") or a.member is not None:
                raise SymbolError(text, at, f"{what}: {_members(ftype)}" if a.member is None
                                  else f"{what}: a member word's bits are numbered 0..15")
            number = found.bit
        a = Address(a.type_letter, a.file, a.element, a.member, number, a.indexed, a.slc)
    return a


def _what(name: str, a: Address) -> str:
    """``PollTimer is T4:0, a timer`` for error messages."""
    kind = a.kind.value
    if a.member is None and a.bit is None and a.ftype.is_structure and not a.ftype.is_string:
        kind = a.ftype.title
    article = "an" if kind[:1] in "aeiou" else "a"
    return f"{name} is {a}, {article} {kind}"


def _members(ftype) -> str:
    if ftype.is_structure and not ftype.is_string:
        return f"members {ftype.member_names()}"
    if ftype.has_bits and ftype.item_bits != WORD_BITS:
        return f"{ftype.title} elements have no named members, only bits /0 to /{ftype.item_bits - 1}"
    if ftype.has_bits:
        return "a word has no named members, only bits /0 to /15 (octal /0 to /17 for I and O)"
    return f"{ftype.title} elements have no members or bits"
