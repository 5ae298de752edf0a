"""The Studio 5000 export readers (softplc_lite/logix/l5x.py, l5k.py):
what each reads out of a hand-written controller, value for value; that the
L5X and L5K forms of the same controller read the same; every error located
where it is; and that no damaged input gives anything but a Project or an
ExportError."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from helpers.located import locate
from helpers.logix_exports import damaged_copies, without_positions
from softplc_lite.ladder.ast import Pos
from softplc_lite.logix.exportfile import EXPORT
from softplc_lite.logix.l5k import read_l5k
from softplc_lite.logix.l5x import read_l5x
from softplc_lite.logix.model import (AddOnInstruction, DataType, ExportError, InitialValue, Line, Member,
                                      Module, ModuleTag, Program, Project, Routine, Rung, Tag, Task)

FIXTURES = Path(__file__).parent / "fixtures" / "logix"
L5X = FIXTURES / "reader_controller.L5X"
L5K = FIXTURES / "reader_controller.L5K"


def _dec(data):
    return InitialValue("decorated", data)


def _expected_l5x() -> Project:
    """What reader_controller.L5X says, its data read in decorated form."""
    ro = "Read Only"
    return Project(
        source="reader_controller.L5X", format="L5X", target_type="Controller", target_name="Mixer",
        controller="Mixer", processor_type="1769-L33ER", software_revision="32.11",
        data_types=[DataType("Valve", [
            Member("ZZZZZZZZZZValve0", "SINT", hidden=True, radix="Decimal"),
            Member("Open", "BIT", target="ZZZZZZZZZZValve0", bit_number=0, description="Command open", radix="Decimal"),
            Member("Closed", "BIT", target="ZZZZZZZZZZValve0", bit_number=1, external_access=ro, radix="Decimal"),
            Member("Travel", "DINT", radix="Decimal"),
            Member("Hist", "INT", dimension=4, external_access="None", radix="Hex"),
        ], description="One valve")],
        add_on_instructions=[AddOnInstruction(
            "Scale",
            parameters=[
                Tag("EnableIn", "BOOL", external_access=ro, radix="Decimal", usage="Input", visible=False),
                Tag("EnableOut", "BOOL", external_access=ro, radix="Decimal", usage="Output", visible=False),
                Tag("Raw", "DINT", radix="Decimal", value=_dec(0), usage="Input", required=True),
                Tag("Gain", "REAL", radix="Float", value=_dec(1.5), usage="Input"),
                Tag("Out", "REAL", external_access=ro, radix="Float", value=_dec(0.0), usage="Output"),
            ],
            local_tags=[Tag("Tmp", "REAL", external_access="None", radix="Float", value=_dec(0.0))],
            routines=[Routine("Logic", "RLL", rungs=[Rung(0, "MUL(Raw,Gain,Tmp)MOV(Tmp,Out);")])],
            revision="1.2", description="Scale a raw count", scan_modes=set())],
        modules=[
            Module("Local", "1769-L33ER", parent="Local"),
            Module("DIO", "1769-IQ6XOW4/B", parent="Local", slot=1, tags=[
                ModuleTag("Local:1:C", "AB:1769_DI6XOW4:C:0", _dec({"ProgToFaultEn": 0, "ProgMode": 0})),
                ModuleTag("Local:1:I", "AB:1769_DI6XOW4:I:0", _dec({"Fault": 0, "Data": 5})),
                ModuleTag("Local:1:O", "AB:1769_DI6XOW4:O:0", _dec({"Data": 0})),
            ]),
            Module("Drive1", "ETHERNET-MODULE", parent="Local", inhibited=True, tags=[
                ModuleTag("Drive1:I", "SINT", _dec([0, 0]))]),
        ],
        module_types=[
            DataType("AB:1769_DI6XOW4:C:0", [Member("ProgToFaultEn", "BOOL"), Member("ProgMode", "INT", radix="Binary")]),
            DataType("AB:1769_DI6XOW4:I:0", [Member("Fault", "DINT", radix="Binary"),
                                            Member("Data", "INT", radix="Binary")]),
            DataType("AB:1769_DI6XOW4:O:0", [Member("Data", "INT", radix="Binary")]),
        ],
        tags=[
            Tag("FillTimer", "TIMER", description="Fill time",
                value=_dec({"PRE": 3000, "ACC": 0, "EN": 0, "TT": 0, "DN": 0})),
            Tag("Batches", "COUNTER", value=_dec({"PRE": 10, "ACC": 7, "CU": 0, "CD": 0, "DN": 0, "OV": 0, "UN": 1})),
            Tag("Recipe", "STRING", value=_dec("It's $5\n")),
            Tag("Grid", "DINT", dims=(2, 3), radix="Hex", value=_dec([[1, 2, 3], [4, 5, 255]])),
            Tag("V1", "Valve", value=_dec({"Open": 0, "Closed": 1, "Travel": -40, "Hist": [1, 2, 0, 0]})),
            Tag("ValveOpen", None, tag_type="Alias", alias_for="V1.Open", radix="Decimal"),
            Tag("Mask", "SINT", external_access=ro, constant=True, radix="Binary", value=_dec(0b01011010)),
            Tag("Perm", "INT", radix="Octal", value=_dec(0o17)),
            Tag("Letter", "SINT", radix="ASCII", value=_dec(65)),
            Tag("Ratio", "REAL", radix="Exponential", value=_dec(0.25)),
            Tag("ScaleIt", "Scale", value=_dec({"EnableIn": 1, "EnableOut": 0, "Raw": 0, "Gain": 1.5, "Out": 0.0})),
        ],
        programs=[
            Program("Batch", "Main", "Fault", tags=[Tag("Step", "DINT", radix="Decimal", value=_dec(3))], routines=[
                Routine("Main", "RLL", rungs=[
                    Rung(0, "XIC(V1.Open)TON(FillTimer,?,?);", "Fill; then mix"),
                    Rung(1, "XIC(FillTimer.DN)[CTU(Batches,?,?),MOV(2,Step)];"),
                    Rung(2, "Scale(ScaleIt,Grid[1,2],1.5,Ratio)XIC(Local:1:I.Data.0)OTE(Local:1:O.Data.1);"),
                    Rung(3, "JSR(Calc,0);"),
                ]),
                Routine("Calc", "ST", lines=[Line(0, "Step := Step + 1;"), Line(1, "IF Step > 5 THEN Step := 0; END_IF;")]),
                Routine("Fault", "RLL", rungs=[Rung(0, "NOP();")]),
            ]),
            Program("Idle", "Main", disabled=True, routines=[
                Routine("Main", "RLL", rungs=[Rung(0, "XIO(ValveOpen)OTE(V1.Closed);")])]),
        ],
        tasks=[
            Task("MainTask", "CONTINUOUS", programs=["Batch"]),
            Task("Slow", "PERIODIC", rate_ms=250.0, priority=8, watchdog_ms=100.0, inhibited=True, programs=["Idle"]),
        ],
    )


def test_l5x_reads_every_part_value_for_value():
    project = read_l5x(L5X, "reader_controller.L5X")
    assert without_positions(project) == without_positions(_expected_l5x())


def test_l5x_read_from_text_equals_read_from_the_file():
    text = L5X.read_text(encoding="utf-8")
    assert read_l5x(text, "reader_controller.L5X") == read_l5x(L5X, "reader_controller.L5X")


def test_l5x_positions_are_where_each_part_starts():
    text = L5X.read_text(encoding="utf-8")
    project = read_l5x(L5X, "r.L5X")
    main = project.programs[0].routines[0]
    assert main.pos == Pos("r.L5X", *locate(text, '<Routine Name="Main"'))
    # a rung's position is where its text starts, inside the CDATA section
    assert main.rungs[1].pos == Pos("r.L5X", *locate(text, "XIC(FillTimer.DN)"))
    assert project.programs[0].routines[1].lines[1].pos == Pos("r.L5X", *locate(text, "IF Step > 5"))
    assert project.tags[3].pos == Pos("r.L5X", *locate(text, '<Tag Name="Grid"'))
    assert project.data_types[0].members[2].pos == Pos("r.L5X", *locate(text, '<Member Name="Closed"'))
    assert project.tasks[1].pos == Pos("r.L5X", *locate(text, '<Task Name="Slow"'))


def test_l5x_positional_data_is_the_l5k_form():
    project = read_l5x(L5X, "r.L5X", prefer="positional")
    by_name = {t.name: t.value for t in project.tags}
    assert by_name["Recipe"].form == "positional"
    assert by_name["Recipe"].data == [9, "It's $5\n\x00\x00"]
    assert by_name["Grid"].data == [1, 2, 3, 4, 5, 255]
    assert by_name["V1"].data == [2, -40, [1, 2, 0, 0]]
    assert by_name["Batches"].data == [536870912, 10, 7]
    assert by_name["ValveOpen"] is None


def _l5x_problems(text: str) -> list:
    with pytest.raises(ExportError) as err:
        read_l5x(text, "bad.L5X")
    return err.value.problems


def _controller(body: str, target: str = "Controller") -> str:
    return (f'<?xml version="1.0"?>\n<RSLogix5000Content TargetType="{target}" SoftwareRevision="32.11">\n'
            f'<Controller Use="Target" Name="C">\n{body}\n</Controller>\n</RSLogix5000Content>\n')


def test_l5x_malformed_xml_is_located_by_expat():
    text = _controller("<Tags>\n  <Tag Name=\"A\" DataType=\"DINT\">\n</Tags>")
    [problem] = _l5x_problems(text)
    # expat points at the closing tag's name
    assert problem.pos == Pos("bad.L5X", *locate(text, "Tags>\n</Controller"))
    assert "malformed XML: mismatched tag" in problem.message


def test_l5x_unknown_target_type():
    text = _controller("", target="Gizmo")
    [problem] = _l5x_problems(text)
    assert problem.pos == Pos("bad.L5X", *locate(text, "<RSLogix5000Content"))
    assert "expected a TargetType of Controller, Program, Routine, Rung" in problem.message
    assert "found 'Gizmo'" in problem.message


def test_l5x_every_problem_at_once_reading_on_past_each():
    text = _controller(
        "<Tags>\n"
        '<Tag TagType="Base" DataType="DINT"/>\n'
        '<Tag Name="B" TagType="Base" DataType="DINT"><Data Format="L5K"><![CDATA[[1,2]]></Data></Tag>\n'
        '<Tag Name="C" TagType="Base" DataType="DINT"><Data Format="Decorated">'
        '<DataValue DataType="DINT" Radix="Hex" Value="16#zz"/></Data></Tag>\n'
        '<Tag Name="D" TagType="Base" DataType="DINT"/>\n'
        "</Tags>\n<Programs>\n"
        '<Program Name="P" MainRoutineName="R"><Routines><Routine Name="R" Type="RLL"><RLLContent>\n'
        '<Rung Number="0" Type="N"><Comment><![CDATA[no text]]></Comment></Rung>\n'
        '<Rung Number="1" Type="N"><Text><![CDATA[NOP();]]></Text></Rung>\n'
        "</RLLContent></Routine></Routines></Program>\n</Programs>")
    problems = _l5x_problems(text)
    assert [(p.pos.line, p.pos.column, p.message) for p in problems] == [
        (*locate(text, '<Tag TagType="Base"'), "expected a Name attribute on this Tag"),
        (*locate(text, "[1,2]"), "bad L5K data: expected ] to close this ["),
        (*locate(text, '<DataValue DataType="DINT" Radix="Hex"'),
         "bad Value for DINT: expected base-16 digits after 16#, found '16#zz'"),
        (*locate(text, '<Rung Number="0"'), "expected a Text element with the rung's text in rung 0"),
    ]


@pytest.mark.parametrize("reader", [read_l5x, read_l5k])
def test_a_file_that_cannot_be_read_is_the_one_problem(tmp_path, reader):
    with pytest.raises(ExportError) as err:
        reader(tmp_path / "missing.L5X", "m.L5X")
    [problem] = err.value.problems
    assert problem.pos.source == "m.L5X" and "cannot read" in problem.message and "missing.L5X" in problem.message
    with pytest.raises(ExportError) as err:
        reader(tmp_path)  # a directory: refused before it is opened (softplc_lite/textfile.py)
    assert "a directory" in str(err.value) or "not a regular file" in str(err.value)


@pytest.mark.parametrize("name", ["whole_controller.L5X", "reader_controller.L5X"])
def test_l5x_damaged_copies_give_a_project_or_an_export_error(name):
    text = (FIXTURES / name).read_text(encoding="utf-8")
    for damaged in damaged_copies(text, seed=len(name), count=150):
        try:
            project = read_l5x(damaged, "d.L5X")
        except ExportError as e:
            assert e.problems and all(p.pos.source == "d.L5X" for p in e.problems)
        else:
            assert isinstance(project, Project)


def test_l5x_partial_exports_read_into_the_same_fields():
    rung = read_l5x(FIXTURES / "public" / "tnunnink__L5Sharp" / "Rung1_from_Main.L5X")
    assert rung.target_type == "Rung" and rung.controller == "KM_TUS_Skid"
    [routine] = [r for p in rung.programs for r in p.routines]
    assert routine.kind == "RLL" and len(routine.rungs) == 1 and routine.rungs[0].text.endswith(";")
    assert rung.data_types and all(dt.members for dt in rung.data_types)
    aoi = read_l5x(FIXTURES / "public" / "Alex-OPTIM__rslogix5000-aois" / "DUTY_CYCLE.L5X")
    assert aoi.target_type == "AddOnInstructionDefinition"
    # the target and the AOIs it uses (Use="Context"), each with its Logic routine
    assert [a.name for a in aoi.add_on_instructions] == ["BOOLS_2_DINT", "DINT_2_BOOLS", "DUTY_CYCLE"]
    assert aoi.target_name == "DUTY_CYCLE"
    assert all(any(r.name == "Logic" for r in a.routines) for a in aoi.add_on_instructions)


def test_l5x_every_public_export_reads():
    for path in sorted((FIXTURES / "public").glob("*/*.L5X")):
        project = read_l5x(path)
        assert project.format == "L5X" and project.target_type, path


def test_l5x_not_a_number_and_radix_forms_in_decorated_data():
    text = _controller(
        "<Tags>\n"
        '<Tag Name="N" DataType="REAL"><Data Format="Decorated"><DataValue DataType="REAL" Radix="Float" Value="1.#QNAN"/></Data></Tag>\n'
        '<Tag Name="M" DataType="REAL"><Data Format="Decorated"><DataValue DataType="REAL" Radix="Float" Value="1.$"/></Data></Tag>\n'
        '<Tag Name="Z" DataType="SINT"><Data Format="Decorated"><DataValue DataType="SINT" Radix="ASCII" Value="\'$00\'"/></Data></Tag>\n'
        '<Tag Name="S" DataType="DINT" Dimensions="2"><Data Format="Decorated"><Array DataType="STRING" Dimensions="2">'
        '<Element Index="[1]"><Structure DataType="STRING"><DataValueMember Name="LEN" DataType="DINT" Value="2"/>'
        '<DataValueMember Name="DATA" DataType="STRING" Radix="ASCII"><![CDATA[\'$0D$0A\']]></DataValueMember>'
        "</Structure></Element></Array></Data></Tag>\n"
        "</Tags>")
    tags = {t.name: t.value.data for t in read_l5x(text, "t.L5X").tags}
    assert math.isnan(tags["N"]) and math.isnan(tags["M"])
    assert tags["Z"] == 0
    assert tags["S"] == [None, {"LEN": 2, "DATA": "\r\n"}]


# -- L5K ---------------------------------------------------------------------------------


def _same_facts(project: Project) -> Project:
    """What both formats say: L5K leaves a type member's Decimal radix
    unsaid and names no module-defined data type, so both are dropped;
    the rest is compared as read."""
    p = without_positions(project)
    p.format = "-"
    p.module_types = []
    for dt in p.data_types:
        for m in dt.members:
            m.radix = None if m.radix == "Decimal" else m.radix
    for mod in p.modules:
        for t in mod.tags:
            t.data_type = None
    return p


def test_l5k_reads_every_part_value_for_value():
    expected = _expected_l5x()
    expected.source, expected.format = "reader_controller.L5K", "L5K"
    positional = read_l5x(L5X, "x", prefer="positional")  # the L5K-form data the L5X also carries
    for got, want in zip(positional.tags, expected.tags):
        want.value = got.value and InitialValue("positional", got.value.data)
    for param, got in zip(expected.add_on_instructions[0].parameters + expected.add_on_instructions[0].local_tags,
                          positional.add_on_instructions[0].parameters + positional.add_on_instructions[0].local_tags):
        param.value = got.value and InitialValue("positional", got.value.data)
    expected.programs[0].tags[0].value = InitialValue("positional", 3)
    for m in expected.data_types[0].members:
        m.radix = None if m.radix == "Decimal" else m.radix
    expected.data_types[0].members[3].radix = "Decimal"  # written out in this fixture
    expected.modules[1].tags = [ModuleTag("Local:1:C", None, InitialValue("positional", [0, 0])),
                                ModuleTag("Local:1:I", None, InitialValue("positional", [0, 0])),
                                ModuleTag("Local:1:O", None, InitialValue("positional", [0]))]
    expected.modules[2].tags = [ModuleTag("Drive1:I", None, InitialValue("positional", [0]))]
    expected.module_types = []  # L5K describes no module-defined type
    project = read_l5k(L5K, "reader_controller.L5K")
    assert without_positions(project) == without_positions(expected)
    # spot checks that do not lean on the L5X reader
    tags = {t.name: t for t in project.tags}
    assert tags["Recipe"].value.data == [9, "It's $5\n\x00\x00"]
    assert tags["Grid"].dims == (2, 3) and tags["Grid"].value.data == [1, 2, 3, 4, 5, 255]
    assert tags["Mask"].value.data == 0b01011010 and tags["Mask"].constant
    assert tags["ValveOpen"].tag_type == "Alias" and tags["ValveOpen"].alias_for == "V1.Open"


@pytest.mark.parametrize("stem", ["reader_controller", "whole_controller"])
def test_l5k_and_l5x_of_one_controller_read_the_same(stem):
    l5x = read_l5x(FIXTURES / f"{stem}.L5X", "same", prefer="positional")
    l5k = read_l5k(FIXTURES / f"{stem}.L5K", "same")
    if stem == "whole_controller":
        # its L5K describes EnableIn and EnableOut, as Studio writes them; its L5X does not
        for param in l5k.add_on_instructions[0].parameters[:2]:
            assert param.description.endswith("System Defined Parameter")
            param.description = None
    assert _same_facts(l5k) == _same_facts(l5x)


def test_l5k_and_l5x_of_a_public_export_have_the_same_routines():
    folder = FIXTURES / "public" / "iotrustlab__sphere-usecases"
    l5k, l5x = read_l5k(folder / "Controller_PLC.L5K"), read_l5x(folder / "Controller_PLC.L5X")

    def routines(p):
        return [(r.name, r.kind, [(g.text, g.comment) for g in r.rungs], [ln.text for ln in r.lines])
                for x in p.add_on_instructions + p.programs for r in x.routines]

    assert routines(l5k) == routines(l5x) and routines(l5k)
    assert [[t.name for t in m.tags] for m in l5k.modules] == [[t.name for t in m.tags] for m in l5x.modules]
    assert [(t.name, t.kind, t.rate_ms, t.programs) for t in l5k.tasks] == [(t.name, t.kind, t.rate_ms, t.programs) for t in l5x.tasks]


def test_l5k_positions_are_where_each_part_starts():
    text = L5K.read_text(encoding="utf-8")
    project = read_l5k(text, "r.L5K")
    main = project.programs[0].routines[0]
    assert main.pos == Pos("r.L5K", *locate(text, "ROUTINE Main", 1))
    assert main.rungs[1].pos == Pos("r.L5K", *locate(text, "XIC(FillTimer.DN)"))
    assert project.programs[0].routines[1].lines[1].pos == Pos("r.L5K", *locate(text, "IF Step > 5"))
    grid = project.tags[3]
    assert grid.pos == Pos("r.L5K", *locate(text, "Grid : DINT"))
    assert grid.value.pos == Pos("r.L5K", *locate(text, "[16#0000_0001"))
    assert project.data_types[0].members[2].pos == Pos("r.L5K", *locate(text, "BIT Closed"))
    assert project.tasks[1].pos == Pos("r.L5K", *locate(text, "TASK Slow"))


def test_l5k_rungs_spanning_lines_strings_with_semicolons_and_comments_in_parts():
    text = ("CONTROLLER C (ProcessorType := \"1756-L83E\")\n\tPROGRAM P (MAIN := \"R\")\n\t\tROUTINE R \n"
            "\t\t\t\tRC: \"first; part $N\"\n\t\t\t\t    \"second $\"part$\"\";\n"
            "\t\t\t\tN: MOV('x;y',s)\n\t\t\t\t   OTE(b);\n"
            "\t\t\t\tN: NOP();\n"
            "\t\tEND_ROUTINE\n\t(* a comment; with END_PROGRAM in it *)\n\tEND_PROGRAM\nEND_CONTROLLER\n")
    [routine] = read_l5k(text, "s.L5K").programs[0].routines
    assert [(r.number, r.text, r.comment) for r in routine.rungs] == [
        (0, "MOV('x;y',s)OTE(b);", 'first; part \nsecond "part"'), (1, "NOP();", None)]


def _l5k_problems(text: str) -> list[tuple[int, int, str]]:
    with pytest.raises(ExportError) as err:
        read_l5k(text, "bad.L5K")
    assert all(p.pos.source == "bad.L5K" for p in err.value.problems)
    return [(p.pos.line, p.pos.column, p.message) for p in err.value.problems]


def test_l5k_an_unterminated_block_says_which_opened_where():
    text = ('IE_VER := 2.24;\nCONTROLLER C (ProcessorType := "x")\n\tPROGRAM P (MAIN := "R")\n'
            "\t\tROUTINE R \n\t\t\t\tN: NOP();\n\t\tEND_ROUTINE\n")
    assert _l5k_problems(text) == [
        (*locate(text, "PROGRAM P"), "expected END_PROGRAM to close PROGRAM P (opened here) before the end of the file"),
        (*locate(text, "CONTROLLER C"), "expected END_CONTROLLER to close CONTROLLER C (opened here) before the end of the file"),
    ]


def test_l5k_every_problem_at_once_reading_on_past_each():
    text = ("CONTROLLER C ()\n\tTAG\n\t\tA : DINT := 16#zz;\n\t\tB : DINT[2] := [1,\n\t\t\t2;\n"
            "\t\t: DINT := 3;\n\t\tD : DINT := 4;\n\tEND_TAG\n"
            "\tPROGRAM P ()\n\t\tROUTINE R \n\t\t\t\tN: ;\n\t\t\t\tN: NOP();\n\t\tEND_ROUTINE\n\tEND_PROGRAM\n"
            "\tDATATYPE T ()\n\t\tDINT ;\n\tEND_DATATYPE\nEND_CONTROLLER\n")
    assert _l5k_problems(text) == [
        (*locate(text, "16#zz"), "bad value: expected base-16 digits after 16#, found '16#zz'"),
        (*locate(text, "[1,"), "bad value: expected ] to close this ["),
        (*locate(text, ": DINT := 3"), "expected a tag name, found ': DINT := 3'"),
        (*locate(text, "N: ;"), "expected the rung's text after N: in rung 0"),
        (*locate(text, "DINT ;"), "expected a member (TYPE Name[dim] (attributes); or BIT Name Host : bit;), found 'DINT'"),
    ]
    # reading went on: the good parts are there when the bad ones are fixed
    fixed = text.replace("16#zz", "16#ff").replace("2;", "2];").replace(": DINT := 3", "Cx : DINT := 3")
    fixed = fixed.replace("N: ;", "N: NOP();").replace("DINT ;", "DINT m;")
    project = read_l5k(fixed, "ok.L5K")
    assert [(t.name, t.value.data) for t in project.tags] == [("A", 255), ("B", [1, 2]), ("Cx", 3), ("D", 4)]
    assert len(project.programs[0].routines[0].rungs) == 2


def test_l5k_a_missing_semicolon_does_not_swallow_the_next_block():
    text = ("CONTROLLER C ()\n\tPROGRAM P ()\n\t\tROUTINE R \n\t\t\t\tN: NOP()\n\t\tEND_ROUTINE\n\tEND_PROGRAM\n"
            "\tTASK T (Type := CONTINUOUS)\n\t\t\tP;\n\tEND_TASK\nEND_CONTROLLER\n")
    assert _l5k_problems(text) == [(*locate(text, "N: NOP()"), "expected ; to end this N: line")]


@pytest.mark.parametrize("name", ["whole_controller.L5K", "reader_controller.L5K"])
def test_l5k_damaged_copies_give_a_project_or_an_export_error(name):
    text = (FIXTURES / name).read_text(encoding="utf-8")
    for damaged in damaged_copies(text, seed=len(name), count=150):
        try:
            project = read_l5k(damaged, "d.L5K")
        except ExportError as e:
            assert e.problems and all(p.pos.source == "d.L5K" for p in e.problems)
        else:
            assert isinstance(project, Project)


def test_l5k_every_public_export_reads():
    for path in sorted((FIXTURES / "public").glob("*/*.L5K")):
        project = read_l5k(path)
        assert project.format == "L5K" and project.programs, path


def test_l5x_source_protected_parts_are_kept_and_marked():
    text = _controller(
        "<AddOnInstructionDefinitions>\n"
        '<EncodedData EncodedType="AddOnInstructionDefinition" Name="Locked" Revision="1.0" EncryptionConfig="9">\n'
        '<Parameters><Parameter Name="In" TagType="Base" DataType="DINT" Usage="Input" Required="true" Visible="true"/>'
        "</Parameters>\nQmFzZTY0\n</EncodedData>\n</AddOnInstructionDefinitions>\n"
        '<Programs><Program Name="P" MainRoutineName="R"><Routines>\n'
        '<Routine Name="R" Type="RLL"><RLLContent><Rung Number="0" Type="N"><Text><![CDATA[JSR(Secret,0);]]></Text>'
        "</Rung></RLLContent></Routine>\n"
        '<EncodedData EncodedType="Routine" Name="Secret" Type="RLL" EncryptionConfig="9">QmFzZTY0</EncodedData>\n'
        "</Routines></Program></Programs>")
    project = read_l5x(text, "e.L5X")
    [aoi] = project.add_on_instructions
    assert (aoi.name, aoi.encoded, [p.name for p in aoi.parameters], aoi.routines) == ("Locked", True, ["In"], [])
    assert aoi.pos == Pos("e.L5X", *locate(text, '<EncodedData EncodedType="AddOnInstructionDefinition"'))
    assert [(r.name, r.kind, r.encoded) for r in project.programs[0].routines] == [
        ("R", "RLL", False), ("Secret", "RLL", True)]


def test_l5k_source_protected_parts_force_data_and_the_older_parameter_spelling():
    text = ('CONTROLLER C ()\n'
            '\tENCODED_DATA (EncodedType := ADD_ON_INSTRUCTION_DEFINITION,\n\t              Name := "Locked",\n'
            '\t              Revision := "1.0",\n\t              EncryptionConfig := 3)\n'
            '\t\tHISTORY_ENTRY (User := "a\\b",\n\t\t               Description := "first")\n\t\tEND_HISTORY_ENTRY\n'
            '\t\tPARAMETERS\n\t\t\tIn : REAL[5] (Type := InOut,\n\t\t\t            Required := Yes);\n'
            '\t\t\tOut : DINT (Type := Output, DefaultData := "7");\n\t\tEND_PARAMETERS\n'
            '5PC4UUeSPrD8+QMe30neT5/97J+VmK95qgOApHiZ7VpmkuGyeYVmzDm3ceYND35YMmzC4xyFQfJYld\n'
            '\tEND_ENCODED_DATA\n'
            '\tTAG\n\t\tT : UDT_A (ProduceCount := 2) := [0,5],\n\t\t    TagForceData := [0,0,0,0,1,0];\n\tEND_TAG\n'
            '\tPROGRAM P ()\n\t\tENCODED_DATA (EncodedType := ROUTINE,\n\t\t              Name := "Secret",\n'
            '\t\t              Type := SFC)\n17r8GxtsZCMLfk3JHFYmU7emZMNhRh90EUUPQb5IKS676d\n\t\tEND_ENCODED_DATA\n'
            '\tEND_PROGRAM\nEND_CONTROLLER\n')
    project = read_l5k(text, "e.L5K")
    [aoi] = project.add_on_instructions
    assert (aoi.name, aoi.encoded, aoi.revision, aoi.routines) == ("Locked", True, "1.0", [])
    assert [(t.name, t.dims, t.usage, t.required, t.value and t.value.data) for t in aoi.parameters] == [
        ("In", (5,), "InOut", True, None), ("Out", (), "Output", False, 7)]
    assert aoi.pos == Pos("e.L5K", *locate(text, "ENCODED_DATA"))
    assert [(t.name, t.tag_type, t.value.data) for t in project.tags] == [("T", "Produced", [0, 5])]
    assert [(r.name, r.kind, r.encoded) for r in project.programs[0].routines] == [("Secret", "SFC", True)]


def test_l5x_pretty_printed_text_is_the_cdata_alone():
    text = _controller(
        '  <Programs>\n    <Program Name="P">\n      <Routines>\n        <Routine Name="S" Type="ST">\n'
        '          <STContent>\n            <Line Number="0">\n              <![CDATA[  IF a THEN]]>\n'
        '            </Line>\n          </STContent>\n        </Routine>\n'
        '        <Routine Name="R" Type="RLL">\n          <RLLContent>\n            <Rung Number="0" Type="N">\n'
        '              <Text>\n                <![CDATA[\n  NOP();]]>\n              </Text>\n'
        '            </Rung>\n          </RLLContent>\n        </Routine>\n      </Routines>\n    </Program>\n  </Programs>\n'
        '  <Tags>\n    <Tag Name="A" DataType="DINT">\n      <Data Format="L5K">\n        <![CDATA[ [1,\n 2 3]]]>\n'
        "      </Data>\n    </Tag>\n  </Tags>")
    [problem] = _l5x_problems(text)
    assert (problem.pos.line, problem.pos.column) == locate(text, "3]]]>")
    fixed = read_l5x(text.replace("2 3", "2,3"), "p.L5X")
    [st, rll] = fixed.programs[0].routines
    assert st.lines[0].text == "  IF a THEN"  # the line's own indentation is kept
    assert st.lines[0].pos == Pos("p.L5X", *locate(text, "  IF a THEN"))
    assert rll.rungs[0].text == "NOP();" and rll.rungs[0].pos == Pos("p.L5X", *locate(text, "NOP();"))
    assert fixed.tags[0].value.data == [1, 2, 3]


def test_l5x_an_unknown_encoding_is_a_problem_not_a_crash():
    [problem] = _l5x_problems('<?xml version="1.0" encoding="UTF-F-8"?>\n<RSLogix5000Content/>\n')
    assert problem.pos == Pos("bad.L5X", 1, 1) and "unknown encoding: UTF-F-8" in problem.message


@pytest.mark.parametrize("reader", [read_l5x, read_l5k])
def test_an_export_over_its_limit_is_refused_before_it_is_read(tmp_path, reader):
    big = tmp_path / "big.L5X"
    with open(big, "wb") as f:
        f.truncate(EXPORT.size + 1)  # sparse: no disk used
    with pytest.raises(ExportError) as err:
        reader(big, "big.L5X")
    [problem] = err.value.problems
    assert problem.message.startswith("cannot read ") and problem.message.endswith(
        "big.L5X: 67,108,865 bytes, over the 64 MiB limit for a Studio 5000 export (L5X, L5K)")
