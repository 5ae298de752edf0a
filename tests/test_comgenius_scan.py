"""COMGENIUS scanning (COMSCAN/STRSCAN format engine, manual 4.3.5).

Sections:

- every row of the manual's scan tables: conversion chars b d i o u x X c C
  e E f g G s S R n, ``%%`` and ``%`` + a whitespace character, ``*``
  suppression, ``#`` on S/R, ``h``/``H`` on S, ``l``/``L``; precision
  (digits only for numeric conversions, ignored for floats), width
  (ignored except by S and R), signs on unsigned conversions;
- the status table: MATCHED / MISMATCH (``used`` = offset of the failure,
  ``specs`` = conversions matched) / NEED_MORE;
- the manual's examples 3, 4 and 5 and strings 7/8;
- errors (FormatError, ParamError);
- streaming: the matcher never consumes, so a caller re-matching from the
  start with more input gets the same result;
- hypothesis round trips scan(print(x)) == x.
"""

from __future__ import annotations

import math
import struct
from array import array

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softplc_lite.tlm.comgenius.formats import FormatError, params_needed, parse_scan
from softplc_lite.tlm.comgenius.params import ParamError, ParamKind, TableParam, ValueParam
from softplc_lite.tlm.comgenius.printf import format_text
from softplc_lite.tlm.comgenius.scanf import (MATCHED, MISMATCH, NEED_MORE, ScanResult, compile_scan,
                                              scan_text)

from helpers.reference_checks import crc16_modbus_ref

WS = " \t\n\r\v\f"


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def chars(data: bytes) -> str:
    return data.decode("latin-1")


def le2(value: int) -> str:
    return chr(value & 0xFF) + chr(value >> 8 & 0xFF)


def word(value: int = 0) -> ValueParam:
    return ValueParam(value)


def words(n: int) -> ValueParam:
    return ValueParam([0] * n)


def flt() -> ValueParam:
    return ValueParam(0.0)


def string() -> ValueParam:
    return ValueParam("", ParamKind.STRING)


def scan1(fmt: str, data: str, dest=None, final: bool = True):
    """Scan into one fresh integer Param; (result, its words)."""
    p = dest if dest is not None else word()
    return scan_text(fmt, data, [p], final), p.value


# ---------------------------------------------------------------------------
# Integer conversions b d i o u x X
# ---------------------------------------------------------------------------

INTEGER_ROWS = [
    # fmt, input, stored word (signed 16-bit), characters used
    ("%b", "1011011", 0b1011011, 7),
    ("%b", "1012", 0b101, 3),  # stops at a non-digit
    ("%b", "1111111111111111", -1, 16),
    ("%d", "-423", -423, 4),
    ("%d", "423", 423, 3),
    ("%d", "+432", 432, 4),
    ("%d", "  \t\r\n42", 42, 7),  # leading whitespace skipped
    ("%d", "42abc", 42, 2),
    ("%d", "007", 7, 3),  # no octal for d
    ("%d", "32767", 32767, 5),
    ("%d", "-32768", -32768, 6),
    ("%d", "32768", -32768, 5),  # kept to 16 bits
    ("%d", "65537", 1, 5),
    ("%i", "077", 0o77, 3),  # leading 0: octal
    ("%i", "0xFF", 255, 4),  # 0x: hex
    ("%i", "0XfF", 255, 4),
    ("%i", "12", 12, 2),  # decimal
    ("%i", "-0x10", -16, 5),
    ("%i", "-017", -15, 4),
    ("%i", "0", 0, 1),
    ("%i", "08", 0, 1),  # octal 0, then 8 is not an octal digit
    ("%i", "0x", 0, 1),  # no hex digit: just the 0
    ("%o", "077", 0o77, 3),
    ("%o", "777", 511, 3),
    ("%o", "178", 0o17, 2),
    ("%o", "177777", -1, 6),
    ("%u", "423", 423, 3),
    ("%u", "65535", -1, 5),  # a word keeps 16 bits
    ("%u", "-1", -1, 2),  # a sign is accepted on unsigned; the value wraps
    ("%u", "+7", 7, 2),
    ("%o", "-1", -1, 2),
    ("%b", "-1", -1, 2),
    ("%x", "AF9B", 0xAF9B - 0x10000, 4),
    ("%x", "af9b", 0xAF9B - 0x10000, 4),
    ("%X", "7fff", 0x7FFF, 4),
    ("%x", "0x1F", 0x1F, 4),  # optional 0x prefix
    ("%X", "0X1f", 0x1F, 4),
    ("%x", "-ff", -255, 3),
    ("%x", "0xg", 0, 1),  # 0x without a hex digit: the 0 alone
    ("%x", "fg", 15, 1),
]


@pytest.mark.parametrize("fmt,data,value,used", INTEGER_ROWS, ids=[f"{f}:{d!r}" for f, d, *_ in INTEGER_ROWS])
def test_integer_conversion_chars(fmt, data, value, used):
    result, stored = scan1(fmt, data)
    assert result == ScanResult(MATCHED, used, 1)
    assert stored == [value]


@pytest.mark.parametrize("fmt,data,used", [
    ("%d", "abc", 0),
    ("%d", "   x", 3),
    ("%d", "-x", 1),  # after the sign
    ("%d", "+-1", 1),
    ("%b", "2", 0),
    ("%o", "8", 0),
    ("%x", "g", 0),
    ("%u", ".5", 0),
    ("%d", "", 0),
    ("%d", "   ", 3),
    ("%d", "-", 1),
], ids=["letters", "ws-then-letter", "sign-letter", "two-signs", "b-2", "o-8", "x-g", "u-dot", "empty",
        "only-ws", "only-sign"])
def test_integer_mismatch_offsets(fmt, data, used):
    result, stored = scan1(fmt, data)
    assert result == ScanResult(MISMATCH, used, 0)
    assert stored == [0]  # nothing written


PRECISION_ROWS = [
    # precision: digits for numeric conversions; a sign or 0x comes on top
    ("%.3d", "-1234", -123, 4),
    ("%.3d", "1234", 123, 3),
    ("%.3d", "+1234", 123, 4),
    ("%.3d", "12", 12, 2),  # fewer digits are fine at a non-digit
    ("%.1d", "987", 9, 1),
    ("%.2x", "0xABC", 0xAB, 4),
    ("%.2x", "ABC", 0xAB, 2),
    ("%.2i", "0x1FF", 0x1F, 4),
    ("%.2i", "0777", 0o7, 2),  # the octal leading 0 is a digit
    ("%.4b", "101101", 0b1011, 4),
    ("%.2o", "777", 0o77, 2),
    ("%.3u", "-65535", -655, 4),
    ("%.5ld", "1234567", 12345, 5),
    # width is ignored (except by S and R)
    ("%2d", "12345", 12345, 5),
    ("%5d", "123456", 123456 & 0xFFFF, 6),
    ("%1x", "ffff", -1, 4),
    ("%3.2d", "12345", 12, 2),
]


