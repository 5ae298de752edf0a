"""Golden snapshots of the watch view: every example program rendered after
a fixed number of scans (fresh, simulated time), compared line for line
with the text files in tests/data/watch/.

After a deliberate change to what the view draws, regenerate the goldens
and review the diff before committing them:

    UPDATE_GOLDENS=1 python -m pytest tests/test_watch_snapshots.py

The same run rewrites the SVG pictures of docs/watch.md (docs/images/); the
text example in docs/watch.md is checked against blinker-80x24.txt and is
updated by hand.

A snapshot is deterministic: time is simulated, and ``render()`` shows the
status file's scan times (S:8, S:9: the simulated ``scan_ms``) where the
live view shows the ones measured on the wall clock. The goldens keep each
line without its trailing blanks; the test checks separately that every
rendered line is exactly the screen's width and that there are exactly
its height of them.
"""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from rich.cells import cell_len

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.snapshot import render, write_snapshot
from softplc_lite.watch.session import WatchOptions, WatchSession

from helpers.cli import softplc, softplc_here

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = ROOT / "programs"
GOLDENS = Path(__file__).resolve().parent / "data" / "watch"
UPDATE = bool(os.environ.get("UPDATE_GOLDENS"))


@dataclass(frozen=True)
class Case:
    name: str
    program: str
    scans: int
    watch: tuple[str, ...] = ()
    sets: tuple[str, ...] = ()
    forces: tuple[str, ...] = ()
    break_when: tuple[str, ...] = ()
    trend: tuple[str, ...] = ()
    rung_breaks: tuple[int, ...] = ()  # rungs of the main file with a breakpoint
    back: int = 0  # steps back through history after scanning
    goto: int = 0  # the selected rung (shown first)
    sizes: tuple[tuple[int, int], ...] = ((80, 24), (120, 40))
    cli: tuple[str, ...] = field(default=(), compare=False)  # the same view as softplc watch arguments


CASES = [
    Case("blinker", "blinker", 120, watch=("C5:0.ACC", "T4:0.ACC"),
         cli=("--watch", "C5:0.ACC", "--watch", "T4:0.ACC")),
    Case("motor", "motor", 150, watch=("Motor", "C5:0.ACC", "T4:0.ACC"), sets=("StopOk=1", "Start=1")),
    Case("strings", "strings", 2, watch=("Ticket", "Weight", "TicketNo"), sets=("NewReading=1",)),
    Case("subroutines", "subroutines", 25, watch=("N7:0", "N7:1", "N7:2", "F8:0")),
    Case("loopback", "loopback", 100, watch=("C5:0.ACC", "GotRack")),
    Case("modbus_master", "modbus_master", 400, watch=("N11:0", "C5:1.ACC"),
         cli=("--watch", "N11:0", "--watch", "C5:1.ACC")),
    Case("modbus_scada", "modbus_scada", 100, watch=("FaultMap", "N20:11", "N20:14", "N11:1")),
    # the lamp forced off while its rung is true (rung 2 selected), two scans back in history
    Case("blinker-forced-history", "blinker", 80, watch=("Lamp", "T4:1.ACC"), forces=("Lamp=0",), back=2,
         goto=2, sizes=((80, 24),)),
    # stopped by --break-when; a rung breakpoint on rung 3 (marked *, not hit)
    Case("motor-break", "motor", 500, watch=("T4:0.ACC",), sets=("StopOk=1", "Start=1"),
         break_when=("T4:0.ACC >= 2",), rung_breaks=(3,), sizes=((120, 40),)),
    # the trend panel: the PID loop settling, the lamp coming on at scan 448 (docs/trends.md)
    Case("tank-trend", "tank", 520, trend=("Level", "Valve", "AtSetpoint"),
         cli=("--trend", "Level", "--trend", "Valve", "--trend", "AtSetpoint")),
    # stepped back to scan 440: the marker on the chart
    Case("tank-trend-history", "tank", 520, trend=("Level", "Valve", "AtSetpoint"), back=80, sizes=((120, 40),)),
    # a Studio 5000 export: tag paths, Logix names, routines (docs/logix.md, "Watching a Logix app")
    Case("tank_line", "logix/tank_line.L5X", 300, watch=("Tanks[0].Level", "Tanks[1].Level", "Batches.ACC"),
         sets=("Start=1",)),
    # a Structured Text routine: its text, tag values and the lines run (docs/watch.md, "Watching Structured Text")
    Case("st_tank", "logix/st_tank.L5X", 30, watch=("Level",)),
]

PARAMS = [pytest.param(case, w, h, id=f"{case.name}-{w}x{h}") for case in CASES for w, h in case.sizes]


def _session(case: Case, state_dir: Path) -> WatchSession:
    app = load_app(PROGRAMS / case.program, state_dir)
    options = WatchOptions(run=RunOptions(fresh=True, sets=case.sets), watch=case.watch, forces=case.forces,
                           break_when=case.break_when, trend=case.trend)
    session = WatchSession(app, options)
    for rung in case.rung_breaks:
        session.goto(rung)
        session.toggle_breakpoint()
    session.goto(case.goto)
    for _ in range(case.scans):  # as softplc watch --snapshot does: stop at a breakpoint
        session.scan()
        if session.last_hit is not None:
            break
    for _ in range(case.back):
        session.back()
    return session


def _render(case: Case, width: int, height: int, state_dir: Path) -> str:
    session = _session(case, state_dir)
    try:
        return render(session, width, height).export_text()
    finally:
        session.quit()


