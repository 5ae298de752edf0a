"""JSON import/export: the documented format, partial loads, exact round
trips, and errors that change nothing."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings

from conftest import random_tables
from softplc_lite.datatable import DataTable
from softplc_lite.datatable import jsonio
from softplc_lite.datatable.jsonio import DataTableJSONError


def test_export_format():
    t = DataTable()
    t.reference("ST9:1")
    t.write("N7:0", -5)
    t.write("F8:0", 3.14)
    t.write("ST9:1", "hi")
    t.write("T4:0", {"PRE": 100, "DN": 1})
    t.write("R6:0", {"EN": 1, "LEN": 8})
    doc = jsonio.export_table(t)
    assert list(doc) == ["O0", "I1", "S2", "B3", "T4", "C5", "R6", "N7", "F8", "ST9"]
    assert doc["N7"] == [-5]
    assert doc["F8"] == [3.140000104904175]
    assert doc["ST9"] == ["", "hi"]
    assert doc["T4"] == [{"EN": 0, "TT": 0, "DN": 1, "PRE": 100, "ACC": 0}]
    assert doc["R6"] == [{"EN": 1, "EU": 0, "DN": 0, "EM": 0, "ER": 0, "UL": 0, "IN": 0, "FD": 0,
                          "LEN": 8, "POS": 0}]
    assert len(doc["O0"]) == 32 and len(doc["S2"]) == 128
    text = jsonio.dumps(t)
    assert json.loads(text) == doc
    assert '  "N7": [-5],' in text.splitlines()


def test_partial_loads():
    t = DataTable()
    t.reference("N7:4")
    for i in range(5):
        t.write(f"N7:{i}", 10 + i)
    t.write("T4:0", {"PRE": 50, "ACC": 9, "EN": 1})
    jsonio.load_text(t, '{"N7": [1, null, 3], "T4": [{"ACC": 5}], "ST12": ["abc"], "O": [1]}')
    assert [t.read(f"N7:{i}") for i in range(5)] == [1, 11, 3, 13, 14]
    assert t.read("T4:0") == {"EN": 1, "TT": 0, "DN": 0, "PRE": 50, "ACC": 5}
    assert t.read("ST12:0") == "abc"
    assert t.read("O:0") == 1


def test_load_grows_files():
    t = DataTable()
    jsonio.load_text(t, '{"N7": [0, 0, 0, 0, 9], "F20": [1.5, 2.5]}')
    assert t.file("N7").size == 5 and t.read("N7:4") == 9
    assert t.file("F20").size == 2 and t.read("F20:1") == 2.5


def test_control_word_with_unnamed_bits_round_trips():
    t = DataTable()
    t.write_word("R6:0", 0x8003)
    doc = jsonio.export_table(t)
    assert doc["R6"][0]["WORD0"] == 0x8003 and doc["R6"][0]["EN"] == 1
    assert jsonio.table_from_json(jsonio.dumps(t)) == t


def test_string_with_hidden_characters_round_trips():
    t = DataTable()
    t.reference("ST9:1")
    t.write("ST9:0", "abcdef")
    t.write("ST9:0.LEN", 2)
    t.write_word("ST9:1", 90)
    doc = jsonio.export_table(t)
    assert doc["ST9"] == [{"LEN": 2, "CHARS": "abcdef"}, {"LEN": 90, "CHARS": ""}]
    back = jsonio.table_from_json(jsonio.dumps(t))
    assert back == t and back.read("ST9:0") == "ab"


def test_non_ascii_and_surrogates_round_trip():
    t = DataTable()
    t.reference("ST9:0")
    t.write("ST9:0", "é\ud800€\uffff")
    text = jsonio.dumps(t)
    assert text.isascii()
    assert jsonio.table_from_json(text).read("ST9:0") == "é\ud800€\uffff"


def test_nan_and_infinity():
    t = DataTable()
    t.reference("F8:1")
    t.write("F8:0", float("nan"))
    t.write("F8:1", float("-inf"))
    back = jsonio.table_from_json(jsonio.dumps(t))
    assert math.isnan(back.read("F8:0")) and back.read("F8:1") == float("-inf")


@settings(max_examples=60, deadline=None)
@given(random_tables())
def test_export_import_reproduces_the_table_exactly(table: DataTable):
    text = jsonio.dumps(table)
    back = jsonio.table_from_json(text)
    assert back == table
    assert jsonio.dumps(back) == text


BAD = [
    ('{"N7": [1, 40000]}', "t.json: N7[1]: 40000 does not fit N7:1"),
    ('{"N7": [1,\n 2,]}', "t.json:2:4: Expecting value"),
    ('[1, 2]', "t.json: expected an object of files"),
    ('{"X3": [1]}', "t.json: key 'X3': unknown file type"),
    ('{"N7x": [1]}', "t.json: key 'N7x': expected a file name"),
    ('{"N7": 5}', "t.json: N7: expected a list of elements, got a number (5)"),
    ('{"N7": "abc"}', "t.json: N7: expected a list of elements, got text"),
    ('[1, 2]', "t.json: expected an object of files such as {\"N7\": [1, 2]}, got a list"),
    ('{"N9": [1], "ST9": ["a"]}', "file number 9 is already N9; ST9 cannot also exist"),
    ('{"T4": [{"ACC": 5, "LEN": 1}]}', "t.json: T4[0]: 'LEN' is not a member of T4:0"),
    ('{"T4": [5]}', "T4:0 is a timer element; give an object of members"),
    ('{"T4": [{"DN": 2}]}', "T4[0]: 2 does not fit T4:0/DN"),
    ('{"ST9": [7]}', "ST9:0 is a string element"),
    ('{"ST9": ["' + "x" * 83 + '"]}', "at most 82 characters"),
    ('{"ST9": [{"LEN": 3, "FOO": 1}]}', "unknown member 'FOO'"),
    ('{"F8": ["1.5"]}', "F8:0 holds a float"),
    ('{"F8": [1e39]}', "does not fit F8:0, which holds a float32"),
    ('{"N7": [1.5]}', "N7:0 holds a 16-bit signed integer (-32768..32767), got 1.5"),
    ('{"N2": [1]}', "N files are numbered 3..9999"),
    ('{"N7": [' + ",".join(["0"] * 10001) + ']}', "a file holds at most 10000"),
]


@pytest.mark.parametrize("text,message", BAD)
def test_bad_documents_are_reported_and_change_nothing(text, message):
    t = DataTable()
    t.write("N7:0", 42)
    before = jsonio.dumps(t)
    with pytest.raises(DataTableJSONError) as info:
        jsonio.load_text(t, text, "t.json")
    assert message in str(info.value)
    assert jsonio.dumps(t) == before


def test_load_file_reports_missing_file(tmp_path):
    with pytest.raises(DataTableJSONError, match="cannot read"):
        jsonio.load_file(DataTable(), str(tmp_path / "nope.json"))


def test_characters_beyond_ucs2_load_as_a_surrogate_pair():
    t = DataTable()
    t.reference("ST9:0")
    jsonio.load_text(t, '{"ST9": ["a\\ud83d\\ude00", {"CHARS": "\U0001F600"}]}')
    assert t.read("ST9:0") == "a\ud83d\ude00" and t.read("ST9:0.LEN") == 3
    assert t.read("ST9:1.LEN") == 0 and t.block("ST9:1", 3).values()[1:] == [0xD83D - 0x10000, 0xDE00 - 0x10000]
