"""softplc fmt keeps every comment: the file header, comment
lines between rungs, SYMBOL/DATA/FILE line comments, comments inside
SOR ... EOR and inside a multi-line neutral rung, trailing rung comments.
What it prints parses back to the same program and is a fixed point."""

from __future__ import annotations

import io
from collections import Counter
from pathlib import Path

import pytest

from softplc_lite.app import app_instructions
from softplc_lite.commands.fmt import fmt_command
from softplc_lite.ladder.fmt import format_source, unprintable
from softplc_lite.ladder.fmt_comments import scan_comments
from softplc_lite.ladder.parser import parse_program

ROOT = Path(__file__).resolve().parent.parent
PROGRAMS = sorted((ROOT / "programs").glob("*/*.lad"))

COMMENTED = """\
// Tank demo: the file header
// second header line

SYMBOL Level N7:0   // the level, in mm
// what the pump is
SYMBOL Pump O:0/1
DATA N9 3 = 1 2 3 // initial values

// a note between the declarations and the program

FILE 2 MAIN // the main file
// rung one's comment
XIC B3/0 OTE Pump // rung one's trailing comment

// a free note between rungs

SOR XIC B3/1 // after the first instruction
  // an own line inside SOR ... EOR
  BST XIC B3/2 NXB XIC B3/3 BND
  OTE B3/4
EOR // after EOR
XIC(B3/5) // inside a neutral rung
// own line inside a neutral rung
OTE(B3/6);
MOV "quoted // not a comment" ST10:0

// the footer
"""


def comment_texts(text: str) -> Counter:
    return Counter(c.text for c in scan_comments(text)[0])


def fmt(text: str, style: str, instructions=None) -> str:
    program = parse_program(text, "t.lad", instructions)
    return format_source(program, text, style)


@pytest.mark.parametrize("style", ["mnemonic", "neutral"])
def test_every_comment_is_kept_and_the_output_is_a_fixed_point(style):
    text = COMMENTED if style == "mnemonic" else COMMENTED.replace('MOV "quoted // not a comment" ST10:0\n', "")
    once = fmt(text, style)
    assert comment_texts(once) == comment_texts(text)
    assert "quoted // not a comment" in once or style == "neutral"
    assert parse_program(once, "t.lad") == parse_program(text, "t.lad")  # rung comments included
    assert fmt(once, style) == once


def test_comments_stay_where_a_reader_expects_them():
    out = fmt(COMMENTED, "mnemonic").splitlines()
    assert out[:3] == ["// Tank demo: the file header", "// second header line", ""]
    assert "SYMBOL Level N7:0  // the level, in mm" in out
    assert out[out.index("SYMBOL Pump O:0/1") - 1] == "// what the pump is"
    assert "DATA N9 3 = 1 2 3  // initial values" in out and "FILE 2 MAIN  // the main file" in out
    assert out[out.index("XIC B3/0 OTE Pump  // rung one's trailing comment") - 1] == "// rung one's comment"
    k = out.index("SOR")
    assert out[k:k + 6] == ["SOR", "    XIC B3/1  // after the first instruction",
                            "    // an own line inside SOR ... EOR", "    BST XIC B3/2 NXB XIC B3/3 BND",
                            "    OTE B3/4", "EOR  // after EOR"]
    assert out[-1] == "// the footer" and out[-2] == ""


def test_neutral_inner_comments_stay_inside_the_rung():
    out = fmt(COMMENTED.replace('MOV "quoted // not a comment" ST10:0\n', ""), "neutral").splitlines()
    k = out.index("XIC(B3/1)  // after the first instruction")
    assert out[k:k + 4] == ["XIC(B3/1)  // after the first instruction", "// an own line inside SOR ... EOR",
                            "[XIC(B3/2),XIC(B3/3)]", "OTE(B3/4);  // after EOR"]


