"""A Studio 5000 export as an app (softplc_lite/logix, docs/logix.md): the
shipped tank line runs on both executors as its rungs say; tag paths are
names on the command line; a broken export has every problem located and
listed at once; what is not run is a warning by name and place; no input
gives a traceback."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.runner import RunOptions, Runner

from helpers.logix_l5x import export_runner
from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
TANK_LINE = ROOT / "programs" / "logix" / "tank_line.L5X"
FIXTURES = ROOT / "tests" / "fixtures" / "logix"


def tank_line(tmp_path: Path, edit=None) -> Path:
    target = tmp_path / "tank_line.L5X"
    text = TANK_LINE.read_text(encoding="utf-8")
    target.write_text(edit(text) if edit else text, encoding="utf-8")
    return target


def runner_of(path: Path, executor: str) -> Runner:
    return export_runner(path, executor)


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_the_tank_line_fills_settles_counts_and_hands_over(tmp_path, executor):
    r = runner_of(tank_line(tmp_path), executor)
    table, names = r.table, r.app.program.symbols

    def read(path):
        return table.read(names.resolve_path(path))

    r.run(5)
    assert read("Running") == 0  # nobody pressed Start
    table.write(names.resolve_path("Start"), 1)
    r.run(1)
    table.write(names.resolve_path("Start"), 0)
    assert read("Running") == 1  # sealed in
    r.run(79)  # 0.5 a scan from the first scan running: 40.0 after 80 scans
    assert read("Tanks[0].Level") == 40.0 and read("Tanks[0].Fill") == 1
    r.run(1)  # at the setpoint: the fill valve closes, the drain opens, the settling starts
    assert read("Tanks[0].Fill") == 0 and read("Tanks[0].Drain") == 1 and read("SettleTimer.TT") == 1
    r.run(200)  # 2 s of 10 ms scans: settled, one batch, the other tank's turn
    assert read("Batches.ACC") == 1 and read("Tanks[0].Fills") == 1 and read("Active") == 1
    assert read("Tanks[0].Level") == 0.0 and read("Flags") == 1 and read("Flags.8") == 0
    r.run(1)  # tank 1 fills, from the next scan
    assert read("Tanks[1].Fill") == 1 and read("Tanks[1].Level") == 0.5
    assert read("Program:MainProgram.Overview") == 0.25  # CPT((Tanks[0].Level + Tanks[1].Level) / 2.0)
    r.close()


def test_tag_paths_on_the_command_line(tmp_path):
    path = tank_line(tmp_path)
    p = softplc_here("run", str(path), "--scans", "90", "--set", "Start=1", "--print", "Tanks[0].Level",
                     "--print", "Tanks[0].Drain", "--print", "LineDone", "--print", "Program:MainProgram.Settled")
    assert p.returncode == 0, p.stderr
    values = dict(re.match(r"(\S+) \(.*\) = (.*)", line).groups() for line in p.stdout.splitlines())
    assert values == {"Tanks[0].Level": "40.0", "Tanks[0].Drain": "1", "LineDone": "0",
                      "Program:MainProgram.Settled": "0"}
    bad = softplc_here("run", str(path), "--scans", "1", "--print", "Tanks[2].Level", "--print", "Tanks[0].Lvl")
    assert bad.returncode == 1 and "Traceback" not in bad.stderr
    assert "index 2 is past the end of a dimension of 2" in bad.stderr
    assert "Tank has no member Lvl (it has Fill, Drain, Level, Setpoint, Fills)" in bad.stderr


def test_every_problem_of_an_export_is_located_and_said_at_once(tmp_path):
    def break_it(text: str) -> str:
        text = text.replace("XIC(Running)JSR(FillTank,0);", "XIC(Runing)JSR(FillTank,0);")
        text = text.replace("LES(Tanks[Active].Level,Tanks[Active].Setpoint)", "LES(Tanks[Active].Lvl,Tanks[3].Setpoint)")
        return text.replace("XIO(Tanks[Active].Fill)OTE(Tanks[Active].Drain);", "XIO(Tanks[Active].Fill)OTE(;")
    path = tank_line(tmp_path, break_it)
    with pytest.raises(AppError) as info:
        load_app(path)
    lines = path.read_text().splitlines()
    reports = [str(e) for e in info.value.errors]
    assert len(reports) == 4, reports

    def at(text: str, column_of: str) -> str:
        line = next(k for k, ln in enumerate(lines, 1) if text in ln)
        return f"{path}:{line}:{lines[line - 1].index(column_of) + 1}"

    assert reports[0].startswith(at("XIC(Runing)", "Runing")) and "unknown tag 'Runing'" in reports[0]
    assert "routine MainProgram.MainRoutine: rung 1" in reports[0]
    assert reports[1].startswith(at("Tanks[Active].Lvl", "Lvl")) and "Tank has no member Lvl" in reports[1]
    assert reports[2].startswith(at("Tanks[3].Setpoint", "3].")) and "index 3 is past the end" in reports[2]
    assert "routine MainProgram.FillTank: rung 2" in reports[3] and "expected" in reports[3]


def test_what_is_not_run_is_a_warning_by_name_and_place_and_the_rest_runs(tmp_path):
    def add_unrun(text: str) -> str:
        text = text.replace('<![CDATA[XIC(Running)JSR(FillTank,0);]]>',
                            '<![CDATA[XIC(Running)JSR(FillTank,0)GSV(Module,Rack,EntryStatus,Now);]]>')
        return text.replace("</Tasks>", '<Task Name="Slow" Type="EVENT" Priority="5" Watchdog="500">'
                                         '<ScheduledPrograms/></Task>\n</Tasks>')
    app = load_app(tank_line(tmp_path, add_unrun))
    warnings = "\n".join(app.warnings)
    assert "GSV: Module.EntryStatus is not an attribute softplc_lite holds" in warnings
    assert "the rung is not run" in warnings
    assert "routine MainProgram.MainRoutine: rung 1" in warnings
    assert "event task Slow: not run: softplc_lite raises no event to trigger it" in warnings
    p = softplc_here("run", str(tmp_path / "tank_line.L5X"), "--scans", "3", "--set", "Start=1", "--print", "Running")
    assert p.returncode == 0 and "warning:" in p.stderr and p.stdout.strip().endswith("= 1")


@pytest.mark.parametrize("export", sorted(p.relative_to(FIXTURES).as_posix()
                                          for p in FIXTURES.rglob("*") if p.suffix.lower() in (".l5x", ".l5k")))
def test_every_fixture_export_loads_or_says_why_never_a_traceback(tmp_path, export):
    path = tmp_path / Path(export).name
    shutil.copy(FIXTURES / export, path)
    p = softplc_here("check", str(path))
    assert p.returncode in (0, 1) and "Traceback" not in p.stderr, p.stderr
    if p.returncode == 1:
        problems = [ln for ln in p.stderr.splitlines() if not ln.startswith("warning:") and ln.strip()]
        located = [ln for ln in problems if ln.startswith(f"{path}:")]
        assert located, p.stderr  # every export problem names its place


def test_addresses_name_their_tag_paths_back(tmp_path):
    from softplc_lite.logix.tags import TagNames

    app = load_app(tank_line(tmp_path))
    names, symbols = TagNames(app.logix.directory), app.program.symbols
    for path in ("Tanks[1].Level", "Tanks[0].Fill", "Tanks[1].Drain", "SettleTimer.DN", "SettleTimer.PRE",
                 "Flags.8", "Flags", "Running", "Batches.ACC", "Program:MainProgram.Overview", "Banner"):
        assert names.name_of(symbols.resolve_path(path)) == path
    assert names.name_of(symbols.resolve_path("LineDone")) == "Batches.DN"  # an alias names its target
    assert names.name_of(symbols.resolve_path("Program:MainProgram.Settled"), "MainProgram") == "Settled"


@pytest.mark.parametrize("export", ["tank_line.L5X", "io_rack.L5X"])
def test_the_shipped_exports_run_the_same_on_both_executors(tmp_path, export):
    """Scan by scan, with their BOOL inputs pulsed now and then, the two
    executors keep equal tables (tests/test_differential.py does this for
    the .lad apps)."""
    path = tmp_path / export
    shutil.copy(ROOT / "programs" / "logix" / export, path)
    pair = [runner_of(path, executor) for executor in ("compiled", "reference")]
    app = pair[0].app
    bools = [d.tag.name for scope in app.logix.directory.scopes.values() for d in scope.values()
             if d.type is not None and d.type.name == "BOOL" and not d.dims and d.scope is None]
    assert bools
    for scan in range(600):
        for r in pair:
            if scan % 97 == 3:
                tag = bools[scan % len(bools)]
                address = r.app.program.symbols.resolve_path(tag)
                r.table.write(address, 1 - r.table.read(address))
            r.run(1)
        assert pair[0].table == pair[1].table, f"scan {scan}"
        assert (pair[0].engine.fault is None) == (pair[1].engine.fault is None)
    for r in pair:
        r.close()


def test_logix_own_types_in_an_export_and_a_date_time_lint(tmp_path):
    """Studio writes Logix's own types into some exports (ProductDefined:
    STRING with its members, UINT with none): the predefined layout stands,
    a type with no members is not held (its tags not laid out, a warning),
    and a LINT's DT# value is its microseconds since 1970."""
    from helpers.logix_l5x import Prog, Task, l5x_text

    text = l5x_text([("Stamp", "LINT"), ("Count", "UINT"), ("Name", "STRING")],
                    [Prog("P", {"Main": ["NOP();"]})], [Task("T", ["P"])])
    text = text.replace("<DataTypes/>", '<DataTypes><DataType Name="STRING" Family="StringFamily" '
                        'Class="ProductDefined"><Members><Member Name="LEN" DataType="DINT" Dimension="0"/>'
                        '<Member Name="DATA" DataType="SINT" Dimension="82"/></Members></DataType>'
                        '<DataType Name="UINT" Family="NoFamily" Class="ProductDefined"/></DataTypes>')
    text = text.replace('<Tag Name="Stamp" TagType="Base" DataType="LINT" Constant="false" ExternalAccess="Read/Write"/>',
                        '<Tag Name="Stamp" TagType="Base" DataType="LINT" Radix="Date/Time" Constant="false" '
                        'ExternalAccess="Read/Write"><Data Format="Decorated"><DataValue DataType="LINT" '
                        'Radix="Date/Time" Value="DT#2022-02-22-06:00:00.000_250Z"/></Data></Tag>')
    path = tmp_path / "types.L5X"
    path.write_text(text, encoding="utf-8")
    app = load_app(path)
    assert any("tag Count: data type UINT is not one softplc_lite holds yet" in w for w in app.warnings)
    r = Runner(app, RunOptions(fresh=True, save_state=False))
    assert r.table.read(app.program.symbols.resolve_path("Stamp")) == 1_645_509_600_000_250
    r.close()


