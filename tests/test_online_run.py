"""`softplc run --online` end to end: a realtime run whose program file is
edited mid-run, first badly, then well. A real process: the run has no end
of its own, Ctrl-C (SIGINT) ends it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent



class Lines:
    """A pipe's lines, collected by a thread, waited for with a deadline."""

    def __init__(self, stream) -> None:
        self.lines: list[str] = []
        self._thread = threading.Thread(target=self._read, args=(stream,), daemon=True)
        self._thread.start()

    def _read(self, stream) -> None:
        for line in stream:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, text: str, timeout_s: float) -> str | None:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            for line in list(self.lines):
                if text in line:
                    return line
            time.sleep(0.02)
        return None


def save(path: Path, text: str) -> None:
    """Write and move the mtime on, as an editor's save a moment later would."""
    path.write_text(text)
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10_000_000))


def test_run_online_takes_a_good_edit_and_refuses_a_bad_one(tmp_path):
    app = tmp_path / "app"
    app.mkdir()
    main = app / "main.lad"
    main.write_text("DATA N7 2\nADD N7:0 1 N7:0\n")  # N7:1 exists: --print checks it before scan 0
    snap = app / ".softplc" / "datatable.snap"
    proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--realtime", "--scan-ms", "5",
                             "--fresh", "--online", "--print", "N7:0", "--print", "N7:1"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    err = Lines(proc.stderr)
    try:
        deadline = time.monotonic() + 20
        while not snap.exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)  # scanning: its first periodic save is there
        assert proc.poll() is None, "\n".join(err.lines)
        save(main, "DATA N7 2\nADD N7:0 1 N7:0\nADD N7:1 1\n")  # bad: ADD needs a destination
        rejected = err.wait_for("online edit rejected", 15)
        assert rejected is not None, "\n".join(err.lines)
        assert err.wait_for("main.lad:3:1: ADD takes 3 operands", 5) is not None, "\n".join(err.lines)
        save(main, "DATA N7 2\nADD N7:0 1 N7:0\nADD N7:1 1 N7:1\n")
        accepted = err.wait_for("online edit accepted", 15)
        assert accepted is not None, "\n".join(err.lines)
        assert "file 2: 1 rung added (1)" in accepted
        time.sleep(0.3)  # scans of the new program
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=20)
    finally:
        proc.kill()
        proc.wait(timeout=20)
    assert proc.returncode == 0, "\n".join(err.lines)
    values = dict(line.split(" = ") for line in out.splitlines())
    assert int(values["N7:1"]) > 10  # the added rung ran, scan after scan
    assert int(values["N7:0"]) > int(values["N7:1"])  # the first rung ran all along, before and after


def test_an_online_edit_growing_a_recorded_file_keeps_the_recording_whole(tmp_path):
    """The trend recording holds views of the files it copies; an edit that
    grows one of them (N7 from 2 elements to 10) lands, and every row of the
    recording keeps its columns, before the edit and after."""
    app = tmp_path / "app"
    app.mkdir()
    main = app / "main.lad"
    main.write_text("DATA N7 2\nADD N7:0 1 N7:0\n")
    out = tmp_path / "n7.csv"
    snap = app / ".softplc" / "datatable.snap"
    proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--realtime", "--scan-ms", "5",
                             "--fresh", "--online", "--trend", "N7:0", "--trend", "N7:1", "--trend-file", str(out)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    err = Lines(proc.stderr)
    try:
        deadline = time.monotonic() + 20
        while not snap.exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)
        assert proc.poll() is None, "\n".join(err.lines)
        save(main, "DATA N7 2\nADD N7:0 1 N7:0\nADD N7:9 1 N7:9\nMOV N7:9 N7:1\n")
        accepted = err.wait_for("online edit accepted", 15)
        assert accepted is not None, "\n".join(err.lines)
        time.sleep(0.3)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=20)
    finally:
        proc.kill()
        proc.wait(timeout=20)
    assert proc.returncode == 0, "\n".join(err.lines)
    rows = [line.split(",") for line in out.read_text().splitlines()]
    assert rows[0][2:] == ["N7:0", "N7:1"], rows[0]
    assert all(len(row) == 4 for row in rows[1:])
    body = [[int(row[0]), float(row[1]), int(row[2]), int(row[3])] for row in rows[1:]]
    assert [row[2] for row in body] == list(range(1, len(body) + 1))  # N7:0 counts every scan, none lost
    assert body[0][3] == 0 and body[-1][3] > 10  # N7:1 follows N7:9 once the edit ran
