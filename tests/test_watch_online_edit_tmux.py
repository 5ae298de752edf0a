"""Online program edit in the real ``softplc watch``, in tmux:
the view watches the app's .lad files; a saved valid version replaces the
running program between two scans with the data table kept, and the view
says what changed; a saved version with errors changes nothing, the message
line says so and ``E`` shows every error with its file:line:col.

Each test edits a copy of programs/blinker in tmp_path, never the shipped one.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from pathlib import Path

from helpers.tmux_helpers import ROOT

ADDED_RUNG = "XIC B3/1 OTE O:0/1\n"  # what the edit adds: the lamp's twin, driven by a bit set before the edit


WIDTH = 200
SIDE = WIDTH - 46  # where the side panels start (screen.py's SIDE_WIDTH)


def copy_of_blinker(tmp_path: Path) -> Path:
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "blinker", app)
    return app


def save(path: Path, text: str) -> None:
    """Write as an editor saves, and move the mtime on so that two saves
    within one timestamp tick are never taken for one."""
    before = path.stat().st_mtime_ns
    path.write_text(text, encoding="utf-8")
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, max(st.st_mtime_ns, before) + 10_000_000))


def start_view(tmux, tmp_path: Path, app: Path) -> None:  # noqa: F811
    tmux.start(f"{sys.executable} -m softplc_lite watch {app} --fresh --state {tmp_path / 'state'} "
               f"--watch B3/1 --watch O:0/1 --watch C5:0.ACC", width=WIDTH, height=40)
    tmux.wait_for("PAUSED")


def watched(screen: str, name: str) -> str:
    """The value the watch list shows for ``name`` (the side panel, from column SIDE)."""
    for line in screen.splitlines():
        parts = line[SIDE:].split()
        if parts[:1] == [name]:
            return parts[1]
    raise AssertionError(f"{name} is not in the watch list:\n{screen}")


def wait_until(tmux, condition, seconds: float = 15.0) -> str:  # noqa: F811
    """The screen once ``condition(screen)`` holds (bounded)."""
    deadline = time.monotonic() + seconds
    screen = tmux.screen()
    while not condition(screen) and time.monotonic() < deadline:
        time.sleep(0.1)
        screen = tmux.screen()
    assert condition(screen), f"not seen after {seconds} s:\n{screen}"
    return screen


def test_an_accepted_edit_adds_a_rung_and_keeps_the_table(tmux, tmp_path):  # noqa: F811
    app = copy_of_blinker(tmp_path)
    main = app / "main.lad"
    start_view(tmux, tmp_path, app)
    assert "rung 0 of 4" in tmux.screen()
    tmux.keys("=", "B3/1 = 1", "Enter")  # a value set before the edit: the new rung reads it
    tmux.wait_for("set B3/1 = 1")
    tmux.keys("n", "n", "n")
    tmux.wait_for("scan 3 ")
    save(main, main.read_text(encoding="utf-8") + ADDED_RUNG)
    screen = tmux.wait_for("online edit accepted: file 2: 1 rung added (4) (at scan 3)")
    assert "rung 0 of 5" in screen  # the view shows the new program
    assert watched(screen, "B3/1") == "1" and watched(screen, "O:0/1") == "0"  # the table kept, not yet scanned
    tmux.keys("End")  # the new rung, drawn
    screen = tmux.wait_for("rung 4 of 5")
    assert "B3/1" in screen and "O:0/1" in screen.split("rung 4 of 5", 1)[1]
    tmux.keys("n")
    screen = tmux.wait_for("scan 4 ")
    assert watched(screen, "O:0/1") == "1"  # the new rung ran on the kept table
    assert "Traceback" not in screen
    tmux.keys("q")
    assert tmux.wait_gone(), "q did not end softplc watch"


def test_a_rejected_edit_changes_nothing_and_E_shows_every_error(tmux, tmp_path):  # noqa: F811
    app = copy_of_blinker(tmp_path)
    main = app / "main.lad"
    start_view(tmux, tmp_path, app)
    tmux.keys("n", "n")
    tmux.wait_for("scan 2 ")
    lines = main.read_text(encoding="utf-8").splitlines()
    bad_line = len(lines) + 1
    save(main, "\n".join(lines) + "\nADD B3:1 1\n")  # one operand short
    screen = tmux.wait_for("online edit rejected, the program is unchanged:")
    assert f"main.lad:{bad_line}:1: ADD takes 3 operands" in screen and "(E: every error)" in screen
    assert "rung 0 of 4" in screen  # the old program, still shown
    tmux.keys("E")
    screen = tmux.wait_for("online edit errors (any key closes this)")
    assert f"{main}:{bad_line}:1: ADD takes 3 operands (ADD a b dest), got 2" in screen
    assert " online edit rejected, the program is unchanged:" in screen.splitlines()  # the report's header line
    tmux.keys("n")  # closes the errors, and does nothing else
    screen = tmux.wait_without("online edit errors")
    assert "scan 2 " in screen and "rung 0 of 4" in screen
    tmux.keys("+", "+", "+", "r")  # the old program runs on: the lamp blinks and is counted
    screen = wait_until(tmux, lambda screen: watched(screen, "C5:0.ACC") not in ("0", "-"))
    assert int(watched(screen, "C5:0.ACC")) >= 1 and "rung 0 of 4" in screen
    tmux.keys("q")
    assert tmux.wait_gone(), "q did not end softplc watch"
