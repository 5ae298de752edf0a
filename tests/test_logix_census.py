"""tools/logix_census.py: the census of Studio 5000 exports the Logix loader is measured against.

Run as a real process on hand-written exports in the shapes Studio 5000 writes
(tests/fixtures/logix/), the same controller as L5X and as L5K, and on the public exports
committed under tests/fixtures/logix/public/."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
TOOL = ROOT / "tools" / "logix_census.py"
FIXTURES = ROOT / "tests" / "fixtures" / "logix"
PUBLIC = FIXTURES / "public"


def census(*paths, expect_rc=0) -> dict:
    proc = subprocess.run([sys.executable, str(TOOL), "--json", *map(str, paths)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == expect_rc, proc.stderr
    assert "Traceback" not in proc.stderr
    return json.loads(proc.stdout)


def _tool_module():
    spec = importlib.util.spec_from_file_location("logix_census", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", ["whole_controller.L5X", "whole_controller.L5K"])
def test_a_whole_controller_is_counted(name):
    result = census(FIXTURES / name)
    assert result["errors"] == {}
    t = result["total"]
    assert t["files"] == 1
    assert t["export_kinds"] == {"Controller": 1}
    assert t["routines"] == {"RLL": 2, "ST": 1, "AOI RLL": 1}
    assert t["rungs"] == 6 and t["st_lines"] == 2
    assert t["instructions"] == {"XIC": 2, "TON": 1, "OTE": 2, "ADD": 1, "Limiter": 1, "MOV": 2,
                                 "JSR": 1, "XIO": 1}
    assert t["tags"] == 8 and t["tag_scopes"] == {"controller": 7, "program": 1}
    assert t["tag_types"] == {"TIMER": 1, "STRING": 1, "DINT": 3, "Tank": 1, "Limiter": 1, "(alias)": 1}
    assert t["alias_tags"] == 1 and t["array_dims"] == {"1-D": 1}
    assert (t["udts"], t["aois"], t["modules"]) == (1, 1, 2)
    assert t["tasks"] == {"CONTINUOUS": 1, "PERIODIC": 1}
    for feature in ("question_operand", "branch", "aoi_call", "constant_index", "module_tag", "bit_of_word"):
        assert t["features"][feature] == 1, feature
    assert t["features"]["member_access"] == 4


def test_external_access_and_data_formats_of_an_l5x():
    t = census(FIXTURES / "whole_controller.L5X")["total"]
    assert t["external_access"] == {"Read/Write": 6, "Read Only": 1, "None": 1}
    assert t["data_formats"] == {"L5K": 7, "Decorated": 6, "String": 1}


def test_an_l5k_names_only_the_access_that_is_not_the_default():
    t = census(FIXTURES / "whole_controller.L5K")["total"]
    assert t["external_access"] == {"Read Only": 1, "None": 1}


def test_the_table_lists_files_and_totals():
    proc = subprocess.run([sys.executable, str(TOOL), "--per-file", str(FIXTURES / "whole_controller.L5X")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    assert "whole_controller.L5X" in proc.stdout
    assert "rungs 6, instruction uses 11" in proc.stdout
    assert "tasks: CONTINUOUS 1, PERIODIC 1" in proc.stdout


def test_a_bad_file_is_named_and_the_others_are_counted(tmp_path):
    (tmp_path / "broken.L5X").write_text('<?xml version="1.0"?>\n<RSLogix5000Content>\n<Controller>\n')
    (tmp_path / "other.L5X").write_text("<Project/>")
    (tmp_path / "notes.L5K").write_text("just some notes\n")
    (tmp_path / "good.L5X").write_bytes((FIXTURES / "whole_controller.L5X").read_bytes())
    result = census(tmp_path)
    assert result["total"]["files"] == 1 and result["total"]["rungs"] == 6
    errors = {Path(k).name: v for k, v in result["errors"].items()}
    assert set(errors) == {"broken.L5X", "other.L5X", "notes.L5K"}
    assert "line 4" in errors["broken.L5X"]
    assert "<Project>" in errors["other.L5X"]
    assert "not an L5K export" in errors["notes.L5K"]


def test_only_bad_files_exit_non_zero(tmp_path):
    (tmp_path / "broken.L5X").write_text("<RSLogix5000Content")
    proc = subprocess.run([sys.executable, str(TOOL), str(tmp_path / "broken.L5X"), str(tmp_path / "missing.L5K")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr + proc.stdout
    assert "broken.L5X: not well-formed XML" in proc.stdout
    assert "missing.L5K: FileNotFoundError" in proc.stdout


@pytest.mark.parametrize("text, expected", [
    ("XIC(A)[XIO(B),XIC(C.DN)]OTE(D);", [("XIC", ["A"]), ("XIO", ["B"]), ("XIC", ["C.DN"]), ("OTE", ["D"])]),
    ("CPT(X,ABS(Y)*2)", [("CPT", ["X", "ABS(Y)*2"])]),
    ("TON(T,?,?)", [("TON", ["T", "?", "?"])]),
    ("MOV(Arr[i+1,2],Local:1:I.Data.0)", [("MOV", ["Arr[i+1,2]", "Local:1:I.Data.0"])]),
    ("EQU(S,'a,b)$'')NOP();", [("EQU", ["S", "'a,b)$''"]), ("NOP", [])]),
])
def test_rung_text_is_split_into_instructions_and_operands(text, expected):
    assert _tool_module().split_instructions(text) == expected


def test_the_public_exports_are_all_read():
    files = sorted(p for p in PUBLIC.rglob("*") if p.suffix.lower() in (".l5x", ".l5k"))
    assert files, "no public exports"
    result = census(PUBLIC)
    assert result["errors"] == {}
    assert result["total"]["files"] == len(files)
    assert result["total"]["rungs"] > 100
    assert set(result["total"]["formats"]) == {"L5X", "L5K"}
