"""Logix's arithmetic rules where they differ from PLC-5's, through an
export's rungs, on both executors (docs/logix.md "Logix's arithmetic"): DINT
overflow wraps and sets S:V and the minor fault, a smaller destination keeps
the low bits, REAL into an integer rounds half to even, S:FS is the first
scan, one-shots on BOOL tags, CPT with Logix's operators."""

from __future__ import annotations

import pytest

from softplc_lite.ladder import status as S
from softplc_lite.runner import Runner

from helpers.logix_l5x import Prog, Task, write_l5x, read_tag, write_tag, export_runner

TAGS = [("D", "DINT"), ("D2", "DINT"), ("I", "INT"), ("Si", "SINT"), ("R", "REAL"), ("Big", "DINT"),
        ("Trig", "BOOL"), ("Store", "BOOL"), ("Pulse", "BOOL"), ("Once", "BOOL"), ("Scans", "DINT"),
        ("Firsts", "DINT"), ("Over", "BOOL"), ("Out", "DINT")]
EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])


def runner(tmp_path, rungs, executor) -> Runner:
    path = write_l5x(tmp_path / "sem.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])])
    return export_runner(path, executor)




@EXECUTORS
def test_dint_overflow_wraps_sets_s_v_and_the_minor_fault(tmp_path, executor):
    r = runner(tmp_path, ["ADD(Big,1,D)XIC(S:V)OTE(Over);"], executor)
    write_tag(r, "Big", 2_147_483_647)
    r.run(1)
    assert read_tag(r, "D") == -2_147_483_648 and read_tag(r, "Over") == 1
    assert r.table.read(f"S:{S.PLC5_MINOR_FAULT_BITS}") >> S.MINOR_OVERFLOW_BIT & 1
    r.close()


@EXECUTORS
def test_a_smaller_destination_keeps_the_low_bits_with_s_v(tmp_path, executor):
    r = runner(tmp_path, ["ADD(30000,30000,I)ADD(100,100,Si)MUL(65536,65536,D);"], executor)
    r.run(1)
    assert read_tag(r, "I") == -5536 and read_tag(r, "Si") == -56 and read_tag(r, "D") == 0
    r.close()


@EXECUTORS
@pytest.mark.parametrize("real, dint", [(2.5, 2), (3.5, 4), (-2.5, -2), (2.4999, 2), (-3.5, -4)])
def test_a_real_into_a_dint_rounds_half_to_even(tmp_path, executor, real, dint):
    r = runner(tmp_path, ["MOV(R,D);"], executor)
    write_tag(r, "R", real)
    r.run(1)
    assert read_tag(r, "D") == dint
    r.close()


@EXECUTORS
def test_s_fs_is_the_first_scan_only_and_ons_osr_fire_once(tmp_path, executor):
    r = runner(tmp_path, ["XIC(S:FS)ADD(Firsts,1,Firsts);", "ADD(Scans,1,Scans);",
                          "XIC(Trig)ONS(Store)ADD(Out,1,Out);", "XIC(Trig)OSR(Once,Pulse);"], executor)
    r.run(3)
    write_tag(r, "Trig", 1)
    r.run(1)
    assert read_tag(r, "Pulse") == 1
    r.run(4)
    assert read_tag(r, "Firsts") == 1 and read_tag(r, "Scans") == 8 and read_tag(r, "Out") == 1 and read_tag(r, "Pulse") == 0
    r.close()


@EXECUTORS
def test_cpt_with_logix_operators_and_functions(tmp_path, executor):
    r = runner(tmp_path, ["CPT(D,(7 MOD 3) + 2 ** 3 + (12 AND 10) + ABS(-4));", "CPT(R,SQR(16.0) / 8);",
                          "CPT(D2,16#10 + 2#101 + 8#7);"], executor)
    r.run(1)
    assert read_tag(r, "D") == 1 + 8 + 8 + 4 and read_tag(r, "R") == 0.5 and read_tag(r, "D2") == 16 + 5 + 7
    r.close()
