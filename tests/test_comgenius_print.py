"""COMGENIUS printing (COMPRINT/STRPRINT format engine, manual 4.3.4).

Sections:

- every row of the manual's print tables (conversion chars b d i o u x X s c
  C f e E g G % S R; flags - + space 0 #; width and precision as digits and
  ``*``; ``l``/``L`` long from two words, low word first; ``h`` for a
  one-byte ``%S``);
- the C99 corners the issue lists (where Python's ``%`` differs from C);
- the manual's examples (1, 2, 5 and string 6) with an independent bitwise
  CRC-16/MODBUS written here;
- errors (FormatError, ParamError) and Params over data table arrays;
- hypothesis properties: integer and float conversions against Python's own
  ``%`` (restricted to flag/width/precision combinations where Python and
  C99 agree: the corners where they do not are pinned by the tables above),
  against the C library's snprintf where one is at hand, and the ``*`` path
  against the digits path.
"""

from __future__ import annotations

import ctypes
import math
import platform
import struct
from array import array

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from softplc_lite.tlm.comgenius.checksum import crc16, little_endian, sum16
from softplc_lite.tlm.comgenius.formats import FormatError, params_needed, parse_print
from softplc_lite.tlm.comgenius.params import Param, ParamError, ParamKind, TableParam, ValueParam
from softplc_lite.tlm.comgenius.printf import c_integer, compile_print, format_text

from helpers.reference_checks import crc16_modbus_ref
from helpers.words import signed

INF = float("inf")
NAN = float("nan")


