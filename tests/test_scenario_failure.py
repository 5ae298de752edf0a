"""A failed expectation draws the rungs that write its address, as they
were at the failing scan (softplc_lite/testing/drawing.py)."""

import io
import pickle
import shutil
from pathlib import Path

from rich.console import Console

from softplc_lite.testing.drawing import MAX_RUNGS, draw_rungs, writer_rungs
from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import run_file
from softplc_lite.watch.rungs import ENERGIZED

ROOT = Path(__file__).resolve().parent.parent
MOTOR = ROOT / "programs" / "motor"


def _failure(tmp_path, app, steps: str):
    f = tmp_path / "f.plctest"
    f.write_text('scenario "s":\n' + "".join(f"    {s}\n" for s in steps.split(";")), encoding="utf-8")
    [r] = run_file(app, f)
    assert r.failure is not None
    return r.failure


def _segments(renderable, width=80):
    """(text, style) of each segment of ``renderable`` drawn in colour."""
    console = Console(width=width, file=io.StringIO(), color_system="truecolor", force_terminal=True)
    return [(s.text, s.style) for s in console.render(renderable)]


def test_the_report_draws_the_rung_that_writes_the_failing_symbol(tmp_path):
    failure = _failure(tmp_path, MOTOR, "set StopOk = 1;set Start = 1;scan 1;expect Motor == 0")
    lines = failure.text(80).splitlines()
    assert lines[0] == failure.report() and "expected Motor == 0, got 1 (scan 1, 0.01 s)" in lines[0]
    assert lines[1] == "  program file 2, rungs that write Motor (O:0/0):"
    assert lines[2].strip() == "Rung 0"
    assert "Seal-in: start, or the motor's own contact" in lines[3]  # the rung's comment
    body = "\n".join(lines[4:])
    assert "Start" in body and "I:0/0" in body and "( )" in body
    # below the contacts, their values: Start 1, StopOk 1, Tripped 0, the coil Motor 1
    values = next(line for line in lines if line.strip().startswith("| |"))
    assert values.split() == ["|", "|", "1", "|", "1", "0", "1", "|"]


def test_power_flow_is_marked_in_colour(tmp_path):
    failure = _failure(tmp_path, MOTOR, "set StopOk = 1;set Start = 1;scan 1;expect Motor == 0")
    segments = _segments(failure)
    assert ("( )", ENERGIZED) in segments or any(t.strip() == "( )" and s == ENERGIZED for t, s in segments)
    assert any(t == "] [" and s == ENERGIZED for t, s in segments)
    # with the stop pressed nothing reaches the coil
    failure = _failure(tmp_path, MOTOR, "set StopOk = 0;set Start = 1;scan 1;expect Motor == 1")
    assert not any("( )" in t and s == ENERGIZED for t, s in _segments(failure))


def test_the_values_drawn_are_those_of_the_failing_scan(tmp_path):
    failure = _failure(tmp_path, MOTOR, "set StopOk = 1;set Start = 1;run 3 s;expect T4:0.ACC == 1")
    assert "got 2 (scan 300, 3 s)" in failure.report()
    text = failure.text(80)
    assert "Rung 2" in text and "ACC 2|" in text
    with PLC.load(MOTOR) as plc:  # a drawing keeps its values while the PLC runs on
        plc.set("StopOk", 1)
        plc.set("Start", 1)
        plc.run(2)
        title, places = writer_rungs(plc.runner.app.program, "T4:0.ACC")
        drawing = draw_rungs(plc.runner.app.program, plc.table, places, title)
        then = plc["T4:0.ACC"]
        plc.run(3)
        later = plc["T4:0.ACC"]
        assert later > then
        out = io.StringIO()
        Console(file=out, width=80, color_system=None).print(pickle.loads(pickle.dumps(drawing)))
    assert f"ACC {then}|" in out.getvalue() and f"ACC {later}" not in out.getvalue()


def test_an_address_no_rung_writes_is_said_to_be_an_input(tmp_path):
    failure = _failure(tmp_path, MOTOR, "scan 1;expect Start == 1")
    assert failure.text(80).splitlines()[1:] == ["  no rung writes Start (I:0/0): it is an input, or set by the test"]
    failure = _failure(tmp_path, MOTOR, "scan 1;expect N7:0 == 1")
    assert "no rung writes N7:0: it is an input, or set by the test" in failure.text(80)


def _many_writers(tmp_path, n: int) -> Path:
    app = tmp_path / "many"
    app.mkdir()
    rungs = "".join(f"// Writer {k}.\nXIC I:0/{k} MOV {k + 1} N7:0\n" for k in range(n))
    (app / "main.lad").write_text(rungs + "XIC B3/0 OTE O:0/0\n", encoding="utf-8")
    return app


def test_at_most_max_rungs_are_drawn_and_the_rest_are_listed(tmp_path):
    app = _many_writers(tmp_path, MAX_RUNGS + 2)
    text = _failure(tmp_path, app, "set I:0/5 = 1;scan 1;expect N7:0 == 0").text(100)
    assert "got 6" in text
    drawn = [line.strip() for line in text.splitlines() if line.strip().startswith("Rung ")]
    assert drawn == [f"Rung {k}" for k in range(MAX_RUNGS)]
    assert text.splitlines()[-1] == f"  and 2 more: file 2 rung {MAX_RUNGS}, file 2 rung {MAX_RUNGS + 1}"
    assert "MOV" in text and "Writer 0." in text


def test_the_drawing_fits_the_width(tmp_path):
    failure = _failure(tmp_path, MOTOR, "set StopOk = 1;set Start = 1;scan 1;expect Motor == 0")
    for width in (50, 120):
        rungs = failure.text(width).splitlines()[1:]
        assert max(len(line) for line in rungs) == width and rungs[-1].startswith("  |")


def test_softplc_test_prints_the_drawing(tmp_path):
    from tests.helpers.cli import softplc_here

    app = tmp_path / "motor"
    shutil.copytree(MOTOR, app, ignore=shutil.ignore_patterns(".softplc"))
    (app / "tests" / "motor.plctest").write_text(
        'scenario "bad":\n    set StopOk = 1\n    set Start = 1\n    scan 1\n    expect Motor == 0\n', encoding="utf-8")
    r = softplc_here("test", str(app), env={"COLUMNS": "70"})
    assert r.returncode == 1
    lines = r.stdout.splitlines()
    assert lines[1].endswith("expected Motor == 0, got 1 (scan 1, 0.01 s)")
    assert lines[2:4] == ["  program file 2, rungs that write Motor (O:0/0):", "     Rung 0"]
    assert max(len(line) for line in lines[2:-1]) == 70 and "\x1b[" not in r.stdout  # piped: plain


def test_a_failure_pickles_and_draws_the_same_after(tmp_path):
    # the strings app's Ticket is written by STRPRINT, an instruction of one of its modules
    failure = _failure(tmp_path, ROOT / "programs" / "strings", 'set NewReading = 1;scan 2;expect Ticket == "x"')
    text = failure.text(100)
    assert "rungs that write Ticket (ST9:1):" in text and "STRPRINT" in text
    assert pickle.loads(pickle.dumps(failure)).text(100) == text
