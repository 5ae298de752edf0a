"""A failed expectation on an address a Structured Text routine writes draws
the routine's lines that write it, not the rungs they became
(softplc_lite/testing/drawing_st.py, docs/testing.md "Structured Text"), on
both executors: the compiled code the scenarios run on, and the reference
interpreter coverage runs them on."""

from __future__ import annotations

import io
import pickle
import re
import shutil
from pathlib import Path

import pytest
from rich.console import Console

from helpers.logix_l5x import Prog, Task, write_l5x
from softplc_lite.testing.coverage import Coverage
from softplc_lite.testing.drawing import MAX_RUNGS, draw_rungs, writer_rungs
from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import run_file
from softplc_lite.watch.cells import SELECTED

ROOT = Path(__file__).resolve().parent.parent
MIXER = ROOT / "programs" / "logix" / "mixer.L5X"
EXECUTORS = ["compiled", "reference"]
LADDER_WORDS = re.compile(r"\b(CPT|LSTB|CMP|JMP|LBL|OTE|Rung \d+)\b")


def _failure(tmp_path: Path, app: Path, executor: str, steps: str, width: int = 100) -> str:
    f = tmp_path / "f.plctest"
    f.write_text('scenario "s":\n' + "".join(f"    {s}\n" for s in steps.split(";")), encoding="utf-8")
    coverage = Coverage() if executor == "reference" else None  # coverage runs the reference interpreter
    [r] = run_file(app, f, coverage=coverage)
    assert r.failure is not None
    return r.failure.text(width)


@pytest.fixture
def mixer(tmp_path) -> Path:
    return Path(shutil.copy(MIXER, tmp_path / "mixer.L5X"))


def _drawn(text: str) -> dict[int, str]:
    """Routine line number -> its drawn row (the line's text and values)."""
    return {int(m.group(2)): m.group(3) for m in re.finditer(r"^  ([> ])[ *●]{2} +(\d+) (.*)$", text, re.M)}


def _marked(text: str) -> list[int]:
    return [int(m.group(1)) for m in re.finditer(r"^  >[ *●]{2} +(\d+) ", text, re.M)]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_st_written_tag_draws_its_lines_with_values_not_the_rungs(tmp_path, mixer, executor):
    text = _failure(tmp_path, mixer, executor, "set Start = 1;scan 3;expect Level == 7")
    lines = text.splitlines()
    assert "expected Level == 7, got 5.0 (scan 3, 0.03 s)" in lines[0]
    assert lines[1].startswith("  routine MainProgram.Sequence, lines that write Level")
    assert not LADDER_WORDS.search("\n".join(lines[1:])), text
    drawn = _drawn(text)
    # the four assignments to Level, by the routine's line numbers (from 1), marked ">"
    assert _marked(text) == [8, 10, 20, 22]
    assert drawn[8].split() == ["Level", ":=", "Level", "+", "FillRate;", "Level=5.0", "FillRate=2.5"]
    assert drawn[22].split()[:3] == ["Level", ":=", "0.0;"] and "Level=5.0" in drawn[22]
    # with the heads of the CASE arms and IFs they sit in, and those heads' values
    assert sorted(drawn) == [7, 8, 9, 10, 19, 20, 21, 22]
    assert drawn[7].lstrip().startswith("1:") and drawn[7].split()[-1] == "State=1"
    assert drawn[9].split() == ["IF", "Level", ">=", "Setpoint", "THEN", "Level=5.0", "Setpoint=50.0"]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_ladder_written_tag_of_the_same_export_still_draws_its_rungs(tmp_path, mixer, executor):
    text = _failure(tmp_path, mixer, executor, "set Stop = 1;set Start = 1;scan 3;expect Running == 1")
    lines = text.splitlines()
    assert lines[1].startswith("  routine MainProgram.MainRoutine, rungs that write Running")
    assert lines[2].strip() == "Rung 0" and "( )" in text and "lines that write" not in text


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_bool_assignment_draws_its_line_and_an_else_its_head(tmp_path, mixer, executor):
    text = _failure(tmp_path, mixer, executor, "set Start = 1;scan 2;expect Filling == 0")
    assert _marked(text) == [30] and "LSTB" not in text
    assert _drawn(text)[30].split() == ["Filling", ":=", "State", "=", "1;", "Filling=1", "State=1"]
    text = _failure(tmp_path, mixer, executor, "scan 1;expect Fault == 1")
    assert sorted(_drawn(text)) == [26, 27] and _marked(text) == [27]
    assert _drawn(text)[26].strip() == "ELSE" and _drawn(text)[27].split()[-1] == "Fault=0"


def test_lines_count_against_the_limit_and_the_rest_are_named_by_line(tmp_path, mixer):
    text = _failure(tmp_path, mixer, "compiled", "set Start = 1;scan 3;expect State == 7")
    assert len(_marked(text)) == MAX_RUNGS == 4 and _marked(text) == [5, 12, 17, 24]
    assert text.splitlines()[-1] == "  and 1 more: routine MainProgram.Sequence line 28"


def test_the_st_drawing_keeps_its_values_and_pickles(tmp_path, mixer):
    with PLC.load(mixer) as plc:
        plc.set("Start", 1)
        plc.scan(3)
        program = plc.runner.app.program
        title, places = writer_rungs(program, "Level")
        drawing = pickle.loads(pickle.dumps(draw_rungs(program, plc.table, places, title)))
        plc.scan(2)
        assert plc["Level"] == 10.0
    out = io.StringIO()
    Console(file=out, width=100, color_system=None).print(drawing)
    assert "Level=5.0" in out.getvalue() and "Level=10.0" not in out.getvalue()
    # in colour, the writers' ">" as the watch view marks its selected line
    console = Console(width=100, file=io.StringIO(), color_system="truecolor", force_terminal=True)
    marks = [s for s in console.render(drawing) if s.text == ">"]
    assert len(marks) == 4 and all(s.style == SELECTED for s in marks)


ST = """// count up, then test
FOR i := 0 TO 2 DO
  Sum := Sum + i;
END_FOR;
Out [:=] Sum > 100;
WHILE n < 3 DO
  n := n + 1;
END_WHILE;"""


@pytest.mark.parametrize("executor", EXECUTORS)
def test_loops_give_their_head_and_a_first_scan_clear_is_no_line(tmp_path, executor):
    tags = [("i", "DINT"), ("Sum", "DINT"), ("n", "DINT"), ("Out", "BOOL")]
    app = write_l5x(tmp_path / "loops.L5X", tags, [Prog("P", {"Main": ["JSR(Calc,0);"], "Calc": ST})],
                    [Task("T", ["P"])])
    text = _failure(tmp_path, app, executor, "scan 2;expect Sum == 0")
    assert _marked(text) == [3] and sorted(_drawn(text)) == [2, 3]
    assert _drawn(text)[2].split()[:2] == ["FOR", "i"] and "Sum=6" in _drawn(text)[3]
    # Out is written by its line and by the rung that clears it on the first scan: one line drawn
    text = _failure(tmp_path, app, executor, "scan 1;expect Out == 1")
    assert _marked(text) == [5] and sorted(_drawn(text)) == [5] and "more" not in text
    text = _failure(tmp_path, app, executor, "scan 1;expect n == 0")
    assert _marked(text) == [7] and sorted(_drawn(text)) == [6, 7] and "n=3" in _drawn(text)[6]