@pytest.mark.parametrize("fmt,data,value,used", PRECISION_ROWS, ids=[f"{f}:{d!r}" for f, d, *_ in PRECISION_ROWS])
def test_integer_precision_and_width(fmt, data, value, used):
    dest = words(2)
    result = scan_text(fmt, data, [dest])
    assert result == ScanResult(MATCHED, used, 1)
    expected = value & (0xFFFFFFFF if "l" in fmt else 0xFFFF)
    got = (dest.value[0] & 0xFFFF) | ((dest.value[1] & 0xFFFF) << 16 if "l" in fmt else 0)
    assert got == expected


def test_example_precision_leaves_the_rest_for_the_next_field():
    a, b = word(), word()
    assert scan_text("%.3d%d", "-1234", [a, b]) == ScanResult(MATCHED, 5, 2)
    assert (a.value, b.value) == ([-123], [4])


LONG_ROWS = [
    # fmt, input, stored words (low word first)
    ("%ld", "-70000", [-4464, -2]),
    ("%Ld", "70000", [4464, 1]),
    ("%ld", "2147483647", [-1, 32767]),
    ("%ld", "-2147483648", [0, -32768]),
    ("%li", "0x12345678", [0x5678, 0x1234]),
    ("%Li", "-1", [-1, -1]),
    ("%lu", "4294967295", [-1, -1]),
    ("%lu", "-1", [-1, -1]),  # sign on unsigned wraps
    ("%Lu", "65536", [0, 1]),
    ("%lx", "12345678", [0x5678, 0x1234]),
    ("%LX", "FFFF0000", [0, -1]),
    ("%lo", "37777777777", [-1, -1]),
    ("%lb", "10000000000000000", [0, 1]),
    ("%ld", "4294967297", [1, 0]),  # kept to 32 bits
]


@pytest.mark.parametrize("fmt,data,stored", LONG_ROWS, ids=[f"{f}:{d}" for f, d, _ in LONG_ROWS])
def test_long_integers_two_words_low_first(fmt, data, stored):
    dest = ValueParam([0, 0, 99])
    assert scan_text(fmt, data, [dest]) == ScanResult(MATCHED, len(data), 1)
    assert dest.value == stored + [99]  # the word after is untouched


def test_without_l_only_one_word_is_written():
    dest = ValueParam([0, 99])
    scan_text("%d", "70000", [dest])
    assert dest.value == [70000 - 65536, 99]


def test_long_into_a_one_word_param_is_a_param_error():
    with pytest.raises(ParamError):
        scan_text("%ld", "5", [word()])


# ---------------------------------------------------------------------------
# Floats e E f g G: precision and width ignored, float32 stored
# ---------------------------------------------------------------------------

FLOAT_ROWS = [
    ("%f", "1.5", 1.5, 3),
    ("%f", "-3.14", f32(-3.14), 5),
    ("%e", "-3.14", f32(-3.14), 5),
    ("%E", "2.5E3", 2500.0, 5),
    ("%g", "1e-5", f32(1e-5), 4),
    ("%G", "+.5", 0.5, 3),
    ("%f", "7", 7.0, 1),  # an integer field is a float too
    ("%f", "5.", 5.0, 2),
    ("%f", "  \r\n12.25", 12.25, 9),  # leading whitespace skipped
    ("%f", "1.5e+2x", 150.0, 6),
    ("%f", "1e", 1.0, 1),  # an e with no exponent digits is not read
    ("%f", "2.5.3", 2.5, 3),
    ("%f", "inf", math.inf, 3),
    ("%f", "-Infinity", -math.inf, 9),
    ("%f", "1e39", math.inf, 4),  # past float32: infinity
    ("%f", "1e-50", 0.0, 5),
    ("%f", "0.1", f32(0.1), 3),  # stored as float32
    ("%f", "3.14159265358979", f32(3.14159265358979), 16),
    # precision and width ignored for floats
    ("%.1f", "1.2345", f32(1.2345), 6),
    ("%3f", "1.2345", f32(1.2345), 6),
    ("%8.2e", "1.2345", f32(1.2345), 6),
    ("%lf", "2.5", 2.5, 3),
]


@pytest.mark.parametrize("fmt,data,value,used", FLOAT_ROWS, ids=[f"{f}:{d!r}" for f, d, *_ in FLOAT_ROWS])
def test_float_conversion_chars(fmt, data, value, used):
    dest = flt()
    assert scan_text(fmt, data, [dest]) == ScanResult(MATCHED, used, 1)
    assert dest.value == value
    assert dest.value == f32(dest.value)


def test_float_nan():
    dest = flt()
    assert scan_text("%g", "nan", [dest]) == ScanResult(MATCHED, 3, 1)
    assert math.isnan(dest.value)


@pytest.mark.parametrize("data,used", [("abc", 0), ("-x", 0), (".", 0), ("e5", 0), ("", 0), ("  ", 2)],
                         ids=["letters", "sign-letter", "dot", "e5", "empty", "only-ws"])
def test_float_mismatch(data, used):
    dest = flt()
    assert scan_text("%f", data, [dest]) == ScanResult(MISMATCH, used, 0)
    assert dest.value == 0.0


# ---------------------------------------------------------------------------
# s: non-whitespace block, up to whitespace / 82 characters / precision
# ---------------------------------------------------------------------------

STRING_ROWS = [
    # fmt, input, stored, used
    ("%s", "hello world", "hello", 5),
    ("%s", "  \t\r\nhello", "hello", 10),  # leading whitespace ignored
    ("%s", "tab\there", "tab", 3),
    ("%s", "cr\rlf", "cr", 2),
    ("%s", "vt\vff\f", "vt", 2),
    ("%.3s", "hello", "hel", 3),  # precision: at most 3
    ("%.14s", "TOOL_12 123", "TOOL_12", 7),
    ("%.0s", "abc", "", 0),
    ("%.99s", "abc def", "abc", 3),
    ("%s", "x" * 100, "x" * 82, 82),  # the STRING element holds 82
    ("%.90s", "y" * 100, "y" * 82, 82),
    ("%s", "\u124f\uffff\u0100 z", "\u124f\uffff\u0100", 3),  # all 16 bits kept
    ("%s", "a%b", "a%b", 3),
    ("%5s", "abcdefg", "abcdefg", 7),  # width ignored
    ("%ls", "ab", "ab", 2),
]


