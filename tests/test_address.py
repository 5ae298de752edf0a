"""Address parsing: every documented form, canonical text, and the errors."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from softplc_lite.datatable import Address, AddressError, ValueKind, parse_address
from softplc_lite.datatable.filetypes import FILE_TYPES

FORMS = [
    # text, canonical, kind, file, element, member, bit, indexed
    ("N7:0", "N7:0", ValueKind.WORD, 7, 0, None, None, False),
    ("N7:0/3", "N7:0/3", ValueKind.BIT, 7, 0, None, 3, False),
    ("B3/17", "B3/17", ValueKind.BIT, 3, 1, None, 1, False),
    ("B3:1/1", "B3/17", ValueKind.BIT, 3, 1, None, 1, False),
    ("B3:1", "B3:1", ValueKind.WORD, 3, 1, None, None, False),
    ("O:0/0", "O:0/0", ValueKind.BIT, 0, 0, None, 0, False),
    ("O0:3/2", "O:3/2", ValueKind.BIT, 0, 3, None, 2, False),
    ("I:1/0", "I:1/0", ValueKind.BIT, 1, 1, None, 0, False),
    ("I:012/17", "I:12/17", ValueKind.BIT, 1, 10, None, 15, False),
    ("S:1/15", "S:1/15", ValueKind.BIT, 2, 1, None, 15, False),
    ("S2:24", "S:24", ValueKind.WORD, 2, 24, None, None, False),
    ("T4:0.ACC", "T4:0.ACC", ValueKind.WORD, 4, 0, "ACC", None, False),
    ("T4:0.PRE", "T4:0.PRE", ValueKind.WORD, 4, 0, "PRE", None, False),
    ("T4:0/DN", "T4:0/DN", ValueKind.BIT, 4, 0, None, 13, False),
    ("T4:0.DN", "T4:0/DN", ValueKind.BIT, 4, 0, None, 13, False),
    ("T4:0/13", "T4:0/DN", ValueKind.BIT, 4, 0, None, 13, False),
    ("T4:2/EN", "T4:2/EN", ValueKind.BIT, 4, 2, None, 15, False),
    ("T4:0/TT", "T4:0/TT", ValueKind.BIT, 4, 0, None, 14, False),
    ("T4:0", "T4:0", ValueKind.TIMER, 4, 0, None, None, False),
    ("C5:0/OV", "C5:0/OV", ValueKind.BIT, 5, 0, None, 12, False),
    ("C5:0/UN", "C5:0/UN", ValueKind.BIT, 5, 0, None, 11, False),
    ("C5:1", "C5:1", ValueKind.COUNTER, 5, 1, None, None, False),
    ("R6:0.LEN", "R6:0.LEN", ValueKind.WORD, 6, 0, "LEN", None, False),
    ("R6:0.POS", "R6:0.POS", ValueKind.WORD, 6, 0, "POS", None, False),
    ("R6:0/ER", "R6:0/ER", ValueKind.BIT, 6, 0, None, 11, False),
    ("R6:0/FD", "R6:0/FD", ValueKind.BIT, 6, 0, None, 8, False),
    ("R6:0", "R6:0", ValueKind.CONTROL, 6, 0, None, None, False),
    ("ST9:0", "ST9:0", ValueKind.STRING, 9, 0, None, None, False),
    ("ST9:0.LEN", "ST9:0.LEN", ValueKind.WORD, 9, 0, "LEN", None, False),
    ("F8:2", "F8:2", ValueKind.FLOAT, 8, 2, None, None, False),
    ("#N7:0", "#N7:0", ValueKind.WORD, 7, 0, None, None, True),
    ("n7:0", "N7:0", ValueKind.WORD, 7, 0, None, None, False),
    ("t4:0.acc", "T4:0.ACC", ValueKind.WORD, 4, 0, "ACC", None, False),
    ("T4:0.ACC/3", "T4:0.ACC/3", ValueKind.BIT, 4, 0, "ACC", 3, False),
    ("N7:9999", "N7:9999", ValueKind.WORD, 7, 9999, None, None, False),
    ("N9999:0", "N9999:0", ValueKind.WORD, 9999, 0, None, None, False),
]


@pytest.mark.parametrize("text,canonical,kind,file,element,member,bit,indexed", FORMS)
def test_forms_parse_to_their_parts(text, canonical, kind, file, element, member, bit, indexed):
    a = parse_address(text)
    assert str(a) == canonical
    assert a.kind is kind
    assert (a.file, a.element, a.member, a.bit, a.indexed) == (file, element, member, bit, indexed)
    assert parse_address(canonical) == a
    assert a.is_direct is (not indexed)


def test_indirect_element():
    a = parse_address("N7:[N7:1]")
    assert a.element == parse_address("N7:1")
    assert str(a) == "N7:[N7:1]"
    assert not a.is_direct


def test_indirect_file_number():
    a = parse_address("N[N7:2]:0")
    assert a.file == parse_address("N7:2")
    assert a.file_name() == "N[N7:2]"
    assert str(a) == "N[N7:2]:0"


def test_indirect_bit_and_bit_across_file():
    assert str(parse_address("N7:0/[N7:3]")) == "N7:0/[N7:3]"
    a = parse_address("B3/[N7:0]")
    assert a.element is None and a.bit == parse_address("N7:0")
    assert str(a) == "B3/[N7:0]"


def test_indirect_may_use_a_timer_word():
    assert str(parse_address("N7:[T4:0.ACC]")) == "N7:[T4:0.ACC]"


def test_same_text_same_object():
    assert parse_address("T4:0.DN") is parse_address("T4:0.DN")  # cached, immutable


ERRORS = [
    ("N7:", "expected an element number but found the end", 3),
    ("N7:-1", "cannot be negative", 3),
    ("X3:0", "unknown file type 'X'", 0),
    ("T4:0.FOO", "'FOO' is not a member of a timer (T) element; members are EN TT DN PRE ACC", 5),
    ("ST9:0/3", "string (ST) elements have no bits", 5),
    ("N7:0/16", "bit number 16 out of range 0..15", 5),
    ("F8:0/1", "float (F) elements have no bits", 4),
    ("N7:10000", "element number 10000 out of range 0..9999", 3),
    ("N7", "expected ':' and an element number", 2),
    ("N2:0", "N files are numbered 3..9999", 1),
    ("N10000:0", "file number 10000 out of range", 1),
    ("I:8", "'8' is not an octal digit", 2),
    ("I:0/20", "out of range 0..17", 4),
    ("O5:0", "the output image file is O0, not O5", 1),
    ("N:0", "integer (N) files need a file number", 1),
    ("N7:0 ", "unexpected ' ' after a complete address 'N7:0'", 4),
    ("", "empty address", 0),
    ("N7:[N7:0", "expected ']' to close the indirect reference opened at column 4", 8),
    ("N7:[F8:0]", "must be a word address", 4),
    ("N7:[N7:0/1]", "must be a word address", 4),
    ("N7:[N7:[N7:0]]", "cannot itself be indirect", 4),
    ("N7:[#N7:0]", "cannot be indexed", 4),
    ("F8:0.X", "float (F) elements have no members", 4),
    ("T4:0/FOO", "'FOO' is not a bit of timer (T) elements; status bits are EN TT DN", 5),
    ("N7:0.ACC", "integer (N) elements have no members", 4),
    ("ST9:0.ACC", "'ACC' is not a member of a string (ST) element", 6),
    ("T4:0.ACC/DN", "'DN' is not a bit", 9),
    ("T4:0.", "expected a member name", 5),
    ("NX7:0", "unknown file type 'NX'", 0),
    ("B3/", "expected a bit number", 3),
    ("B3/160000", "out of range 0..159999", 3),
    ("N7:0/3/4", "unexpected '/'", 6),
]


@pytest.mark.parametrize("text,message,position", ERRORS)
def test_bad_addresses_say_what_is_wrong(text, message, position):
    with pytest.raises(AddressError) as info:
        parse_address(text)
    err = info.value
    assert f"'{text}'" in str(err)  # quotes the text
    assert message in str(err)
    assert err.position == position
    assert err.context().splitlines()[-1] == " " * position + "^"


def test_address_text_must_be_str():
    with pytest.raises(TypeError):
        parse_address(7)  # type: ignore[arg-type]


# -- property: every address prints to text that parses back to itself ------

_plain_types = ["B", "N", "T", "C", "R", "ST", "F"]


@st.composite
def direct_word_addresses(draw) -> Address:
    """Direct word addresses, usable inside an indirect reference."""
    letter = draw(st.sampled_from(["N", "B", "S", "T", "R", "ST", "O", "I"]))
    ftype = FILE_TYPES[letter]
    number = ftype.fixed_number if ftype.fixed_number is not None else draw(st.integers(3, 9999))
    element = draw(st.integers(0, 9999))
    member = None
    if ftype.word_members:
        member = draw(st.sampled_from([m.name for m in ftype.word_members] + ([None] if not ftype.is_string else [])))
    if letter in ("T", "R") and member is None:
        member = ftype.word_members[0].name
    return Address(letter, number, element, member, None, False)


@st.composite
def addresses(draw) -> Address:
    letter = draw(st.sampled_from(list(FILE_TYPES)))
    ftype = FILE_TYPES[letter]
    indirect = direct_word_addresses()
    if ftype.fixed_number is not None:
        file = ftype.fixed_number
    else:
        file = draw(st.one_of(st.integers(3, 9999), indirect))
    element = draw(st.one_of(st.integers(0, 9999), indirect))
    member = None
    if ftype.word_members and draw(st.booleans()):
        member = draw(st.sampled_from([m.name for m in ftype.word_members]))
    bit = None
    if ftype.has_bits and draw(st.booleans()):
        top = 15 if member is not None else ftype.element_bits - 1
        bit = draw(st.one_of(st.integers(0, top), indirect))
    if ftype.bits_across_file and bit is not None and isinstance(element, int) and draw(st.booleans()):
        element = None
        bit = draw(indirect)  # B3/[N7:0]
    indexed = draw(st.booleans())
    return Address(letter, file, element, member, bit, indexed)


@given(addresses())
def test_print_parse_round_trip(a: Address):
    text = str(a)
    assert parse_address(text) == a
    assert str(parse_address(text)) == text


@given(st.text(alphabet="NBTCRSFIO0123456789:/.[]#ACDENLPOSTUVX-", max_size=16))
def test_any_text_parses_or_fails_cleanly(text: str):
    try:
        a = parse_address(text)
    except AddressError as e:
        assert 0 <= e.position <= len(text)
        assert text in str(e)
    else:
        assert parse_address(str(a)) == a
