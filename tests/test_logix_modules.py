"""I/O module tags as simulated I/O (softplc_lite/logix/modules.py,
docs/logix.md "I/O modules"): the module-defined types the decorated data
shows, module tags as controller tags of them, reached in rungs, through
aliases, by --set, --print and forces, on both executors; what the export
does not describe is not run, with a warning, never an error."""

from __future__ import annotations


import pytest

from helpers.cli import ROOT, softplc_here
from softplc_lite.app import load_app
from softplc_lite.ladder.symbols import resolve_name
from softplc_lite.logix.l5x import read_l5x
from softplc_lite.logix.load import load_export
from softplc_lite.runner import Runner, RunOptions
from softplc_lite.watch.forces import Forces, parse_force

EXPORT = ROOT / "programs" / "logix" / "io_rack.L5X"
PUBLIC = ROOT / "tests" / "fixtures" / "logix" / "public"
BOOSTER = PUBLIC / "andreenko-repo__rockwell_logic_l5x_extractor" / "BoosterCompressor_20260128.L5X"
COLT = PUBLIC / "Colt-H__L5X-Creator" / "L5x_Creation_Populated.L5X"
EXECUTORS = ("compiled", "reference")


def _runner(executor: str, *sets: str) -> Runner:
    app = load_app(EXPORT, use_cache=False)
    return Runner(app, RunOptions(executor=executor, fresh=True, save_state=False, sets=sets), log=lambda m: None)


def _read(runner: Runner, path: str):
    return runner.table.read(resolve_name(path, runner.app.program.symbols))


# -- the reader: module-defined types as the decorated data shows them -------------------------

def test_the_l5x_reader_keeps_each_module_defined_type_once_with_nested_and_array_members():
    project = read_l5x(EXPORT)
    types = {d.name: d for d in project.module_types}
    assert sorted(types) == ["AB:1756_DI:C:1", "AB:1756_DI:I:0", "AB:1756_DO:C:0", "AB:1756_DO:O:0",
                             "AB:1756_DO_Fused:I:0", "AB:1756_IF4_Float:C:0", "AB:1756_IF4_Float:I:0",
                             "AB:1756_NII_Struct:C:0"]  # two DI modules, one AB:1756_DI:I:0
    members = {m.name: m for m in types["AB:1756_IF4_Float:I:0"].members}
    assert members["Ch0Fault"].data_type == "BOOL" and members["Ch2Data"].data_type == "REAL"
    assert members["Ch0Status"].data_type == "SINT" and members["ChannelFaults"].data_type == "INT"
    config = {m.name: m for m in types["AB:1756_IF4_Float:C:0"].members}
    assert config["Ch2Config"].data_type == "AB:1756_NII_Struct:C:0"
    fused = {m.name: m for m in types["AB:1756_DO_Fused:I:0"].members}
    assert fused["CSTTimestamp"].data_type == "DINT" and fused["CSTTimestamp"].dimension == 2
    tags = {t.name: t for m in project.modules for t in m.tags}
    assert tags["Local:4:I"].data_type == "AB:1756_IF4_Float:I:0" and tags["Local:5:I"].value.data["Data"] == 8


def test_module_tags_are_controller_tags_with_their_data_as_initial_values():
    result = load_export(EXPORT)
    assert not result.problems and not result.warnings
    d = result.directory
    for path in ("Local:1:I.Data.0", "Local:4:I.Ch0Fault", "Local:2:O.Data.5", "Local:2:I.CSTTimestamp[1]",
                 "Local:4:C.Ch2Config.HighEngineering", "PT102_PV", "SpareIn_03"):
        assert d.resolve(path).address is not None, path
    assert d.resolve("PT102_PV").address == d.resolve("Local:4:I.Ch2Data").address  # the alias goes through
    with pytest.raises(Exception, match="has no member Ch9Data"):
        d.resolve("Local:4:I.Ch9Data")


# -- running: the CLI and the Runner on both executors -------------------------------------------

@pytest.mark.parametrize("value", ["1", "0"])
def test_cli_sets_an_input_bit_and_prints_the_output_a_rung_drives(value):
    r = softplc_here("run", str(EXPORT), "--scans", "2", "--set", f"Local:1:I.Data.0={value}",
                     "--print", "Local:2:O.Data.5", "--print", "Local:1:I.Data")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("Local:2:O.Data.5 (") and lines[0].endswith(f"= {value}")
    assert lines[1].endswith(f"= {value}")  # Data is the DINT whose bit 0 was set


