"""What CIP tag a path names on a real DataTable: file tags, members, bits,
symbols, and the paths refused, with paths built by pylogix's own builder."""

from __future__ import annotations

import pytest
from pylogix import PLC

from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips.access import TableAccessOnTable
from softplc_lite.tlm.enips.tagnames import (BOOL, DINT, INT, LINT, REAL, SINT, STRUCT, Catalogue, PathError,
                                             parse_path)

SYMBOLS = {"Speed": "N7:3", "Running": "B3:1/4", "Flag": "B3/20", "PollTimer": "T4:1", "Late": "T4:1/DN",
           "Count": "C5:0.ACC", "Label": "ST9:1", "Bad": "N7:[N7:0]", "Gone": "N50:0"}


@pytest.fixture(scope="module")
def catalogue() -> Catalogue:
    t = DataTable()
    for a in ("N7:9", "F8:3", "L10:3", "B3:3", "T4:2", "ST9:2", "SI12:4", "LI13:1"):
        t.reference(a)
    return Catalogue(TableAccessOnTable(t), SYMBOLS)


def target(catalogue: Catalogue, tag: str, extra: bytes = b""):
    return catalogue.target(parse_path(PLC()._build_ioi(tag, INT) + extra))


@pytest.mark.parametrize("tag, file, item, ctype, units, bit", [
    ("N7", "N7", 0, INT, 10, None),
    ("N7[4]", "N7", 4, INT, 6, None),
    ("F8[3]", "F8", 3, REAL, 1, None),
    ("L10[1]", "L10", 1, DINT, 3, None),
    ("SI12[1]", "SI12", 1, SINT, 4, None),
    ("LI13", "LI13", 0, LINT, 2, None),
    ("T4[1]", "T4", 3, INT, 6, None),
    ("T4[1,2]", "T4", 5, INT, 4, None),
    ("T4[1].ACC", "T4", 5, INT, 1, None),
    ("T4[2].DN", "T4", 6, BOOL, 1, 13),
    ("ST9[1]", "ST9", 83, STRUCT, 2, None),
    ("Speed", "N7", 3, INT, 1, None),
    ("RUNNING", "B3", 1, BOOL, 1, 4),
    ("Flag", "B3", 1, BOOL, 1, 4),
    ("PollTimer.PRE", "T4", 4, INT, 1, None),
    ("PollTimer[2]", "T4", 5, INT, 1, None),
    ("Late", "T4", 3, BOOL, 1, 13),
    ("Count", "C5", 2, INT, 1, None),
    ("Label", "ST9", 83, STRUCT, 1, None),
])
def test_targets(catalogue, tag, file, item, ctype, units, bit):
    t = target(catalogue, tag)
    assert (t.file, t.item, t.ctype, t.units, t.bit) == (file, item, ctype, units, bit)


def test_bit_by_number_and_string_length(catalogue):
    t = target(catalogue, "B3[2]", b"\x91\x0215")
    assert (t.item, t.ctype, t.bit) == (2, BOOL, 15)
    t = target(catalogue, "ST9[1].LEN")
    assert (t.item, t.ctype, t.member_len) == (83, DINT, True)


def test_symbols_that_are_no_tags_are_said(catalogue):
    names = [t.name for t in catalogue.tags]
    assert "Bad" not in names and "Gone" not in names
    assert any(s.startswith("Bad:") for s in catalogue.skipped)
    assert any(s.startswith("Gone:") for s in catalogue.skipped)
    assert names[:3] == ["O0", "I1", "S2"]


@pytest.mark.parametrize("tag, extra, status", [
    ("N99", b"", 0x05), ("Nope", b"", 0x05), ("N7[10]", b"", 0x05), ("T4[3].ACC", b"", 0x05),
    ("T4[0].XYZ", b"", 0x04), ("N7[0]", b"\x91\x0216", 0x04), ("F8[0]", b"\x91\x013\x00", 0x04),
    ("N7[0]", b"\x55\x00", 0x04), ("N7[0]", b"\x91\x09", 0x04), ("Speed[1]", b"", 0x04),
])
def test_refused(catalogue, tag, extra, status):
    with pytest.raises(PathError) as e:
        target(catalogue, tag, extra)
    assert e.value.status == status


def test_symbols_of_a_program():
    from softplc_lite.ladder.ast import Program, SymbolDecl
    from softplc_lite.datatable import parse_address
    from softplc_lite.tlm.enips.tagnames import symbol_addresses

    program = Program(symbols={"POLLTIMER": SymbolDecl("PollTimer", parse_address("T4:1")),
                               "BIT": SymbolDecl("Bit", parse_address("B3/20"))})
    symbols = symbol_addresses(program.symbols)
    assert symbols == {"PollTimer": "T4:1", "Bit": "B3/20"}
    t = DataTable()
    t.reference("T4:1")
    c = Catalogue(TableAccessOnTable(t), symbols)
    assert c.target([("name", "pollTIMER"), ("name", "ACC")]).item == 5
