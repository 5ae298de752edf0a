"""``softplc fmt EXPORT`` (docs/logix.md, "fmt and an export"): the
routines printed in the L5K routine form, the export never rewritten."""

from __future__ import annotations

import shutil
from pathlib import Path

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
TANK_LINE = ROOT / "programs" / "logix" / "tank_line.L5X"


def _copy(tmp_path: Path) -> Path:
    export = tmp_path / "tank_line.L5X"
    shutil.copy(TANK_LINE, export)
    return export


def test_fmt_prints_the_routines_rung_by_rung(tmp_path):
    export = _copy(tmp_path)
    before = export.read_bytes()
    r = softplc_here("fmt", str(export))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:4] == ["PROGRAM MainProgram", "    ROUTINE MainRoutine",
                         '        RC: "Start and stop the line: a seal-in";',
                         "        N: [XIC(Start) ,XIC(Running) ]XIO(Stop)XIO(LineDone)OTE(Running);"]
    assert "        N: XIC(Tanks[Active].Drain)TON(SettleTimer,?,?);" in lines
    assert lines.count("    END_ROUTINE") == 2 and lines[-1] == "END_PROGRAM"
    rungs = [line for line in lines if line.lstrip().startswith("N: ")]
    assert len(rungs) == 9  # every rung of the export (the check's 10 holds the continuous task's JSR)
    assert export.read_bytes() == before


def test_write_and_check_refuse_an_export_and_leave_it(tmp_path):
    export = _copy(tmp_path)
    before = export.read_bytes()
    for flag in ("--write", "--check"):
        r = softplc_here("fmt", flag, str(export))
        assert r.returncode == 1
        assert r.stdout == ""
        assert f"a Studio 5000 export is Studio's file: fmt {flag} takes .lad files" in r.stderr
        assert export.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["tank_line.L5X"]  # no temporary file left either


def test_an_export_check_refuses_is_refused_located(tmp_path):
    export = _copy(tmp_path)
    text = export.read_text(encoding="utf-8").replace("XIC(Running)JSR", "XIC(Runing)JSR")
    export.write_text(text, encoding="utf-8")
    line = text[:text.index("XIC(Runing)")].count("\n") + 1
    r = softplc_here("fmt", str(export))
    assert r.returncode == 1 and r.stdout == ""
    assert r.stderr.startswith(f"{export}:{line}:") and "Runing" in r.stderr
    assert "nothing formatted" in r.stderr


def test_comments_are_escaped_as_l5k_strings(tmp_path):
    export = _copy(tmp_path)
    text = export.read_text(encoding="utf-8").replace("a seal-in]]>", 'a "seal-in"\ncosts $0]]>')
    export.write_text(text, encoding="utf-8")
    r = softplc_here("fmt", str(export))
    assert r.returncode == 0, r.stderr
    assert '        RC: "Start and stop the line: a $"seal-in$"$Ncosts $$0";' in r.stdout.splitlines()


def test_an_l5k_export_prints_the_same_form():
    r = softplc_here("fmt", "tests/fixtures/logix/whole_controller.L5K")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:4] == ["PROGRAM MainProgram", "    ROUTINE MainRoutine",
                         '        RC: "Fill for five seconds while the tank runs";',
                         "        N: XIC(Tank1.Running)TON(T1,?,?);"]
    at = lines.index("    ST_ROUTINE Calc")  # the L5K form of an ST routine: its lines, each after a '
    assert lines[at:at + 4] == ["    ST_ROUTINE Calc", "        'Count := Count + 1;", "        'Levels[1] := Count;",
                                "    END_ST_ROUTINE"]
    assert lines.count("END_PROGRAM") == 2