def f32(x: float) -> float:
    """``x`` rounded to IEEE single precision, as an F element holds it."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def param(v) -> Param:
    return v if isinstance(v, Param) else ValueParam(v)


def pr(fmt: str, *values) -> str:
    """``format_text`` with plain values as Params."""
    return format_text(fmt, [param(v) for v in values])


def le2(value: int) -> str:
    return chr(value & 0xFF) + chr(value >> 8 & 0xFF)


def wire(text: str) -> bytes:
    return text.encode("latin-1")


# ---------------------------------------------------------------------------
# Integer conversion characters: b d i o u x X (one 16-bit word)
# ---------------------------------------------------------------------------

INTEGER_ROWS = [
    # fmt, word, expected
    ("%b", 5, "101"),
    ("%b", 0, "0"),
    ("%b", -1, "1" * 16),  # unsigned: all 16 bits
    ("%b", -32768, "1" + "0" * 15),
    ("%d", 42, "42"),
    ("%d", -42, "-42"),
    ("%d", 32767, "32767"),
    ("%d", -32768, "-32768"),
    ("%d", 0, "0"),
    ("%i", -7, "-7"),
    ("%i", 1234, "1234"),
    ("%o", 8, "10"),
    ("%o", 0o777, "777"),
    ("%o", -1, "177777"),  # unsigned
    ("%u", 65535, "65535"),
    ("%u", -1, "65535"),  # the word read unsigned
    ("%u", -32768, "32768"),
    ("%u", 0, "0"),
    ("%x", 0xABC, "abc"),  # lowercase
    ("%x", -1, "ffff"),
    ("%X", 0xABC, "ABC"),  # uppercase
    ("%X", -2, "FFFE"),
]


@pytest.mark.parametrize("fmt,word,expected", INTEGER_ROWS,
                         ids=[f"{f}:{w}" for f, w, _ in INTEGER_ROWS])
def test_integer_conversion_chars(fmt, word, expected):
    assert pr(fmt, word) == expected


# l / L: two words, low word first; d/i signed, the others unsigned.
LONG_ROWS = [
    ("%ld", [1, 0], "1"),
    ("%ld", [0, 1], "65536"),  # the second word is the high word
    ("%Ld", [0x5678, 0x1234], str(0x12345678)),
    ("%ld", [-1, -1], "-1"),
    ("%ld", [0, -32768], "-2147483648"),
    ("%ld", [-1, 32767], "2147483647"),
    ("%li", [-2, -1], "-2"),
    ("%Li", [-4464, -2], "-70000"),
    ("%lu", [-1, -1], "4294967295"),
    ("%Lu", [0, -32768], "2147483648"),
    ("%lx", [0x5678, 0x1234], "12345678"),
    ("%lX", [-1, 0x7FFF], "7FFFFFFF"),
    ("%lx", [-1, -1], "ffffffff"),
    ("%lo", [-1, -1], "37777777777"),
    ("%lb", [0, 1], "1" + "0" * 16),
    ("%Lb", [5, 0], "101"),
    ("%08lx", [0xFF, 0], "000000ff"),
    ("%+ld", [5, 0], "+5"),
    ("%.12ld", [-1, -1], "-000000000001"),
]


@pytest.mark.parametrize("fmt,words,expected", LONG_ROWS,
                         ids=[f"{f}:{w}" for f, w, _ in LONG_ROWS])
def test_long_integers_low_word_first(fmt, words, expected):
    assert pr(fmt, words) == expected


def test_long_needs_the_word_after_the_param():
    with pytest.raises(ParamError):
        pr("%ld", [5])  # one word only


def test_without_l_only_the_first_word_is_read():
    assert pr("%d", [5, 99]) == "5"
    assert pr("%x", [-1, -1]) == "ffff"


@pytest.mark.parametrize("fmt,value,expected", [
    ("%lc", 0x4142, "B"),
    ("%lC", 0x4142, "A"),
    ("%ls", "abc", "abc"),
    ("%lf", 1.5, "1.500000"),
    ("%Le", 1.5, "1.500000e+00"),
    ("%lg", 1.5, "1.5"),
    ("%hd", 300, "300"),  # h means something only for %S
], ids=["lc", "lC", "ls", "lf", "Le", "lg", "hd"])
def test_length_modifier_ignored_elsewhere(fmt, value, expected):
    assert pr(fmt, value) == expected


# ---------------------------------------------------------------------------
# Flags, width and precision (manual's field tables)
# ---------------------------------------------------------------------------

FLAG_ROWS = [
    # -: left adjustment
    ("%-5d|", 42, "42   |"),
    ("%-5x|", 255, "ff   |"),
    ("%-8.3f|", 1.5, "1.500   |"),
    # +: always a sign (signed conversions)
    ("%+d", 42, "+42"),
    ("%+d", -42, "-42"),
    ("%+d", 0, "+0"),
    ("%+i", 7, "+7"),
    ("%+f", 1.5, "+1.500000"),
    ("%+e", -1.5, "-1.500000e+00"),
    # space: a space when there is no sign
    ("% d", 42, " 42"),
    ("% d", -42, "-42"),
    ("% g", 2.5, " 2.5"),
    ("%+ d", 3, "+3"),  # + wins over space
    # 0: leading zeros up to the width
    ("%05d", 42, "00042"),
    ("%05d", -42, "-0042"),
    ("%+05d", 42, "+0042"),
    ("% 05d", 42, " 0042"),
    ("%08b", 5, "00000101"),
    ("%06o", 8, "000010"),
    ("%06X", 255, "0000FF"),
    ("%06u", -1, "065535"),
    ("%010.2f", -1.5, "-000001.50"),
    ("%010.3e", -1.5, "-1.500e+00"),
    ("%0-5d|", 3, "3    |"),  # - wins over 0
    # #: alternate form
    ("%#o", 8, "010"),
    ("%#o", 0, "0"),
    ("%#x", 255, "0xff"),
    ("%#X", 255, "0XFF"),
    ("%#08x", 255, "0x0000ff"),  # zeros go after the prefix
    ("%-#8x|", 255, "0xff    |"),
    ("%#08o", 8, "00000010"),
    ("%#.0f", 2.0, "2."),  # always a decimal point
    ("%#.0e", 2.0, "2.e+00"),
    ("%#.0E", 2.0, "2.E+00"),
    ("%#g", 1.5, "1.50000"),  # trailing zeros kept
    ("%#G", 1e-10, "1.00000E-10"),
    ("%#.3g", 1.0, "1.00"),
]


@pytest.mark.parametrize("fmt,value,expected", FLAG_ROWS, ids=[f"{f}:{v}" for f, v, _ in FLAG_ROWS])
def test_flags(fmt, value, expected):
    if isinstance(value, float):
        value = f32(value)
    assert pr(fmt, value) == expected


WIDTH_PRECISION_ROWS = [
    # width: minimum field width, padded on the left
    ("%5d|", 42, "   42|"),
    ("%1d", 12345, "12345"),  # wider if necessary
    ("%3o", 5, "  5"),
    ("%10b", 5, "       101"),
    ("%8.2f", 3.25, "    3.25"),
    # precision on integers: minimum number of digits
    ("%.5d", 42, "00042"),
    ("%.5d", -42, "-00042"),
    ("%.3i", 7, "007"),
    ("%.8b", 5, "00000101"),
    ("%.4o", 8, "0010"),
    ("%.4u", 9, "0009"),
    ("%.4x", 255, "00ff"),
    ("%.4X", 255, "00FF"),
    ("%6.3d|", 7, "   007|"),
    ("%-6.3d|", -7, "-007  |"),
    ("%.1d", 123, "123"),  # a minimum, never truncates
    # '.' alone is precision 0
    ("%.f", 2.0, "2"),
    ("%.e", 2.0, "2e+00"),
    ("%.d", 5, "5"),
    # floats: f/e/E digits after the point, g/G significant digits
    ("%.3f", 0.5, "0.500"),
    ("%.0f", 2.5, "2"),  # round half to even, as C
    ("%.0f", 3.5, "4"),
    ("%.2e", 1234.5, "1.23e+03"),
    ("%.3g", 1234.5, "1.23e+03"),
    ("%.4g", 1234.5, "1234"),
    ("%.10g", 0.5, "0.5"),
    ("%.0g", 25.0, "2e+01"),  # precision 0 counts as 1 (2.5 rounds to even)
    ("%.0g", 35.0, "4e+01"),
]


@pytest.mark.parametrize("fmt,value,expected", WIDTH_PRECISION_ROWS,
                         ids=[f"{f}:{v}" for f, v, _ in WIDTH_PRECISION_ROWS])
def test_width_and_precision_digits(fmt, value, expected):
    if isinstance(value, float):
        value = f32(value)
    assert pr(fmt, value) == expected


STAR_ROWS = [
    # fmt, params, expected: * takes the next integer Param and consumes it
    ("%*d|", [5, 42], "   42|"),
    ("%.*d|", [4, 42], "0042|"),
    ("%*.*d|", [6, 3, 7], "   007|"),
    ("%-*d|", [4, 1], "1   |"),
    ("%0*d", [5, -3], "-0003"),
    ("%*s|", [4, "ab"], "  ab|"),
    ("%.*s|", [1, "ab"], "a|"),
    ("%*.*f|", [8, 2, 3.25], "    3.25|"),
    ("%.*e", [1, 1.5], "1.5e+00"),
    ("%.*c", [3, [0x4241, 0x43]], "ABC"),
    ("%*c|", [3, 65], "  A|"),
    ("%*%|", [3], "  %|"),
    ("%*ld", [12, [0, 1]], "       65536"),
    ("%*d %d", [3, 1, 2], "  1 2"),  # later specs take the following Params
    # a negative * width: left-justify with its absolute value
    ("%*d|", [-5, 42], "42   |"),
    ("%*s|", [-4, "ab"], "ab  |"),
    ("%0*d|", [-5, 3], "3    |"),
    ("%*f|", [-10, 1.5], "1.500000  |"),
    # a negative * precision counts as none
    ("%.*d|", [-1, 3], "3|"),
    ("%.*d|", [-1, 0], "0|"),  # not the precision-0 "no digits"
    ("%0*.*d", [5, -1, 3], "00003"),  # 0 flag back in force
    ("%.*f", [-3, 1.5], "1.500000"),
    ("%.*s", [-1, "abc"], "abc"),
    ("%.*c", [-1, 0x4241], "A"),  # default 1 byte
]


@pytest.mark.parametrize("fmt,values,expected", STAR_ROWS, ids=[f"{f}:{v}" for f, v, _ in STAR_ROWS])
def test_star_width_and_precision(fmt, values, expected):
    assert pr(fmt, *values) == expected


def test_star_needs_an_integer_param():
    with pytest.raises(ParamError):
        pr("%*d", 1.5, 3)
    with pytest.raises(ParamError):
        pr("%.*d", "x", 3)
    with pytest.raises(ParamError):
        pr("%*d", 5)  # the star took the only Param


# ---------------------------------------------------------------------------
# s, c, C
# ---------------------------------------------------------------------------

STRING_ROWS = [
    ("%s", "hello", "hello"),
    ("%s", "", ""),
    ("[%s]", "two words", "[two words]"),
    ("%7s|", "abc", "    abc|"),
    ("%-7s|", "abc", "abc    |"),
    ("%.2s", "abc", "ab"),
    ("%.0s|", "abc", "|"),
    ("%.9s", "abc", "abc"),
    ("%12.12s|", "short", "       short|"),  # manual: padded because width is 12
    ("%12.12s|", "a long string here", "a long strin|"),  # truncated: precision 12
    ("%-12.12s|", "short", "short       |"),
    ("%05s", "ab", "   ab"),  # 0 is for numeric conversions
    ("%#s", "ab", "ab"),  # # no effect on s
    ("%+s", "ab", "ab"),
    ("%s", "\u124f\uffff\x00", "\u124f\uffff\x00"),  # 16-bit characters kept
]


@pytest.mark.parametrize("fmt,text,expected", STRING_ROWS, ids=[f"{f}:{t!r}" for f, t, _ in STRING_ROWS])
def test_s_conversion(fmt, text, expected):
    assert pr(fmt, text) == expected


CHAR_ROWS = [
    # c: little endian, low byte of the Param first
    ("%c", [0x4142], "B"),
    ("%c", [65], "A"),
    ("%c", [-1], "\xff"),  # a byte 0..255, upper 8 bits of the character 0
    ("%c", [0], "\x00"),
    ("%.2c", [0x4142], "BA"),
    ("%.6c", [0x0201, 0x0403, 0x0605], "\x01\x02\x03\x04\x05\x06"),  # manual: N7:10..N7:12
    ("%.3c", [0x0201, 0x0403], "\x01\x02\x03"),
    ("%.0c|", [65], "|"),
    # C: big endian, high byte of the Param first
    ("%C", [0x4142], "A"),
    ("%C", [0x00FF], "\x00"),
    ("%.2C", [0x4142], "AB"),
    ("%.6C", [0x0102, 0x0304, 0x0506], "\x01\x02\x03\x04\x05\x06"),
    ("%.3C", [0x0102, 0x0304], "\x01\x02\x03"),
    ("%.2C", [-2], "\xff\xfe"),
    # width pads with spaces; flags other than - change nothing
    ("%3c|", [65], "  A|"),
    ("%-3c|", [65], "A  |"),
    ("%03c", [65], "  A"),
    ("%#c", [65], "A"),
    ("%+C", [0x4100], "A"),
]


@pytest.mark.parametrize("fmt,words,expected", CHAR_ROWS, ids=[f"{f}:{w}" for f, w, _ in CHAR_ROWS])
def test_c_and_C_conversions(fmt, words, expected):
    assert pr(fmt, words) == expected


def test_c_bytes_past_the_param_words_are_a_param_error():
    with pytest.raises(ParamError):
        pr("%.3c", [0x4142])  # needs a second word
    with pytest.raises(ParamError):
        pr("%.4C", [1])


# ---------------------------------------------------------------------------
# Floats f e E g G, and %
# ---------------------------------------------------------------------------

FLOAT_ROWS = [
    ("%f", 1.5, "1.500000"),  # default precision 6
    ("%f", -0.25, "-0.250000"),
    ("%f", 0.0, "0.000000"),
    ("%f", 1024.0, "1024.000000"),
    ("%.0f", 7.0, "7"),  # no point, no fraction
    ("%f", -3.14, "-3.140000"),
    ("%e", 1.5, "1.500000e+00"),
    ("%e", 12345.0, "1.234500e+04"),
    ("%e", -0.00048828125, "-4.882812e-04"),  # round half even on the exact binary value
    ("%.0e", 5.0, "5e+00"),
    ("%E", 1.5, "1.500000E+00"),
    ("%E", 1e-30, "1.000000E-30"),
    ("%e", 1e38, "1.000000e+38"),
    ("%g", 1.5, "1.5"),  # trailing zeros removed
    ("%g", 100000.0, "100000"),
    ("%g", 1e6, "1e+06"),  # exponent >= precision: e style
    ("%g", 0.0001, "0.0001"),
    ("%g", 0.00001, "1e-05"),  # exponent < -4: e style
    ("%g", 2.0, "2"),  # no point when nothing follows it
    ("%g", 0.0, "0"),
    ("%G", 0.00001, "1E-05"),
    ("%G", 1.5e20, "1.5E+20"),
    ("%G", 2.5, "2.5"),
    ("%f", INF, "inf"),
    ("%E", -INF, "-INF"),
    ("%g", NAN, "nan"),
    ("%G", NAN, "NAN"),
    ("%8.3f|", -INF, "    -inf|"),
    # C99: the 0 flag does not zero-pad an infinity or NaN (Python's % does)
    ("%010f", INF, "       inf"),
    ("%+010f", -INF, "      -inf"),
    ("%010e", NAN, "       nan"),
    ("% 08G", INF, "     INF"),
    ("%-010g|", INF, "inf       |"),
]


@pytest.mark.parametrize("fmt,value,expected", FLOAT_ROWS, ids=[f"{f}:{v}" for f, v, _ in FLOAT_ROWS])
def test_float_conversions(fmt, value, expected):
    assert pr(fmt, f32(value)) == expected


def test_zero_flag_on_infinity_through_star_width_too():
    assert pr("%0*f", 10, INF) == "       inf"
    assert pr("%0*.*e|", 9, 2, -INF) == "     -inf|"


@pytest.mark.parametrize("fmt,expected", [
    ("%%", "%"),
    ("100%%", "100%"),
    ("%%d", "%d"),
    ("%%%%", "%%"),
    ("a%%b%%c", "a%b%c"),
], ids=["alone", "after", "not-a-spec", "two", "between"])
def test_percent_consumes_no_param(fmt, expected):
    assert format_text(fmt, []) == expected


def test_percent_between_conversions():
    assert pr("%d%%%d", 1, 2) == "1%2"


def test_literal_text_is_kept_verbatim():
    text = "\x00\x02\u124f plain \r\n\t"
    assert format_text(text, []) == text
    assert pr(text + "%d" + text, 7) == text + "7" + text


# ---------------------------------------------------------------------------
# S (sum) and R (CRC-16): no Param consumed
# ---------------------------------------------------------------------------

def sum_ref(data: bytes) -> int:
    return sum(data) & 0xFFFF


SUM_ROWS = [
    # fmt, covered bytes, expected check characters
    ("AB%S", b"AB", le2(0x83)),
    ("AB%#S", b"AB", le2(-0x83 & 0xFFFF)),  # two's complement
    ("AB%hS", b"AB", chr(0x83)),  # one byte
    ("AB%#hS", b"AB", chr(-0x83 & 0xFF)),
    ("ABC%1S", b"BC", le2(ord("B") + ord("C"))),  # width: start offset
    ("ABC%.2S", b"AB", le2(ord("A") + ord("B"))),  # precision 2: skip the last character
    ("ABC%1.2S", b"B", le2(ord("B"))),
    ("ABC%.3S", b"A", le2(ord("A"))),
    ("ABC%5S", b"", le2(0)),  # start past the end: nothing summed
    ("%S", b"", le2(0)),
]


@pytest.mark.parametrize("fmt,covered,check", SUM_ROWS, ids=[r[0] for r in SUM_ROWS])
def test_sum_check(fmt, covered, check):
    out = format_text(fmt, [])
    head = fmt[:fmt.index("%")]
    assert out == head + check
    if "#" not in fmt:
        assert int.from_bytes(wire(check), "little") == sum_ref(covered) & (0xFF if "h" in fmt else 0xFFFF)


def test_sum_uses_low_byte_of_16_bit_characters_and_wraps_at_16_bits():
    assert format_text("\u0141\u01ff%S", []) == "\u0141\u01ff" + le2(0x41 + 0xFF)
    text = "\xff" * 300  # 76500 > 0xFFFF
    assert format_text(text + "%S", [])[-2:] == le2(76500 & 0xFFFF)
    assert format_text(text + "%hS", [])[-1:] == chr(76500 & 0xFF)
    assert format_text(text + "%#S", [])[-2:] == le2(-76500 & 0xFFFF)


def test_sum_covers_converted_output_not_the_format():
    out = pr("N%dX%S", 123)
    assert out == "N123X" + le2(sum_ref(b"N123X"))


CRC_ROWS = [
    ("AB%R", b"AB", 0),
    ("AB%#R", b"AB", 0xFFFF),  # Modbus preload
    ("ABCD%1R", b"BCD", 0),
    ("ABCD%.2R", b"ABC", 0),
    ("ABCD%#1.3R", b"B", 0xFFFF),  # from offset 1 to 3 characters back
    ("ABCD%#1.2R", b"BC", 0xFFFF),
    ("%R", b"", 0),
    ("%#R", b"", 0xFFFF),
]


@pytest.mark.parametrize("fmt,covered,preload", CRC_ROWS, ids=[r[0] for r in CRC_ROWS])
def test_crc_check(fmt, covered, preload):
    out = format_text(fmt, [])
    head = fmt[:fmt.index("%")]
    assert out == head + le2(crc16_modbus_ref(covered, preload))


def test_crc_reference_implementation_known_values():
    # the published check values of CRC-16/MODBUS and CRC-16/ARC over "123456789"
    assert crc16_modbus_ref(b"123456789", 0xFFFF) == 0x4B37
    assert crc16_modbus_ref(b"123456789", 0) == 0xBB3D
    assert format_text("123456789%#R", [])[-2:] == "\x37\x4b"
    assert format_text("123456789%R", [])[-2:] == "\x3d\xbb"
    assert crc16("123456789", 0xFFFF) == 0x4B37  # checksum.py agrees


def test_checks_see_earlier_checks_and_conversions():
    out = pr("%.2C%S%#R", 0x0102)
    body = "\x01\x02" + le2(3)
    assert out == body + le2(crc16_modbus_ref(wire(body), 0xFFFF))


def test_check_star_width_and_precision_take_integer_params():
    # %*.*R: width 1 and precision 2 from Params, then %d takes the third
    out = pr("ABCD%*.*R%d", 1, 2, 9)
    assert out == "ABCD" + le2(crc16_modbus_ref(b"BC", 0)) + "9"
    assert pr("ABC%*.*S", 0, 1) == "ABC" + le2(sum_ref(b"ABC"))
    assert pr("ABC%.*S", -1) == "ABC" + le2(sum_ref(b"ABC"))  # negative: the default 1
    # a negative * start offset starts at the first character, not at |offset|
    assert pr("ABCD%*R", -2) == "ABCD" + le2(crc16_modbus_ref(b"ABCD", 0))
    assert pr("ABCD%*S", -2) == "ABCD" + le2(sum_ref(b"ABCD"))


def test_checksum_helpers():
    assert sum16("AB") == 0x83
    assert sum16("AB", negate=True) == 0xFF7D
    assert sum16("AB", one_byte=True) == 0x83
    assert sum16("AB", negate=True, one_byte=True) == 0x7D
    assert little_endian(0x1234) == "\x34\x12"
    assert little_endian(0x1234, 1) == "\x34"
    assert little_endian(0x12345678, 4) == "\x78\x56\x34\x12"
    assert crc16("\u0141B", 0) == crc16("AB", 0)  # low bytes only


# ---------------------------------------------------------------------------
# C99 corners (the list; Python's % differs on each)
# ---------------------------------------------------------------------------

C99_ROWS = [
    # a precision on an integer conversion makes 0 ignored
    ("%05.3d", 7, "  007"),
    ("%05.3d", -7, " -007"),
    ("%08.4x", 255, "    00ff"),
    ("%06.2u", 5, "    05"),
    ("%06.1b", 1, "     1"),
    ("%08.3o", 8, "     010"),
    ("%#08.4x", 255, "  0x00ff"),
    # + and space have no effect on the unsigned conversions
    ("%+u", 5, "5"),
    ("% u", 5, "5"),
    ("%+x", 255, "ff"),
    ("% X", 255, "FF"),
    ("%+o", 8, "10"),
    ("% o", 8, "10"),
    ("%+b", 5, "101"),
    ("% b", 5, "101"),
    ("%+5u|", -1, "65535|"),
    # a zero value with precision 0 prints no digits
    ("%.0d", 0, ""),
    ("%.0i", 0, ""),
    ("%.0u", 0, ""),
    ("%.0x", 0, ""),
    ("%.0X", 0, ""),
    ("%.0o", 0, ""),
    ("%.0b", 0, ""),
    ("%.d", 0, ""),
    ("%5.0d|", 0, "     |"),
    ("%+.0d", 0, "+"),
    ("% .0d", 0, " "),
    ("%#.0x", 0, ""),  # no 0x for zero
    ("%#.0o", 0, "0"),  # # makes the first digit 0
    ("%#5.0o|", 0, "    0|"),
    ("%.0d", 5, "5"),  # only zero loses its digits
    # # has no effect on b d i u
    ("%#b", 5, "101"),
    ("%#d", 5, "5"),
    ("%#i", -5, "-5"),
    ("%#u", 5, "5"),
    ("%#5d|", 5, "    5|"),
    # %#x prefixes only non-zero values; %#o makes the first digit 0
    ("%#x", 0, "0"),
    ("%#X", 0, "0"),
    ("%#5x|", 0, "    0|"),
    ("%#x", 1, "0x1"),
    ("%#o", 8, "010"),
    ("%#.3o", 8, "010"),  # precision already gives the 0
    ("%#.4o", 8, "0010"),
    ("%#.4x", 255, "0x00ff"),
]


@pytest.mark.parametrize("fmt,word,expected", C99_ROWS, ids=[f"{f}:{w}" for f, w, _ in C99_ROWS])
def test_c99_integer_corners(fmt, word, expected):
    assert pr(fmt, word) == expected


@pytest.mark.parametrize("fmt,value,expected", [
    ("%#g", 1.5, "1.50000"),
    ("%#g", 100.0, "100.000"),
    ("%#G", 2.0, "2.00000"),
    ("%#.2g", 1.0, "1.0"),
    ("%g", 100.0, "100"),  # without #, trailing zeros go
], ids=["1.5", "100", "G", "prec2", "no-hash"])
def test_c99_hash_g_keeps_trailing_zeros(fmt, value, expected):
    assert pr(fmt, value) == expected


def test_c99_hash_no_effect_on_s_and_c():
    assert pr("%#s|%#c|%#5s", "ab", 65, "x") == "ab|A|    x"


@pytest.mark.parametrize("value,conv,flags,width,precision,expected", [
    (0, "x", "#", None, 0, ""),
    (0, "o", "#", None, 0, "0"),
    (-5, "d", "0", 6, None, "-00005"),
    (5, "u", "+ ", None, None, "5"),
    (2**32 - 1, "x", "#", None, None, "0xffffffff"),
    (-(2**31), "d", "", 13, 11, " -02147483648"),
    (6, "b", "-", 5, None, "110  "),
], ids=["hash-x-0", "hash-o-0", "zero-neg", "unsigned-sign", "long-hex", "long-prec", "b-left"])
def test_c_integer_helper(value, conv, flags, width, precision, expected):
    assert c_integer(value, conv, flags, width, precision) == expected


# ---------------------------------------------------------------------------
# The manual's examples
# ---------------------------------------------------------------------------

def test_example_1_rack_text():
    assert pr("Rack no: %3o has %2d modules.\r\n", 5, 2) == "Rack no:   5 has  2 modules.\r\n"


def test_example_1_octal_rack_numbers():
    assert pr("Rack no: %3o has %2d modules.\r\n", 8, 16) == "Rack no:  10 has 16 modules.\r\n"


def test_example_2_modbus_query():
    out = pr("\x02\x03%.2C%.2C%#R", 0, 125)
    assert wire(out) == bytes.fromhex("02 03 00 00 00 7D 85 D8")
    body = bytes.fromhex("02 03 00 00 00 7D")
    assert wire(out)[6:] == crc16_modbus_ref(body, 0xFFFF).to_bytes(2, "little")


@pytest.mark.parametrize("slave_fmt,ref,count", [
    ("\x01\x03", 0, 10),  # the widely published 01 03 00 00 00 0A C5 CD
    ("\x02\x03", 0x1234, 1),
    ("\x11\x03", 0x006B, 3),
    ("\x02\x03", -1, 125),
], ids=["01-03-0-10", "ref-1234", "11-03-6B-3", "ref-FFFF"])
def test_example_2_shape_with_other_refs(slave_fmt, ref, count):
    out = wire(pr(slave_fmt + "%.2C%.2C%#R", ref, count))
    body = wire(slave_fmt) + (ref & 0xFFFF).to_bytes(2, "big") + count.to_bytes(2, "big")
    assert out == body + crc16_modbus_ref(body, 0xFFFF).to_bytes(2, "little")
    if ref == 0 and count == 10:
        assert out[-2:] == bytes.fromhex("C5 CD")


def test_example_5_exception_format_printed():
    out = wire(pr("\x02\x83%c%#R", 2))
    body = bytes([0x02, 0x83, 0x02])
    assert out == body + crc16_modbus_ref(body, 0xFFFF).to_bytes(2, "little")
    assert len(out) == 5


def test_string_6_strprint():
    out = pr("A STRPRINT test: number:%2d float:%g ST:%s", 5, f32(1.5), "hello")
    assert out == "A STRPRINT test: number: 5 float:1.5 ST:hello"


# ---------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("fmt,offset", [
    ("%k", 0),
    ("ab %k", 3),
    ("%5.2k", 0),
    ("%d %k", 3),
    ("%", 0),
    ("abc%", 3),
    ("%-5", 0),
    ("%.", 0),
    ("%l", 0),
    ("%n", 0),  # n is a scan conversion only
    ("%lk", 0),
    ("%*", 0),
], ids=["k", "k-after-text", "k-with-fields", "k-after-spec", "lone", "trailing", "no-conv",
        "dot", "l-alone", "n", "lk", "star"])
def test_illegal_format_is_format_error(fmt, offset):
    with pytest.raises(FormatError) as err:
        format_text(fmt, [ValueParam(1)] * 6)
    assert err.value.offset == offset
    with pytest.raises(FormatError):
        compile_print(fmt)


def test_too_few_params():
    with pytest.raises(ParamError, match="too few"):
        pr("%d %d", 1)
    with pytest.raises(ParamError, match="too few"):
        format_text("%d", [])
    with pytest.raises(ParamError, match="too few"):
        pr("%x%.*d", 1, 2)  # general path
    with pytest.raises(ParamError, match="too few"):
        format_text("%s", [])
    # conversions that take no Param need none
    assert format_text("%%%S%R", []) == "%" + le2(ord("%")) + le2(crc16_modbus_ref(b"%" + wire(le2(37)), 0))


def test_extra_params_are_ignored():
    assert pr("%d", 1, 2, 3) == "1"


@pytest.mark.parametrize("fmt,value", [
    ("%d", "abc"),
    ("%i", "abc"),
    ("%u", 1.5),
    ("%x", ValueParam("", ParamKind.STRING)),
    ("%5.2b", 1.5),
    ("%c", "A"),
    ("%.2C", 1.5),
    ("%ld", "ab"),
    ("%f", 5),
    ("%e", "1.5"),
    ("%g", [1, 2]),
    ("%s", 5),
    ("%s", 1.5),
    ("%-5s", 5),
], ids=["d-string", "i-string", "u-float", "x-empty-string", "b-general-float", "c-string",
        "C-float", "ld-string", "f-int", "e-string", "g-words", "s-int", "s-float", "s-general-int"])
def test_wrong_param_kind_is_param_error(fmt, value):
    with pytest.raises(ParamError):
        pr(fmt, value)


def test_params_needed_lists_kinds_in_order():
    needed = params_needed(parse_print("%*.*d %s %% %S %f %.2c %#R %lx"), scan=False)
    assert [kind for _, kind in needed] == ["integer", "integer", "integer", "STRING", "float", "integer", "integer"]


def test_compile_print_is_cached_and_counts_params():
    fmt = "a%db%*dc%5.2u%%%S"
    pf = compile_print(fmt)
    assert compile_print(fmt) is pf
    assert pf.params_used == 4
    assert pf.render([ValueParam(v) for v in (1, 3, 2, 7)]) == "a1b  2c   07%" + le2(sum_ref(b"a1b  2c   07%"))


# ---------------------------------------------------------------------------
# Params over the data table (TableParam)
# ---------------------------------------------------------------------------

def test_table_params_integer_long_float_string():
    n7 = array("h", [5, 0x5678, 0x1234, -1, 0x4142])
    f8 = array("f", [0.0, f32(-3.14)])
    st9 = array("h", [0] * 83 * 2)
    text = "Hi\u8001"
    st9[83] = len(text)
    for k, ch in enumerate(text):
        st9[84 + k] = signed(ord(ch))
    params = [
        TableParam(ParamKind.INTEGER, n7, 0, "N7:0"),
        TableParam(ParamKind.INTEGER, n7, 1, "N7:1"),
        TableParam(ParamKind.FLOAT, f8, 1, "F8:1"),
        TableParam(ParamKind.STRING, st9, 83, "ST9:1"),
        TableParam(ParamKind.INTEGER, n7, 3, "N7:3"),
    ]
    out = format_text("%d %lx %.2f %s %.4C", params)
    assert out == "5 12345678 -3.14 Hi\u8001 \xff\xffAB"


def test_table_param_past_the_end_of_its_file():
    n7 = array("h", [1, 2])
    with pytest.raises(ParamError):
        format_text("%ld", [TableParam(ParamKind.INTEGER, n7, 1, "N7:1")])
    with pytest.raises(ParamError):
        format_text("%.6c", [TableParam(ParamKind.INTEGER, n7, 0, "N7:0")])
    with pytest.raises(ParamError):
        format_text("%d", [TableParam(ParamKind.FLOAT, array("f", [1.0]), 0, "F8:0")])


# ---------------------------------------------------------------------------
# Properties
# ---------------------------------------------------------------------------

words16 = st.integers(-32768, 32767)
widths = st.none() | st.integers(1, 24)
precisions = st.none() | st.integers(0, 12)


def spec_text(flags: str, width, precision, length: str, conv: str) -> str:
    return ("%" + flags + ("" if width is None else str(width))
            + ("" if precision is None else f".{precision}") + length + conv)


def python_agrees(conv: str, flags: str, precision, value: int) -> bool:
    """Python's % gives C99's result unless a corner applies (tested above)."""
    if precision is not None and "0" in flags:
        return False  # C ignores 0 under a precision
    if precision == 0 and value == 0:
        return False  # C prints no digits
    if conv in "ouxX" and ("+" in flags or " " in flags or "#" in flags):
        return False  # no sign on unsigned; 0o / 0x0 prefixes differ
    return True


signed_flags = st.lists(st.sampled_from("-+ 0"), unique=True).map("".join)
unsigned_flags = st.lists(st.sampled_from("-0"), unique=True).map("".join)


@settings(max_examples=300, deadline=None)
@given(data=st.data(), conv=st.sampled_from("diouxX"), long=st.booleans(),
       width=widths, precision=precisions)
def test_integers_match_python_percent(data, conv, long, width, precision):
    flags = data.draw(signed_flags if conv in "di" else unsigned_flags)
    if long:
        value = data.draw(st.integers(-(2**31), 2**31 - 1))
        words = [value & 0xFFFF, (value >> 16) & 0xFFFF]
        shown = value if conv in "di" else value & 0xFFFFFFFF
    else:
        value = data.draw(words16)
        words = [value]
        shown = value if conv in "di" else value & 0xFFFF
    assume(python_agrees(conv, flags, precision, shown))
    fmt = spec_text(flags, width, precision, "l" if long else "", conv)
    expected = spec_text(flags, width, precision, "", conv) % shown
    assert pr(fmt, words) == expected
    # the same through the general (star) path
    star = spec_text(flags, None if width is None else "*", None if precision is None else "*",
                     "l" if long else "", conv)
    star_params = ([width] if width is not None else []) + ([precision] if precision is not None else [])
    assert pr(star, *star_params, words) == expected


@settings(max_examples=150, deadline=None)
@given(value=words16, flags=st.lists(st.sampled_from("-0"), unique=True).map("".join),
       width=widths, precision=precisions)
def test_binary_matches_python_format(value, flags, width, precision):
    """Python's % has no b: compare with format(value, 'b') under the same rules."""
    shown = value & 0xFFFF
    assume(python_agrees("o", flags, precision, shown))
    digits = format(shown, "b")
    if precision is not None:
        digits = digits.rjust(precision, "0")
    if width is not None and len(digits) < width:
        digits = (digits.ljust(width) if "-" in flags else
                  digits.rjust(width, "0") if "0" in flags else digits.rjust(width))
    assert pr(spec_text(flags, width, precision, "", "b"), value) == digits


