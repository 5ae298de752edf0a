"""Coverage of a Structured Text routine (docs/testing.md, "Structured Text:
statements, arms and mutants"): the mixer of programs/logix/mixer.L5X,
whose batch sequence is ST, counted as statements and arms in the summary,
the annotated export, LCOV and Cobertura. The figures are counted by hand
from the routine's text (comments below)."""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from helpers.cli import softplc_here
from softplc_lite.testing import coverage_st
from softplc_lite.testing.coverage import Coverage
from softplc_lite.testing.coverage_annotate import annotate_source
from softplc_lite.testing.coverage_formats import cobertura, lcov
from softplc_lite.testing.coverage_report import figures
from softplc_lite.testing.runner import run_file

ROOT = Path(__file__).resolve().parent.parent
MIXER = ROOT / "programs" / "logix" / "mixer.L5X"
SEQUENCE = 4  # the ST routine's program file (2 the continuous task, 3 MainRoutine)

# One scenario that starts the mixer, lets it fill (20 scans) and mixes 5 scans of 20.
PARTIAL = ('scenario "fills, then mixes a little":\n    set Start = 1\n'
           '    wait until State == 2 within 1 s\n    scan 5\n')


def line_of(text: str) -> int:
    """The export's line (from 1) holding ``text`` inside its CDATA."""
    lines = MIXER.read_text(encoding="utf-8").split("\n")
    return next(k for k, line in enumerate(lines, 1) if line == f"<![CDATA[{text}]]>")


def routine_line(text: str) -> int:
    """The routine's own number (from 1) of its line ``text``."""
    lines = MIXER.read_text(encoding="utf-8").split("\n")
    first = next(k for k, line in enumerate(lines) if line.startswith("<![CDATA[// One step"))
    return (line_of(text) - first - 1) // 3 + 1  # each <Line> three lines of the export


def mixer_copy(tmp_path: Path, scenario: str) -> Path:
    export = tmp_path / "mixer.L5X"
    shutil.copy(MIXER, export)
    (tmp_path / "mixer.tests").mkdir()
    (tmp_path / "mixer.tests" / "t.plctest").write_text(scenario, encoding="utf-8")
    return export


@pytest.fixture(scope="module")
def partial(tmp_path_factory):
    export = mixer_copy(tmp_path_factory.mktemp("mixer"), PARTIAL)
    cov = Coverage()
    results = run_file(export, export.parent / "mixer.tests" / "t.plctest", coverage=cov)
    assert all(r.passed for r in results)
    return export, cov


def missed_arms(cov: Coverage) -> list[tuple[str, int]]:
    info = cov.files[SEQUENCE]
    return [(a.arm.label, a.line) for a in coverage_st.arms(cov, info) if not a.covered]


def test_the_shipped_scenarios_miss_only_the_case_else(tmp_path):
    cov = Coverage()
    export = mixer_copy(tmp_path, (ROOT / "programs/logix/mixer.tests/batch.plctest").read_text(encoding="utf-8"))
    assert all(r.passed for r in run_file(export, tmp_path / "mixer.tests" / "t.plctest", coverage=cov))
    fig = figures(cov)[0][SEQUENCE]
    # 21 statements: the two of the CASE's ELSE never run; 13 arms (4 CASE labels, 4 IFs and their
    # "no arm", the ELSE): the ELSE is the one never taken (no step makes a state past 3).
    assert (fig.statements_run, fig.statements, fig.arms_taken, fig.arms) == (19, 21, 12, 13)
    assert (fig.rungs, fig.legs, fig.conditions) == (0, 0, 0)  # its rungs are counted as the text
    assert missed_arms(cov) == [("ELSE", line_of("ELSE"))]


def test_arms_a_scenario_set_misses(partial):
    _, cov = partial
    fig = figures(cov)[0][SEQUENCE]
    # Run: the CASE, idle's 2, fill's 5, mix's first 2, the 3 after END_CASE; not run: State := 3,
    # drain's 5 and the ELSE's 2.
    assert (fig.statements_run, fig.statements) == (13, 21)
    # Taken: CASE 0, 1, 2; idle's IF (never its no arm: the mixer runs from the first scan); fill's
    # IF and no arm; mix's no arm.
    assert (fig.arms_taken, fig.arms) == (7, 13)
    assert fig.covered == 20 and fig.total == 34
    assert missed_arms(cov) == [("no arm", line_of("    IF Running AND NOT Fault THEN")),
                                ("IF", line_of("    IF MixCount > MixScans THEN")),
                                ("CASE 3", line_of("  3:  // drain, then count the batch")),
                                ("IF", line_of("    IF Level <= 0.0 THEN")),
                                ("no arm", line_of("    IF Level <= 0.0 THEN")),
                                ("ELSE", line_of("ELSE"))]


def test_the_summary_names_statements_and_branches_beside_rungs(partial):
    export, _ = partial
    r = softplc_here("test", str(export), "--coverage")
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    header = next(line for line in lines if line.startswith("File"))
    assert header.split()[-3:] == ["Statements", "Branches", "Total"] and "Rungs" in header
    row = next(line for line in lines if line.startswith("4 MainProgram.Sequence")).split()
    assert row[-3:] == ["13/21", "7/13", "59%"]
    missing = next(line for line in lines if line.startswith("4 MainProgram.Sequence:"))
    # by the routine's own line numbers: its lines from 1
    assert missing == ("4 MainProgram.Sequence: statements never run: lines 17, 20, 21, 22, 23, 24, 27, 28; "
                       "arms never taken: no arm (line 4), IF (line 16), CASE 3 (line 19), IF (line 21), "
                       "no arm (line 21), ELSE (line 26)")
    assert routine_line("      State := 3;") == 17 and routine_line("ELSE") == 26