@pytest.mark.parametrize("fmt,data,stored,used", STRING_ROWS, ids=[f"{f}:{d[:12]!r}" for f, d, *_ in STRING_ROWS])
def test_s_conversion(fmt, data, stored, used):
    dest = ValueParam("old", ParamKind.STRING)
    assert scan_text(fmt, data, [dest]) == ScanResult(MATCHED, used, 1)
    assert dest.value == stored


def test_s_runs_out_of_input_before_any_character():
    dest = string()
    assert scan_text("%s", "", [dest]) == ScanResult(MISMATCH, 0, 0)
    assert scan_text("%s", "   ", [dest]) == ScanResult(MISMATCH, 3, 0)
    assert scan_text("%s", "   ", [dest], final=False) == ScanResult(NEED_MORE, 3, 0)


def test_s_into_a_table_string_element_keeps_16_bits():
    st9 = array("h", [0] * 83)
    st9[5] = 77  # old contents past the new length are cleared
    dest = TableParam(ParamKind.STRING, st9, 0, "ST9:0")
    assert scan_text("%s", "A\u8001\uffff rest", [dest]) == ScanResult(MATCHED, 3, 1)
    assert st9[0] == 3
    assert [w & 0xFFFF for w in st9[1:4]] == [0x41, 0x8001, 0xFFFF]
    assert list(st9[4:]) == [0] * 79
    assert dest.string() == "A\u8001\uffff"


# ---------------------------------------------------------------------------
# c / C: raw characters packed two per word (little / big endian)
# ---------------------------------------------------------------------------

CHAR_ROWS = [
    # fmt, input, words to check, used (odd counts: only the written byte is checked)
    ("%c", "A", [0x41], 1),
    ("%c", " ", [0x20], 1),  # no whitespace skipping
    ("%c", "\n", [0x0A], 1),
    ("%c", "\xff", [0xFF], 1),
    ("%c", "\u1234", [0x34], 1),  # low 8 bits of the character
    ("%.2c", "AB", [0x4241], 2),  # first character in the low byte
    ("%.6c", "\x01\x02\x03\x04\x05\x06", [0x0201, 0x0403, 0x0605], 6),
    ("%.4c", "\xff\xfe\x00\x80", [0xFEFF - 0x10000, -0x8000], 4),
    ("%C", "A", [0x4100], 1),  # first character in the high byte
    ("%.2C", "AB", [0x4142], 2),
    ("%.6C", "\x01\x02\x03\x04\x05\x06", [0x0102, 0x0304, 0x0506], 6),
    ("%.2C", "\x00\x7d", [125], 2),
    ("%.2C", "\u0141\u0242", [0x4142], 2),
    ("%5c", "A", [0x41], 1),  # width ignored
]


@pytest.mark.parametrize("fmt,data,expected,used", CHAR_ROWS, ids=[f"{f}:{d!r}" for f, d, *_ in CHAR_ROWS])
def test_c_and_C_conversions(fmt, data, expected, used):
    dest = words(len(expected) + 1)
    dest.value[-1] = 99
    assert scan_text(fmt, data, [dest]) == ScanResult(MATCHED, used, 1)
    got = dest.value[:len(expected)]
    if used & 1:  # the one byte written in the last word
        shift = 8 if fmt.endswith("C") else 0
        assert (got[-1] >> shift) & 0xFF == (expected[-1] >> shift) & 0xFF
        assert got[:-1] == expected[:-1]
    else:
        assert got == expected
    assert dest.value[-1] == 99  # words past the field untouched


def test_c_30_fills_15_words_and_matches_anything():
    data = "".join(chr(i) for i in (0, 32, 10, 13, 255, 37) * 5)
    dest = words(15)
    assert scan_text("%.30c", data, [dest]) == ScanResult(MATCHED, 30, 1)
    assert bytes(array("h", dest.value).tobytes()) == data.encode("latin-1")


def test_c_too_few_characters():
    assert scan_text("%.3c", "AB", [words(2)]) == ScanResult(MISMATCH, 2, 0)
    assert scan_text("%.3c", "AB", [words(2)], final=False) == ScanResult(NEED_MORE, 2, 0)


def test_c_past_the_end_of_the_param_is_a_param_error():
    with pytest.raises(ParamError):
        scan_text("%.4c", "ABCD", [word()])
    n7 = array("h", [0, 0, 0])
    with pytest.raises(ParamError):
        scan_text("%.6C", "ABCDEF", [TableParam(ParamKind.INTEGER, n7, 1, "N7:1")])


# ---------------------------------------------------------------------------
# %%, % + whitespace, whitespace and literal text in the format
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("fmt,data,result", [
    ("%%", "%", ScanResult(MATCHED, 1, 0)),
    ("%%", "x", ScanResult(MISMATCH, 0, 0)),
    ("%%", " %", ScanResult(MISMATCH, 0, 0)),  # no whitespace skipping
    ("% ", " ", ScanResult(MATCHED, 1, 0)),
    ("% ", "\t", ScanResult(MISMATCH, 0, 0)),
    ("% ", "  ", ScanResult(MATCHED, 1, 0)),  # exactly one
    ("%\t", "\t", ScanResult(MATCHED, 1, 0)),
    ("%\n", "\n", ScanResult(MATCHED, 1, 0)),
    ("%\r", "\r", ScanResult(MATCHED, 1, 0)),
    ("%\v", "\v", ScanResult(MATCHED, 1, 0)),
    ("%\f", "\f", ScanResult(MATCHED, 1, 0)),
    ("%\r%\n", "\r\n", ScanResult(MATCHED, 2, 0)),
    ("%\r%\n", "\n\r", ScanResult(MISMATCH, 0, 0)),
    ("a% b", "a b", ScanResult(MATCHED, 3, 0)),
    ("a% b", "ab", ScanResult(MISMATCH, 1, 0)),
    ("a% b", "a  b", ScanResult(MISMATCH, 2, 0)),
    ("100%%", "100%", ScanResult(MATCHED, 4, 0)),
    ("%", "", None),
], ids=["pct", "pct-x", "pct-no-skip", "space", "space-vs-tab", "one-space", "tab", "lf", "cr", "vt", "ff",
        "crlf", "crlf-swapped", "a-space-b", "a-b-missing", "a-two-spaces-b", "100pct", "lone-pct"])
