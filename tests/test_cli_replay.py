"""``--replay`` as a CI gate. Output differences exit
5; a trace says how many scans it covers (``# scans: N``) and a replay
without --scans stops at the end of the trace. Real runs of the shipped
Modbus master against its shipped recording, by cli.main in the test's
process: each test checks what the run prints and returns."""

from __future__ import annotations

import subprocess
from pathlib import Path

from helpers.cli import ROOT, softplc_here
from softplc_lite.cli import EXIT_REPLAY
from softplc_lite.ports.trace import covered_scans, read_trace, scans_in

APP = ROOT / "programs" / "modbus_master"
SHIPPED = APP / "pymodbus-session.trace"
SUMMARY = "modbus_master: 1195 scans, 1.20 s simulated time\npolls (C5:0.ACC) = 13\ngood (C5:1.ACC) = 8\n"


def replay(trace: Path, state: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return softplc_here("run", str(APP), "--fresh", "--state", str(state), "--replay", str(trace), *extra)


def test_the_shipped_trace_says_how_many_scans_it_covers():
    assert covered_scans(SHIPPED) == 1195
    assert any(line.startswith("# scans: 1195") for line in SHIPPED.read_text().splitlines()[:10])
    assert len(read_trace(SHIPPED)) == 24  # the reader takes the comment as a comment


def test_a_replay_without_scans_stops_at_the_end_of_the_trace(tmp_path):
    p = replay(SHIPPED, tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith(SUMMARY), p.stdout
    assert "13 of 13 exchanges, output matched" in p.stderr


def test_without_the_scans_comment_the_replay_stops_after_the_last_recorded_byte(tmp_path):
    trace = tmp_path / "session.trace"
    trace.write_text("".join(line for line in SHIPPED.read_text().splitlines(keepends=True)
                             if not line.startswith("# scans:")))
    assert covered_scans(trace) is None
    p = replay(trace, tmp_path / "state")
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith(SUMMARY), p.stdout  # the last reply is counted in the scan that reads it


def test_scans_given_win_over_the_trace(tmp_path):
    p = replay(SHIPPED, tmp_path, "--scans", "100")
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("modbus_master: 100 scans, 0.10 s simulated time\n")
    assert "output matched so far" in p.stderr


def test_output_differences_exit_5_naming_them(tmp_path):
    p = replay(SHIPPED, tmp_path, "--set", "Start=150")  # the program now asks for register 150
    assert p.returncode == EXIT_REPLAY == 5, p.stderr
    assert "13 output difference(s):\n  line 9: TX 0 byte 3: expected 00 00 7D 85 D8, got 96 00 7D 65 F4" in p.stderr
    assert p.stderr.rstrip().endswith("modbus_master: --replay: the program's output differed from the recording "
                                      "(13 differences, listed above)")
    assert "Traceback" not in p.stderr


def test_scans_comment_forms():
    assert scans_in("# softplc_lite port trace 1\n#scans: 7\n") == 7
    assert scans_in("# scans: 7 (at 10 ms a scan)\n# scans: 9\n") == 7  # the first counts
    assert scans_in("# scans: seven\n") is None
    assert scans_in("0.000 0 TX 01 # scans: 7\n") is None  # a comment after an event is not the header's
