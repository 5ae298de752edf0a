"""A Studio 5000 export's tags over EtherNet/IP (docs/logix.md, "EtherNet/IP:
Logix tags"): programs/logix/tank_line.L5X, copied into the test's
directory with a tank_line.ENIPS.XML beside it, run with its server on a
free port; pycomm3's LogixDriver and pylogix read, write and browse its tags
by path, structures through their templates, and are refused what the
export's External Access and the configuration keep closed."""

from __future__ import annotations

import struct

import pytest
from pycomm3 import LogixDriver, SLCDriver
from pylogix import PLC

from softplc_lite.app import AppError, load_app
from softplc_lite.tlm.enips.logixview import build_view

from helpers.enips_apps import TANK_LINE, connect, register, tank_line, unconnected
from helpers.modbtcps_apps import Running

pytestmark = pytest.mark.timeout(120)


def _fill_rate_none(text: str) -> str:
    """The export with FillRate's External Access None (the ladder still uses it)."""
    return text.replace('<Tag Name="FillRate" TagType="Base" DataType="REAL" Radix="Float" Constant="false" '
                        'ExternalAccess="Read/Write">', '<Tag Name="FillRate" TagType="Base" DataType="REAL" '
                        'Radix="Float" Constant="false" ExternalAccess="None">')


@pytest.fixture
def line(tmp_path):
    plc = Running(tank_line(tmp_path / "line", edit=_fill_rate_none), module="ENIPS")
    yield plc
    plc.stop()


def value(plc: Running, path: str):
    """A tag's value as the scan holds it, by its path."""
    return plc.engine.table.read(str(plc.engine.program.symbols.resolve_path(path)))


def test_pycomm3_reads_tags_structures_and_arrays_by_path(line):
    with LogixDriver(f"127.0.0.1:{line.port}") as plc:
        assert plc.read("Tanks[1].Setpoint").value == 80.0 and plc.read("Tanks[1].Level").value == 0.0
        assert plc.read("SettleTimer.PRE").value == 2000
        assert plc.read("Banner").value == "idle" and plc.read("Banner").type == "STRING"
        assert plc.read("Flags.8").value is False
        assert plc.read("Program:MainProgram.Overview").type == "REAL"
        assert plc.read("LineDone").value is False  # an alias of Batches.DN
        tank = plc.read("Tanks[0]")
        assert tank.type == "Tank" and tank.value["Setpoint"] == 40.0 and set(tank.value) == {
            "Fill", "Drain", "Level", "Setpoint", "Fills"}
        timer = plc.read("SettleTimer").value
        assert (timer["PRE"], timer["ACC"], timer["DN"]) == (2000, 0, False) and "CTL" not in timer
        both = plc.read("Tanks{2}").value
        assert [t["Setpoint"] for t in both] == [40.0, 80.0]
        assert plc.read("Batches").value["PRE"] == 3


def test_pycomm3_writes_land_in_the_tags_and_the_ladder_sees_them(line):
    with LogixDriver(f"127.0.0.1:{line.port}") as plc:
        assert plc.write("Tanks[1].Setpoint", 70.0).error is None  # answered once the scan applied it
        assert value(line, "Tanks[1].Setpoint") == 70.0
        assert plc.write("SettleTimer.PRE.3", True).error is None  # a bit of a DINT member: read-modify-write
        assert value(line, "SettleTimer.PRE") == 2008
        assert plc.write("Banner", "filling").error is None and value(line, "Banner") == "filling"
        timer = dict(plc.read("SettleTimer").value, PRE=1500)
        assert plc.write("SettleTimer", timer).error is None and value(line, "SettleTimer.PRE") == 1500
        assert plc.write("Start", True).error is None
        line.wait_for(lambda: plc.read("Running").value is True, "the ladder's seal-in on the written Start")
        line.wait_for(lambda: value(line, "Tanks[0].Level") > 0, "tank 0 filling")


def test_read_only_and_none_are_refused_as_a_logix_controller_refuses_them(line):
    with LogixDriver(f"127.0.0.1:{line.port}") as plc:
        names = {t["tag_name"] for t in plc.get_tag_list("*")}
        assert "FillRate" not in names and {"Running", "Tanks", "Program:MainProgram.Overview"} <= names
        assert plc.write("Running", True).error == "Permission denied"  # Read Only in the export
        assert plc.write("Tanks[0].Fills", 3).error == "Permission denied"  # a Read Only member
        tank = plc.read("Tanks[0]").value
        assert plc.write("Tanks[0]", tank).error == "Permission denied"  # a whole structure holding it
        assert plc.read("Running").value is False and plc.read("Tanks[0].Fills").error is None
    with connect(line.port) as sock:
        session = register(sock)
        _, reply = unconnected(sock, session, 0x4C, b"\x91\x08FillRate", struct.pack("<H", 1))  # Read Tag
        assert reply.status == 0x0F  # None: privilege violation, never its value
    assert value(line, "FillRate") == 0.5  # the ladder has it all the same
    with PLC("127.0.0.1") as c:
        c.Port = line.port
        assert c.Read("FillRate").Status == "Privilege violation"
        assert c.Write("Running", 1).Status == "Privilege violation"