def test_percent_and_percent_whitespace_match_one_character(fmt, data, result):
    if result is None:
        with pytest.raises(FormatError):
            scan_text(fmt, data)
        return
    assert scan_text(fmt, data) == result


@pytest.mark.parametrize("fmt,data,result", [
    ("a b", "ab", ScanResult(MATCHED, 2, 0)),  # whitespace matches none
    ("a b", "a \t\r\n\v\f b", ScanResult(MATCHED, 9, 0)),  # or any run
    ("a\r\nb", "a  b", ScanResult(MATCHED, 4, 0)),  # any whitespace for any whitespace
    ("AK HM", "AK HX", ScanResult(MISMATCH, 4, 0)),  # offset of the differing character
    ("AK HM", "AKHM", ScanResult(MATCHED, 4, 0)),
    ("ab", "a", ScanResult(MISMATCH, 1, 0)),
    (" x", "x", ScanResult(MATCHED, 1, 0)),
    ("x ", "x", ScanResult(MATCHED, 1, 0)),
    ("x ", "x  y", ScanResult(MATCHED, 3, 0)),
    ("\x02\x03", "\x02\x03", ScanResult(MATCHED, 2, 0)),
    ("\u124f", "\u124f", ScanResult(MATCHED, 1, 0)),
    ("\u124f", "\u004f", ScanResult(MISMATCH, 0, 0)),  # all 16 bits compared
    ("", "anything", ScanResult(MATCHED, 0, 0)),
], ids=["ws-none", "ws-run", "ws-any", "literal-offset", "ws-none-2", "short", "lead-ws", "trail-ws",
        "trail-ws-run", "binary", "ucs2", "ucs2-high-byte", "empty-format"])
def test_whitespace_and_literals_in_the_format(fmt, data, result):
    assert scan_text(fmt, data) == result


# ---------------------------------------------------------------------------
# * suppression, n
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("fmt,data,used", [
    ("%*d", "-12", 3),
    ("%*.3d", "123", 3),
    ("%*ld", "70000", 5),
    ("%*x", "ff", 2),
    ("%*f", "1.5", 3),
    ("%*s", "word", 4),
    ("%*.2c", "  ", 2),  # the manual: throw away two characters
    ("%*C", "A", 1),
    ("%*n", "", 0),
], ids=["d", "d-prec", "ld", "x", "f", "s", "c2", "C", "n"])
def test_star_suppresses_assignment_and_consumes_no_param(fmt, data, used):
    canary = ValueParam(7)
    assert scan_text(fmt + " %d", data + " 9", [canary]) == ScanResult(MATCHED, used + 2, 2)
    assert canary.value == [9]  # the first Param went to the %d after
    assert params_needed(parse_scan(fmt), scan=True) == []


def test_star_still_matches():
    assert scan_text("%*d", "x", []) == ScanResult(MISMATCH, 0, 0)


@pytest.mark.parametrize("fmt,data,counts", [
    ("%n", "", [0]),
    ("%d%n", " 12 ", [12, 3]),
    ("%d %n", " 12 ", [12, 4]),
    ("abc%n%.2c%n", "abcde", [3, 0x6564, 5]),
    ("%ln", "", [0]),
], ids=["start", "after-d", "after-ws", "between", "ln"])
def test_n_stores_characters_read_so_far(fmt, data, counts):
    params = [ValueParam(-1) for _ in counts]
    result = scan_text(fmt, data, params)
    assert result.status == MATCHED
    assert result.specs == len(counts)  # n counts as a conversion spec
    assert [p.value[0] for p in params] == counts


def test_n_needs_an_integer_param():
    with pytest.raises(ParamError):
        scan_text("%n", "", [flt()])


# ---------------------------------------------------------------------------
# S (sum) and R (CRC-16) checks
# ---------------------------------------------------------------------------

def sum_bytes(data: bytes) -> int:
    return sum(data) & 0xFFFF


CHECK_ROWS = [
    # fmt, input, status, used
    ("AB%S", "AB" + le2(0x83), MATCHED, 4),
    ("AB%S", "AB" + le2(0x84), MISMATCH, 2),
    ("AB%#S", "AB" + le2(-0x83 & 0xFFFF), MATCHED, 4),  # two's complement
    ("AB%#S", "AB" + le2(0x83), MISMATCH, 2),
    ("AB%hS", "AB\x83", MATCHED, 3),  # one byte
    ("AB%HS", "AB\x83", MATCHED, 3),
    ("AB%#hS", "AB\x7d", MATCHED, 3),
    ("AB%#HS", "AB\x83", MISMATCH, 2),
    ("ABC%1S", "ABC" + le2(ord("B") + ord("C")), MATCHED, 5),  # width: start offset
    ("ABC%.2S", "ABC" + le2(ord("A") + ord("B")), MATCHED, 5),  # precision 2: skip one
    ("ABC%1.2S", "ABC" + le2(ord("B")), MATCHED, 5),
    ("AB%S", "AB\x83\x00tail", MATCHED, 4),
    ("\u0141B%S", "\u0141B" + le2(0x83), MATCHED, 4),  # low bytes only
    ("AB%S", "AB\u0183\u0100", MATCHED, 4),  # compared on low bytes
    ("AB%R", "AB" + le2(crc16_modbus_ref(b"AB", 0)), MATCHED, 4),
    ("AB%#R", "AB" + le2(crc16_modbus_ref(b"AB", 0xFFFF)), MATCHED, 4),  # 0xFFFF preload
    ("AB%#R", "AB" + le2(crc16_modbus_ref(b"AB", 0)), MISMATCH, 2),
    ("AB%R", "AB" + le2(crc16_modbus_ref(b"AB", 0))[::-1], MISMATCH, 2),  # little endian only
    ("ABCD%1.2R", "ABCD" + le2(crc16_modbus_ref(b"BC", 0)), MATCHED, 6),
    ("%d,%#R", "12," + le2(crc16_modbus_ref(b"12,", 0xFFFF)), MATCHED, 5),  # over the characters read
]


@pytest.mark.parametrize("fmt,data,status,used", CHECK_ROWS, ids=[f"{r[0]}:{r[2]}" for r in CHECK_ROWS])
def test_sum_and_crc_checks(fmt, data, status, used):
    params = [word()] if "%d" in fmt else []
    result = scan_text(fmt, data, params)
    assert (result.status, result.used) == (status, used)
    assert result.specs == (len(params) + 1 if status == MATCHED else len(params))


