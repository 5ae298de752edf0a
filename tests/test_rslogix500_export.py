"""A real RSLogix 500 text export runs through ``softplc check``.

tests/data/rslogix500/59-BSGS.SLC is an RSLogix 500 ASCII export of a
MicroLogix 1400 program (source and licence in the README there). RSLogix
500 writes its ladder as ``SOR ... EOR`` mnemonic rungs, which softplc
reads as they are; around them it writes lines that are not ladder. The
test turns the export into a softplc program by this rule, and nothing else:

* the processor and slot header before the first ``LADDER`` line is dropped;
* ``LADDER n`` (with an optional name) becomes ``FILE n`` (a program file);
* ``% Rung: n %`` lines (RSLogix's rung number markers) are dropped;
* the data table part from the first ``DATA`` line on is dropped (softplc
  takes initial values as ``DATA`` directives or JSON, in its own form).

Every rung is kept as written: no mnemonic, operand or address is changed.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from softplc_lite.cli import main
from softplc_lite.ladder import load_text, run_text

EXPORT = Path(__file__).parent / "data" / "rslogix500" / "59-BSGS.SLC"

_LADDER = re.compile(r"^LADDER\s+(\d+)\b")
_RUNG_MARKER = re.compile(r"^%\s*Rung:\s*\d+\s*%\s*$")


def ladder_of_export(text: str) -> str:
    """The export's ladder as a softplc program (the rule in the module docstring)."""
    out: list[str] = []
    in_ladder = False
    for line in text.splitlines():
        header = _LADDER.match(line)
        if header:
            in_ladder = True
            out.append(f"FILE {header.group(1)}")
        elif line.startswith("DATA ") or line.startswith("DATA\t"):
            break
        elif in_ladder and not _RUNG_MARKER.match(line):
            out.append(line)
    return "\n".join(out) + "\n"


def _export_rungs(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.startswith("SOR ")]


def test_every_rung_of_the_export_is_kept_by_the_conversion():
    text = EXPORT.read_text(encoding="ascii")
    program = ladder_of_export(text)
    rungs = _export_rungs(text)
    assert len(rungs) == 35
    assert _export_rungs(program) == rungs  # not one rung changed or lost


def test_the_rslogix500_export_passes_softplc_check(tmp_path, capsys):
    path = tmp_path / "bsgs.lad"
    path.write_text(ladder_of_export(EXPORT.read_text(encoding="ascii")))
    code = main(["check", str(path)])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err


def test_the_export_loads_with_its_slc_addresses_and_long_files():
    program = load_text(ladder_of_export(EXPORT.read_text(encoding="ascii")), "59-BSGS.SLC")
    assert sorted(program.files) == [2, 3, 4, 5, 6, 7]
    assert sum(len(f.rungs) for f in program.files.values()) == 35
    text = "\n".join(str(op.address) for f in program.files.values() for r in f.rungs
                     for ins in _walk(r.elements) for op in ins.operands if hasattr(op, "address"))
    assert "I:1.0/5" in text  # printed back in the SLC form it was written in
    assert "L42:0" in text


def _walk(elements):
    from softplc_lite.ladder.ast import walk

    return walk(elements)


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_the_export_runs_an_input_through_to_its_bits(executor):
    """Input slot 1 word 0 bit 2 (I:1.0/2) is copied to B13:1/2 by file 5,
    and file 6 sets B31:2/15 and B51:2/15 from it: the SLC address reaches
    the same word whether written I:1.0/2 or through its PLC-5 alias."""
    program = ladder_of_export(EXPORT.read_text(encoding="ascii"))
    engine = run_text(program, 2, executor=executor, values={"I:1.0/2": 1})
    t = engine.table
    assert t.read("B13:1/2") == 1 and t.read("B31:2/15") == 1 and t.read("B51:2/15") == 1
    assert t.read("B13:1/3") == 0
    assert t.read("I:40/2") == 1  # slot 1 word 0 is word 32 of the input file (octal 40)