float32s = st.floats(width=32, allow_nan=False)
float_flags = st.lists(st.sampled_from("-+ 0#"), unique=True).map("".join)


@settings(max_examples=300, deadline=None)
@given(value=float32s, conv=st.sampled_from("feEgG"), flags=float_flags,
       width=widths, precision=precisions)
def test_floats_match_python_percent(value, conv, flags, width, precision):
    if not math.isfinite(value):
        flags = flags.replace("0", "")  # C99 space-pads inf (tested above); Python zero-pads
    fmt = spec_text(flags, width, precision, "", conv)
    assert pr(fmt, value) == fmt % value


def _libc_snprintf():
    if platform.libc_ver()[0] != "glibc":
        return None
    try:
        return ctypes.CDLL(None).snprintf
    except (OSError, AttributeError):
        return None


SNPRINTF = _libc_snprintf()
needs_glibc = pytest.mark.skipif(SNPRINTF is None, reason="needs glibc's snprintf as a C99 oracle")


def c_printf(fmt: str, *args) -> str:
    buf = ctypes.create_string_buffer(512)
    SNPRINTF(buf, 512, fmt.encode("ascii"), *args)
    return buf.value.decode("ascii")


any_int_flags = st.lists(st.sampled_from("-+ 0#"), unique=True).map("".join)