def test_the_annotated_export_marks_st_lines(partial):
    export, cov = partial
    out = annotate_source(cov, str(export)).split("\n")
    src = export.read_text(encoding="utf-8").split("\n")
    assert len([line for line in out if not line.startswith("   ")]) >= len(src)  # every line, marks beside

    def marked(text: str) -> tuple[str, list[str]]:
        k = next(k for k, line in enumerate(out) if line[2:] == f"<![CDATA[{text}]]>")
        marks = []
        while out[k + 1 + len(marks)].startswith("  ") and "^" in out[k + 1 + len(marks)]:
            marks.append(out[k + 1 + len(marks)])
        return out[k][:2], marks

    assert marked("    Level := Level + FillRate;") == ("> ", [])
    assert marked("      State := 3;") == ("- ", [])  # never run: nothing else is said of it
    gutter, marks = marked("    IF MixCount > MixScans THEN")
    column = len("  <![CDATA[    ")  # under the IF
    assert gutter == "! " and marks == [" " * column + "^ never taken: IF"]
    assert marked("    IF Running AND NOT Fault THEN") == ("! ", [" " * column + "^ never taken: no arm (every test false)"])
    assert marked("ELSE") == ("! ", [" " * len("  <![CDATA[") + "^ never taken: ELSE"])
    assert marked("  Fault := 1;  // a state no step makes")[0] == "- "
    assert marked("END_CASE;") == ("  ", [])  # no statement starts there


def test_lcov_lines_and_arms(partial):
    export, cov = partial
    record = lcov(cov).split("SF:" + str(export))[1].split("end_of_record")[0].splitlines()
    da = dict(line[3:].split(",") for line in record if line.startswith("DA:"))
    brda = [line[5:].split(",") for line in record if line.startswith("BRDA:")]
    # A line hits once a scan its first statement or test ran: the mix lasted 5 scans.
    assert da[str(line_of("    MixCount := MixCount + 1;"))] == "5"
    assert da[str(line_of("      State := 3;"))] == "0"
    assert da[str(line_of("  Fault := 1;  // a state no step makes"))] == "0"
    assert str(line_of("END_CASE;")) not in da
    mix_if = str(line_of("    IF MixCount > MixScans THEN"))
    assert [b for b in brda if b[0] == mix_if] == [[mix_if, "7", "0", "0"], [mix_if, "8", "0", "5"]]
    drain_if = str(line_of("    IF Level <= 0.0 THEN"))
    assert [b[3] for b in brda if b[0] == drain_if] == ["-", "-"]  # its test never ran
    assert [b for b in brda if b[1] == "12"] == [[str(line_of("ELSE")), "12", "0", "0"]]
    totals = dict(line.split(":") for line in record if line[:3] in ("LF:", "LH:", "BRF", "BRH"))
    # The export's record: MainRoutine's rungs and outcomes beside the routine's lines and arms.
    ladder = figures(cov)[0][3]
    assert totals["BRF"] == str(13 + ladder.branches) and totals["BRH"] == str(7 + ladder.branches_seen)
    # The routine's lines: the 21 statements' (each on a line of its own; the CASE's is its first
    # test, on the line of label 0), labels 1, 2 and 3, and the ELSE.
    st_lines = set(da) - {str(line_of("[XIC(Start) ,XIC(Running) ]XIO(Stop)OTE(Running);")),
                          str(line_of("JSR(Sequence,0);"))}
    assert len(st_lines) == 25 and totals["LF"] == str(len(da))


@pytest.mark.skipif(shutil.which("genhtml") is None, reason="genhtml (lcov) is not installed")
def test_genhtml_reads_the_exports_tracefile(partial, tmp_path):
    """Every record is a file a CI tool can show: the export (the continuous task the loader made
    has no file, and no record)."""
    _, cov = partial
    text = lcov(cov)
    assert [line for line in text.splitlines() if line.startswith("SF:")] == [f"SF:{partial[0]}"]
    (tmp_path / "m.info").write_text(text, encoding="utf-8")
    subprocess.run(["genhtml", "--branch-coverage", "-q", "-o", str(tmp_path / "html"), str(tmp_path / "m.info")],
                   capture_output=True, text=True, check=True)
    assert (tmp_path / "html" / "index.html").is_file()


def test_cobertura_class_of_the_routine(partial):
    export, cov = partial
    root = ET.fromstring(cobertura(cov).split("\n", 2)[2])
    cls = next(c for c in root.iter("class") if c.get("name").endswith("MainProgram.Sequence"))
    lines = {line.get("number"): line for line in cls.iter("line")}
    mix_if = lines[str(line_of("    IF MixCount > MixScans THEN"))]
    assert (mix_if.get("hits"), mix_if.get("condition-coverage")) == ("5", "50% (1/2)")
    assert lines[str(line_of("    Level := Level + FillRate;"))].get("branch") == "false"
    hit = sum(1 for line in lines.values() if int(line.get("hits")) > 0)
    assert cls.get("line-rate") == f"{hit / len(lines):.4g}" and cls.get("branch-rate") == f"{7 / 13:.4g}"


def test_the_scenarios_pass_on_both_executors(partial):
    """Coverage scans with the reference interpreter; a plain run, the compiled code: the same results."""
    export, _ = partial
    for cov in (None, Coverage()):
        assert [r.passed for r in run_file(export, export.parent / "mixer.tests" / "t.plctest", coverage=cov)] \
            == [True]