def _golden_text(screen: str) -> str:
    return "".join(line.rstrip() + "\n" for line in screen.splitlines())


def _compare(path: Path, screen: str) -> None:
    text = _golden_text(screen)
    if UPDATE:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    assert path.exists(), f"no golden {path.name}: run UPDATE_GOLDENS=1 python -m pytest {Path(__file__).name}"
    expected = path.read_text(encoding="utf-8")
    assert text == expected, (f"the view differs from {path.relative_to(ROOT)}; if the change is meant, "
                              f"regenerate with UPDATE_GOLDENS=1 (see this file's docstring)")


@pytest.mark.parametrize("case,width,height", PARAMS)
def test_view_matches_its_golden(case: Case, width: int, height: int, tmp_path):
    screen = _render(case, width, height, tmp_path)
    lines = screen.splitlines()
    assert len(lines) == height
    too_wide = [(k, cell_len(line)) for k, line in enumerate(lines) if cell_len(line) != width]
    assert not too_wide, f"lines not {width} cells wide (line, width): {too_wide}"
    _compare(GOLDENS / f"{case.name}-{width}x{height}.txt", screen)


def test_goldens_are_what_the_view_shows(tmp_path):
    """Spot checks, so a golden regenerated by mistake does not pass unread."""
    text = (GOLDENS / "blinker-80x24.txt").read_text(encoding="utf-8")
    assert text.startswith(" blinker  RUN  scan 120  1.200 s sim  PAUSED 100 scans/s  scan time 10 ms")
    assert "C5:0.ACC" in text and "T4:0.ACC" in text and "q quit" in text
    text = (GOLDENS / "modbus_master-120x40.txt").read_text(encoding="utf-8")
    assert "scan time 1 ms, max 1" in text and "0 up" in text and "Polls(C5:0)" in text
    text = (GOLDENS / "blinker-forced-history-80x24.txt").read_text(encoding="utf-8")
    assert "scan 78 of 80 (history)" in text and "forces: O:0/0=OFF" in text and "0 F" in text
    text = (GOLDENS / "motor-break-120x40.txt").read_text(encoding="utf-8")
    assert "break: T4:0.ACC >= 2 became true at scan 201" in text and " * Rung 3" in text
    for size in ("80x24", "120x40"):
        text = (GOLDENS / f"tank-trend-{size}.txt").read_text(encoding="utf-8")
        assert " Level 1974  Valve 2006  AtSetpoint 1  y auto" in text and "scan 520 5.200 s" in text
        assert "AtSetpoint│" in text and "▲" not in text
    text = (GOLDENS / "tank-trend-history-120x40.txt").read_text(encoding="utf-8")
    assert "scan 440 of 520 (history)" in text and " AtSetpoint 0 " in text and text.count("▲") == 1


def test_the_doc_shows_the_golden_view():
    """docs/watch.md shows the text of its --snapshot example: the blinker golden."""
    doc = (ROOT / "docs" / "watch.md").read_text(encoding="utf-8")
    shown = doc.split("`/tmp/softplc-watch-blinker.txt` then holds", 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    assert shown == (GOLDENS / "blinker-80x24.txt").read_text(encoding="utf-8")


@pytest.mark.parametrize("case,width,height,image", [
    (CASES[0], 80, 24, "watch-blinker.svg"), (CASES[5], 120, 40, "watch-modbus.svg")], ids=["blinker", "modbus"])
def test_the_doc_pictures_are_current(case: Case, width: int, height: int, image: str, tmp_path):
    """docs/images/*.svg are the view as it draws now (regenerated with UPDATE_GOLDENS=1)."""
    session = _session(case, tmp_path / "state")
    try:
        write_snapshot(session, str(tmp_path / image), width, height)
    finally:
        session.quit()
    svg = (tmp_path / image).read_text(encoding="utf-8")
    path = ROOT / "docs" / "images" / image
    if UPDATE:
        path.write_text(svg, encoding="utf-8")
    assert svg == path.read_text(encoding="utf-8"), f"{path.relative_to(ROOT)} is out of date: UPDATE_GOLDENS=1"


def test_cli_snapshot_writes_the_golden_view(tmp_path):
    case = CASES[0]
    out = tmp_path / "view.txt"
    proc = softplc_here("watch", f"programs/{case.program}", "--fresh", "--state", str(tmp_path / "state"),
                        "--scans", str(case.scans), *case.cli, "--snapshot", str(out), "--width", "80", "--height",
                        "24")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ""
    _compare(GOLDENS / f"{case.name}-80x24.txt", out.read_text(encoding="utf-8"))


def test_cli_snapshot_svg(tmp_path):
    out = tmp_path / "view.svg"
    proc = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"), "--scans", "60",
                        "--snapshot", str(out), "--width", "80", "--height", "24")
    assert proc.returncode == 0, proc.stderr
    svg = out.read_text(encoding="utf-8")
    assert svg.startswith("<svg") and svg.rstrip().endswith("</svg>")
    assert "softplc watch blinker" in svg.replace("&#160;", " ")  # the window title


def test_cli_without_a_terminal_says_so_and_suggests_a_snapshot(tmp_path):
    # a process, its standard input /dev/null: what "not a terminal" is to a user
    proc = softplc("watch", "programs/blinker", "--fresh", "--state", str(tmp_path), stdin=subprocess.DEVNULL)
    assert proc.returncode == 2
    assert "needs a terminal" in proc.stderr and "--snapshot" in proc.stderr
    assert proc.stdout == ""
    assert not (tmp_path / "datatable.snap").exists()  # nothing ran, nothing saved
