"""softplc check's warning for an input instruction after an output
instruction in series (ladder/verify.py): outputs end a rung or a branch leg,
and in neutral text a forgotten ';' joins two rungs in just that way."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers.cli import softplc_here
from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.validate import check
from softplc_lite.ladder.verify import verify

SERIES = "in series: an output instruction ends its rung or branch leg"


def warnings(text: str) -> list[str]:
    parsed = parse_program(text, "w.lad")
    resolved, errors = check(parsed)
    assert errors == []
    return [str(w) for w in verify(resolved, parsed=parsed)]


def test_a_forgotten_semicolon_in_neutral_text_is_warned_at_the_input_and_named():
    found = warnings("XIC(B3/0)OTE(O:0/0)\nXIC(B3/1)OTE(O:0/1);\n")
    assert found == [f"w.lad:2:1: XIC after OTE at w.lad:1:10 {SERIES} (a ';' missing after the OTE on "
                     "line 1 would join two rungs into this one)"]


def test_an_input_after_an_output_on_one_line_names_both_ways_to_end_a_rung():
    found = warnings("XIC B3/0 OTE O:0/0 XIO B3/1 OTE O:0/1\n")
    assert found == [f"w.lad:1:20: XIO after OTE at w.lad:1:10 {SERIES} (if two rungs were meant, end the "
                     "first: ';' in neutral text, a new line in mnemonic form)"]


def test_a_sor_rung_spans_lines_on_purpose_so_no_semicolon_is_suggested():
    found = warnings("SOR XIC B3/0 OTE O:0/0\n    XIC B3/1 OTE O:0/1 EOR\n")
    assert found == [f"w.lad:2:5: XIC after OTE at w.lad:1:14 {SERIES}"]
    found = warnings("SOR\nXIC B3/0 OTE O:0/0\nXIC B3/2 OTE O:0/1 EOR\n")
    assert found == [f"w.lad:3:1: XIC after OTE at w.lad:2:10 {SERIES}"]


def test_a_neutral_rung_that_opens_with_a_branch_or_is_indented_gets_the_semicolon_hint():
    for text, where in [
        ("[XIC(B3/0),XIC(B3/1)]OTE(O:0/0)\nXIC(B3/2)OTE(O:0/1);\n", "w.lad:2:1: XIC after OTE at w.lad:1:22"),
        ("  XIC(B3/0)OTE(O:0/0) // note\n  XIC(B3/2)OTE(O:0/1);\n", "w.lad:2:3: XIC after OTE at w.lad:1:12"),
    ]:
        assert warnings(text) == [f"{where} {SERIES} (a ';' missing after the OTE on line 1 would join two rungs "
                                  "into this one)"]


@pytest.mark.parametrize("rung", [
    "XIC B3/0 BST OTE O:0/0 NXB OTE O:0/1 BND\n",  # parallel outputs
    "XIC B3/0 BST OTE O:0/0 NXB XIC B3/2 OTE O:0/1 BND\n",  # a condition on an output leg, before its output
    "BST XIC B3/0 NXB XIC B3/1 BND BST XIC B3/2 OTE O:0/0 NXB OTE O:0/1 BND\n",
    "XIC(B3/0)[OTE(O:0/0),XIO(B3/1)[OTE(O:0/1),XIC(B3/3)OTE(O:0/2)]];\n",  # nested output branches
    "XIC B3/0 MOV N7:0 N7:1 ADD N7:1 1 N7:2\n",  # outputs in series (no input after them)
])
def test_outputs_last_in_their_rung_or_leg_are_not_warned(rung):
    assert warnings(rung) == []


@pytest.mark.parametrize("rung, where", [
    ("XIC B3/0 BST OTE O:0/0 XIC B3/1 OTE O:0/1 NXB OTE O:0/2 BND\n", "w.lad:1:24: XIC after OTE at w.lad:1:14"),
    ("XIC B3/0 BST OTE O:0/0 NXB XIC B3/2 BND XIO B3/1 OTE O:0/2\n", "w.lad:1:41: XIO after OTE at w.lad:1:14"),
    ("XIC B3/0 MOV N7:0 N7:1 BST XIC B3/1 NXB XIC B3/2 BND OTE O:0/2\n", "w.lad:1:28: XIC after MOV at w.lad:1:10"),
    ("XIC B3/0 OTE O:0/0 EQU N7:0 1 OTE O:0/1\n", "w.lad:1:20: EQU after OTE at w.lad:1:10"),
])
def test_an_input_after_an_output_in_series_within_a_leg_or_across_a_branch(rung, where):
    found = warnings(rung)
    assert len(found) == 1 and found[0].startswith(f"{where} {SERIES}"), found


def test_one_warning_a_rung_at_the_first_input_after_an_output():
    found = warnings("XIC B3/0 OTE O:0/0 XIC B3/1 OTE O:0/1 XIC B3/2 OTE O:0/2\n")
    assert len(found) == 1 and found[0].startswith("w.lad:1:20: XIC after OTE")


def test_check_warns_of_the_joined_rungs_and_exits_0(tmp_path):
    app = tmp_path / "joined"
    app.mkdir()
    (app / "main.lad").write_text("XIC(B3/0)OTE(O:0/0)\nXIC(B3/1)OTE(O:0/1);\n")
    p = softplc_here("check", "joined", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    main = Path("joined", "main.lad")
    assert p.stderr.splitlines() == [
        f"warning: {main}:2:1: XIC after OTE at {main}:1:10 {SERIES} (a ';' missing after the OTE on line 1 "
        "would join two rungs into this one)"]
    assert p.stdout == "joined: ok (1 program file, 1 rung, 1 warning)\n"
