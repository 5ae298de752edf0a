"""The watch view of a Studio 5000 export (docs/logix.md, "Watching a Logix
app"): operands by tag path in the routine's scope, Logix instruction names,
timers and counters with their status bits, routines as the files, rung
comments from the export. The goldens (tests/data/watch/tank_line-*.txt)
are checked by test_watch_snapshots.py; here each rule on its own."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from helpers.watch_sessions import save_edit, scan_to_break
from softplc_lite.app import load_app
from softplc_lite.datatable import Address
from softplc_lite.runner import RunOptions
from softplc_lite.watch.naming import Naming
from softplc_lite.watch.session import WatchOptions, WatchSession
from softplc_lite.watch.snapshot import render

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
TANK_LINE = ROOT / "programs" / "logix" / "tank_line.L5X"
GOLDENS = Path(__file__).resolve().parent / "data" / "watch"


@pytest.fixture
def session(tmp_path):
    app = load_app(TANK_LINE, tmp_path / "state")
    s = WatchSession(app, WatchOptions(run=RunOptions(fresh=True, sets=("Start=1",)), online=False))
    yield s
    s.quit()


def _screen(s: WatchSession, width: int = 120, height: int = 40) -> list[str]:
    return [line.rstrip() for line in render(s, width, height).export_text().splitlines()]


def test_operands_are_named_by_tag_path_in_the_routines_scope(tmp_path):
    app = load_app(TANK_LINE, tmp_path)
    naming = Naming(app)
    main = app.logix.routine_files[("MAINPROGRAM", "MAINROUTINE")]
    names = naming.for_file(main)
    settled = app.program.symbols.resolve_path("Program:MainProgram.Settled")
    assert names.name(settled) == "Settled"  # the program's own tag, from its routine
    assert naming.for_file(2).name(settled) == "Program:MainProgram.Settled"  # from the continuous task
    assert names.name(app.program.symbols.resolve_path("SettleTimer.DN")) == "SettleTimer.DN"
    assert names.name(app.program.symbols.resolve_path("Tanks[1].Level")) == "Tanks[1].Level"
    # an element an index tag picks: the tag's name as the subscript
    level = app.program.symbols.resolve_path("Tanks[1].Level")
    active = app.program.symbols.resolve_path("Active")
    indexed = Address(level.type_letter, level.file, active)
    assert names.name(indexed) == "Tanks[Active].Level"
    fill = app.program.symbols.resolve_path("Tanks[1].Fill")
    assert names.name(Address(fill.type_letter, fill.file, active, None, fill.bit)) == "Tanks[Active].Fill"
    assert names.name(Address("N", 7, 0)) is None  # not a tag's: the address is shown
    assert names.mnemonic("LTON") == "TON" and names.mnemonic("LCTU") == "CTU" and names.mnemonic("XIC") == "XIC"


def test_a_plc5_app_keeps_addresses_and_symbols(tmp_path):
    app = load_app(ROOT / "programs" / "motor", tmp_path)
    naming = Naming(app)
    assert not naming.is_logix and naming.what_files == ("program file", "files")
    assert naming.for_file(2).replaces_address is False
    assert naming.for_file(2).mnemonic("TON") == "TON"
    assert naming.first_file(sorted(app.program.files)) == 2


def test_the_view_starts_at_the_routine_the_task_runs_and_lists_routines(session):
    lines = _screen(session)
    header = lines[2]
    assert header.startswith(" routine MainProgram.MainRoutine  rung 0 of 6  routines: continuous task")
    assert "program file" not in "\n".join(lines) and "B10/" not in "\n".join(lines)
    assert "Start and stop the line: a seal-in" in lines[4]  # the export's rung comment
    session.next_file()
    assert _screen(session)[2].startswith(" routine MainProgram.FillTank  rung 0 of 3")
    session.next_file()
    text = "\n".join(_screen(session))
    assert " routine continuous task" in text and "|MainProgram.MainRoutine|" in text  # its JSR, by routine


def test_boxes_show_logix_names_tag_values_and_status_bits(session):
    for _ in range(150):  # tank 0 full at scan 80: the settle timer is timing
        session.scan()
    text = "\n".join(_screen(session))
    assert "+-TON" in text and "+-CTU" in text and "LTON" not in text and "LCTU" not in text
    assert "|SettleTimer " in text and "|Batches " in text
    acc = session.engine.table.read(session.app.program.symbols.resolve_path("SettleTimer.ACC"))
    assert 0 < acc < 2000
    assert f"|EN TT . PRE 2000 ACC {acc}|" in text
    assert "|. . . . . PRE 3 ACC 0|" in text
    assert "+-JSR" in text and "|FillTank|" in text  # a JSR in the program names its routine
    session.goto(5)
    text = "\n".join(_screen(session))
    # CPT: the expression as Logix writes it, by tag path; each read with its value
    assert "(Tanks[0].Level + Tanks[1].Level)" in text and "/ 2.0" in text and "|" + " 2.0" not in text
    assert "-> Overview=" in text and "Tanks[0].Level=40.0" in text
    assert "Batches.ACC=0 -> Flags=0" in text


def test_goldens_show_the_tank_line_by_name():
    """Spot checks of the goldens, so one regenerated by mistake does not pass unread."""
    for size in ("120x40", "80x24"):
        text = (GOLDENS / f"tank_line-{size}.txt").read_text(encoding="utf-8")
        assert " tank_line  RUN  scan 300  3.000 s sim" in text
        assert " routine MainProgram.MainRoutine  rung 0 of 6" in text
        assert "Tanks[0].Level 0.0" in text and "Tanks[1].Level 9.5" in text and "Batches.ACC      1" in text
        assert "Batches.DN" in text and "Running" in text and "B10/" not in text
    text = (GOLDENS / "tank_line-120x40.txt").read_text(encoding="utf-8")
    assert "|. . . . . PRE 3 ACC 1|" in text and "Tanks[Active].Drain" in text and "Active=1 XOR 1" in text


def test_the_tag_monitor_lists_tags_and_opens_structures_and_arrays(session):
    for _ in range(150):
        session.scan()
    session.show_file("")
    assert session.message.startswith("tags: name a structure or an array to open it")
    text = "\n".join(_screen(session, 100, 24))
    assert " tags  13 tags  radix decimal  1..13" in text
    rows = {line.split()[0]: line.split()[1:] for line in text.splitlines()[3:-1] if line.strip()}
    assert rows["Running"] == ["BOOL", "1"] and rows["Tanks"] == ["Tank[2]"]
    assert rows["SettleTimer"] == ["TIMER", "{...}"] and rows["Banner"] == ["STRING", '"idle"']
    assert rows["LineDone"] == ["BOOL", "0", "->", "Batches.DN"]  # an alias, its target's value
    assert rows["Program:MainProgram.Overview"] == ["REAL", "20.0"]
    session.show_file("Tanks")
    text = "\n".join(_screen(session, 100, 24))
    assert "Tanks[0]  Tank  {...}" in text and "Tanks[1]  Tank  {...}" in text
    session.show_file("Tanks[0]")
    lines = _screen(session, 100, 24)
    members = [line.split() for line in lines[3:8]]
    assert members == [["Tanks[0].Fill", "BOOL", "0"], ["Tanks[0].Drain", "BOOL", "1"],
                       ["Tanks[0].Level", "REAL", "40.0"], ["Tanks[0].Setpoint", "REAL", "40.0"],
                       ["Tanks[0].Fills", "DINT", "0"]]  # the hidden host of Fill and Drain left out
    session.show_file("SettleTimer")
    acc = session.engine.table.read(session.app.program.symbols.resolve_path("SettleTimer.ACC"))
    assert f"SettleTimer.ACC  DINT  {acc}" in "\n".join(_screen(session, 100, 24))
    session.scan()  # the values are the table's at each drawing
    assert f"SettleTimer.ACC  DINT  {acc + 10}" in "\n".join(_screen(session, 100, 24))
    session.cycle_radix()
    assert session.message == "SettleTimer: radix hex (REAL values show in decimal)"
    assert f"SettleTimer.PRE  DINT  {2000:08X}" in "\n".join(_screen(session, 100, 24))


def test_the_monitor_still_shows_data_files_and_says_what_it_expected(session):
    session.show_file("F12")
    assert session.message.startswith("data file F12:")
    assert "F12:0" in "\n".join(_screen(session, 100, 24))
    session.show_file("Tanks[7]")
    assert session.message.startswith("Tanks[7]: ") and "expected a tag (Tanks, Tanks[1]" in session.message
    session.close_panels()
    assert session.grid is None


def test_the_view_starts_at_the_continuous_tasks_first_routine_not_a_periodic_tasks_file(tmp_path):
    app = load_app(ROOT / "programs" / "logix" / "dosing.L5X", tmp_path)
    first = Naming(app).first_file(sorted(app.program.files))
    assert app.program.files[first].name == "MainProgram.MainRoutine"


def test_the_doc_shows_the_golden_view():
    """docs/logix.md shows the text of its --snapshot example: the tank line's 80x24 golden (the
    console example beside it, run by test_docs.py, is the same view: test_watch_snapshots.py)."""
    doc = (ROOT / "docs" / "logix.md").read_text(encoding="utf-8")
    shown = doc.split("`/tmp/tank_line-watch.txt` then holds:", 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    assert shown == (GOLDENS / "tank_line-80x24.txt").read_text(encoding="utf-8")


def test_the_cli_snapshot_is_the_golden_view(tmp_path):
    out = tmp_path / "view.txt"
    r = softplc_here("watch", "programs/logix/tank_line.L5X", "--fresh", "--scans", "300", "--set", "Start=1",
                     "--watch", "Tanks[0].Level", "--watch", "Tanks[1].Level", "--watch", "Batches.ACC",
                     "--snapshot", str(out), "--width", "80", "--height", "24")
    assert r.returncode == 0, r.stderr
    text = "".join(line.rstrip() + "\n" for line in out.read_text(encoding="utf-8").splitlines())
    assert text == (GOLDENS / "tank_line-80x24.txt").read_text(encoding="utf-8")


def test_break_when_find_set_and_force_take_tag_paths(tmp_path):
    app = load_app(TANK_LINE, tmp_path / "state")
    s = WatchSession(app, WatchOptions(run=RunOptions(fresh=True), break_when=("Batches.ACC >= 1",),
                                       forces=("Stop=0",), online=False))
    try:
        s.find("SettleTimer.DN")
        assert s.message.startswith("SettleTimer.DN (L15:1/29) 1 of 2: MainProgram.MainRoutine rung 2")
        s.set_value("Start = 1")
        assert s.message == "set Start = 1"
        hit = scan_to_break(s, 400)
        assert hit is not None and s.engine.scans == 281  # 80 scans filling, 200 settling, one to count
        assert s.message == "break: Batches.ACC >= 1 became true at scan 281"
        assert (s.file, s.selected) == (3, 2)  # the break is shown in its routine
    finally:
        s.quit()


def test_the_find_list_names_routines_instructions_and_tags(session):
    session.scan()
    session.find("Tanks[0].Level")
    assert session.message == ("Tanks[0].Level (F12:0) 1 of 5: MainProgram.MainRoutine rung 4  instruction 3 MOV  "
                               "operand 2 Tanks[Active].Level  indirect write")
    text = "\n".join(_screen(session, 80, 40))
    assert "find Tanks[0].Level (F12:0): 5 uses, 2 writing" in text
    assert "▶ indirect write  MainProgram.MainRoutine rung 4  MOV Tanks[Active].Level" in text
    assert "  read            MainProgram.MainRoutine rung 5  CPT Tanks[0].Level" in text
    assert "  indirect write  MainProgram.FillTank rung 1  ADD Tanks[Active].Level" in text
    session.find("SettleTimer.DN")
    assert "instruction 2 TON  operand 1 SettleTimer  read/write" in session.message  # LTON as TON, its timer


def test_a_re_exported_file_is_put_in_place_and_named_anew(tmp_path):
    """Online program edit: the export saved again (a rung changed, a tag added before the others, so
    every tag moves in the data table) is loaded as any app's edit, and the view names the new layout."""
    export = tmp_path / "tank_line.L5X"
    shutil.copy(TANK_LINE, export)
    s = WatchSession(load_app(export, tmp_path / "state"), WatchOptions(run=RunOptions(fresh=True)))
    try:
        s.scan()
        text = export.read_text(encoding="utf-8")
        text = text.replace("XIC(Running)JSR(FillTank,0);", "XIC(Running)XIO(Hold)JSR(FillTank,0);")
        text = text.replace("<Tags>\n<Tag Name=\"Start\"", "<Tags>\n<Tag Name=\"Hold\" TagType=\"Base\" "
                            "DataType=\"BOOL\" Radix=\"Decimal\" Constant=\"false\" ExternalAccess=\"Read/Write\"/>\n"
                            "<Tag Name=\"Start\"", 1)
        save_edit(s, export, text)
        assert s.last_edit is not None and s.last_edit.applied, s.message
        s.goto(1)
        lines = _screen(s)
        rung = next(k for k, line in enumerate(lines) if line.startswith(">  Rung 1"))
        assert lines[rung + 1].split()[:4] == ["|", "Running", "Hold", "+-JSR----+"]
        s.show_file("tags")
        assert "Hold " in "\n".join(_screen(s))
    finally:
        s.quit()


def test_the_d_key_asks_for_a_tag_and_enter_alone_lists_them_all(session):
    from softplc_lite.watch.terminal import PROMPTS, Controller

    c = Controller(session)
    c.key("d")
    assert c.prompt == PROMPTS["tags"] and c.prompt.startswith("tag (Tanks, Tanks[1]; Enter: every tag)")
    c.key("\r")
    assert session.grid is not None and session.grid.name == "tags"
    c.key("esc")
    assert session.grid is None
    c.key("d")
    for ch in "Tanks[1]":
        c.key(ch)
    c.key("\r")
    assert session.grid.name == "Tanks[1]"
    assert "Tanks[1].Setpoint  REAL  80.0" in "\n".join(_screen(session))
