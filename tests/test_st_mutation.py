"""Mutation testing of Structured Text (docs/testing.md, "Structured Text:
statements, arms and mutants"): the mutants of an ST routine's operators
and constants, described as the text shows them at their line and column,
judged by the same run as a ladder file's; the mixer of
programs/logix/mixer.L5X, whose batch sequence is ST, with its scenarios and
with a set that misses a boundary."""

from __future__ import annotations

import io
import re
import shutil
from pathlib import Path

from rich.console import Console

from helpers.logix_l5x import Prog, Task, write_l5x
from softplc_lite.app import load_app
from softplc_lite.testing.mutants import mutants
from softplc_lite.testing.mutation import INVALID, KILLED, NOT_COVERED, SURVIVED, run_mutation
from softplc_lite.testing.mutation_report import print_report
from softplc_lite.testing.st_mutants import render
from softplc_lite.st.parser import parse_routine

ROOT = Path(__file__).resolve().parent.parent
MIXER = ROOT / "programs" / "logix" / "mixer.L5X"

ROUTINE = """n := 0;
FOR i := 1 TO 10 BY 2 DO
  n := (n + i) * 2 MOD 7;
END_FOR;
CASE Count OF
  1, 5: Sel := -5;
  2..4: Sel := Count ** 2;
END_CASE;
Big := NOT (Count > 3) AND Flag OR Count = 9;
Flag := 0;
r := ABS(r - 1.5) / 2.0;
WHILE n < 3 DO n := n + 1; END_WHILE;
IF Flag THEN Sum := 1; ELSIF Count >= 4 THEN Sum := 2; END_IF;
Sum := Count / 3;"""
TAGS = [("Count", "DINT"), ("Big", "BOOL"), ("Flag", "BOOL"), ("Sel", "DINT"), ("Sum", "DINT"), ("i", "DINT"),
        ("n", "DINT"), ("r", "REAL")]


def st_mutants_of(tmp_path: Path) -> list:
    export = write_l5x(tmp_path / "st.L5X", TAGS, [Prog("MainProgram", {"Main": ["JSR(Calc,0);"], "Calc": ROUTINE})],
                       [Task("T", ["MainProgram"])])
    app = load_app(str(export), state_dir=str(tmp_path / "state"), use_cache=False)
    calc = next(n for n, f in app.source_program.files.items() if f.name == "MainProgram.Calc")
    return [m for m in mutants(app.source_program, app.instructions) if m.key[0] == calc], export


def test_operators_and_constants_as_the_text_shows_them(tmp_path):
    found, export = st_mutants_of(tmp_path)
    described = [(m.operator, m.description) for m in found]
    for expected in [
        ("constant", "line 1: n := 0 -> n := 1"),
        ("constant", "line 2: FOR i := 1 TO 10 BY 2 -> FOR i := 1 TO 11 BY 2"),
        ("constant", "line 2: FOR i := 1 TO 10 BY 2 -> FOR i := 1 TO 10 BY 1"),
        ("arithmetic", "line 3: (n + i) * 2 MOD 7 -> (n + i) * 2 / 7"),
        ("arithmetic", "line 3: (n + i) * 2 -> (n + i) / 2"),
        ("arithmetic", "line 3: n + i -> n - i"),
        ("constant", "line 6: 1, 5: -> 1, 6:"),
        ("constant", "line 6: Sel := -5 -> Sel := -4"),
        ("constant", "line 7: 2..4: -> 2..5:"),
        ("arithmetic", "line 7: Count ** 2 -> Count * 2"),
        ("logic", "line 9: NOT (Count > 3) AND Flag OR Count = 9 -> NOT (Count > 3) AND Flag AND Count = 9"),
        ("logic", "line 9: NOT (Count > 3) AND Flag -> NOT (Count > 3) OR Flag"),
        ("logic", "line 9: NOT (Count > 3) -> Count > 3"),
        ("compare", "line 9: Count > 3 -> Count >= 3"),
        ("constant", "line 9: Count = 9 -> Count = 10"),
        ("arithmetic", "line 11: ABS(r - 1.5) / 2.0 -> ABS(r - 1.5) * 2.0"),
        ("constant", "line 11: r - 1.5 -> r - 0.5"),
        ("compare", "line 12: n < 3 -> n <= 3"),
        ("compare", "line 13: Count >= 4 -> Count > 4"),
        ("arithmetic", "line 14: Count / 3 -> Count * 3"),
    ]:
        assert expected in described
    # A constant given to a BOOL is the other truth value only.
    assert [d for _, d in described if d.startswith("line 10:")] == ["line 10: Flag := 0 -> Flag := 1"]
    # What the translation made up is not the text's: the IF's "= 0", the FOR's end test and
    # step, the CASE's comparisons with its selector. Every mutant names its line.
    assert all(d.startswith("line ") and not re.search(r"(?<!:)= 0\b|<> 0", d) for _, d in described)
    assert not [d for _, d in described if d.startswith("line 5:") or d.startswith("line 4:")]
    assert len([d for _, d in described if d.startswith("line 2:")]) == 6  # FOR's 3 numbers, 2 each
    # each at its expression's column in the export: the comparison at its left operand
    lines = export.read_text(encoding="utf-8").split("\n")
    m = next(m for m in found if m.description == "line 9: Count > 3 -> Count >= 3")
    assert lines[m.pos.line - 1][m.pos.column - 1:].startswith("Count > 3) AND Flag")
    low = next(m for m in found if m.description == "line 7: 2..4: -> 3..4:")
    high = next(m for m in found if m.description == "line 7: 2..4: -> 2..5:")
    assert lines[low.pos.line - 1][low.pos.column - 1:].startswith("2..4:")
    assert lines[high.pos.line - 1][high.pos.column - 1:].startswith("4: Sel")