@pytest.mark.parametrize("executor", EXECUTORS)
def test_rungs_read_and_write_module_tags_on_both_executors(executor):
    r = _runner(executor, "Local:1:I.Data.0=1", "Local:4:I.Ch0Fault=1")
    r.run(2)
    assert _read(r, "Local:2:O.Data.5") == 1 and _read(r, "Local:2:O.Data") == (1 << 5) | (1 << 6)
    assert _read(r, "AnalogFault") == 1
    assert _read(r, "HighPressure") == 0  # Ch2Data starts at the export's 37.25 barg
    assert _read(r, "Span") == 60.0  # a nested member of the config tag, from its data
    assert _read(r, "Local:2:O.Data.6") == 1  # the inhibited module's Data.3 (8 in the export), by its alias
    r.table.write(resolve_name("Local:4:I.Ch2Data", r.app.program.symbols), 55.5)
    r.table.write(resolve_name("Local:4:I.Ch0Fault", r.app.program.symbols), 0)
    r.run(1)
    assert _read(r, "HighPressure") == 1 and _read(r, "AnalogFault") == 0
    r.close()


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_forced_input_bit_holds_against_writes_and_drives_its_rung(executor):
    r = _runner(executor)
    forces = Forces(r.engine)
    forces.set(parse_force("Local:1:I.Data.0=1", r.app.program.symbols))
    r.run(1)
    assert _read(r, "Local:2:O.Data.5") == 1
    r.table.write(resolve_name("Local:1:I.Data", r.app.program.symbols), 0)
    r.run(1)
    assert _read(r, "Local:1:I.Data.0") == 1 and _read(r, "Local:2:O.Data.5") == 1
    forces.remove(resolve_name("Local:1:I.Data.0", r.app.program.symbols))
    r.table.write(resolve_name("Local:1:I.Data", r.app.program.symbols), 0)
    r.run(1)
    assert _read(r, "Local:2:O.Data.5") == 0
    r.close()


@pytest.mark.parametrize("force", ["1", "0"])
def test_watch_forces_an_input_bit_by_its_path(tmp_path, force):
    view = tmp_path / "view.txt"
    r = softplc_here("watch", str(EXPORT), "--scans", "2", "--force", f"Local:1:I.Data.0={force}",
                     "--watch", "Local:2:O.Data.5", "--snapshot", str(view))
    assert r.returncode == 0, r.stderr
    row = next(line for line in view.read_text().splitlines() if line.startswith("Local:2:O.Data.5"))
    assert row.split()[1] == force


# -- what the export does not describe: not run, with a warning ---------------------------------

def _l5k_only(text: str) -> str:
    """The example with its digital input's data in L5K form only (no decorated data)."""
    start = text.index('<Module Name="Inputs"')
    end = text.index("</Module>", start)
    module = text[start:end]
    cut = module.index('<Data Format="Decorated">\n<Structure DataType="AB:1756_DI:I:0">')
    stop = module.index("</Data>", cut) + len("</Data>")
    return text[:start] + module[:cut] + module[stop:] + text[end:]


def test_a_module_tag_without_a_description_makes_its_rungs_not_run(tmp_path):
    path = tmp_path / "io.L5X"
    path.write_text(_l5k_only(EXPORT.read_text()))
    r = softplc_here("check", str(path))
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout + r.stderr
    assert "module Inputs: its data is not in decorated form, so its tags (Local:1:I) are not laid out" in out
    assert "rung 0" in out and "Local:1:I" in out and "not run" in out
    result = load_export(path)
    assert not result.problems
    assert result.directory.resolve("Local:1:C.COSOnOffEn").address is not None  # its other tags are


L5K = """IE_VER := 2.28;
CONTROLLER IoRack (ProcessorType := "1756-L83E")
	MODULE Local (Parent := "Local", CatalogNumber := "1756-L83E", Slot := 0)
	END_MODULE
	MODULE Inputs (Parent := "Local", CatalogNumber := "1756-IB16", Slot := 1, Mode := 2#0000_0000_0000_0000)
			ConfigData  := [28,16,0,0,0,0,1,1,1,1,1,1,1,1,-1,-1];
		CONNECTION StandardInput (Rate := 20000, EventID := 0)
				InputData  := [0,1];
		END_CONNECTION
	END_MODULE
	TAG
		Lamp : BOOL := 0;
	END_TAG
	PROGRAM MainProgram (MAIN := "MainRoutine")
		ROUTINE MainRoutine
				N: XIC(Local:1:I.Data.0)OTE(Lamp);
				N: OTE(Lamp);
		END_ROUTINE
	END_PROGRAM
	TASK MainTask (Type := CONTINUOUS)
			MainProgram;
	END_TASK
END_CONTROLLER
"""


def test_l5k_module_tags_are_not_laid_out_and_their_rungs_are_not_run(tmp_path):
    path = tmp_path / "io.L5K"
    path.write_text(L5K)
    result = load_export(path)
    assert not result.problems
    messages = [p.message for p in result.warnings]
    assert any(m.startswith("module Inputs: an L5K export gives module data by position, without member names, "
                            "so its tags (Local:1:C, Local:1:I) are not laid out") for m in messages), messages
    assert any("rung 0" in m and "Local:1:I" in m for m in messages), messages
    r = softplc_here("run", str(path), "--scans", "1", "--print", "Lamp")
    assert r.returncode == 0 and r.stdout.strip().endswith("= 1"), r.stdout + r.stderr  # rung 1 runs


# -- public exports ------------------------------------------------------------------------------

