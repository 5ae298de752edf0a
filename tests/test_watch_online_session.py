"""Online data edits, modes, fault clearing and the view's keys, through the
session and the Controller (no terminal): tests/test_watch_online_keys.py
presses the same keys in tmux."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from softplc_lite.datatable.display import format_value
from softplc_lite.ladder import status as S
from softplc_lite.ladder.engine import Mode
from softplc_lite.watch.screen import WatchScreen, rung_view
from softplc_lite.watch.session import WatchSession
from softplc_lite.watch.terminal import BINDINGS, KEYS, PROMPTS, Controller

from helpers.watch_sessions import sessions

PROGRAM = """
SYMBOL Start I:0/0
SYMBOL Speed N7:0
// count scans
// (a second comment line)
ADD N7:1 1 N7:1
XIC Start OTE O:0/0
// faults when N7:9 points past N7
MOV N7:[N7:9] N7:2
MOV F8:0 F8:1
MOV T4:0.PRE N7:3
"""


@pytest.fixture
def session(tmp_path):
    yield from sessions(tmp_path, PROGRAM, {"datatable.json": '{"ST9": [""]}'})


def press(control: Controller, *keys: str) -> None:
    """Each argument a key, or a prompt's text typed and Enter pressed."""
    for k in keys:
        if len(k) > 1 and k not in ("up", "down", "home", "end", "pgup", "pgdown", "esc"):
            for ch in k:
                control.key(ch)
            control.key("\r")
        else:
            control.key(k)


def read(s: WatchSession, addr: str):
    return s.engine.table.read(addr)


# -- set and toggle ---------------------------------------------------------------------------

@pytest.mark.parametrize("entry, address, value", [
    ("N7:0 = 150", "N7:0", 150),
    ("T4:0.PRE = 50", "T4:0.PRE", 50),
    ("F8:0 = 1.5", "F8:0", 1.5),
    ('ST9:0 = "text"', "ST9:0", "text"),
    ("ST9:0 = plain words", "ST9:0", "plain words"),
    ("Speed = -7", "N7:0", -7),
    ("N7:0/3 = 1", "N7:0", 8),
])
def test_set_writes_any_word_float_string_member_or_symbol(session, entry, address, value):
    s = session()
    c = Controller(s)
    press(c, "=", entry)
    assert read(s, address) == value
    assert s.message.startswith("set ") and "=" in s.message, s.message


def test_a_set_value_is_what_the_next_scan_reads(session):
    s = session()
    c = Controller(s)
    press(c, "n", "=", "T4:0.PRE = 50", "=", "F8:0 = 2.25", "n")
    assert read(s, "N7:3") == 50 and read(s, "F8:1") == 2.25


@pytest.mark.parametrize("entry, said", [
    ("N7:0", "expected ADDR = VALUE"),
    ("N7:0 = ", "expected ADDR = VALUE"),
    ("N7:0 = 70000", "N7:0"),
    ("N7:0 = abc", "N7:0"),
    ("Q9:0 = 1", "set Q9:0"),
    ("NoSuchSymbol = 1", "NoSuchSymbol"),
    ("F8:0 = \"x\"", "F8:0"),
])
def test_a_bad_set_says_why_and_changes_nothing(session, entry, said):
    s = session()
    s.scan()
    raws = [bytes(f.data) for f in s.engine.table.files()]
    c = Controller(s)
    press(c, "=", entry)
    assert said in s.message and "Traceback" not in s.message
    assert [bytes(f.data) for f in s.engine.table.files()] == raws, s.message


def test_toggle_offers_the_selected_rungs_bit_and_inverts_it(session):
    s = session()
    c = Controller(s)
    press(c, "down")  # rung 1: XIC Start OTE O:0/0
    c.key("t")
    assert c.prompt == PROMPTS["t"] + "I:0/0"  # the first bit operand, offered
    c.key("\r")
    assert read(s, "I:0/0") == 1 and s.message == "toggled I:0/0: now 1"
    s.scan()
    assert read(s, "O:0/0") == 1
    press(c, "\x14", "\x7f" * 5 + "O:0/0")  # Ctrl-T; erase the offer, type another bit
    assert read(s, "O:0/0") == 0
    press(c, "t", "\x7f" * 5 + "N7:1")
    assert s.message == "toggle N7:1: expected a bit address (B3/5, O:0/0, N7:0/3, T4:0.EN)"


