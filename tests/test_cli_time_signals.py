"""Which clock ``softplc run`` follows, SIGTERM handled as Ctrl-C (``run``
and ``watch``), and the status line of an unbounded run in a terminal.
What ends by SIGTERM or Ctrl-C is a real process (in a real terminal, tmux,
for the status line), bounded by a timeout and ended by its own pid; a
bounded command whose output is all a test checks runs in-process."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers.cli_tmux import SOFTPLC, open_terminal

from helpers.cli import ROOT, softplc_here


@pytest.fixture(name="terminal")
def fixture_terminal(request):
    yield from open_terminal(request)
BLINKER = ROOT / "programs" / "blinker" / "main.lad"  # C5:0.ACC counts blinks: one a second of PLC time


def run_then_sigterm(args: list[str], state: Path, seconds: float) -> subprocess.CompletedProcess:
    """Start ``softplc run``, let it scan ``seconds`` of wall time after its
    first retentive save, then SIGTERM it; (returncode, stdout, stderr)."""
    # a process: it ends by SIGTERM
    proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", *args, "--state", str(state)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        snap = state / "datatable.snap"
        deadline = time.monotonic() + 30
        while not snap.exists():
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no retentive save: the run did not start"
            time.sleep(0.05)
        time.sleep(seconds)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def test_an_unbounded_run_follows_the_wall_clock_and_sigterm_ends_it_like_ctrl_c(tmp_path):
    dump = tmp_path / "end.json"
    p = run_then_sigterm([str(BLINKER), "--fresh", "--print", "C5:0.ACC", "--dump", str(dump)],
                         tmp_path / "state", seconds=2.5)
    assert p.returncode == 0, p.stderr
    blinks = int(re.fullmatch(r"C5:0.ACC = (\d+)\n", p.stdout).group(1))
    assert 1 <= blinks <= 4, p.stdout  # about 2.5 s of PLC time: the wall clock, not simulated time
    assert json.loads(dump.read_text())["C5"][0]["ACC"] == blinks  # --dump written at the SIGTERM
    # the final save holds the last scan: a fresh-less run starts from it
    again = softplc_here("run", str(BLINKER), "--state", str(tmp_path / "state"), "--scans", "0",
                         "--print", "C5:0.ACC")
    assert again.returncode == 0 and again.stdout == f"C5:0.ACC = {blinks}\n", again


def test_simulated_makes_an_unbounded_run_use_simulated_time(tmp_path):
    p = run_then_sigterm([str(BLINKER), "--fresh", "--simulated", "--print", "C5:0.ACC"],
                         tmp_path / "state", seconds=1.5)
    assert p.returncode == 0, p.stderr
    blinks = int(re.fullmatch(r"C5:0.ACC = (\d+)\n", p.stdout).group(1))
    assert blinks > 20, p.stdout  # simulated 10 ms scans go far faster than the wall clock


@pytest.mark.parametrize("clock,expected", [((), "simulated"), (("--realtime",), "real")])
def test_a_bounded_run_is_on_simulated_time_unless_realtime(tmp_path, clock, expected):
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.lad").write_text(BLINKER.read_text())
    (app / "softplc.toml").write_text('[display]\nsummary = { blinks = "C5:0.ACC" }\n')
    p = softplc_here("run", str(app), "--fresh", "--scans", "20", *clock)
    assert p.returncode == 0, p.stderr
    first = p.stdout.splitlines()[0]
    assert re.fullmatch(rf"app: 20 scans, [\d.]+ s {expected} time", first), p.stdout
    if expected == "simulated":
        assert first == "app: 20 scans, 0.20 s simulated time"  # 20 scans of 10 ms
    else:
        assert 0.15 <= float(first.split()[3]) < 5  # 20 periods of 10 ms on the wall clock


def test_realtime_and_simulated_together_are_a_usage_error():
    p = softplc_here("run", str(BLINKER), "--realtime", "--simulated", "--scans", "1")
    assert p.returncode == 2
    assert p.stderr.splitlines()[-1] == "softplc run: error: argument --simulated: not allowed with argument --realtime"


def test_an_unbounded_run_shows_a_status_line_in_a_terminal_for_an_app_without_display(terminal, tmp_path):
    assert not (ROOT / "programs" / "motor" / "softplc.toml").exists()  # no [display] section
    terminal.start(f"{SOFTPLC} run programs/motor --fresh --state {tmp_path} --print Motor")
    m = terminal.wait_for(r"motor  scan (\d+)  [\d.]+ s real  (\d+) scans/s  x([\d.]+) real time")
    assert int(m.group(2)) > 10 and abs(float(m.group(3)) - 1) < 0.3, m.group(0)
    terminal.keys("C-c")
    assert terminal.exit_status() == 0
    assert "Motor (O:0/0) = 0" in terminal.screen()


def test_sigterm_quits_watch_as_q_does(terminal, tmp_path):
    terminal.start(f"{SOFTPLC} watch programs/blinker --fresh --state {tmp_path}")
    terminal.wait_for("PAUSED")
    terminal.keys("n", "n", "n")
    terminal.wait_for("scan 3")
    os.kill(terminal.command_pid(), signal.SIGTERM)  # the softplc process the pane's shell started
    assert terminal.exit_status() == 0
    # the final save holds the newest scan: the OFF timer as after 3 scans of softplc run
    p = softplc_here("datatable", str(tmp_path / "datatable.snap"), "--print", "T4:0.ACC")
    three = softplc_here("run", str(BLINKER), "--scans", "3", "--print", "T4:0.ACC")
    assert p.returncode == 0 and p.stdout == three.stdout == "T4:0.ACC = 2\n", (p, three)