def test_check_width_and_precision_together_and_star_flag():
    # from offset 3 to 2 characters back: just the "d"
    assert scan_text("abcde%3.2S", "abcde" + le2(ord("d"))) == ScanResult(MATCHED, 7, 1)
    assert scan_text("abcde%*3.2S", "abcde" + le2(ord("d"))) == ScanResult(MATCHED, 7, 1)  # * changes nothing
    assert scan_text("abcde%3.2S", "abcde" + le2(ord("e"))) == ScanResult(MISMATCH, 5, 0)


def test_check_needs_its_characters():
    assert scan_text("AB%S", "AB\x83") == ScanResult(MISMATCH, 3, 0)
    assert scan_text("AB%S", "AB\x83", final=False) == ScanResult(NEED_MORE, 3, 0)
    assert scan_text("AB%R", "AB", final=False) == ScanResult(NEED_MORE, 2, 0)


def test_crc_known_value_modbus_check_string():
    data = "123456789\x37\x4b"  # CRC-16/MODBUS of 123456789 is 0x4B37
    assert crc16_modbus_ref(b"123456789", 0xFFFF) == 0x4B37
    assert scan_text("123456789%#R", data) == ScanResult(MATCHED, 11, 1)
    assert scan_text("%*.9c%#R", data) == ScanResult(MATCHED, 11, 2)


# ---------------------------------------------------------------------------
# The manual's examples
# ---------------------------------------------------------------------------

EXAMPLE_3 = "AK HM %.14s %.3d"


@pytest.mark.parametrize("data,name,number,used", [
    ("AK HM TOOL_12 123\r\n", "TOOL_12", 123, 17),
    ("AK HM X -12\r\n", "X", -12, 11),
    ("AK HM ABCDEFGHIJKLMN 999\r\n", "ABCDEFGHIJKLMN", 999, 24),  # 14 characters
    ("AK HM TOOL 1234\r\n", "TOOL", 123, 14),  # at most 3 digits
    ("AK  HM\tT 7 ", "T", 7, 10),
], ids=["manual", "negative", "14-chars", "4-digits", "odd-spacing"])
def test_example_3_text_with_integers(data, name, number, used):
    s, n = string(), word()
    assert scan_text(EXAMPLE_3, data, [s, n]) == ScanResult(MATCHED, used, 2)
    assert (s.value, n.value) == (name, [number])


def test_example_3_name_longer_than_14_fails_on_the_number():
    s, n = string(), word()
    data = "AK HM ABCDEFGHIJKLMNO 123\r\n"
    assert scan_text(EXAMPLE_3, data, [s, n]) == ScanResult(MISMATCH, 20, 1)
    assert s.value == "ABCDEFGHIJKLMN"  # Params are staging areas: written even on failure


def test_example_3_streaming():
    fmt = compile_scan(EXAMPLE_3)
    s, n = string(), word()
    assert fmt.match("AK H", [s, n]) == ScanResult(NEED_MORE, 4, 0)
    assert fmt.match("AK HM TOO", [s, n]) == ScanResult(NEED_MORE, 9, 0)
    assert fmt.match("AK HM TOOL_12 ", [s, n]) == ScanResult(NEED_MORE, 14, 1)
    assert fmt.match("AK HM TOOL_12 12", [s, n]) == ScanResult(NEED_MORE, 16, 1)
    assert fmt.match("AK HM TOOL_12 123", [s, n]) == ScanResult(MATCHED, 17, 2)  # precision reached
    assert (s.value, n.value) == ("TOOL_12", [123])
    assert fmt.match("AK HX", [s, n]) == ScanResult(MISMATCH, 4, 0)


EXAMPLE_4 = "\x02\x03\xfa%.250C%#R"


def modbus_response(values) -> str:
    body = b"\x02\x03\xfa" + struct.pack(">125h", *values)
    return chars(body + crc16_modbus_ref(body, 0xFFFF).to_bytes(2, "little"))


REGISTERS = [(i * 263 - 16000) for i in range(125)]


def test_example_4_modbus_response_into_125_words():
    data = modbus_response(REGISTERS)
    assert len(data) == 255
    dest = words(125)
    assert scan_text(EXAMPLE_4, data, [dest]) == ScanResult(MATCHED, 255, 2)
    assert dest.value == REGISTERS


def test_example_4_into_a_data_table_file():
    n7 = array("h", [0] * 130)
    data = modbus_response(REGISTERS)
    assert scan_text(EXAMPLE_4, data, [TableParam(ParamKind.INTEGER, n7, 5, "N7:5")]).status == MATCHED
    assert list(n7[5:130]) == REGISTERS and list(n7[:5]) == [0] * 5


def test_example_4_corrupted_crc_mismatches_at_the_crc():
    data = modbus_response(REGISTERS)
    bad = data[:253] + chr(ord(data[253]) ^ 1) + data[254]
    assert scan_text(EXAMPLE_4, bad, [words(125)]) == ScanResult(MISMATCH, 253, 1)
    flipped = data[:100] + chr(ord(data[100]) ^ 0x10) + data[101:]  # a data byte
    assert scan_text(EXAMPLE_4, flipped, [words(125)]) == ScanResult(MISMATCH, 253, 1)


@pytest.mark.parametrize("cut", [0, 1, 3, 100, 253, 254], ids=lambda c: f"first-{c}")
def test_example_4_truncated_needs_more(cut):
    data = modbus_response(REGISTERS)[:cut]
    result = scan_text(EXAMPLE_4, data, [words(125)], final=False)
    assert result.status == NEED_MORE
    assert result.specs == (1 if cut >= 253 else 0)


@pytest.mark.parametrize("data,used", [
    ("\x01\x03\xfa", 0),  # another slave
    ("\x02\x04\xfa", 1),  # another function
    ("\x02\x03\xfb", 2),  # another byte count
    ("\x02\x83\x02", 1),  # an exception packet
], ids=["slave", "function", "count", "exception"])
def test_example_4_header_mismatch(data, used):
    assert scan_text(EXAMPLE_4, data + "\x00" * 252, [words(125)], final=False) == ScanResult(MISMATCH, used, 0)


EXAMPLE_5_EXCEPTION = "\x02\x83%c%#R"


def test_example_5_exception_packet():
    body = b"\x02\x83\x02"
    data = chars(body + crc16_modbus_ref(body, 0xFFFF).to_bytes(2, "little"))
    code = ValueParam(-1)
    assert scan_text(EXAMPLE_5_EXCEPTION, data, [code]) == ScanResult(MATCHED, 5, 2)
    assert code.value[0] & 0xFF == 2  # the exception code in the low byte
    # the same characters fail the response format first, and stay for this one
    assert scan_text(EXAMPLE_4, data, [words(125)], final=False) == ScanResult(MISMATCH, 1, 0)
    assert scan_text(EXAMPLE_5_EXCEPTION, data, [code]) == ScanResult(MATCHED, 5, 2)