@pytest.mark.parametrize("path", [BOOSTER, COLT], ids=["BoosterCompressor", "Colt-H"])
def test_public_exports_load_their_module_tags(path):
    r = softplc_here("check", str(path))
    out = r.stdout + r.stderr
    assert "unknown tag 'Local:" not in out and "module" not in out.lower(), out
    result = load_export(path)
    assert result.directory.resolve("Local:3:O.Data.8").address is not None


def _with_rung(text: str, rung: str) -> str:
    """The example with ``rung`` as the last rung of its routine."""
    last = '<![CDATA[MOV(Local:4:C.Ch2Config.HighEngineering,Span);]]>\n</Text>\n</Rung>\n'
    assert last in text
    return text.replace(last, last + f'<Rung Number="5" Type="N">\n<Text>\n<![CDATA[{rung}]]>\n</Text>\n</Rung>\n')


def test_a_module_tag_the_modules_have_no_data_for_is_not_run_a_name_of_no_module_is_unknown(tmp_path):
    path = tmp_path / "io.L5X"
    path.write_text(_with_rung(EXPORT.read_text(), "XIC(Local:0:I.Data.1)OTE(Local:7:O.Data.0);"))
    result = load_export(path)
    assert not result.problems
    assert [w.message for w in result.warnings] == [
        "routine MainProgram.MainRoutine: rung 5: XIC operand 'Local:0:I.Data.1': module tag Local:0:I: "
        "the export's modules have no data for it; the rung is not run",
        "routine MainProgram.MainRoutine: rung 5: OTE operand 'Local:7:O.Data.0': module tag Local:7:O: "
        "the export's modules have no data for it; the rung is not run"]
    path.write_text(_with_rung(EXPORT.read_text(), "XIC(Locl:1:I.Data.1)OTE(HighPressure);"))
    r = softplc_here("check", str(path))
    assert r.returncode == 1 and "unknown tag 'Locl:1:I'" in r.stdout + r.stderr


def test_a_type_shown_differently_by_two_modules_takes_the_first_with_a_warning(tmp_path):
    text = EXPORT.read_text()
    spare = text.index('<Module Name="SpareInputs"')
    text = text[:spare] + text[spare:].replace(
        '<DataValueMember Name="Fault" DataType="DINT"', '<DataValueMember Name="Faults" DataType="DINT"', 1)
    path = tmp_path / "io.L5X"
    path.write_text(text)
    result = load_export(path)
    assert not result.problems
    assert any(w.message.startswith("module-defined type AB:1756_DI:I:0 is shown with other members than at ")
               for w in result.warnings), result.warnings
    assert result.directory.resolve("Local:5:I.Data.3").address is not None  # the first description: Fault, Data
    with pytest.raises(Exception, match="has no member Faults"):
        result.directory.resolve("Local:5:I.Faults")


def test_an_array_member_of_no_element_holds_nothing(tmp_path):
    text = EXPORT.read_text().replace(
        '<DataValueMember Name="ProgToFaultEn" DataType="BOOL" Value="0"/>',
        '<DataValueMember Name="ProgToFaultEn" DataType="BOOL" Value="0"/>\n'
        '<ArrayMember Name="Spare" DataType="SINT" Dimensions="0" Radix="Hex"></ArrayMember>', 1)
    path = tmp_path / "io.L5X"
    path.write_text(text)
    result = load_export(path)
    assert not result.problems and not result.warnings
    assert result.directory.resolve("Local:2:C.ProgToFaultEn").address is not None


def test_an_export_without_modules_runs_the_rungs_that_use_none(tmp_path):
    text = EXPORT.read_text()
    text = text[:text.index("<Modules>")] + "<Modules/>" + text[text.index("</Modules>") + len("</Modules>"):]
    path = tmp_path / "io.L5X"
    path.write_text(text)
    result = load_export(path)
    assert not result.problems
    not_run = sorted({w.message.split(":")[1].strip() for w in result.warnings})
    assert not_run == ["rung 0", "rung 1", "rung 2", "rung 3", "rung 4"], result.warnings
    assert all("the export holds no modules; the rung is not run" in w.message for w in result.warnings)


def test_scenarios_set_force_and_expect_module_tags(tmp_path):
    export = tmp_path / "io_rack.L5X"
    export.write_text(EXPORT.read_text())
    (tmp_path / "io_rack.tests").mkdir()
    (tmp_path / "io_rack.tests" / "io.plctest").write_text(
        'scenario "simulated I/O":\n'
        '    force Local:1:I.Data.0 = 1\n'
        '    set Local:4:I.Ch2Data = 55.5\n'
        '    scan 1\n'
        '    expect Local:2:O.Data.5 == 1\n'
        '    expect HighPressure == 1\n'
        '    expect PT102_PV == 55.5\n'
        '    unforce Local:1:I.Data.0\n'
        '    set Local:1:I.Data = 0\n'
        '    scan 1\n'
        '    expect Local:2:O.Data.5 == 0\n', encoding="utf-8")
    r = softplc_here("test", str(export))
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1] == "1 passed, 0 failed"
