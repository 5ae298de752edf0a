"""softplc run / check / fmt as a user runs them: what each prints, returns
and writes, through the command's main() in this process; a real process
for the run that only Ctrl-C ends."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers.cli import ROOT, softplc_here
from helpers.apps import make_app


@pytest.fixture
def app(tmp_path: Path) -> Path:
    return make_app(tmp_path / "counter", "// count scans\nADD N7:0 1 N7:0\nXIC S:1/15 MOV 7 N7:1\n")


def test_run_counts_scans_and_keeps_retentive_memory(app):
    p = softplc_here("run", str(app), "--scans", "25", "--print", "N7:0")
    assert p.returncode == 0, p.stderr
    assert p.stdout == "N7:0 = 25\n"
    assert (app / ".softplc" / "datatable.snap").exists()
    p = softplc_here("run", str(app), "--scans", "5", "--print", "N7:0")
    assert p.stdout == "N7:0 = 30\n"  # restored from the snapshot
    p = softplc_here("run", str(app), "--scans", "5", "--fresh", "--print", "N7:0")
    assert p.stdout == "N7:0 = 5\n"


def test_datatable_json_then_load_then_set(app, tmp_path):
    (app / "datatable.json").write_text('{"N7": [100, 0, 0, 0]}')
    extra = tmp_path / "extra.json"
    extra.write_text('{"N7": [null, null, 3]}')
    dump = tmp_path / "out.json"
    p = softplc_here("run", str(app), "--fresh", "--scans", "1", "--load", str(extra), "--set", "N7:3=9",
                     "--set", "F8:0=2.5", "--dump", str(dump), "--print", "N7:0", "--print", "N7:2", "--print", "N7:3")
    assert p.returncode == 0, p.stderr
    assert p.stdout.splitlines() == ["N7:0 = 101", "N7:2 = 3", "N7:3 = 9"]
    doc = json.loads(dump.read_text())
    assert doc["N7"][:4] == [101, 7, 3, 9] and doc["F8"] == [2.5]


def test_single_lad_file_has_no_state_unless_asked(app, tmp_path):
    lad = app / "main.lad"
    p = softplc_here("run", str(lad), "--scans", "3", "--print", "N7:0")
    assert p.stdout == "N7:0 = 3\n" and not (app / ".softplc").exists()
    state = tmp_path / "state"
    softplc_here("run", str(lad), "--scans", "3", "--state", str(state))
    p = softplc_here("run", str(lad), "--scans", "3", "--state", str(state), "--print", "N7:0")
    assert p.stdout == "N7:0 = 6\n"


def test_fault_exits_3_with_the_fault_in_words(tmp_path):
    lad = tmp_path / "bad.lad"
    lad.write_text("MOV 40 N7:1\nMOV N7:[N7:1] N7:0\n")
    p = softplc_here("run", str(lad), "--scans", "5")
    assert p.returncode == 3
    assert "major fault 20: program file 2, rung 1, MOV N7:[N7:1] N7:0" in p.stderr
    assert "Traceback" not in p.stderr


def test_check_lists_every_problem_and_exits_1(tmp_path):
    d = tmp_path / "broken"
    d.mkdir()
    (d / "a.lad").write_text("XIC B3/0 XIX B3/1\nJMP 4\n")
    (d / "b.lad").write_text("FILE 3\nXIC(B3/0;\n")
    p = softplc_here("check", str(d))
    assert p.returncode == 1
    lines = p.stderr.splitlines()
    assert any(line.endswith("a.lad:1:10: unknown instruction 'XIX' (did you mean XIC?)") for line in lines)
    assert any("a.lad:2:5: JMP to label 4" in line for line in lines)
    assert any("b.lad:2:" in line for line in lines)
    assert lines[-1] == "3 problems found"
    assert "Traceback" not in p.stderr


def test_check_lists_the_problems_around_a_syntax_error(tmp_path):
    # Parsing resumes after a syntax error, and the lines before it are
    # checked on their own, so every problem in the file is listed.
    f = tmp_path / "broken.lad"
    f.write_text("XIX B3/0 OTE O:0/0\n"
                 "XIC B3/1 OTE O:0/1\n"
                 "XIC(B3/0)[XIO(B3/2)OTE(O:0/0);\n"
                 "XIC B3/1 BND OTE O:0/1\n"
                 "SOR XIC B3/0\n"
                 " OTE O:0/0\n")
    p = softplc_here("check", str(f))
    assert p.returncode == 1
    where = [line.split(": ", 1)[0].rsplit(".lad:", 1)[1] for line in p.stderr.splitlines() if ".lad:" in line]
    assert where == ["1:1", "3:30", "4:10", "6:6"]
    assert "BND without a BST" in p.stderr and "SOR without EOR" in p.stderr
    assert p.stderr.splitlines()[-1] == "4 problems found"


def test_check_ok(app):
    p = softplc_here("check", str(app))
    assert p.returncode == 0 and p.stdout == "counter: ok (1 program file, 2 rungs)\n"


def test_fmt_both_styles(app):
    p = softplc_here("fmt", str(app / "main.lad"), "--style", "neutral")
    assert p.returncode == 0
    assert p.stdout == "// count scans\nADD(N7:0,1,N7:0);\nXIC(S:1/15)MOV(7,N7:1);\n"
    p = softplc_here("fmt", str(app / "main.lad"))
    assert p.stdout == "// count scans\nADD N7:0 1 N7:0\nXIC S:1/15 MOV 7 N7:1\n"


def test_bad_settings_and_usage(app, tmp_path):
    (app / "softplc.toml").write_text("[math]\noverflow = 'saturate'\n")
    p = softplc_here("run", str(app), "--scans", "1")
    assert p.returncode == 1 and "overflow = 'saturate'; expected one of 'clamp', 'wrap'" in p.stderr
    (app / "softplc.toml").write_text("[math\n")
    p = softplc_here("run", str(app), "--scans", "1")
    assert p.returncode == 1 and "softplc.toml:1:6: Expected" in p.stderr
    assert softplc_here("run").returncode == 2
    p = softplc_here("run", str(tmp_path / "nope"))
    assert p.returncode == 1 and "no such app directory" in p.stderr
    p = softplc_here("run", str(app / "main.lad"), "--scans", "1", "--set", "N7:0=99999")
    assert p.returncode == 1 and "99999 does not fit N7:0" in p.stderr


def test_without_scans_it_runs_until_ctrl_c_then_saves(app):
    # a process: an unbounded run, ended by Ctrl-C (SIGINT)
    proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--realtime",
                             "--scan-ms", "5", "--print", "N7:0"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    snap = app / ".softplc" / "datatable.snap"
    try:
        # Interrupt once it scans (its first periodic save is there), not after
        # a fixed delay that a slow start on a loaded machine can eat whole.
        deadline = time.monotonic() + 20
        while not snap.exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    scans = int(out.split("=")[1])
    assert 20 < scans < 400  # about 5 ms per scan for about half a second or more
    p = softplc_here("run", str(app), "--scans", "1", "--print", "N7:0")
    assert p.stdout == f"N7:0 = {scans + 1}\n"


def test_record_then_replay_repeats_the_run_and_reports_differences(tmp_path):
    trace = tmp_path / "loop.trace"
    args = ("run", "programs/loopback", "--fresh", "--state", str(tmp_path / "state"), "--scans", "30",
            "--print", "C5:0.ACC", "--print", "N7:10")
    first = softplc_here(*args, "--record", str(trace))
    assert first.returncode == 0, first.stderr
    assert first.stdout == "C5:0.ACC = 4\nN7:10 = 8\n"
    lines = trace.read_text().splitlines()
    assert lines[0] == "# softplc_lite port trace 1" and sum(" TX " in ln for ln in lines) == 4
    again = softplc_here(*args, "--replay", str(trace))
    assert again.returncode == 0, again.stderr
    assert again.stdout == first.stdout
    assert "4 of 4 exchanges, output matched" in again.stderr
    # change what the recording says the program sent first: the replay names the line and byte
    trace.write_text(trace.read_text().replace(" TX 52", " TX 53", 1))
    changed = softplc_here(*args, "--replay", str(trace))
    assert "1 output difference(s)" in changed.stderr and "line 3: TX 0 byte 0: expected 53, got 52" in changed.stderr


def test_port_override_and_a_missing_device(tmp_path):
    args = ("run", "programs/loopback", "--fresh", "--state", str(tmp_path / "state"), "--scans", "30")
    missing = softplc_here(*args, "--port", "0=/dev/softplc-no-such-tty")
    assert missing.returncode == 1
    assert missing.stderr.startswith("error: --port 0=/dev/softplc-no-such-tty: cannot open "
                                     "/dev/softplc-no-such-tty: no such device") and "Traceback" not in missing.stderr
    bad = softplc_here(*args, "--port", "zero=loop://")
    assert bad.returncode == 1 and "expected N=DEVICE" in bad.stderr
    unknown = softplc_here(*args, "--port", "3=loop://")
    assert unknown.returncode == 1 and "--port 3=loop://: no module has a port 3 (ports: COMGENIUS: 0)" \
        in unknown.stderr and "Traceback" not in unknown.stderr
