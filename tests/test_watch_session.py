"""The watch view's engine parts, without a terminal: forces, breakpoints,
stepping back through history, the watch list."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.app import load_app
from softplc_lite.datatable import DataTableError
from softplc_lite.runner import RunOptions
from softplc_lite.watch.breakpoints import Condition
from softplc_lite.watch.forces import ForceError, parse_force
from softplc_lite.watch.history import DEPTH
from softplc_lite.watch.session import WatchOptions, WatchSession

from helpers.watch_sessions import sessions

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"

MOTOR = """
SYMBOL Start I:0/0
SYMBOL Motor O:0/0
// count scans
ADD N7:0 1 N7:0
// the motor follows the start input
XIC Start OTE Motor
// a subroutine-free rung that is energized only when N7:0 is a multiple of 5
CMP "N7:0 MOD 5 = 0" OTE B3/0
// the program tries to switch O:0/1 on every scan
OTE O:0/1
"""


@pytest.fixture
def session(tmp_path):
    yield from sessions(tmp_path, MOTOR)


def read(s: WatchSession, addr: str):
    return s.engine.table.read(addr)


# -- forces ---------------------------------------------------------------------------------

def test_a_forced_input_wins_over_the_input_scan_and_the_program_sees_it(session):
    s = session(forces=("Start=1",))
    s.scan()
    assert read(s, "O:0/0") == 1  # the ladder read the forced input
    s.engine.table.write("I:0/0", 0)  # what an input scan would write
    s.scan()
    assert read(s, "I:0/0") == 1 and read(s, "O:0/0") == 1
    s.unforce("Start")
    s.engine.table.write("I:0/0", 0)
    s.scan()
    assert read(s, "O:0/0") == 0


def test_a_forced_output_wins_over_the_program(session):
    s = session()
    s.force("O:0/1=0")
    for _ in range(3):
        s.scan()
        assert read(s, "O:0/1") == 0  # OTE O:0/1 writes 1 every scan; the force holds 0
    assert [str(f) for f in s.forces.listed()] == ["O:0/1=0"]
    s.forces.clear()
    s.scan()
    assert read(s, "O:0/1") == 1


def test_any_bit_can_be_forced_but_only_bits(session):
    s = session()
    s.force("N7:3/15=1")
    s.scan()
    assert read(s, "N7:3") == -32768
    with pytest.raises(ForceError, match="only a direct bit address"):
        parse_force("N7:0=1")
    with pytest.raises(ForceError, match="expected ADDR=1 or ADDR=0"):
        parse_force("O:0/0=2")


# -- breakpoints --------------------------------------------------------------------------------

def test_break_when_a_condition_becomes_true(session):
    s = session(break_when=("N7:0 > 7",))
    s.start()
    s.run_for(5.0)
    assert not s.running and read(s, "N7:0") == 8
    assert s.message == "break: N7:0 > 7 became true at scan 8"
    s.start()
    s.run_for(0.05)  # stays true: no new break until it goes false and true again
    assert read(s, "N7:0") > 8


def test_break_when_a_bit_address_goes_on(session):
    s = session(break_when=("B3/0",))
    s.start()
    s.run_for(5.0)
    assert read(s, "N7:0") == 5 and s.last_hit.condition == "B3/0"


def test_rung_breakpoint_stops_when_the_rung_is_energized(session):
    s = session()
    s.goto(2)  # the CMP rung
    s.toggle_breakpoint()
    s.start()
    s.run_for(5.0)
    assert not s.running and read(s, "N7:0") == 5
    assert (s.last_hit.file, s.last_hit.rung, s.last_hit.scan) == (2, 2, 5)
    assert s.message == "break: file 2 rung 2 energized at scan 5"
    s.start()
    s.run_for(5.0)
    assert read(s, "N7:0") == 10  # the next time
    s.toggle_breakpoint()  # cleared: runs on
    s.start()
    s.run_for(0.05)
    assert s.running and read(s, "N7:0") > 10


def test_rung_breakpoint_judges_the_rung_on_the_values_it_reads(session):
    # a self-resetting timer writes what it reads: true in the scan DN goes on, false in the next
    s = session("XIO T4:0/DN TON T4:0 0.01 3 0\n")
    s.toggle_breakpoint()
    hits = [s.scan() is not None for _ in range(6)]
    assert hits == [True, True, True, True, False, True]


def test_bad_break_condition_is_a_clear_error(session):
    with pytest.raises(DataTableError, match="--break-when"):
        Condition("N7:0 >")
    with pytest.raises(DataTableError, match="neither an address nor a program symbol"):
        session(break_when=("Nothing > 1",))


# -- history --------------------------------------------------------------------------------------

def test_step_back_and_forward_through_history_without_rerunning(session):
    s = session()
    for _ in range(10):
        s.scan()
    assert read(s, "N7:0") == 10
    s.back()
    s.back()
    assert read(s, "N7:0") == 8 and s.shown_scan == 8 and s.engine.scans == 10
    s.scan()  # forward in history, not a new scan
    assert read(s, "N7:0") == 9 and s.engine.scans == 10
    s.scan()
    s.scan()  # live again: now a new scan
    assert read(s, "N7:0") == 11 and s.engine.scans == 11 and s.history.live


def test_history_keeps_at_least_a_thousand_scans(session):
    s = session()
    for _ in range(DEPTH + 50):
        s.scan()
    for _ in range(DEPTH - 1):
        s.back()
    assert s.shown_scan == 51 and read(s, "N7:0") == 51
    s.back()
    assert "no earlier scan" in s.message and s.shown_scan == 51
    s.start()  # running goes back to the newest scan first
    while not s.run_for(0.02):  # 20 ms of a busy machine may hold no scan
        pass
    assert read(s, "N7:0") > DEPTH + 50


def test_watch_list_samples_values_and_trends(session):
    s = session(watch=("N7:0", "O:0/0"))
    for _ in range(5):
        s.scan()
    n7 = s.watch.items[0]
    assert n7.value == 5 and n7.changed and list(n7.trend) == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]


def test_quit_saves_the_retentive_table(session, tmp_path):
    s = session()
    for _ in range(3):
        s.scan()
    s.quit()
    from softplc_lite.datatable import snapshot

    assert snapshot.load(tmp_path / "state0" / "datatable.snap").read("N7:0") == 3


def test_modbus_master_session_shows_ports(session):
    app = load_app(PROGRAMS / "modbus_master", use_cache=False)
    app.state_dir = None  # nothing written in the repository: no code cache, no snapshot
    s = WatchSession(app, WatchOptions(run=RunOptions(fresh=True)))
    try:
        for _ in range(200):
            s.scan()
        from softplc_lite.watch.portsview import ports_of

        (port,) = ports_of(s.engine)
        assert port.tx_bytes >= 8 and port.rx_bytes >= 255
    finally:
        s.quit()


def test_history_steps_do_not_add_to_the_trend(session):
    s = session(watch=("N7:0",))
    for _ in range(4):
        s.scan()
    s.back()
    s.back()
    s.scan()
    item = s.watch.items[0]
    assert item.value == 3 and list(item.trend) == [0.0, 1.0, 2.0, 3.0, 4.0]


def test_the_mode_prompt_changes_modes_and_program_again_reloads_the_drivers(tmp_path):
    """M, then program / run / test, through the real key handling; PROGRAM
    while in PROGRAM makes MODBMAST read its file again (manual 5.2)."""
    import shutil

    from softplc_lite.ladder.engine import Mode
    from softplc_lite.watch.terminal import Controller

    app_dir = tmp_path / "scada"
    shutil.copytree(Path(__file__).resolve().parent.parent / "programs" / "modbus_scada", app_dir,
                    ignore=shutil.ignore_patterns(".softplc"))
    s = WatchSession(load_app(app_dir, tmp_path / "state"), WatchOptions(run=RunOptions(fresh=True)))
    keys = Controller(s)

    def type_(text: str) -> None:
        for k in ["M", *text, "\r"]:
            keys.key(k)

    try:
        assert s.engine.mode is Mode.RUN
        type_("p")
        assert s.engine.mode is Mode.PROGRAM and s.message == "mode PROGRAM"
        xml = (app_dir / "MODBMAST.XML").read_text().replace('dest="N11:0" count="6"', 'dest="N14:0" count="6"')
        (app_dir / "MODBMAST.XML").write_text(xml)
        type_("program")
        assert s.message == "PROGRAM again: the modules reloaded their configuration"
        for _ in range(20):
            s.scan()
        assert s.engine.table.read("N14:5") == 5  # the drive's registers land where the new file says
        type_("sideways")
        assert s.message == "mode 'sideways': expected program, run or test" and s.engine.mode is Mode.PROGRAM
        (app_dir / "MODBMAST.XML").write_text("<ModbusSerial><Port/></ModbusSerial>")
        type_("PROGRAM")
        assert s.engine.mode is Mode.FAULTED and "major fault 203" in s.message
        type_("run")
        assert "clear the fault first" in s.message and s.engine.mode is Mode.FAULTED
        type_("p")
        type_("test")
        assert s.engine.mode is Mode.TEST and s.message == "mode TEST"
    finally:
        s.quit()