def test_example_5_response_is_not_an_exception():
    data = modbus_response(REGISTERS)
    assert scan_text(EXAMPLE_5_EXCEPTION, data, [word()], final=False) == ScanResult(MISMATCH, 1, 0)


def test_example_2_query_printed_then_scanned():
    query = format_text("\x02\x03%.2C%.2C%#R", [ValueParam(0), ValueParam(125)])
    ref, count = word(), word()
    assert scan_text("\x02\x03%.2C%.2C%#R", query, [ref, count]) == ScanResult(MATCHED, 8, 3)
    assert (ref.value, count.value) == ([0], [125])


def test_strings_7_and_8():
    s, f, d = string(), flt(), word()
    assert scan_text("%s %f %d", "A_STRing -3.14 -4555", [s, f, d]) == ScanResult(MATCHED, 20, 3)
    assert s.value == "A_STRing"
    assert f.value == f32(-3.14)
    assert d.value == [-4555]


# ---------------------------------------------------------------------------
# Status table: MATCHED / MISMATCH / NEED_MORE with used and specs
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("fmt,data,final,result", [
    ("%d,%d", "1,2", True, ScanResult(MATCHED, 3, 2)),
    ("%d,%d", "1,2rest", True, ScanResult(MATCHED, 3, 2)),  # the rest is not read
    ("%d,%d", "1;2", True, ScanResult(MISMATCH, 1, 1)),  # offset of the ';', one spec matched
    ("%d,%d", "1,x", True, ScanResult(MISMATCH, 2, 1)),
    ("%d,%d", "1,", True, ScanResult(MISMATCH, 2, 1)),  # the end of a final input
    ("%d,%d", "1,", False, ScanResult(NEED_MORE, 2, 1)),
    ("%d,%d", "1", False, ScanResult(NEED_MORE, 1, 0)),  # more digits may come
    ("%d,%d", "1", True, ScanResult(MISMATCH, 1, 1)),
    ("%.1d,%.1d", "1,2", False, ScanResult(MATCHED, 3, 2)),  # precision reached: decided
    ("%d,%d", "", False, ScanResult(NEED_MORE, 0, 0)),
    ("%d,%d", "", True, ScanResult(MISMATCH, 0, 0)),
    ("%d,%d", "x", False, ScanResult(MISMATCH, 0, 0)),  # decided without more input
    ("%d %s", "5 ab", False, ScanResult(NEED_MORE, 4, 1)),
    ("%d %s", "5 ab ", False, ScanResult(MATCHED, 4, 2)),
    ("%d %s", "5 ab", True, ScanResult(MATCHED, 4, 2)),
], ids=["match", "match-rest", "mismatch-literal", "mismatch-field", "final-end", "need-literal",
        "need-digits", "final-digits-then-literal", "precision-decides", "need-empty", "final-empty",
        "mismatch-early", "need-string", "string-ws", "string-final"])
def test_status_table(fmt, data, final, result):
    assert scan_text(fmt, data, [word(), ValueParam("", ParamKind.STRING) if "%s" in fmt else word()],
                     final) == result


@pytest.mark.parametrize("fmt,data", [
    ("%d", "-"), ("%d", "+"), ("%x", "0"), ("%x", "0x"), ("%i", "0"), ("%i", "-0x"),
    ("%f", "-"), ("%f", "+"), ("%f", "."), ("%f", "-."), ("%f", "1."), ("%f", "1e"), ("%f", "1e+"),
    ("%f", "2.5E-"), ("%f", "i"), ("%f", "IN"), ("%f", "infin"), ("%f", "n"), ("%f", "na"),
    ("%f", "12"), ("%f", " \r\n"), ("%s", "abc"), ("%.2C", "A"), ("%e", "-1.5"),
], ids=lambda v: repr(v))
def test_a_field_cut_short_needs_more(fmt, data):
    """An input that could still become a match is NEED_MORE, never MISMATCH
    or an early MATCHED, when it is not final."""
    dest = flt() if fmt[-1] in "feEgG" else string() if fmt[-1] == "s" else words(2)
    assert scan_text(fmt, data, [dest], final=False).status == NEED_MORE


@pytest.mark.parametrize("data,value,used", [
    ("1e5 ", 1e5, 3),
    ("1ex", 1.0, 1),
    ("-1.5x", -1.5, 4),
    ("inf ", math.inf, 3),
    ("1.5e+3,", 1500.0, 6),
], ids=["exponent", "e-then-letter", "letter", "inf", "comma"])
def test_a_complete_float_field_matches_without_more(data, value, used):
    dest = flt()
    assert scan_text("%f", data, [dest], final=False) == ScanResult(MATCHED, used, 1)
    assert dest.value == value


# ---------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("fmt,offset", [
    ("%k", 0),
    ("AK %k", 3),
    ("%.3k", 0),
    ("%", 0),
    ("ab%", 2),
    ("%*", 0),
    ("%.", 0),
    ("%l", 0),
    ("%5%", 0),  # %% takes no fields
    ("%-d", 0),  # no print flags in a scan
    ("%+d", 0),
    ("%p", 0),
    ("%*d %k", 4),
], ids=["k", "k-after-text", "k-with-prec", "lone", "trailing", "star-only", "dot", "l", "pct-width",
        "minus", "plus", "p", "k-after-spec"])
def test_illegal_scan_format_is_format_error(fmt, offset):
    with pytest.raises(FormatError) as err:
        scan_text(fmt, "anything", [word()] * 6)
    assert err.value.offset == offset


@pytest.mark.parametrize("fmt", ["%5*d", "%.*d", "%3.*s", "%#.*R"], ids=["width-star", "prec-star", "s", "R"])
def test_star_width_or_precision_is_not_allowed_in_scan(fmt):
    # The manual forbids '*' in a scan width or precision; softplc's one
    # exception is the precision of c and C (below).
    with pytest.raises(FormatError, match="may not be|may be '\\*' only"):
        compile_scan(fmt)


