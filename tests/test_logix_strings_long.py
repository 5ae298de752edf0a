"""String types longer than an ST element holds (STRING_200: an SL file,
datatable/filetypes.py) and a string's characters one by one
(``Str.DATA[3]``), through an export's rungs on both executors
(docs/logix.md, "Strings")."""

from __future__ import annotations

import pytest

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner

from helpers.logix_l5x import Prog, Task, write_l5x, export_runner

EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])
TYPES = """<DataType Name="STRING_200" Family="StringFamily" Class="User"><Members>
<Member Name="LEN" DataType="DINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="DATA" DataType="SINT" Dimension="200" Radix="ASCII" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>
<DataType Name="Huge" Family="StringFamily" Class="User"><Members>
<Member Name="LEN" DataType="DINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="DATA" DataType="SINT" Dimension="64000" Radix="ASCII" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>"""
TAGS = [("L1", "STRING_200"), ("L2", "STRING_200"), ("L3", "STRING_200"), ("Ls", "STRING_200[3]"),
        ("S1", "STRING"), ("N", "DINT"), ("C", "SINT"), ("Same", "BOOL"), ("Big", "Huge"),
        ("Bytes", "SINT[6]")]
LONG_TEXT = "x" * 90 + "end"


def runner(tmp_path, rungs, executor="compiled", tags=TAGS) -> Runner:
    path = write_l5x(tmp_path / "x.L5X", tags, [Prog("P", {"Main": rungs})], [Task("T", ["P"])], data_types=TYPES)
    return export_runner(path, executor)


def read(r, tag):
    return r.table.read(r.app.program.symbols.resolve_path(tag))


def write(r, tag, value):
    r.table.write(r.app.program.symbols.resolve_path(tag), value)


@EXECUTORS
def test_a_long_string_type_runs_concat_mid_equ_and_mov(tmp_path, executor):
    r = runner(tmp_path, ["CONCAT(L1,L2,L3);", "MID(L3,11,88,L2);", "EQU(L1,Ls[1])OTE(Same);", "MOV(L3,Ls[1]);",
                          "MOV(L3,S1);"], executor)
    write(r, "L1", LONG_TEXT)
    write(r, "L2", "-tail")
    r.run(1)
    assert read(r, "L3") == LONG_TEXT + "-tail"  # 98 characters: more than an ST element holds
    assert read(r, "L3.LEN") == 98 and read(r, "L2") == LONG_TEXT[87:] + "-tail"
    assert read(r, "Ls[1]") == LONG_TEXT + "-tail" and read(r, "Ls[0]") == "" and read(r, "Same") == 0
    assert read(r, "S1") == (LONG_TEXT + "-tail")[:82]  # into a STRING: cut to its 82
    write(r, "L1", LONG_TEXT + "-tail")
    r.run(1)
    assert read(r, "Same") == 1
    r.close()


@EXECUTORS
def test_concat_past_the_types_length_stops_at_200(tmp_path, executor):
    r = runner(tmp_path, ["CONCAT(L1,L1,L3);"], executor)
    write(r, "L1", "a" * 150)
    r.run(1)
    assert read(r, "L3") == "a" * 200 and read(r, "L3.LEN") == 200
    r.close()


def test_a_long_strings_initial_value_is_loaded(tmp_path):
    path = write_l5x(tmp_path / "x.L5X", TAGS, [Prog("P", {"Main": ["NOP();"]})], [Task("T", ["P"])],
                     data_types=TYPES)
    text = path.read_text(encoding="utf-8").replace(
        '<Tag Name="L1" TagType="Base" DataType="STRING_200" Constant="false" ExternalAccess="Read/Write"/>',
        '<Tag Name="L1" TagType="Base" DataType="STRING_200" Constant="false" ExternalAccess="Read/Write">'
        f'<Data Format="String" Length="93"><![CDATA[\'{LONG_TEXT}\']]></Data></Tag>')
    path.write_text(text, encoding="utf-8")
    r = export_runner(path)
    assert read(r, "L1") == LONG_TEXT
    r.close()


@EXECUTORS
def test_data_k_reads_and_writes_one_character(tmp_path, executor):
    r = runner(tmp_path, ["MOV(L1.DATA[2],N);", "MOV(S1.DATA[0],C);", "MOV(90,L2.DATA[0]);",
                          "MOV(L2.DATA[0],Ls[2].DATA[199]);", "EQU(S1.DATA[1],66)OTE(Same);"], executor)
    write(r, "L1", "abc")
    write(r, "S1", "AB")
    write(r, "L2", "yes")
    r.run(1)
    assert read(r, "N") == ord("c") and read(r, "C") == ord("A") and read(r, "Same") == 1
    assert read(r, "L2") == "Zes" and read(r, "L2.LEN") == 3  # LEN stays: DATA is the characters only
    assert read(r, "Ls[2].DATA[199]") == 90 and read(r, "Ls[2].LEN") == 0
    r.close()