def test_render_keeps_the_texts_meaning():
    for text in ["a + b * c", "(a + b) * c", "a - (b - c)", "a - b - c", "NOT (a AND b)", "-(a + 1)",
                 "a ** 2 ** 3", "a ** (2 ** 3)", "a OR b AND c XOR d", "(a OR b) AND c", "a = b = c",
                 "a = (b = c)", "ABS(x - 1.5) / 2.0", "Tanks[i+1].Level MOD 4"]:
        e = parse_routine(f"x := {text};")[0].value
        assert render(e) == text
        assert parse_routine(f"x := {render(e)};")[0].value == e


def mixer_copy(tmp_path: Path, scenarios: str) -> Path:
    export = tmp_path / "mixer.L5X"
    shutil.copy(MIXER, export)
    (tmp_path / "mixer.tests").mkdir()
    (tmp_path / "mixer.tests" / "t.plctest").write_text(scenarios, encoding="utf-8")
    return export


def test_the_mixers_scenarios_kill_every_st_mutant_they_reach(tmp_path):
    export = mixer_copy(tmp_path, (ROOT / "programs/logix/mixer.tests/batch.plctest").read_text(encoding="utf-8"))
    report = run_mutation(export, jobs=1)
    st = [(m, o) for m, o in zip(report.mutants, report.outcomes) if m.key[0] == 4]
    assert report.count(INVALID) == 0 and report.count(SURVIVED) == 0
    assert len([1 for _, o in st if o.status == KILLED]) == 45
    # the CASE's ELSE (no step makes a state past 3) is not reached: its 3 mutants are not run
    assert sorted(m.description for m, o in st if o.status == NOT_COVERED) == [
        "line 27: Fault := 1 -> Fault := 0", "line 28: State := 0 -> State := -1", "line 28: State := 0 -> State := 1"]
    assert all("Error:" not in o.detail for _, o in st if o.status == KILLED)


# Scenarios that let the batch mix "long enough" without saying how long: the mix's boundary
# (MixCount > MixScans) and its start (MixCount := 0) go unchecked.
LOOSE = """scenario "a batch mixes, then drains":
    set Start = 1
    wait until State == 2 within 1 s
    wait until State == 3 within 1 s
    expect Level == 50
"""


def test_a_scenario_set_that_misses_the_boundary_lets_it_survive(tmp_path):
    export = mixer_copy(tmp_path, LOOSE)
    mix = ["line 11: MixCount := 0 -> MixCount := 1",
           "line 15: MixCount + 1 -> MixCount - 1",
           "line 16: MixCount > MixScans -> MixCount >= MixScans"]
    report = run_mutation(export, jobs=1, select=lambda m: m.description.startswith(("line 11:", "line 15:", "line 16:")))
    outcome = {m.description: o.status for m, o in zip(report.mutants, report.outcomes)}
    assert outcome[mix[2]] == SURVIVED and outcome[mix[0]] == SURVIVED
    assert outcome[mix[1]] == KILLED  # counting down never passes MixScans: the wait times out
    assert outcome["line 11: MixCount := 0 -> MixCount := -1"] == SURVIVED
    out = io.StringIO()
    print_report(report, Console(file=out, width=300, color_system=None))
    text = out.getvalue().splitlines()
    k = text.index(f"SURVIVED {export}:{_line(export, '    IF MixCount > MixScans THEN')}:{len('<![CDATA[    ') + 4}: "
                   f"MainProgram.Sequence {mix[2]} (compare)")
    assert text[k + 1:k + 3] == ["      IF MixCount > MixScans THEN", " " * 9 + "^"]
    # the shipped scenarios count the scans: both killed
    (tmp_path / "strict").mkdir()
    strict = mixer_copy(tmp_path / "strict",
                        (ROOT / "programs/logix/mixer.tests/batch.plctest").read_text(encoding="utf-8"))
    report = run_mutation(strict, jobs=1, select=lambda m: m.description in mix)
    assert [o.status for o in report.outcomes] == [KILLED, KILLED, KILLED]


def _line(export: Path, text: str) -> int:
    return export.read_text(encoding="utf-8").split("\n").index(f"<![CDATA[{text}]]>") + 1