@pytest.mark.parametrize("style", ["mnemonic", "neutral"])
@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_shipped_programs_keep_every_comment(path, style):
    text = path.read_text(encoding="utf-8")
    instructions = app_instructions(path.parent)
    program = parse_program(text, str(path), instructions)
    if unprintable(program, style, instructions):
        pytest.skip("string operands: neutral text cannot write them")
    once = format_source(program, text, style)
    assert comment_texts(once) == comment_texts(text)
    again = parse_program(once, str(path), instructions)
    assert again == program
    assert format_source(again, once, style) == once


@pytest.mark.parametrize("lad, style", [
    ("XIC(B3/0)OTE(O:0/0);\n;\n", "neutral"),
    ("XIC B3/0 BST NXB XIC B3/1 BND OTE O:0/0\n", "neutral"),
    ("SYMBOL Temp N7:[N9:2]\nDATA N9 5 = 1 2 3 70 7\n\nFILE 2", "mnemonic"),
    ("SYMBOL Temp N7:[N9:2]\nDATA N9 5 = 1 2 3 70 7\n\nFILE 2", "neutral"),
    ("// only a comment\n", "mnemonic"),
    ("SOR // empty\nEOR\n", "mnemonic"),
    ("XIC(B3/0) OTE(B3/1); XIC(B3/2) OTE(B3/3); // two rungs on a line\n", "neutral"),
    ("[XIC(B3/0) // in a branch\n,XIC(B3/1)]OTE(B3/2);\n", "mnemonic"),
    ("[XIC(B3/0) // in a branch\n,XIC(B3/1)]OTE(B3/2);\n", "neutral"),
])
def test_edge_cases_are_fixed_points_with_their_comments(lad, style):
    once = fmt(lad, style)
    assert comment_texts(once) == comment_texts(lad)
    assert parse_program(once, "t.lad") == parse_program(lad, "t.lad")
    assert fmt(once, style) == once


def run_fmt(*paths, style="mnemonic", check=False, write=False, stdin=b""):
    out, err = io.StringIO(), io.StringIO()
    code = fmt_command([str(p) for p in paths], style, check, write, io.BytesIO(stdin), out, err)
    return code, out.getvalue(), err.getvalue()


def test_invalid_programs_are_refused_with_every_problem_located(tmp_path):
    bad = tmp_path / "bad.lad"
    bad.write_text("XIC B3/0 OTE N7:\nFOO N7:0\nXIC B3/0 OTE O:0/0\nMOV 1 N7:x\n")
    code, out, err = run_fmt(bad)
    assert code == 1 and out == ""
    assert f"{bad}:1:" in err and f"{bad}:2:1: unknown instruction 'FOO'" in err and f"{bad}:4:" in err
    assert "3 problems found; nothing formatted" in err
    code, out, err = run_fmt(tmp_path / "nosuch.lad")
    assert code == 1 and "no such file or directory" in err


def test_check_lists_the_files_that_are_not_formatted(tmp_path):
    app = tmp_path / "app"
    app.mkdir()
    (app / "a.lad").write_text("XIC B3/0 OTE O:0/0\n")
    (app / "b.lad").write_text("FILE 3\nxic   b3/1   ote o:0/1   // messy\n")
    code, out, err = run_fmt(app, check=True)
    assert code == 1 and out == "" and err == f"would reformat {app / 'b.lad'}\n"
    assert run_fmt(app / "a.lad", check=True)[0] == 0


def test_write_rewrites_every_file_of_an_app_in_place(tmp_path):
    app = tmp_path / "app"
    app.mkdir()
    (app / "a.lad").write_bytes(b"\xef\xbb\xbf// header\r\nxic b3/0  ote o:0/0 // trailing\r\n")
    (app / "b.lad").write_text("FILE 3\nXIC B3/1 OTE O:0/1\n")
    (app / "b.lad").chmod(0o640)
    before_b = (app / "b.lad").stat().st_mtime_ns
    code, out, err = run_fmt(app, write=True)
    assert code == 0 and out == "" and err == f"reformatted {app / 'a.lad'}\n"
    assert (app / "a.lad").read_bytes() == b"// header\nXIC B3/0 OTE O:0/0  // trailing\n"
    assert (app / "b.lad").stat().st_mtime_ns == before_b  # already formatted: not touched
    assert sorted(p.name for p in app.iterdir()) == ["a.lad", "b.lad"]  # no temporary file left
    assert run_fmt(app, check=True)[0] == 0
    (app / "a.lad").write_text("XIC B3/0 OTE N7:\n")  # invalid: nothing is written, not even b.lad
    (app / "b.lad").write_text("FILE 3\nxic b3/1 ote o:0/1\n")
    code, out, err = run_fmt(app, write=True)
    assert code == 1 and (app / "b.lad").read_text() == "FILE 3\nxic b3/1 ote o:0/1\n"
    assert (app / "b.lad").stat().st_mode & 0o777 == 0o640


