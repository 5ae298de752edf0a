"""The coverage reporters' files read back: the annotated listing, Cobertura
XML (the coverage-04 DTD's shape), LCOV (the tracefile grammar, and lcov
itself when it is installed), all from one measurement of the conveyor
example whose figures are counted by hand below."""

from __future__ import annotations

import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from helpers.apps import make_app
from helpers.cli import softplc_here
from softplc_lite.testing.coverage import Coverage
from softplc_lite.testing.coverage_annotate import annotate
from softplc_lite.testing.coverage_formats import cobertura, lcov
from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import run_file

ROOT = Path(__file__).resolve().parent.parent
CONVEYOR = ROOT / "docs" / "examples" / "conveyor"

# By hand, over the two scenarios (3 scans): rung 1 (line 10) ran 3 times, ended true and false;
# leg 1 powered, leg 2 (Manual) never; Enable never false, PartSensor both, Manual never true,
# XIO Jam never false, Conveyor on and off: 2 + 1 + 5 + 2 = 10 of 14 outcomes. Rung 2 (line 11)
# ran 3 times, always false: rung false, XIC Jam false, JamLamp off: 3 of 6.
LINES = {"10": ("3", "71% (10/14)"), "11": ("3", "50% (3/6)")}


@pytest.fixture(scope="module")
def conveyor(tmp_path_factory):
    app = tmp_path_factory.mktemp("c") / "conveyor"
    shutil.copytree(CONVEYOR, app)
    cov = Coverage()
    assert all(r.passed for r in run_file(app, app / "tests" / "conveyor.plctest", coverage=cov))
    return app, cov


def test_cobertura_has_the_dtd_shape_and_the_counts(conveyor):
    app, cov = conveyor
    text = cobertura(cov)
    assert text.startswith('<?xml version="1.0" ?>\n<!DOCTYPE coverage SYSTEM '
                           '"http://cobertura.sourceforge.net/xml/coverage-04.dtd">\n')
    root = ET.fromstring(text)
    assert root.tag == "coverage" and [c.tag for c in root] == ["sources", "packages"]
    required = {"line-rate", "branch-rate", "lines-covered", "lines-valid", "branches-covered",
                "branches-valid", "complexity", "version", "timestamp"}
    assert required <= set(root.attrib)
    assert (root.get("lines-covered"), root.get("lines-valid")) == ("2", "2")
    assert (root.get("branches-covered"), root.get("branches-valid")) == ("13", "20")
    assert root.get("branch-rate") == "0.65" and root.get("line-rate") == "1"
    assert [s.text for s in root.find("sources")] == [str(app)]
    (package,) = root.find("packages")
    assert package.tag == "package" and {"name", "line-rate", "branch-rate", "complexity"} <= set(package.attrib)
    (cls,) = package.find("classes")
    assert cls.get("filename") == "main.lad" and cls.get("name") == "main.lad file 2"
    assert [c.tag for c in cls] == ["methods", "lines"]
    lines = {ln.get("number"): (ln.get("hits"), ln.get("condition-coverage")) for ln in cls.find("lines")}
    assert lines == LINES
    assert all(ln.get("branch") == "true" for ln in cls.find("lines"))
    for el in root.iter():
        for name in ("line-rate", "branch-rate"):
            if name in el.attrib:
                assert 0 <= float(el.get(name)) <= 1


def test_pycobertura_reads_the_report(conveyor, tmp_path):
    """An independent reader (pycobertura, what CI coverage tools build on) sees the same file,
    the same rates, and both rungs as partly covered lines."""
    from pycobertura import Cobertura
    from pycobertura.filesystem import filesystem_factory

    app, cov = conveyor
    (tmp_path / "c.xml").write_text(cobertura(cov), encoding="utf-8")
    report = Cobertura(str(tmp_path / "c.xml"), filesystem=filesystem_factory(str(app)))
    assert report.files() == ["main.lad"]
    assert (report.line_rate("main.lad"), report.branch_rate("main.lad")) == (1.0, 0.65)
    assert report.line_statuses("main.lad") == [(10, "partial"), (11, "partial")]
    assert report.total_statements("main.lad") == 2


LCOV_RECORD = re.compile(r"TN:.*|SF:.+|FN:\d+,\S+|FNDA:\d+,\S+|FNF:\d+|FNH:\d+|DA:\d+,\d+|"
                         r"BRDA:\d+,\d+,\d+,(\d+|-)|BRF:\d+|BRH:\d+|LF:\d+|LH:\d+|end_of_record")