def test_an_edit_is_kept_in_history(session):
    """Set after scan 2; one scan more; back to scan 2 shows the edit, as does forward."""
    s = session()
    s.scan()
    s.scan()
    s.set_value("N7:0 = 150")
    s.scan()
    s.set_value("N7:0 = 7")
    s.back()  # scan 2, as the edit after it left it
    assert s.shown_scan == 2 and read(s, "N7:0") == 150
    s.back()  # scan 1: before the edit
    assert s.shown_scan == 1 and read(s, "N7:0") == 0
    s.scan()
    s.scan()  # forward again to the newest (live)
    assert s.history.live and read(s, "N7:0") == 7


def test_an_edit_while_stepped_back_goes_to_the_newest_scan(session):
    s = session()
    for _ in range(3):
        s.scan()
    s.back()
    s.set_value("N7:0 = 42")
    assert s.history.live and read(s, "N7:0") == 42 and read(s, "N7:1") == 3


def test_the_watch_list_shows_an_edit_and_a_force_at_once(session):
    s = session(watch=("N7:0", "O:0/1"))
    s.scan()
    s.set_value("N7:0 = 150")
    assert s.watch.items[0].value == 150
    s.force("O:0/1=1")
    assert s.watch.items[1].value == 1  # before any scan
    s.unforce("O:0/1")
    s.toggle("O:0/1")
    assert s.watch.items[1].value == 0


def test_setting_a_forced_bit_says_the_force_holds_it(session):
    s = session()
    s.force("O:0/0=1")
    s.set_value("O:0/0 = 0")
    assert "forced" in s.message
    s.scan()
    assert read(s, "O:0/0") == 1


# -- modes and faults --------------------------------------------------------------------------

def test_modes_from_every_state_and_a_fault_cleared_without_quitting(session):
    s = session()
    c = Controller(s)
    press(c, "M", "test")
    assert s.engine.mode is Mode.TEST
    press(c, "M", "program")
    assert s.engine.mode is Mode.PROGRAM
    press(c, "C")
    assert s.message == "no major fault to clear"
    press(c, "M", "run")
    assert s.engine.mode is Mode.RUN
    press(c, "=", "N7:9 = 500", "n")  # MOV N7:[N7:9] reads past N7: a major fault
    e = s.engine
    assert e.mode is Mode.FAULTED and e.fault.rung == 2 and e.fault.file == 2
    assert "program file 2, rung 2, MOV" in s.message
    assert (s.file, s.selected) == (2, 2)  # the faulted rung selected
    press(c, "M", "run")
    assert "clear the fault first" in s.message and e.mode is Mode.FAULTED
    press(c, "r")
    assert not s.running and s.message == "FAULTED: C clears the fault (to PROGRAM), then M run"
    assert s.run_for(0.05) == 0  # a faulted PLC does not scan
    press(c, "C")
    assert e.mode is Mode.PROGRAM and e.fault is None and s.message.startswith("fault cleared")
    press(c, "=", "N7:9 = 0", "M", "run", "n", "n")
    assert e.mode is Mode.RUN and e.fault is None and read(s, "N7:1") == 3


def test_the_mode_word_change_survives_stepping_back_and_forward(session):
    s = session()
    s.scan()
    s.scan()
    s.set_mode("test")
    assert s.engine.s[S.MODE_WORD] == Mode.TEST.value
    s.back()
    assert s.engine.s[S.MODE_WORD] == Mode.RUN.value  # scan 1 ran in RUN
    s.scan()
    assert s.history.live and s.engine.s[S.MODE_WORD] == Mode.TEST.value


# -- navigation, comments, help ------------------------------------------------------------------

def test_home_end_and_go_to(session):
    s = session()
    c = Controller(s)
    press(c, "end")
    assert s.selected == len(s.rungs) - 1
    press(c, "home")
    assert s.selected == 0
    press(c, "g", "abc")
    assert s.message == "go to rung 'abc': expected a rung number, 0 to 4" and s.selected == 0
    press(c, "g", "99")
    assert s.selected == 4 and s.message == "go to rung: file 2 has rungs 0 to 4; at rung 4"
    press(c, "g", "2", "\r")
    assert s.selected == 2 and s.message == ""


