"""SL files (long strings: LEN and 5,000 code units an element) and the
DATAk member of a string element: typed access, JSON and snapshot round
trips, DATA declarations and the ladder's file instructions on both
executors (docs/datatable.md, "SL files")."""

from __future__ import annotations

import pytest

from softplc_lite.datatable import DataTable, ValueKind, ValueRangeError, jsonio, parse_address, snapshot
from softplc_lite.datatable.errors import AddressError
from softplc_lite.datatable.filetypes import FILE_TYPES, LONG_STRING_CHARS
from softplc_lite.ladder import run_text

TEXT = "long " * 300  # 1,500 characters


def test_an_sl_element_holds_5000_characters_and_refuses_more():
    t = DataTable()
    t.create_file("SL", 11, 2)
    assert len(t.file("SL11").data) == 2 * (1 + LONG_STRING_CHARS)
    t.write("SL11:0", TEXT)
    assert t.read("SL11:0") == TEXT and t.read("SL11:0.LEN") == 1500 and t.read("SL11:1") == ""
    t.write("SL11:1", "y" * LONG_STRING_CHARS)
    assert t.read("SL11:1.LEN") == LONG_STRING_CHARS and t.read("SL11:0") == TEXT  # elements apart
    with pytest.raises(ValueRangeError, match="at most 5000 characters"):
        t.write("SL11:0", "z" * (LONG_STRING_CHARS + 1))
    with pytest.raises(ValueRangeError, match="a string length"):
        t.write("SL11:0.LEN", LONG_STRING_CHARS + 1)
    assert parse_address("SL11:0").kind is ValueKind.STRING and FILE_TYPES["SL"].is_string


def test_the_data_member_is_one_code_unit_of_st_and_sl():
    t = DataTable()
    t.create_file("SL", 11, 1)
    t.create_file("ST", 9, 1)
    t.write("ST9:0", "AB")
    t.write("SL11:0", "xyz")
    assert t.read("ST9:0.DATA1") == ord("B") and t.read("SL11:0.DATA2") == ord("z")
    t.write("SL11:0.DATA4999", 65)
    t.write("ST9:0.DATA0", 67)
    assert t.read("ST9:0") == "CB" and t.read("SL11:0.LEN") == 3  # LEN is not changed
    assert t.read("SL11:0.DATA4999") == 65
    with pytest.raises(AddressError, match="DATA0..DATA81"):
        parse_address("ST9:0.DATA82")
    with pytest.raises(AddressError, match="DATA0..DATA4999"):
        parse_address("SL11:0.DATA5000")


def test_snapshot_and_json_round_trip_sl():
    t = DataTable()
    t.create_file("SL", 11, 3)
    t.write("SL11:0", TEXT)
    t.write("SL11:2", "é ✓")
    back = snapshot.decode(snapshot.encode(t))
    assert back == t and back.read("SL11:0") == TEXT
    text = jsonio.dumps(t)
    again = jsonio.table_from_json(text)
    assert again == t and again.read("SL11:2") == "é ✓"
    raw = jsonio.table_from_json('{"SL11": [{"LEN": 2, "CHARS": "' + "q" * 100 + '"}]}')
    assert raw.read("SL11:0") == "qq" and raw.read("SL11:0.DATA99") == ord("q")


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_data_declarations_and_a_move_of_a_character(executor):
    t = run_text('DATA SL11 2 = "' + "ab" * 60 + '"\nMOV SL11:0.DATA1 N7:0\nMOV 90 SL11:1.DATA0\n',
                 executor=executor).table
    assert t.read("SL11:0") == "ab" * 60 and t.read("N7:0") == ord("b")
    assert t.read("SL11:1.DATA0") == 90 and t.read("SL11:1") == ""


def test_datatable_print_shows_a_long_string_and_one_character(tmp_path, capsys):
    from softplc_lite.cli import main

    t = DataTable()
    t.create_file("SL", 11, 1)
    t.write("SL11:0", "w" * 99 + "!")
    path = tmp_path / "t.json"
    path.write_text(jsonio.dumps(t), encoding="utf-8")
    assert main(["datatable", str(path), "--print", "SL11:0", "--print", "SL11:0.DATA99"]) == 0
    out = capsys.readouterr().out
    assert "w" * 99 + "!" in out and "SL11:0.DATA99 = 33" in out


def test_the_enips_server_leaves_an_sl_file_out_and_serves_a_character_as_an_int():
    from softplc_lite.tlm.enips import pccc_object
    from softplc_lite.tlm.enips.access import TableAccessOnTable
    from softplc_lite.tlm.enips.tagnames import DINT, INT, Catalogue

    t = DataTable()
    t.create_file("SL", 11, 2)
    t.create_file("ST", 9, 1)
    access = TableAccessOnTable(t)
    catalogue = Catalogue(access, {"Msg": "SL11:0", "Second": "ST9:0.DATA1", "Size": "ST9:0.LEN"})
    tags = {tag.name: tag for tag in catalogue.tags}
    assert "SL11" not in tags and "Msg" not in tags and "ST9" in tags
    assert catalogue.skipped == ["Msg: SL11:0 is not a direct address of a served file"]
    assert (tags["Second"].ctype, tags["Second"].item) == (INT, 2) and (tags["Size"].ctype, tags["Size"].item) == (DINT, 0)
    with pytest.raises(pccc_object.Refused, match="SL11 is a long string file: PCCC has no type for it"):
        pccc_object._file(access, None, 11)