def test_lcov_follows_the_tracefile_grammar_and_counts(conveyor):
    app, cov = conveyor
    text = lcov(cov)
    lines = text.splitlines()
    assert all(LCOV_RECORD.fullmatch(line) for line in lines), [ln for ln in lines if not LCOV_RECORD.fullmatch(ln)]
    assert lines[1] == f"SF:{app / 'main.lad'}" and lines[-1] == "end_of_record"
    da = dict(ln[3:].split(",") for ln in lines if ln.startswith("DA:"))
    assert da == {line: hits for line, (hits, _) in LINES.items()}
    brda = [ln[5:].split(",") for ln in lines if ln.startswith("BRDA:")]
    taken = {line: sum(1 for b in brda if b[0] == line and b[3] not in ("0", "-")) for line in LINES}
    assert {line: (taken[line], sum(1 for b in brda if b[0] == line)) for line in LINES} == {"10": (10, 14),
                                                                                         "11": (3, 6)}
    assert len({tuple(b[:3]) for b in brda}) == len(brda)  # each (line, block, branch) once
    assert f"BRF:{len(brda)}" in lines and "BRH:13" in lines and "LF:2" in lines and "LH:2" in lines
    assert "FN:10,file_2" in lines and "FNDA:3,file_2" in lines


@pytest.mark.skipif(shutil.which("lcov") is None, reason="lcov is not installed")
def test_lcov_reads_the_tracefile(conveyor, tmp_path):
    _, cov = conveyor
    (tmp_path / "c.info").write_text(lcov(cov), encoding="utf-8")
    out = subprocess.run(["lcov", "--summary", str(tmp_path / "c.info"), "--rc", "lcov_branch_coverage=1"],
                         capture_output=True, text=True, check=True)
    summary = out.stdout + out.stderr
    assert "(2 of 2 lines)" in summary and "(13 of 20 branches)" in summary and "(1 of 1 function)" in summary


ANNOTATED = """\
! BST XIC Enable XIC PartSensor NXB XIC Manual BND XIO Jam OTE Conveyor
      ^^^^^^^^^^ never false
                                    ^^^^^^^^^^ leg never powered
                                    ^^^^^^^^^^ never true
                                                   ^^^^^^^ never false
! XIC Jam OTE JamLamp
  ^ rung never true
  ^^^^^^^ never true
          ^^^^^^^^^^^ never on
"""


def test_the_annotated_listing_marks_what_never_happened(conveyor, tmp_path):
    _, cov = conveyor
    (path,) = annotate(cov, tmp_path / "ann")
    assert path == tmp_path / "ann" / "main.lad.cover"
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "  // A conveyor runs while enabled and a part is at the sensor, or while the"
    assert "\n".join(lines[9:]) + "\n" == ANNOTATED


def test_annotated_gutters_a_rung_never_scanned_and_a_covered_one(tmp_path):
    app = make_app(tmp_path / "app", "XIC B3/0 JMP 1\nOTE B3/4\nLBL 1 XIC B3/0 OTE B3/5\n"
                                     "FILE 3 Never\nSBR\nRET\n")
    cov = Coverage()
    for value in (0, 1):
        with PLC.load(app, coverage=cov) as plc:
            plc.set("B3/0", value)
            plc.scan(1)
    (path,) = annotate(cov, tmp_path / "ann")
    assert path.read_text(encoding="utf-8").splitlines() == [
        "> XIC B3/0 JMP 1",
        "> OTE B3/4",  # scanned only with B3/0 off: ended true, and nothing in it can end it false
        "> LBL 1 XIC B3/0 OTE B3/5",
        "  FILE 3 Never",
        "- SBR",
        "- RET",
    ]


def test_the_command_writes_each_report(tmp_path):
    app = tmp_path / "conveyor"
    shutil.copytree(CONVEYOR, app)
    r = softplc_here("test", str(app), "--coverage-xml", str(tmp_path / "c.xml"), "--coverage-lcov",
                     str(tmp_path / "c.info"), "--coverage-annotate", str(tmp_path / "ann"))
    assert r.returncode == 0, r.stderr
    assert "Rung T/F" in r.stdout  # a report option measures and prints the summary too
    assert ET.parse(tmp_path / "c.xml").getroot().get("branches-covered") == "13"
    assert "BRH:13" in (tmp_path / "c.info").read_text().splitlines()
    assert (tmp_path / "ann" / "main.lad.cover").exists()
    bad = softplc_here("test", str(app), "--coverage-xml", str(tmp_path / "missing" / "c.xml"))
    assert bad.returncode == 1
    assert bad.stderr == f"{tmp_path / 'missing' / 'c.xml'}: cannot write the coverage report: No such file or directory\n"


def test_annotated_neutral_text_marks_each_instruction_and_leg(tmp_path):
    app = make_app(tmp_path / "app", "XIC(B3/0)[XIC(B3/2),XIO(B3/3)]OTE(B3/1);\n")
    cov = Coverage()
    with PLC.load(app, coverage=cov) as plc:
        plc.set("B3/0", 1)
        plc.set("B3/2", 1)
        plc.set("B3/3", 1)
        plc.scan(1)
    (path,) = annotate(cov, tmp_path / "ann")
    assert path.read_text(encoding="utf-8").splitlines() == [
        "! XIC(B3/0)[XIC(B3/2),XIO(B3/3)]OTE(B3/1);",
        "  ^ rung never false",
        "  ^^^^^^^^^ never false",
        "            ^^^^^^^^^ never false",
        "                      ^^^^^^^^^ leg never powered",
        "                      ^^^^^^^^^ never true",
        "                                ^^^^^^^^^ never off",
    ]