def draw(s: WatchSession, width: int = 100, height: int = 30, help_keys=None) -> str:
    screen = WatchScreen(s, rung_view, measured=False)
    screen.help = help_keys
    console = Console(width=width, height=height, color_system=None, file=io.StringIO(), legacy_windows=False)
    with console.capture() as cap:
        console.print(screen)
    return cap.get()


def test_comments_cycle_full_first_line_hidden(session):
    s = session()
    full = draw(s)
    assert "count scans" in full and "(a second comment line)" in full
    Controller(s).key("c")
    first = draw(s)
    assert "count scans ..." in first and "(a second comment line)" not in first
    assert "comments first line" in first
    Controller(s).key("c")
    hidden = draw(s)
    assert "count scans" not in hidden and "faults when" not in hidden and "comments hidden" in hidden
    Controller(s).key("c")
    assert s.comments == "full"


def test_the_header_names_the_program_files(session):
    s = session(text="FILE 2 MAIN\nJSR 3\nFILE 3 FILL\nOTE B3/0\n")
    shown = draw(s)
    assert "program file 2 MAIN  rung 0 of 1  files: 2 MAIN  3 FILL" in shown
    s.next_file()
    assert "program file 3 FILL" in draw(s)


def test_help_lists_every_key_and_any_key_closes_it(session):
    s = session()
    c = Controller(s)
    c.key("?")
    assert c.help
    shown = draw(s, height=40, help_keys=KEYS)
    for label, text in KEYS:
        assert label in shown and text[:30] in shown
    c.key("n")  # closes the help, does not scan
    assert not c.help and s.engine.scans == 0


def test_every_binding_has_an_action_and_no_key_is_bound_twice():
    keys = [k for b in BINDINGS for k in b.keys]
    assert len(keys) == len(set(keys))
    assert all(hasattr(Controller, f"_do_{b.action}") for b in BINDINGS)
    actions = {k: b.action for b in BINDINGS for k in b.keys}
    assert [actions[k] for k in ("/", "x", "X", "d", "R", "esc", "E")] == \
        ["find", "use", "use", "data_file", "radix", "close", "edit_errors"]


# -- value formats ---------------------------------------------------------------------------------

def test_floats_show_seven_significant_digits():
    assert format_value(3.140000104904175) == "3.14"
    assert format_value(1.5) == "1.5" and format_value(150.0) == "150.0" and format_value(-0.0) == "-0.0"
    assert format_value(123456789.0) == "1.234568e+08"
    assert format_value({"EN": 1, "PRE": 5}) == "EN=1 PRE=5" and format_value(7) == "7"


def test_the_watch_list_keeps_values_whole_and_shortens_only_names_that_do_not_fit(session):
    s = session(text="SYMBOL AVeryLongNameForTheInfeedConveyorPhotoEyeTimer F8:0\nMOV F8:0 F8:1\n",
                watch=("AVeryLongNameForTheInfeedConveyorPhotoEyeTimer", "F8:1"))
    s.set_value("F8:0 = -1234.5678")
    console = Console(width=46, color_system=None, file=io.StringIO())
    with console.capture() as cap:
        console.print(s.watch)
    lines = cap.get().splitlines()
    assert lines[1].startswith("AVeryLongNameForTheInfeedConveyor") and "…" in lines[1]
    assert lines[1].split()[1] == "-1234.568"  # the value whole
    assert lines[2].split() == ["F8:1", "0.0"]
    assert all(len(line) <= 46 for line in lines)


def test_help_goes_to_pages_when_one_column_does_not_fit(session):
    s = session()
    screen = WatchScreen(s, rung_view, measured=False)
    screen.help, pages = KEYS, []
    while True:
        console = Console(width=100, height=14, color_system=None, file=io.StringIO(), legacy_windows=False)
        with console.capture() as cap:
            console.print(screen)
        pages.append(cap.get())
        if screen.help_page + 1 >= screen.help_pages:
            break
        screen.help_page += 1
    assert len(pages) == screen.help_pages > 1 and all(len(p.splitlines()) == 14 for p in pages)
    assert f"keys, page 1 of {len(pages)}" in pages[0]
    shown = "".join(pages)
    assert all(label in shown and text in shown for label, text in KEYS)  # one column: every text whole