def test_dash_reads_standard_input():
    code, out, err = run_fmt("-", stdin=b"// from stdin\nxic b3/0 ote o:0/0\n", style="neutral")
    assert code == 0 and out == "// from stdin\nXIC(B3/0)OTE(O:0/0);\n" and err == ""
    code, out, err = run_fmt("-", stdin=b"XIC B3/0 OTE N7:\n")
    assert code == 1 and err.startswith("<stdin>:1:")
    code, out, err = run_fmt("-", stdin=b"xic b3/0 ote o:0/0\n", check=True)
    assert code == 1 and err == "would reformat <stdin>\n"


def _sprinkle(src: str, style: str, rng) -> str:
    """``src`` (fmt's output) with comments put in every kind of place:
    end of line, own line above, free blocks between blank lines, inside a
    rung wrapped in SOR ... EOR, inside a neutral rung split over lines."""
    out, n = [], 0
    for line in src.splitlines():
        r, n = rng.random(), n + 1
        plain = line and not line.startswith(("//", "SYMBOL", "DATA", "FILE", "SOR")) and "//" not in line
        if r < 0.12 and style == "mnemonic" and plain and '"' not in line:
            toks = line.split()
            k = rng.randrange(0, len(toks) + 1)
            out += ["SOR " + " ".join(toks[:k]) + f" // in {n}", f"  // own in {n}", "  " + " ".join(toks[k:]), "EOR"]
        elif r < 0.12 and style == "neutral" and plain and ");" in line:
            k = line.index(")") + 1
            out += [line[:k] + f" // inside {n}", f"// own inside {n}", line[k:]]
        elif r < 0.2 and plain:
            out.append(line + f" // at the end {n}")
        elif r < 0.3:
            out += [f"// above {n}", line]
        elif r < 0.35:
            out += ["", f"// free {n}", "", line]
        else:
            out.append(line)
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("style", ["mnemonic", "neutral"])
@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_comments_anywhere_in_shipped_programs_are_kept(path, style):
    import random

    rng = random.Random(f"{path.name}-{style}")
    instructions = app_instructions(path.parent)
    program = parse_program(path.read_text(encoding="utf-8"), str(path), instructions)
    if unprintable(program, style, instructions):
        pytest.skip("string operands: neutral text cannot write them")
    src = format_source(program, path.read_text(encoding="utf-8"), style)
    for _ in range(8):
        text = _sprinkle(src, style, rng)
        parsed = parse_program(text, str(path), instructions)
        once = format_source(parsed, text, style)
        assert comment_texts(once) == comment_texts(text)
        again = parse_program(once, str(path), instructions)
        assert again == parsed
        assert format_source(again, once, style) == once


def test_what_check_refuses_is_refused_and_an_apps_files_are_validated_together(tmp_path):
    code, out, err = run_fmt("-", stdin=b"XIC B3/0 OTE\n")
    assert code == 1 and out == "" and "<stdin>:1:10: OTE takes 1 operand" in err and "nothing formatted" in err
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.lad").write_text("XIC B3/0 JSR 3\n")  # calls a file defined in the other .lad file
    (app / "sub.lad").write_text("FILE 3\nXIC B3/1 OTE O:0/1\n")
    code, out, err = run_fmt(app)
    assert code == 0 and "JSR 3" in out and "FILE 3" in out, err