def test_star_precision_of_c_takes_the_count_from_a_param():
    buf = ValueParam([0] * 4)
    assert scan_text("%.*c", "ABCDE", [word(3), buf]) == ScanResult(MATCHED, 3, 1)
    assert buf.value[:2] == [0x4241, 0x43]
    assert scan_text("%.*C%c", "ABCDE", [word(4), buf, word()]) == ScanResult(MATCHED, 5, 2)
    assert buf.value[:2] == [0x4142, 0x4344]
    # the count Param is consumed even when the field is suppressed
    n = word()
    assert scan_text("%*.*c%c", "ABCDE", [word(4), n]) == ScanResult(MATCHED, 5, 2) and n.value == [ord("E")]
    assert [k for _, k in params_needed(parse_scan("%*.*c%.*hc"), scan=True)] == ["integer", "integer", "integer"]
    # short input waits for more (or fails at the end); a count of 0 reads nothing
    assert scan_text("%.*c", "AB", [word(3), buf], final=False) == ScanResult(NEED_MORE, 2, 0)
    assert scan_text("%.*cZ", "Z", [word(0), buf]) == ScanResult(MATCHED, 1, 1)
    with pytest.raises(ParamError, match="below 0"):
        scan_text("%.*c", "AB", [word(-1), buf])


def test_h_on_c_stores_one_character_a_word():
    buf = ValueParam([7] * 6)
    assert scan_text("%.4hc", "\x01\x03\xff\x00", [buf]) == ScanResult(MATCHED, 4, 1)
    assert buf.value == [1, 3, 255, 0, 7, 7]
    assert scan_text("%.*HC", "\u0141\x80", [word(2), buf]).status == MATCHED
    assert buf.value[:2] == [0x41, 0x80]  # low 8 bits of each character, high byte 0
    table = array("h", [0] * 3)
    with pytest.raises(ParamError, match="past the end"):
        scan_text("%.*hc", "ABCD", [word(4), TableParam(ParamKind.INTEGER, table, 0, "N7:0")])


def test_h_on_c_prints_the_low_byte_of_each_word():
    assert format_text("%.*hc", [word(3), ValueParam([0x141, 0x42, -189])]) == "ABC"
    assert format_text("%.2hC|%.0hc", [ValueParam([0x7F01, 2]), ValueParam([1])]) == "\x01\x02|"


def test_too_few_params():
    with pytest.raises(ParamError, match="too few"):
        scan_text("%d %d", "1 2", [word()])
    with pytest.raises(ParamError, match="too few"):
        scan_text("%s", "x", [])
    assert scan_text("%*d %d", "1 2", [word()]).status == MATCHED  # suppressed: none needed


@pytest.mark.parametrize("fmt,data,dest", [
    ("%d", "1", lambda: flt()),
    ("%u", "1", lambda: flt()),  # the manual's example
    ("%x", "1", lambda: string()),
    ("%c", "A", lambda: string()),
    ("%.2C", "AB", lambda: flt()),
    ("%f", "1.5", lambda: word()),
    ("%g", "1.5", lambda: string()),
    ("%s", "abc", lambda: word()),
    ("%s", "abc", lambda: flt()),
    ("%n", "", lambda: string()),
], ids=["d-float", "u-float", "x-string", "c-string", "C-float", "f-int", "g-string", "s-int",
        "s-float", "n-string"])
def test_wrong_param_kind_is_param_error(fmt, data, dest):
    with pytest.raises(ParamError):
        scan_text(fmt, data, [dest()])


@pytest.mark.parametrize("fmt,data,dest", [
    ("%d", "1", ValueParam(0, writable=False)),
    ("%f", "1.5", ValueParam(0.0, writable=False)),
    ("%s", "ab", ValueParam("", ParamKind.STRING, writable=False)),
    ("%.2c", "ab", ValueParam(0, writable=False)),
    ("%n", "", ValueParam(0, writable=False)),
], ids=["d", "f", "s", "c", "n"])
def test_scan_into_a_constant_is_param_error(fmt, data, dest):
    with pytest.raises(ParamError, match="constant"):
        scan_text(fmt, data, [dest])


def test_a_constant_is_fine_where_nothing_is_stored():
    assert scan_text("%*d", "1", [ValueParam(0, writable=False)]).status == MATCHED


def test_params_needed_for_scan():
    needed = params_needed(parse_scan("%d %*d %s %f %% %.2C %#R %n %S"), scan=True)
    assert [kind for _, kind in needed] == ["integer", "STRING", "float", "integer", "integer"]


def test_compile_scan_is_cached():
    assert compile_scan("%d,%d") is compile_scan("%d,%d")


# ---------------------------------------------------------------------------
# Streaming: the matcher never consumes; re-matching from the start gives
# the same result once enough input is there
# ---------------------------------------------------------------------------

STREAM_CASES = [
    ("AK HM %.14s %.3d", "AK HM TOOL_12 123\r\n"),
    ("%s %f %d", "A_STRing -3.14 -4555\r\n"),
    ("\x02\x03\xfa%.250C%#R", modbus_response(REGISTERS)),
    ("T=%f;P=%ld;%x!", "T=-12.5e1;P=-70000;ff!"),
    ("%i,%i,%i%%", "0x1f,-017,42%"),
    ("<%.4c>%hS", "<\x00\x01\x02\x03>" + chr(sum(b"<\x00\x01\x02\x03>") & 0xFF)),
]


def _fresh_params(fmt):
    out = []
    for _, kind in params_needed(parse_scan(fmt), scan=True):
        out.append(flt() if kind == "float" else string() if kind == "STRING" else words(125))
    return out


@pytest.mark.parametrize("fmt,data", STREAM_CASES, ids=[f[:12] for f, _ in STREAM_CASES])
def test_every_prefix_needs_more_until_the_match(fmt, data):
    whole_params = _fresh_params(fmt)
    whole = compile_scan(fmt).match(data, whole_params, final=False)
    assert whole.status == MATCHED
    matcher = compile_scan(fmt)
    first_match = None
    for k in range(len(data) + 1):
        params = _fresh_params(fmt)
        result = matcher.match(data[:k], params, final=False)
        assert result.status in (NEED_MORE, MATCHED), (k, result)
        if result.status == MATCHED:
            first_match = first_match if first_match is not None else k
            assert result == whole
            assert [p.value for p in params] == [p.value for p in whole_params]
        else:
            assert first_match is None  # once matched, more input keeps it matched
            assert result.used <= k
    assert first_match is not None and first_match >= whole.used


def test_matching_twice_gives_the_same_result():
    matcher = compile_scan("%d,%s")
    data = "12,abc def"
    p1 = [word(), string()]
    p2 = [word(), string()]
    assert matcher.match(data, p1, final=True) == matcher.match(data, p2, final=True) == ScanResult(MATCHED, 6, 2)
    assert [p.value for p in p1] == [p.value for p in p2] == [[12], "abc"]