def test_data_past_the_end_is_an_error_and_a_variable_index_is_not_run(tmp_path):
    path = write_l5x(tmp_path / "x.L5X", TAGS, [Prog("P", {"Main": ["MOV(L1.DATA[N],C);", "NOP();"]})],
                     [Task("T", ["P"])], data_types=TYPES)
    warnings = "\n".join(load_app(path).warnings)
    assert "a string's DATA indexed at run time is not reached" in warnings
    path = write_l5x(tmp_path / "y.L5X", TAGS, [Prog("P", {"Main": ["MOV(L1.DATA[200],C);"]})],
                     [Task("T", ["P"])], data_types=TYPES)
    with pytest.raises(Exception) as info:
        load_app(path)
    assert "index 200 is past the end of STRING_200.DATA (SINT[200])" in str(info.value.errors[0])


def test_a_string_type_longer_than_an_sl_element_is_not_held(tmp_path):
    path = write_l5x(tmp_path / "x.L5X", TAGS, [Prog("P", {"Main": ["MOV(Big,L1);", "NOP();"]})],
                     [Task("T", ["P"])], data_types=TYPES)
    warnings = "\n".join(load_app(path).warnings)
    assert "string type Huge holds 64000 characters; softplc_lite holds strings of 1 to 5000" in warnings


@EXECUTORS
def test_cop_and_fll_take_a_strings_characters_as_sints(tmp_path, executor):
    r = runner(tmp_path, ["COP(L1.DATA[0],Bytes[0],3);", "COP(Bytes[4],S1.DATA[1],2);", "FLL(90,L2.DATA[1],2);",
                          "COP(L1.DATA[198],Bytes[3],5);"], executor)
    write(r, "L1", "a\u00e9c")
    write(r, "S1", "pqrs")
    write(r, "L2", "wxyz")
    write(r, "Bytes[4]", 72)
    write(r, "Bytes[5]", -23)
    r.run(1)
    assert [read(r, f"Bytes[{k}]") for k in range(3)] == [97, -23, 99]  # the code unit's low byte, signed
    assert read(r, "S1") == "pH\u00e9s" and read(r, "L2") == "wZZz"  # a SINT's byte as the character
    assert read(r, "Bytes[3]") == 0 and read(r, "Bytes[4]") == 0  # DATA[198..199]: stops at the type's end
    r.close()


def test_a_cop_between_a_strings_data_and_a_dint_is_not_run(tmp_path):
    path = write_l5x(tmp_path / "x.L5X", TAGS, [Prog("P", {"Main": ["COP(L1.DATA[0],N,3);"]})],
                     [Task("T", ["P"])], data_types=TYPES)
    assert "a copy between a string's DATA and DINT copies Logix's bytes" in "\n".join(load_app(path).warnings)


def test_a_string_type_the_export_leaves_out_is_taken_from_its_name(tmp_path):
    udt = """<DataType Name="Valve" Family="NoFamily" Class="User"><Members>
<Member Name="Name" DataType="STRING_16" Dimension="0" Radix="NullType" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="Pos" DataType="DINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>"""
    rungs = ["CONCAT(V.Name,V.Name,V.Name);", "MOV(V.Name.LEN,V.Pos);", "CONCAT(Note,Note,Note);"]
    path = write_l5x(tmp_path / "x.L5X", [("V", "Valve"), ("Note", "STRING120")], [Prog("P", {"Main": rungs})],
                     [Task("T", ["P"])], data_types=udt)
    app = load_app(path)
    warnings = "\n".join(app.warnings)
    assert "data type STRING_16 is not in the export: taken as a string type of 16 characters" in warnings
    assert "data type STRING120 is not in the export: taken as a string type of 120 characters" in warnings
    r = Runner(app, RunOptions(fresh=True, save_state=False))
    write(r, "V.Name", "abcdefghij")
    write(r, "Note", "n" * 70)
    r.run(1)
    assert read(r, "V.Name") == "abcdefghijabcdef" and read(r, "V.Pos") == 16  # cut to the type's 16
    assert read(r, "Note") == "n" * 120
    r.close()
