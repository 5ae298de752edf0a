"""The real ``softplc watch --trend`` in a terminal (tmux): the panel drawn
as the view steps, the T and W keys, the marker while stepping back."""

from __future__ import annotations

import csv
import sys


def test_the_trend_panel_in_a_real_terminal(tmux, tmp_path):
    tmux.start(f"{sys.executable} -m softplc_lite watch programs/tank --fresh --state {tmp_path / 'state'} "
               f"--trend Level --trend AtSetpoint")
    screen = tmux.wait_for("PAUSED")
    assert "trend: no scan recorded yet" in screen
    tmux.keys("n", "n", "n")
    screen = tmux.wait_for(" Level 60  AtSetpoint 0  y auto 20..60")  # the first three scans' levels
    assert "AtSetpoint│" in screen and "└scan 1 0.010 s" in screen
    tmux.keys("T")  # offers rung 0's first operand, the PID's control block, by its symbol
    tmux.wait_for("trend: ADDR (add/remove), range LO HI | range auto: Loop")
    tmux.keys("BSpace", "BSpace", "BSpace", "BSpace", "Valve", "Enter")
    screen = tmux.wait_for("trend: Valve added")
    assert " Level 60  AtSetpoint 0  Valve 4000" in screen
    tmux.keys("T", "C-u")  # an error is said on the message line (C-u is not a key of the prompt)
    tmux.keys("BSpace", "BSpace", "BSpace", "BSpace", "range 9 1", "Enter")
    tmux.wait_for("LO must be below HI")
    tmux.keys("+", "+", "+", "+", "r")  # run faster for a moment
    tmux.wait_for("RUNNING")
    tmux.keys("p")
    tmux.wait_for("paused at scan")
    tmux.keys("BSpace", "BSpace")
    screen = tmux.wait_for("(history)")
    assert "▲" in screen  # the marker on the chart's axis
    path = tmp_path / "trend.csv"
    tmux.keys("W", str(path), "Enter")
    screen = tmux.wait_for("written to")
    rows = list(csv.reader(path.open(encoding="utf-8")))
    assert rows[0] == ["scan", "time_s (simulated)", "Level", "AtSetpoint", "Valve"]
    scans = [int(row[0]) for row in rows[1:]]
    assert 4 <= len(scans) <= 1000 and scans == list(range(scans[0], scans[0] + len(scans)))  # the history kept
    assert f"trend of {len(scans)} scans ({scans[0]} to {scans[-1]}) written to" in screen
    tmux.keys("q")
    assert tmux.wait_gone(), "q did not end softplc watch"
