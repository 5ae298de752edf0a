"""Logix's bit instructions (ladder/instr/logix_bits.py) on both executors:
AND/OR/XOR/NOT, MEQ and MVM 32 bits wide, BTD on DINTs, SWPB's three order
modes, with 1756-RM003's cases; then TRN, and each through an export's rungs
(logix/bits.py), with their operand errors located."""

from __future__ import annotations

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.runner import Runner

from helpers.logix_l5x import Prog, Task, write_l5x, export_runner

EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])


def u32(v: int) -> int:
    return v & 0xFFFFFFFF


@pytest.mark.parametrize("mnemonic, result", [("LAND", 0x12340000), ("LOR", 0xFFFF5678), ("LXOR", 0xEDCB5678)])
def test_land_lor_lxor_are_32_bits_wide(engine, mnemonic, result):
    e = engine(f"DATA L10 2\n{mnemonic} L10:0 4294901760 L10:1", {"L10:0": 0x12345678})
    e.scan()
    assert u32(e.table.read("L10:1")) == result and e.table.read("S:0/3") == (result >> 31)


def test_lnot_of_a_dint_and_an_int(engine):
    e = engine("DATA L10 2\nLNOT L10:0 L10:1\nLNOT L10:0 N7:0", {"L10:0": 0x0000FFFF})
    e.scan()
    assert u32(e.table.read("L10:1")) == 0xFFFF0000 and e.table.read("N7:0") == 0 and e.table.read("S:0/2") == 1


@pytest.mark.parametrize("source, out", [(0x12345678, 1), (0x1234FFFF, 1), (0x1235_5678, 0)])
def test_lmeq_compares_the_masked_32_bits(engine, source, out):
    e = engine("DATA L10 1\nLMEQ L10:0 4294901760 305397760 OTE B3/0", {"L10:0": source})
    e.scan()
    assert e.table.read("B3/0") == out


def test_lmvm_moves_the_masked_bits_of_a_dint(engine):
    e = engine("DATA L10 2\nLMVM L10:0 4278255360 L10:1", {"L10:0": 0x12345678, "L10:1": 0x0F0F0F0F})
    e.scan()
    assert u32(e.table.read("L10:1")) == 0x120F560F  # mask 16#FF00_FF00


@pytest.mark.parametrize("sbit, dbit, length, result", [
    (4, 0, 8, 0x67), (0, 16, 16, 0x56780000), (4, 20, 16, 0x56700000),  # past bit 31: the extra bits lost
    (28, 0, 8, 0x1),  # past the source's bit 31: only 4 bits
])
def test_lbtd_moves_a_bit_field_of_a_dint(engine, sbit, dbit, length, result):
    e = engine(f"DATA L10 2\nLBTD L10:0 {sbit} L10:1 {dbit} {length}", {"L10:0": 0x12345678})
    e.scan()
    assert u32(e.table.read("L10:1")) == result


def test_lbtd_sign_extends_an_int_source_and_keeps_the_rest_of_the_destination(engine):
    e = engine("DATA L10 1\nLBTD N7:0 8 L10:0 8 16", {"N7:0": -256, "L10:0": 0x55})
    e.scan()
    assert u32(e.table.read("L10:0")) == 0x00FFFF55


@pytest.mark.parametrize("mode, result", [(0, 0x78563412), (1, 0x56781234), (2, 0x34127856)])
def test_lswpb_order_modes(engine, mode, result):
    e = engine(f"DATA L10 2\nLSWPB L10:0 {mode} L10:1", {"L10:0": 0x12345678})
    e.scan()
    assert u32(e.table.read("L10:1")) == result


def test_lswpb_of_an_int_swaps_its_bytes_in_every_mode(engine):
    e = engine("LSWPB N7:0 0 N7:1\nLSWPB N7:0 1 N7:2", {"N7:0": 0x1234})
    e.scan()
    assert e.table.read("N7:1") == 0x3412 == e.table.read("N7:2")


TAGS = [("D", "DINT"), ("E", "DINT"), ("F", "REAL"), ("G", "REAL"), ("I", "INT"), ("J", "INT"), ("K", "DINT"),
        ("Hit", "BOOL")]


def runner(tmp_path, rungs, executor) -> Runner:
    path = write_l5x(tmp_path / "b.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])])
    return export_runner(path, executor)


@EXECUTORS
def test_band_bor_bxor_bnot_meq_mvm_btd_swpb_in_an_export(tmp_path, executor):
    r = runner(tmp_path, ["BAND(D,16#FFFF_0000,E);", "BOR(E,16#8000_0000,E);", "BXOR(D,2#1111,K);",
                          "MEQ(D,16#FFFF_0000,16#1234_0000)OTE(Hit);", "MVM(16#FFFF_FFFF,16#0000_FF00,K);",
                          "BTD(D,28,J,0,8);", "SWPB(D,HIGH/LOW,D);"], executor)
    names = r.app.program.symbols
    r.table.write(names.resolve_path("D"), 0x12345678)
    r.run(1)
    read = lambda tag: r.table.read(names.resolve_path(tag))  # noqa: E731
    assert u32(read("E")) == 0x92340000 and u32(read("K")) == 0x1234FF77 and read("Hit") == 1
    assert read("J") == 1 and u32(read("D")) == 0x34127856
    r.close()


@EXECUTORS
@pytest.mark.parametrize("value, out", [(3.7, 3.0), (-3.7, -3.0), (2.0, 2.0), (-0.5, 0.0)])
def test_trn_instruction_and_function_cut_the_fraction(tmp_path, executor, value, out):
    r = runner(tmp_path, ["TRN(F,G);", "CPT(I,TRN(F)*10);", "TRN(F,D);"], executor)
    names = r.app.program.symbols
    r.table.write(names.resolve_path("F"), value)
    r.run(1)
    read = lambda tag: r.table.read(names.resolve_path(tag))  # noqa: E731
    assert read("G") == out and read("I") == int(out) * 10 and read("D") == int(out)
    r.close()


def test_btd_and_swpb_operand_errors_are_located(tmp_path):
    path = write_l5x(tmp_path / "e.L5X", TAGS, [Prog("P", {"Main": ["BTD(D,32,E,0,4);", "SWPB(D,BYTES,E);",
                                                                    "BTD(F,0,E,0,4);"]})], [Task("T", ["P"])])
    with pytest.raises(AppError) as info:
        load_app(path)
    errors = [str(e) for e in info.value.errors]
    assert "BTD operand '32': expected the source bit as a number from 0 to 31" in errors[0]
    assert "SWPB operand 'BYTES': expected the order mode REVERSE, WORD or HIGH/LOW" in errors[1]
    assert "BTD operand 'F': expected an integer (SINT, INT, DINT)" in errors[2]
