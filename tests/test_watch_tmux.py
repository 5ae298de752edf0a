"""The real ``softplc watch`` in a terminal: tmux runs it, ``send-keys``
steps and quits, ``capture-pane`` reads the screen."""

from __future__ import annotations

import sys
import time


def test_step_run_and_quit_in_a_real_terminal(tmux, tmp_path):
    state = tmp_path / "state"
    tmux.start(f"{sys.executable} -m softplc_lite watch programs/blinker --fresh --state {state} "
               f"--watch C5:0.ACC --watch T4:0.ACC")
    tmux.wait_for("PAUSED")
    assert "scan 0" in tmux.screen()
    tmux.keys("n", "n", "n")
    screen = tmux.wait_for("scan 3")
    assert "T4:0.ACC" in screen and "XIO" in screen or "]/[" in screen  # rungs and the watch list are drawn
    tmux.keys("Space")
    screen = tmux.wait_for("scan 4")
    tmux.keys("BSpace")  # step back through history
    screen = tmux.wait_for("scan 3 of 4 (history)")
    tmux.keys("n")
    tmux.wait_for("scan 4 ")
    tmux.keys("F", "O:0/0=1", "Enter")  # force the lamp on from the view
    tmux.wait_for("forces: O:0/0=ON")
    tmux.keys("n")
    tmux.wait_for("scan 5 ")
    tmux.keys("U", "O:0/0", "Enter")  # and remove the force
    tmux.wait_for("forces: none")
    tmux.keys("q")
    deadline = time.monotonic() + 10
    while tmux.alive() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not tmux.alive(), "q did not end softplc watch"
    from softplc_lite.datatable import snapshot

    saved = snapshot.load(state / "datatable.snap")
    assert saved.read("S:100") == 5 and saved.read("O:0/0") == 1  # saved at quit: 5 scans, the forced lamp


def test_run_until_a_breakpoint_condition(tmux, tmp_path):
    tmux.start(f"{sys.executable} -m softplc_lite watch programs/blinker --fresh --state {tmp_path} "
               f'--break-when "C5:0.ACC >= 2" --watch C5:0.ACC')
    tmux.wait_for("PAUSED")
    tmux.keys("+", "+", "+", "+", "+", "r")  # faster, run
    screen = tmux.wait_for("became true at scan", seconds=30)
    assert "break: C5:0.ACC >= 2 became true at scan 153" in screen and "scan 153 " in screen
    tmux.keys("q")