@needs_glibc
@settings(max_examples=400, deadline=None)
@given(data=st.data(), conv=st.sampled_from("diouxX"), long=st.booleans(), flags=any_int_flags,
       width=st.none() | st.integers(-20, 20), precision=st.none() | st.integers(-3, 12),
       star_w=st.booleans(), star_p=st.booleans())
def test_integers_match_c_library_all_flags(data, conv, long, flags, width, precision, star_w, star_p):
    """Every flag combination, corners included, against glibc's snprintf
    (b is left out: C23's %#b prints 0b, the manual says # does nothing)."""
    if not star_w and width is not None and width < 0:
        width = -width or None
    if not star_p and precision is not None and precision < 0:
        precision = None
    if long:
        value = data.draw(st.integers(-(2**31), 2**31 - 1))
        words = [value & 0xFFFF, (value >> 16) & 0xFFFF]
        c_arg = ctypes.c_int(value) if conv in "di" else ctypes.c_uint(value & 0xFFFFFFFF)
    else:
        value = data.draw(words16)
        words = [value]
        c_arg = ctypes.c_int(value) if conv in "di" else ctypes.c_uint(value & 0xFFFF)
    w_text = "" if width is None else ("*" if star_w else str(width))
    p_text = "" if precision is None else "." + ("*" if star_p else str(precision))
    ours = "%" + flags + w_text + p_text + ("l" if long else "") + conv
    theirs = "%" + flags + w_text + p_text + conv  # c_int/c_uint hold the 32 bits
    params, c_args = [], []
    if width is not None and star_w:
        params.append(width)
        c_args.append(ctypes.c_int(width))
    if precision is not None and star_p:
        params.append(precision)
        c_args.append(ctypes.c_int(precision))
    assert pr(ours, *params, words) == c_printf(theirs, *c_args, c_arg)


