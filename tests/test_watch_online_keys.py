"""The watch view's online keys in a real terminal (tmux): set a value,
toggle a bit, change mode, clear a major fault, the help overlay, Home/End
and the comment key. Each test starts its own tmux server (killed by the
fixture) and every wait is bounded."""

from __future__ import annotations

import sys


PROGRAM = """FILE 2 MAIN
SYMBOL InfeedConveyorPhotoEyeBlockedSeconds F8:1
// count scans
// (the second line of the comment)
ADD N7:1 1 N7:1
// the lamp follows B3/0
XIC B3/0 OTE O:0/0
// faults when N7:9 points past N7
MOV N7:[N7:9] N7:2
MOV F8:0 F8:1
OTE B3/9
"""


def start(tmux, tmp_path, *watch: str, width: int = 120, height: int = 40) -> None:
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.lad").write_text(PROGRAM)
    flags = " ".join(f"--watch {w}" for w in watch)
    tmux.start(f"{sys.executable} -m softplc_lite watch {app} --fresh --state {tmp_path / 'state'} {flags}",
               width=width, height=height)
    tmux.wait_for("PAUSED")


def row(screen: str, name: str) -> str:
    """The watch list's line of ``name``: the lines under the ``watch``
    title, from its column (beside the rungs or below them)."""
    lines = screen.splitlines()
    title = next(k for k, line in enumerate(lines) if line.rstrip().endswith("watch"))
    column = len(lines[title].rstrip()) - len("watch")
    for line in lines[title + 1:]:
        if line[column:].startswith(f"{name} "):
            return line[column:].strip()
    raise AssertionError(f"no watch row {name!r} in:\n{screen}")


def quit_view(tmux) -> None:
    tmux.keys("q")
    assert tmux.wait_gone(10), "q did not end softplc watch"


def test_set_a_value_shows_at_once_and_stays_in_history(tmux, tmp_path):
    start(tmux, tmp_path, "N7:0", "F8:1", "InfeedConveyorPhotoEyeBlockedSeconds")
    tmux.keys("n", "n")
    tmux.wait_for("scan 2 ")
    tmux.keys("=")
    tmux.wait_for("set ADDR = VALUE:")
    tmux.keys("N7:0 = 150", "Enter")
    screen = tmux.wait_for("set N7:0 = 150")
    assert row(screen, "N7:0").split()[:2] == ["N7:0", "150"]  # in the watch list before any scan
    tmux.keys("=", "F8:0 = 3.14159265", "Enter")
    tmux.wait_for("set F8:0 = 3.141593")
    tmux.keys("n")
    screen = tmux.wait_for("scan 3 ")
    assert row(screen, "F8:1").split()[:2] == ["F8:1", "3.141593"]  # 7 digits, read by the scan
    # a long name and its value, both whole at 120 columns (rich's table cut the name before)
    assert row(screen, "InfeedConveyorPhotoEyeBlockedSeconds").split()[:2] == ["InfeedConveyorPhotoEyeBlockedSeconds", "3.141593"]
    tmux.keys("BSpace")
    screen = tmux.wait_for("scan 2 of 3 (history)")
    assert row(screen, "N7:0").split()[:2] == ["N7:0", "150"]  # the edit is part of scan 2's frame
    tmux.keys("=", "N7:0 = lots", "Enter")  # bad input: says why, changes nothing
    screen = tmux.wait_for("set N7:0: N7:0 holds a 16-bit signed integer")
    assert row(screen, "N7:0").split()[:2] == ["N7:0", "150"]
    quit_view(tmux)


def test_toggle_the_selected_rungs_bit(tmux, tmp_path):
    start(tmux, tmp_path, "B3/0")
    tmux.keys("Down", "t")  # rung 1: XIC B3/0 OTE O:0/0
    tmux.wait_for("toggle bit: B3/0")
    tmux.keys("Enter")
    screen = tmux.wait_for("toggled B3/0: now 1")
    assert row(screen, "B3/0").split()[:2] == ["B3/0", "1"]
    tmux.keys("C-t")  # RSLogix's Ctrl-T
    tmux.wait_for("toggle bit: B3/0")
    tmux.keys("Enter")
    tmux.wait_for("toggled B3/0: now 0")
    tmux.keys("t", "BSpace", "BSpace", "BSpace", "BSpace", "N7:1", "Enter")
    tmux.wait_for("toggle N7:1: expected a bit address")
    quit_view(tmux)


def test_mode_changes_from_the_view(tmux, tmp_path):
    start(tmux, tmp_path)
    tmux.keys("M", "test", "Enter")
    tmux.wait_for(" TEST ")
    tmux.keys("M", "program", "Enter")
    tmux.wait_for(" PROGRAM ")
    tmux.keys("M", "sideways", "Enter")
    tmux.wait_for("mode 'sideways': expected program, run or test")
    tmux.keys("M", "r", "Enter")
    screen = tmux.wait_for("mode RUN")
    assert " RUN " in screen
    quit_view(tmux)


def test_a_major_fault_is_shown_selected_and_cleared_without_quitting(tmux, tmp_path):
    start(tmux, tmp_path, "N7:1")
    tmux.keys("=", "N7:9 = 500", "Enter", "n")  # MOV N7:[N7:9]: past the end of N7
    screen = tmux.wait_for("FAULTED")
    assert "program file 2, rung 2, MOV" in screen
    assert "> " in next(line for line in screen.splitlines() if "Rung 2" in line)  # the faulted rung selected
    tmux.keys("M", "run", "Enter")
    tmux.wait_for("clear the fault first")
    tmux.keys("C")
    screen = tmux.wait_for("fault cleared")
    assert " PROGRAM " in screen and "FAULTED" not in screen
    tmux.keys("=", "N7:9 = 0", "Enter", "M", "run", "Enter")
    tmux.wait_for("mode RUN")
    tmux.keys("n", "n")
    screen = tmux.wait_for("scan 3 ")
    assert " RUN " in screen and row(screen, "N7:1").split()[:2] == ["N7:1", "3"]
    quit_view(tmux)


def test_help_overlay_home_end_and_comments(tmux, tmp_path):
    start(tmux, tmp_path)
    screen = tmux.screen()
    assert "program file 2 MAIN" in screen and "? help" in screen
    tmux.keys("?")
    tmux.wait_for("keys (any key closes this)")
    for text in ("one scan forward", "toggle a bit", "clear the major fault", "first / last rung", "quit"):
        tmux.wait_for(text)  # a capture can fall in the middle of the overlay's drawing
    tmux.keys("z")  # any key closes it (and does nothing else)
    screen = tmux.wait_without("keys (any key closes this)")
    assert "Rung 0" in screen and "scan 0 " in screen
    tmux.keys("End")
    tmux.wait_for("rung 4 of 5")
    tmux.keys("Home")
    tmux.wait_for("rung 0 of 5")
    assert "(the second line of the comment)" in tmux.screen()
    tmux.keys("c")
    screen = tmux.wait_for("comments first line")
    assert "count scans ..." in screen and "(the second line" not in screen
    tmux.keys("c")
    screen = tmux.wait_for("comments hidden")
    assert "count scans" not in screen
    tmux.keys("g", "abc", "Enter")
    tmux.wait_for("go to rung 'abc': expected a rung number, 0 to 4")
    quit_view(tmux)
