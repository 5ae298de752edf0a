"""The value syntax both Logix readers share (softplc_lite/logix/values.py)."""

from __future__ import annotations

import math

import pytest

from softplc_lite.logix.values import (MAX_DEPTH, ValueSyntax, parse_l5k_value, parse_number, parse_quoted,
                                       typed_scalar, unescape)


@pytest.mark.parametrize("text, value", [
    ("42", 42), ("-7", -7), ("16#00ff", 255), ("16#ffff_ffff", 0xFFFFFFFF), ("2#0101_1010", 90), ("8#17", 15),
    ("-16#10", -16), ("2.50000000e+001", 25.0), ("1.5", 1.5), ("-1.#INF", -math.inf),
])
def test_numbers_in_every_radix(text, value):
    assert parse_number(text) == value


@pytest.mark.parametrize("text", ["1.#QNAN", "1.$", "-1.#IND"])
def test_logix_not_a_number_forms(text):
    assert math.isnan(parse_number(text))


def test_string_escapes():
    assert unescape("It$'s $$5$N$0D$t$\"") == "It's $5\n\r\t\""
    assert parse_quoted("'$00A'") == "\x00A"
    with pytest.raises(ValueSyntax) as err:
        unescape("ab$q")
    assert err.value.offset == 2


def test_typed_scalars_by_data_type_and_radix():
    assert typed_scalar("'$00'", "SINT", "ASCII") == 0
    assert typed_scalar("'AB'", "INT", "ASCII") == 0x4142
    assert typed_scalar("0", "REAL", "Float") == 0.0 and isinstance(typed_scalar("0", "REAL", "Float"), float)
    assert typed_scalar("DT#1970-01-01-00:00:00.000_000Z", "LINT", "Date/Time") == "DT#1970-01-01-00:00:00.000_000Z"
    with pytest.raises(ValueSyntax, match="expected an integer for a DINT"):
        typed_scalar("1.5", "DINT", "Decimal")


def test_positional_values_nest():
    assert parse_l5k_value("[5,'READY$00',[1,2.0e+000],16#ff,[]]") == [5, "READY\x00", [1, 2.0], 255, []]


@pytest.mark.parametrize("text, offset, message", [
    ("[1,2", 0, "expected ] to close this ["),
    ("[1 2]", 3, "expected , or ] in a list, found '2'"),
    ("'abc", 0, "expected ' to close this string"),
    ("[1,]", 3, "expected a value, found ']'"),
    ("12x", 0, "expected a number, found '12x'"),
    ("[1] 2", 4, "expected the end of the value, found '2'"),
])
def test_bad_positional_values_say_where_and_what(text, offset, message):
    with pytest.raises(ValueSyntax) as err:
        parse_l5k_value(text)
    assert (err.value.offset, err.value.message) == (offset, message)


def test_nesting_is_bounded():
    assert parse_l5k_value("[" * MAX_DEPTH + "1" + "]" * MAX_DEPTH) is not None
    with pytest.raises(ValueSyntax, match="levels of nested"):
        parse_l5k_value("[" * 5000 + "1" + "]" * 5000)