@needs_glibc
@settings(max_examples=300, deadline=None)
@given(value=float32s, conv=st.sampled_from("feEgG"), flags=float_flags,
       width=st.none() | st.integers(1, 30), precision=precisions)
def test_floats_match_c_library(value, conv, flags, width, precision):
    fmt = spec_text(flags, width, precision, "", conv)
    assert pr(fmt, value) == c_printf(fmt, ctypes.c_double(value))


@settings(max_examples=150, deadline=None)
@given(text=st.text(st.characters(max_codepoint=0xFFFF), max_size=82),
       flags=st.lists(st.sampled_from("-0#+ "), unique=True).map("".join),
       width=widths, precision=precisions)
def test_strings_pad_and_truncate(text, flags, width, precision):
    out = pr(spec_text(flags, width, precision, "", "s"), text)
    body = text if precision is None else text[:precision]
    pad = " " * max(0, (width or 0) - len(body))  # never zeros, whatever the flags
    assert out == (body + pad if "-" in flags else pad + body)


@settings(max_examples=150, deadline=None)
@given(words=st.lists(words16, min_size=1, max_size=8), data=st.data())
def test_c_and_C_emit_bytes_little_and_big_endian(words, data):
    count = data.draw(st.integers(0, 2 * len(words)))
    raw = b"".join(struct.pack("<H", w & 0xFFFF) for w in words)
    assert wire(pr(f"%.{count}c", words)) == raw[:count]
    raw_be = b"".join(struct.pack(">H", w & 0xFFFF) for w in words)
    assert wire(pr(f"%.{count}C", words)) == raw_be[:count]


@settings(max_examples=150, deadline=None)
@given(body=st.binary(max_size=64), preload=st.sampled_from(["", "#"]),
       start=st.integers(0, 70), back=st.integers(1, 70))
def test_R_and_S_match_reference_over_any_bytes(body, preload, start, back):
    text = body.decode("latin-1").replace("%", "%%")  # literal text in a format
    end = len(body) - back + 1
    covered = body[start:end] if end > start else b""
    out = format_text(text + f"%{preload}{start}.{back}R", [])
    assert wire(out) == body + crc16_modbus_ref(covered, 0xFFFF if preload else 0).to_bytes(2, "little")
    out = format_text(text + f"%{preload}{start}.{back}S", [])
    total = sum(covered)
    assert wire(out)[-2:] == ((-total if preload else total) & 0xFFFF).to_bytes(2, "little")