def test_mismatch_then_another_format_on_the_same_input():
    data = "ERR 7\r\n"
    code = word()
    assert scan_text("OK %d", data, [word()], final=False) == ScanResult(MISMATCH, 0, 0)
    assert scan_text("ERR %d", data, [code], final=False) == ScanResult(MATCHED, 5, 1)
    assert code.value == [7]


# ---------------------------------------------------------------------------
# Params over the data table
# ---------------------------------------------------------------------------

def test_table_params_integer_long_float():
    n7 = array("h", [0] * 4)
    f8 = array("f", [0.0] * 2)
    params = [TableParam(ParamKind.INTEGER, n7, 0, "N7:0"), TableParam(ParamKind.INTEGER, n7, 2, "N7:2"),
              TableParam(ParamKind.FLOAT, f8, 1, "F8:1")]
    assert scan_text("%d %ld %g", "-5 -70000 -3.14", params) == ScanResult(MATCHED, 15, 3)
    assert list(n7) == [-5, 0, -4464, -2]
    assert f8[1] == f32(-3.14)
    with pytest.raises(ParamError):
        scan_text("%ld", "1", [TableParam(ParamKind.INTEGER, n7, 3, "N7:3")])  # past the file's end


# ---------------------------------------------------------------------------
# Round trips: scan(print(x)) == x
# ---------------------------------------------------------------------------

words16 = st.integers(-32768, 32767)
longs = st.integers(-(2**31), 2**31 - 1)
float32s = st.floats(width=32, allow_nan=False)
no_ws_text = st.text(st.characters(max_codepoint=0xFFFF, blacklist_characters=WS), min_size=1, max_size=82)


@settings(max_examples=200, deadline=None)
@given(value=words16, conv=st.sampled_from("dibouxX"), flags=st.sampled_from(["", "#", "0", "-", "+"]),
       precision=st.none() | st.integers(1, 8))
def test_round_trip_words(value, conv, flags, precision):
    spec = "%" + flags + ("" if precision is None else f".{precision}") + conv
    text = format_text(spec + ";", [ValueParam(value)])
    # %#x / %#o are read back by %i; %i prints decimal, which %i would read
    # as octal after a zero-padding precision ("08"), so %d reads it
    scan_conv = "i" if flags == "#" and conv in "ox" else "d" if conv == "i" else conv
    dest = ValueParam(12345)
    assert scan_text("%" + scan_conv + ";", text, [dest]) == ScanResult(MATCHED, len(text), 1)
    assert dest.value == [value]


@settings(max_examples=200, deadline=None)
@given(value=longs, conv=st.sampled_from("dibouxX"), length=st.sampled_from("lL"))
def test_round_trip_longs(value, conv, length):
    words = [value & 0xFFFF, (value >> 16) & 0xFFFF]
    text = format_text(f"%{length}{conv}", [ValueParam(words)])
    dest = ValueParam([0, 0])
    assert scan_text(f"%{length}{conv}", text, [dest]) == ScanResult(MATCHED, len(text), 1)
    assert dest.value == ValueParam(words).value


@settings(max_examples=200, deadline=None)
@given(value=float32s, fmt=st.sampled_from(["%.9g", "%.8e", "%.8E", "%.9G", "%+.9g", "%#.8e"]),
       scan_conv=st.sampled_from("feEgG"))
def test_round_trip_floats(value, fmt, scan_conv):
    text = format_text(fmt, [ValueParam(value)])
    dest = ValueParam(1.0)
    assert scan_text("%" + scan_conv, text, [dest]) == ScanResult(MATCHED, len(text), 1)
    assert dest.value == value
    assert math.copysign(1.0, dest.value) == math.copysign(1.0, value)  # -0.0 too


def test_round_trip_nan():
    text = format_text("%g", [ValueParam(math.nan)])
    dest = flt()
    assert scan_text("%f", text, [dest]).status == MATCHED and math.isnan(dest.value)


@settings(max_examples=200, deadline=None)
@given(text=no_ws_text, precision=st.none() | st.integers(1, 82))
def test_round_trip_strings(text, precision):
    fmt = "%s" if precision is None else f"%.{precision}s"
    printed = format_text(fmt + " ", [ValueParam(text)])
    dest = string()
    result = scan_text(fmt, printed, [dest])
    assert result.status == MATCHED
    assert dest.value == (text if precision is None else text[:precision])


@settings(max_examples=150, deadline=None)
@given(block=st.lists(words16, min_size=1, max_size=40), big=st.booleans(), cross=st.booleans())
def test_round_trip_byte_blocks(block, big, cross):
    count = 2 * len(block)
    out_conv = "C" if big else "c"
    in_conv = out_conv if not cross else ("c" if big else "C")
    printed = format_text(f"%.{count}{out_conv}", [ValueParam(block)])
    assert len(printed) == count and all(ord(c) < 256 for c in printed)
    dest = words(len(block))
    assert scan_text(f"%.{count}{in_conv}", printed, [dest]) == ScanResult(MATCHED, count, 1)
    if cross:  # the other byte order: each word byte swapped
        swapped = [struct.unpack("<h", struct.pack(">h", w))[0] for w in block]
        assert dest.value == swapped
    else:
        assert dest.value == block


@settings(max_examples=100, deadline=None)
@given(n=words16, name=st.text(st.characters(max_codepoint=0x7E, min_codepoint=0x21), min_size=1, max_size=14),
       x=float32s, payload=st.lists(words16, min_size=1, max_size=6))
def test_round_trip_mixed_packet_with_crc(n, name, x, payload):
    """A whole packet printed and scanned with one format: every field comes
    back, and every proper prefix is NEED_MORE (nothing decided too early)."""
    pfmt = "%d %s %.9g %.{}C%#R".format(2 * len(payload))
    sfmt = "%.6d% %s% %g% %.{}C%#R".format(2 * len(payload))  # "% ": exactly one space
    printed = format_text(pfmt, [ValueParam(n), ValueParam(name), ValueParam(x), ValueParam(payload)])
    params = [word(), string(), flt(), words(len(payload))]
    assert scan_text(sfmt, printed, params) == ScanResult(MATCHED, len(printed), 5)
    assert [p.value for p in params] == [[n], name, x, payload]
    for k in (0, len(printed) // 2, len(printed) - 1):
        fresh = [word(), string(), flt(), words(len(payload))]
        assert compile_scan(sfmt).match(printed[:k], fresh).status == NEED_MORE
