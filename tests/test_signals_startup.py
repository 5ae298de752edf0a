"""Signals at the edges of a run (docs/cli.md, "Signals"): Ctrl-C while
softplc starts exits 130 with no traceback, and a SIGTERM sent again and
again while a run ends never cuts it short (exit 0, the final save made).
Real ``softplc`` processes; each is bounded by a timeout and ended by its
own pid."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BLINKER = ROOT / "programs" / "blinker" / "main.lad"
# The two ways the command starts: python -m, and the console script pip
# installed beside this interpreter (which imports softplc_lite.cli itself).
ENTRIES = {"python -m": [sys.executable, "-m", "softplc_lite"],
           "console script": [sys.executable, str(Path(sys.executable).parent / "softplc")]}


@pytest.fixture(name="app")
def fixture_app(tmp_path) -> Path:
    app = tmp_path / "blinker"
    app.mkdir()
    (app / "main.lad").write_text(BLINKER.read_text())
    return app


def start(app: Path, *args: str, env: dict | None = None, entry: str = "python -m") -> subprocess.Popen:
    """``softplc run APP`` on the wall clock, until stopped."""
    return subprocess.Popen([*ENTRIES[entry], "run", str(app), "--fresh", "--print", "C5:0.ACC", *args],
                            cwd=app.parent, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def finish(proc: subprocess.Popen) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, out, err


def softplc_loading(app: Path, entry: str) -> subprocess.Popen:
    """A run whose standard error says, line by line, each module Python
    has finished importing (PYTHONPROFILEIMPORTTIME), read up to the first
    of softplc's own modules after softplc_lite.interrupt: from there on
    softplc's code handles Ctrl-C."""
    env = dict(os.environ, PYTHONPROFILEIMPORTTIME="1")
    proc = start(app, "--state", str(app / "state"), env=env, entry=entry)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        assert line, "the process ended while it was loading"
        if re.search(r"\|\s+softplc_lite\.(?!interrupt\b)", line):
            return proc
    proc.kill()
    pytest.fail("softplc's modules never loaded")


@pytest.mark.parametrize("entry", ENTRIES)
@pytest.mark.parametrize("delay", [0, 0.005, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3])
def test_ctrl_c_while_softplc_loads_exits_130_without_a_traceback(app, delay, entry):
    proc = softplc_loading(app, entry)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    code, out, err = finish(proc)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-3000:]
    if code == 0:  # the run had started scanning: Ctrl-C ended it as documented, printing its values
        assert re.fullmatch(r"C5:0.ACC = \d+\n", out), out
    else:
        assert code == 130 and out == "", (code, out, err[-3000:])


@pytest.mark.parametrize("delay", [0.01 * k for k in range(31)])
def test_ctrl_c_in_the_first_third_of_a_second_never_shows_a_traceback_through_softplc(app, delay):
    # Before softplc's first line runs, the interpreter's own start-up may
    # still end on Python's own terms (docs/cli.md): never in softplc's code.
    proc = start(app, "--state", str(app / "state"))
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    code, out, err = finish(proc)
    assert not re.search(r'File "[^"]*/softplc_lite/', err), err[-3000:]  # no frame of softplc's
    if code in (0, 130):  # softplc's own end: quiet
        assert "Traceback" not in err, err[-3000:]


def _snapshot_acc(state: Path) -> str:
    p = subprocess.run([sys.executable, "-m", "softplc_lite", "datatable", str(state / "datatable.snap"),
                        "--print", "C5:0.ACC"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout


def _running(proc: subprocess.Popen, state: Path) -> None:
    """Wait until the run scans (its first retentive save)."""
    deadline = time.monotonic() + 30
    while not (state / "datatable.snap").exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no retentive save: the run did not start"
        time.sleep(0.02)
    time.sleep(0.3)


@pytest.mark.parametrize("gap", [0.0, 0.01, 0.03, 0.1])
def test_a_second_sigterm_does_not_cut_the_end_of_a_run_short(app, gap):
    state = app / "state"
    proc = start(app, "--state", str(state))
    _running(proc, state)
    proc.send_signal(signal.SIGTERM)
    time.sleep(gap)
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    code, out, err = finish(proc)
    assert code == 0, (code, err[-3000:])
    assert re.fullmatch(r"C5:0.ACC = \d+\n", out), out
    assert _snapshot_acc(state) == out  # the final save happened, and holds what was printed


def test_sigterm_sent_over_and_over_until_the_run_exits_never_kills_it(app):
    state = app / "state"
    proc = start(app, "--state", str(state))
    _running(proc, state)
    sent = 0
    deadline = time.monotonic() + 30
    while proc.poll() is None and time.monotonic() < deadline:
        proc.send_signal(signal.SIGTERM)
        sent += 1
        time.sleep(0.002)
    code, out, err = finish(proc)
    assert sent > 1 and code == 0, (sent, code, err[-3000:])
    assert re.fullmatch(r"C5:0.ACC = \d+\n", out), out
    assert _snapshot_acc(state) == out