def test_pylogix_reads_writes_and_lists_every_scope(line):
    with PLC("127.0.0.1") as c:
        c.Port = line.port
        assert c.Read("Tanks[1].Setpoint").Value == 80.0
        assert c.Read("SettleTimer.PRE").Value == 2000
        assert c.Read("Banner").Value == "idle"
        assert c.Read("Flags.8").Value is False
        assert c.Write("Tanks[0].Setpoint", 35.0).Status == "Success" and value(line, "Tanks[0].Setpoint") == 35.0
        assert c.Write("Program:MainProgram.Overview", 1.5).Status == "Success"
        raw = c.Read("Tanks[0]").Value  # a structure: its bytes, laid out as its template says
        assert len(raw) == 16 and struct.unpack_from("<f", raw, 8)[0] == 35.0
        listed = {t.TagName: t.DataType for t in c.GetTagList(allTags=True).Value}
    assert listed["Tanks"] == "Tank" and listed["SettleTimer"] == "TIMER" and listed["Flags"] == "DINT"
    assert listed["Program:MainProgram.Overview"] == "REAL" and "Program:MainProgram.Settled" in listed
    assert "FillRate" not in listed


def test_without_writable_tags_every_tag_is_read_only(tmp_path):
    plc = Running(tank_line(tmp_path / "line", body=""), module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            assert driver.read("Tanks[1].Setpoint").value == 80.0
            assert driver.write("Tanks[1].Setpoint", 1.0).error == "Permission denied"
            assert driver.write("Start", True).error == "Permission denied"
        with PLC("127.0.0.1") as c:  # the data table files are not tags of a Logix app
            c.Port = plc.port
            assert c.Read("N7[0]").Status == "Path destination unknown"
        with SLCDriver(f"127.0.0.1:{plc.port}") as panel:  # nor reached by PCCC: no file is mapped
            assert panel.read("F12:0").error is not None
    finally:
        plc.stop()
    assert value(plc, "Tanks[1].Setpoint") == 80.0


def test_writable_names_tags_and_the_export_keeps_read_only_tags_closed(tmp_path):
    body = '  <Writable tag="Running"/>\n  <Writable tag="Tanks[0].Fills"/>\n  <Writable tag="Nowhere"/>\n'
    with pytest.raises(AppError) as e:
        load_app(tank_line(tmp_path / "bad", body=body))
    text = str(e.value)
    assert "tank_line.ENIPS.XML:3:3: <Writable tag='Running'>: the export makes it Read Only" in text
    assert "tank_line.ENIPS.XML:4:3: <Writable tag='Tanks[0].Fills'>: the export makes it Read Only" in text
    assert "tank_line.ENIPS.XML:5:3: <Writable tag='Nowhere'>: no tag named 'Nowhere'" in text


def test_the_templates_lay_out_the_export_types():
    app = load_app(TANK_LINE)
    view = build_view(app.logix.directory)
    tank = view.templates[view.find("Tanks", None).template]
    assert (tank.name, tank.size) == ("Tank", 16)
    assert {m.name: (m.offset, m.bit) for m in tank.members} == {
        "ZZZZZZZZZZTank0": (0, None), "Fill": (0, 0), "Drain": (0, 1), "Level": (4, None), "Setpoint": (8, None),
        "Fills": (12, None)}
    timer = view.templates[view.find("SettleTimer", None).template]
    assert (timer.name, timer.size, timer.predefined) == ("TIMER", 12, True)
    assert timer.member("DN").bit == 29 and timer.member("ACC").offset == 8
    assert view.programs == ["MainProgram"] and [t.name for t in view.tags["MainProgram"]] == ["Settled", "Overview"]


def test_module_tags_with_booleans_of_their_own_are_read_and_written_whole(tmp_path):
    """programs/logix/io_rack.L5X: module-defined types whose BOOL members
    are no host's bits (a byte each in the template) read and written whole,
    each BOOL masked into its word so its neighbours keep their value."""
    source = TANK_LINE.parent / "io_rack.L5X"
    plc = Running(tank_line(tmp_path / "rack", body='  <Writable tag="Local:2:C"/>\n', source=source), module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            config = driver.read("Local:2:C")
            assert config.error is None and config.value["ProgToFaultEn"] is False
            assert driver.read("Local:4:I").value["Ch0Fault"] is False
            assert driver.write("Local:2:C", dict(config.value, ProgToFaultEn=True, FaultValue=5)).error is None
            assert value(plc, "Local:2:C.ProgToFaultEn") == 1 and value(plc, "Local:2:C.FaultValue") == 5
            assert driver.read("Local:2:C.ProgToFaultEn").value is True
            assert driver.write("Local:4:I.Ch0Fault", True).error == "Permission denied"  # no <Writable>
    finally:
        plc.stop()


ARRAYS = """<Tag Name="Counts" TagType="Base" DataType="DINT" Dimensions="5" ExternalAccess="Read/Write"/>
<Tag Name="Grid" TagType="Base" DataType="INT" Dimensions="2 3" Radix="Decimal" ExternalAccess="Read/Write"/>
<Tag Name="Lamps" TagType="Base" DataType="BOOL" Dimensions="32" Radix="Decimal" ExternalAccess="Read/Write"/>
</Tags>
<Programs>"""


def test_atomic_arrays_are_read_and_written_by_element_and_by_count(tmp_path):
    body = '  <Writable tag="Counts"/>\n  <Writable tag="Grid"/>\n  <Writable tag="Lamps[3]"/>\n'
    export = tank_line(tmp_path / "arrays", body=body, edit=lambda t: t.replace("</Tags>\n<Programs>", ARRAYS, 1))
    plc = Running(export, module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            assert driver.write("Counts{5}", [1, 2, 3, 4, 5]).error is None and value(plc, "Counts[4]") == 5
            assert driver.read("Counts[2]{3}").value == [3, 4, 5]  # from an element to the array's end
            assert driver.write("Grid[1,2]", 7).error is None and driver.read("Grid{6}").value == [0] * 5 + [7]
            assert driver.write("Lamps[3]", True).error is None and value(plc, "Lamps[3]") == 1
            assert driver.write("Lamps[4]", True).error == "Permission denied"  # its word's other bits stay closed
            listed = {t["tag_name"]: (t["data_type"], t["dimensions"]) for t in driver.get_tag_list()}
            assert listed["Grid"] == ("INT", [2, 3, 0]) and listed["Lamps"] == ("BOOL", [32, 0, 0])
        with PLC("127.0.0.1") as c:
            c.Port = plc.port
            assert c.Read("Counts[1]", 4).Value == [2, 3, 4, 5] and c.Read("Grid[1,2]").Value == 7
            assert c.Read("Lamps[3]").Value is True
    finally:
        plc.stop()
    assert value(plc, "Lamps[4]") == 0


RECIPE = """<DataType Name="Recipe" Family="NoFamily" Class="User">
<Members>
<Member Name="Name" DataType="STRING" Dimension="0" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="Steps" DataType="INT" Dimension="3" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="Big" DataType="LINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="T" DataType="TIMER" Dimension="0" Hidden="false" ExternalAccess="Read/Write"/>
</Members>
</DataType>
</DataTypes>"""


def _with_recipes(text: str) -> str:
    """Recipe structures, and in MainProgram an alias of a controller tag."""
    text = text.replace("</DataTypes>", RECIPE, 1)
    text = text.replace('<Program Name="MainProgram" TestEdits="false" MainRoutineName="MainRoutine" Disabled="false" '
                        'UseAsFolder="false">\n<Tags>', '<Program Name="MainProgram" TestEdits="false" MainRoutineName='
                        '"MainRoutine" Disabled="false" UseAsFolder="false">\n<Tags>\n<Tag Name="Fill1" TagType='
                        '"Alias" AliasFor="Tanks[1].Fill" ExternalAccess="Read/Write"/>', 1)
    return text.replace("</Tags>\n<Programs>", '<Tag Name="Rec" TagType="Base" DataType="Recipe" Dimensions="2" '
                                                'ExternalAccess="Read/Write"/>\n</Tags>\n<Programs>', 1)


def test_nested_structures_strings_and_member_arrays_round_trip(tmp_path):
    plc = Running(tank_line(tmp_path / "recipes", body='  <Writable tag="Rec"/>\n', edit=_with_recipes),
                  module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            recipe = driver.read("Rec[1]").value
            recipe.update(Name="cola", Steps=[1, 2, 3], Big=2 ** 40)
            recipe["T"]["PRE"] = 77
            assert driver.write("Rec[1]", recipe).error is None  # one structure: applied at one input point
            assert (value(plc, "Rec[1].T.PRE"), value(plc, "Rec[1].Steps[2]"), value(plc, "Rec[1].Big")) == (
                77, 3, 2 ** 40)
            assert driver.read("Rec[1].Name").value == "cola" and driver.read("Rec[1].Steps{3}").value == [1, 2, 3]
            assert driver.read("Rec[0]").value["Name"] == ""
            assert driver.read("Program:MainProgram.Fill1").value is False  # a program's alias of a controller tag
    finally:
        plc.stop()


def test_every_program_is_listed_with_or_without_tags(tmp_path):
    source = TANK_LINE.parent / "dosing.L5X"
    plc = Running(tank_line(tmp_path / "dosing", body="", source=source), module="ENIPS")
    try:
        with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
            assert set(driver.info["programs"]) == {"MainProgram", "Sampler", "Service"}
        with PLC("127.0.0.1") as c:
            c.Port = plc.port
            names = [t.TagName for t in c.GetTagList(allTags=True).Value]
        assert {"Program:Sampler", "Program:Service"} <= set(names)
    finally:
        plc.stop()