# -- online program edit: what the view does when the program is replaced -------------------------

def wait_for_edit(s: WatchSession, seconds: float = 10.0) -> None:
    """Poll as the terminal loop does (bounded) until an edit is taken or refused."""
    import time

    deadline = time.monotonic() + seconds
    while s.last_edit is None and s.pending_edit is None and time.monotonic() < deadline:
        s.poll_online()
        time.sleep(0.05)
    assert s.last_edit is not None or s.pending_edit is not None, "no online edit seen"


def resave(path, text: str) -> None:
    import os

    before = path.stat().st_mtime_ns
    path.write_text(text)
    os.utime(path, ns=(before, before + 10_000_000))  # a new timestamp even within one tick


def test_online_edit_moves_breakpoints_the_selection_and_the_find_list(session):
    s = session()
    main = s.app.path / "main.lad"
    s.goto(1)
    s.toggle_breakpoint()  # rung 1 (XIC Start OTE O:0/0): unchanged by the edit, it moves to rung 2
    s.goto(3)
    s.toggle_breakpoint()  # rung 3 (MOV F8:0 F8:1): changed by the edit, its breakpoint goes
    s.find("N7:2")
    assert {(u.file, u.rung) for u in s.finding.uses} == {(2, 2)}
    s.goto(1)
    resave(main, PROGRAM.replace("// count scans", "MOV 7 N7:5\n// count scans").replace("F8:1", "F8:2"))
    wait_for_edit(s)
    assert s.message.startswith("online edit accepted: file 2: 1 rung added (0), 1 changed (4)"), s.message
    assert s.message.endswith("; 1 breakpoint(s) on edited rungs cleared")
    assert s.breaks.rungs == {(2, 2)} and s.selected == 2  # the selected rung followed its text
    assert {(u.file, u.rung) for u in s.finding.uses} == {(2, 3)}  # the list shows the new numbers
    s.scan()
    assert s.engine.table.read("N7:5") == 7  # the added rung runs
    s.set_value("Start = 1")
    hit = s.scan()
    assert hit is not None and (hit.file, hit.rung) == (2, 2)  # the moved breakpoint stops on the new code


def test_an_accepted_edit_waits_while_stepping_back(session):
    s = session()
    main = s.app.path / "main.lad"
    s.scan()
    s.scan()
    s.back()
    resave(main, PROGRAM + "MOV 9 N7:6\n")
    wait_for_edit(s)
    assert s.pending_edit is not None and s.last_edit is None and len(s.rungs) == 5  # not in while in history
    s.scan()  # forward to the newest scan: live
    s.poll_online()
    assert s.last_edit is s.online.last and s.last_edit.applied and len(s.rungs) == 6


def test_a_rejected_edit_keeps_the_program_and_E_shows_it(session):
    s = session()
    control = Controller(s)
    main = s.app.path / "main.lad"
    control.key("E")
    assert s.message == "no rejected online edit" and s.edit_report is None
    resave(main, PROGRAM + "ADD N7:1 1\n")
    wait_for_edit(s)
    assert "online edit rejected, the program is unchanged: " in s.message
    assert "main.lad:12:1: ADD takes 3 operands" in s.message and s.message.startswith("(E: every error)")
    assert len(s.rungs) == 5 and s.app.program is s.engine.program
    control.key("E")
    assert s.edit_report is not None, s.message
    shown = draw(s, width=100, height=24)
    assert "online edit errors (any key closes this)" in shown, shown
    overlay = "".join(shown.split("closes this)", 1)[1].split())  # long lines wrap: compare without spaces
    assert "".join(f"{main}:12:1: ADD takes 3 operands (ADD a b dest), got 2".split()) in overlay
    control.key("n")  # closes the errors, scans nothing
    assert s.edit_report is None and s.engine.scans == 0
    assert "online edit errors" not in draw(s, width=100, height=24)