def test_a_message_tag_is_held_and_its_msg_not_run(tmp_path):
    """A MSG is not sent (no network: a warning, its rung a NOP), but its
    MESSAGE tag is laid out, so the rungs that read its status bits run."""
    from helpers.logix_l5x import Prog, Task, write_l5x

    path = write_l5x(tmp_path / "msg.L5X", [("Msg", "MESSAGE"), ("Go", "BOOL"), ("Done", "BOOL"), ("Err", "DINT")],
                     [Prog("P", {"Main": ["XIC(Go)MSG(Msg);", "XIC(Msg.DN)OTE(Done);", "MOV(Msg.ERR,Err);"]})],
                     [Task("T", ["P"])])
    app = load_app(path)
    assert any("MSG: a message to another device" in w and "rung 0" in w for w in app.warnings)
    r = Runner(app, RunOptions(fresh=True, save_state=False))
    names = app.program.symbols
    r.table.write(names.resolve_path("Msg.DN"), 1)
    r.table.write(names.resolve_path("Msg.ERR"), 7)
    r.run(1)
    assert r.table.read(names.resolve_path("Done")) == 1 and r.table.read(names.resolve_path("Err")) == 7
    r.close()


def test_an_array_larger_than_a_data_table_file_is_a_warning_not_an_error(tmp_path):
    from helpers.logix_l5x import Prog, Task, write_l5x

    path = write_l5x(tmp_path / "big.L5X", [("Regs", "INT[65536]"), ("i", "DINT"), ("x", "INT"), ("y", "INT")],
                     [Prog("P", {"Main": ["MOV(Regs[i],x);", "ADD(y,1,y);"]})], [Task("T", ["P"])])
    app = load_app(path)
    assert any("tag Regs: 65536 elements" in w and "not run" in w for w in app.warnings), app.warnings
    assert any("rung 0: MOV operand 'Regs[i]'" in w for w in app.warnings)
    r = Runner(app, RunOptions(fresh=True, save_state=False))
    r.run(3)
    assert r.table.read(app.program.symbols.resolve_path("y")) == 3  # the rest runs
    r.close()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_a_jsr_whose_parameters_do_not_match_faults_when_it_runs_as_logix_does(tmp_path, executor):
    """1756-PM014: major fault type 4, code 31 (invalid JSR parameter) comes
    when the JSR runs, not at download: the export loads, warns, and runs
    until the rung goes true."""
    from helpers.logix_l5x import Prog, Task, export_runner, write_l5x, write_tag

    path = write_l5x(tmp_path / "jsr.L5X", [("Go", "BOOL"), ("x", "DINT"), ("n", "DINT")],
                     [Prog("P", {"Main": ["ADD(n,1,n);", "XIC(Go)JSR(Sub,1,x);"], "Sub": ["NOP();"]})],
                     [Task("T", ["P"])])
    app = load_app(path)
    assert any("JSR to P.Sub: its parameters do not match" in w and "code 31" in w for w in app.warnings)
    r = export_runner(path, executor)
    r.run(3)
    assert r.engine.fault is None
    write_tag(r, "Go", 1)
    r.run(1)
    assert r.engine.fault is not None and r.engine.fault.code == 31 and "invalid JSR parameter" in r.engine.fault.message
    r.close()


def test_date_time_values_of_lints_in_microseconds_and_nanoseconds():
    from softplc_lite.logix.initial import date_time

    assert date_time("DT#1970-01-01-00:00:00.000_000Z") == 0
    assert date_time("DT#2022-01-01-06:00:00.100_100_100Z") == 1_641_016_800_100_100
    assert date_time("LDT#2022-01-01-06:00:00.100_100_100Z") == 1_641_016_800_100_100_100
    assert date_time("DT#2022-13-01-06:00:00Z") is None and date_time("12") is None
