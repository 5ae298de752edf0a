"""Every ladder instruction, its PLC-5 behaviour with concrete values.

Each test runs on both executors (the compiled fast path and the reference
interpreter) through the ``run`` fixture, so both must agree on every value.
docs/instructions.md documents the rules these tests pin down.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from helpers.instr_helpers import flags
from softplc_lite.ladder import Mode, Settings
from softplc_lite.ladder import status as S
from softplc_lite.ladder.instructions import all_specs

BUILTIN = [s.mnemonic for s in all_specs() if s.module is None]





def minor_bits(e) -> set[str]:
    """The minor faults raised: overflow is PLC-5's S:10/14, the others softplc's S:17 bits."""
    s10, s17 = e.table.read("S:10"), e.table.read("S:17")
    names = {S.MINOR_DIV_ZERO_BIT: "div0", S.MINOR_STRING_BIT: "string"}
    found = {name for bit, name in names.items() if s17 >> bit & 1}
    return found | ({"overflow"} if s10 >> S.MINOR_OVERFLOW_BIT & 1 else set())


def timer(e, addr: str = "T4:0") -> tuple[int, int, int, int]:
    t = e.table.read(addr)
    return t["EN"], t["TT"], t["DN"], t["ACC"]


def steps(e, inputs: list[int], probe, bit: str = "B3/0") -> list:
    """Scan once per entry of ``inputs`` (written to ``bit`` first); probe after each."""
    out = []
    for v in inputs:
        e.table.write(bit, v)
        e.scan()
        out.append(probe(e))
    return out


def scans(e, n: int, probe) -> list:
    """Scan ``n`` times; probe after each."""
    out = []
    for _ in range(n):
        e.scan()
        out.append(probe(e))
    return out


def test_every_builtin_instruction_has_a_test():
    # Groups of bound instructions (ladder/instr/) have test files of their own.
    texts = [p.read_text() for p in sorted(Path(__file__).parent.glob("test_*.py"))]
    words = {w for text in texts for name in re.findall(r"^def test_(\w+)", text, re.M) for w in name.split("_")}
    assert [m for m in BUILTIN if m.lower() not in words] == []


def test_every_builtin_instruction_has_a_doc_section_with_an_example():
    doc = (Path(__file__).resolve().parent.parent / "docs" / "instructions.md").read_text()
    sections = dict(re.findall(r"^### ([A-Z]+): .*?\n(.*?)(?=^##)", doc + "\n##", re.M | re.S))
    assert sorted(sections) == sorted(BUILTIN)
    for mnemonic, body in sections.items():
        assert "| operands |" in body and ">>> " in body and mnemonic in body.split(">>> ", 1)[1], mnemonic


# -- bit -------------------------------------------------------------------------------------


@pytest.mark.parametrize("value,out", [(0, 0), (1, 1)])
def test_xic(run, value, out):
    e = run("XIC B3/0 OTE O:0/0\nXIC N7:0/3 OTE O:0/1", values={"B3/0": value, "N7:0": 8 * value})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (out, out)


@pytest.mark.parametrize("value,out", [(0, 1), (1, 0)])
def test_xio(run, value, out):
    e = run("XIO B3/0 OTE O:0/0", values={"B3/0": value})
    assert e.table.read("O:0/0") == out


def test_ote_follows_the_rung_every_scan(run):
    e = run("XIC B3/0 OTE O:0/0", scans=0)
    assert steps(e, [1, 1, 0, 1], lambda e: e.table.read("O:0/0")) == [1, 1, 0, 1]


def test_ote_in_branches(run):
    e = run("XIC B3/0 BST XIO B3/1 NXB XIC B3/2 BND BST OTE O:0/0 NXB OTE O:0/1 BND",
            values={"B3/0": 1, "B3/1": 1, "B3/2": 1})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (1, 1)
    e.table.write("B3/2", 0)
    e.scan()
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (0, 0)


def test_otl_stays_on_when_the_rung_goes_false(run):
    e = run("XIC B3/0 OTL O:0/0", scans=0)
    assert steps(e, [0, 1, 0, 0], lambda e: e.table.read("O:0/0")) == [0, 1, 1, 1]


def test_otu_clears_a_latched_bit_and_leaves_it_when_false(run):
    e = run("XIC B3/0 OTU O:0/0", scans=0, values={"O:0/0": 1})
    assert steps(e, [0, 1, 0], lambda e: e.table.read("O:0/0")) == [1, 0, 0]


def test_ons_passes_one_scan_per_rising_edge(run):
    e = run("XIC B3/0 ONS B3/1 ADD N7:0 1 N7:0", scans=0)
    seen = steps(e, [1, 1, 1, 0, 1], lambda e: (e.table.read("N7:0"), e.table.read("B3/1")))
    assert seen == [(1, 1), (1, 1), (1, 1), (1, 0), (2, 1)]


def test_osr_sets_its_output_bit_for_one_scan(run):
    e = run("XIC B3/0 OSR B3/1 B3/2", scans=0)
    seen = steps(e, [1, 1, 0, 1, 0], lambda e: (e.table.read("B3/2"), e.table.read("B3/1")))
    assert seen == [(1, 1), (0, 1), (0, 0), (1, 1), (0, 0)]


def test_osf_sets_its_output_bit_for_one_scan_on_the_falling_edge(run):
    e = run("XIC B3/0 OSF B3/1 B3/2", scans=0)
    seen = steps(e, [0, 1, 1, 0, 0, 1, 0], lambda e: e.table.read("B3/2"))
    assert seen == [0, 0, 0, 1, 0, 0, 1]


# -- timers --------------------------------------------------------------------------------------


def test_ton_hundredths_scan_by_scan(run):
    # 10 ms per scan, time base 0.01: one tick per scan, counted from the scan after the rung goes true.
    e = run("XIC B3/0 TON T4:0 0.01 3 0", scans=0)
    seen = steps(e, [1, 1, 1, 1, 1, 0], timer)
    assert seen == [(1, 1, 0, 0), (1, 1, 0, 1), (1, 1, 0, 2), (1, 0, 1, 3), (1, 0, 1, 3), (0, 0, 0, 0)]


def test_ton_seconds_base_with_quarter_second_scans(run):
    e = run("XIC B3/0 TON T4:0 1.0 2 0", scans=0, settings=Settings(scan_ms=250))
    seen = steps(e, [1] * 9, timer)
    assert [acc for *_, acc in seen] == [0, 0, 0, 0, 1, 1, 1, 1, 2]
    assert [dn for _, _, dn, _ in seen] == [0] * 8 + [1]
    assert seen[-1] == (1, 0, 1, 2)


def test_ton_seconds_base_keeps_the_fraction_across_scans(run):
    e = run("TON T4:0 1.0 5 0", scans=100)  # scan 1 starts it; 99 scans x 10 ms = 990 ms
    assert timer(e) == (1, 1, 0, 0)
    e.scan()
    assert timer(e) == (1, 1, 0, 1)


def test_ton_several_ticks_per_scan_stop_at_the_preset(run):
    e = run("TON T4:0 0.01 10 0", scans=0, settings=Settings(scan_ms=30))
    assert [t[3] for t in scans(e, 5, timer)] == [0, 3, 6, 9, 10]
    assert timer(e) == (1, 0, 1, 10)


def test_ton_millisecond_base_counts_each_ms(run):
    # MicroLogix 1100's 0.001 base: one tick a millisecond, no fraction to keep.
    e = run("TON T4:0 0.001 7 0", scans=0, settings=Settings(scan_ms=3))
    assert [t[3] for t in scans(e, 4, timer)] == [0, 3, 6, 7]
    assert timer(e) == (1, 0, 1, 7)
    e = run("RTO T4:0 0.001 50 0", scans=4, settings=Settings(scan_ms=2))
    assert e.table.read("T4:0.ACC") == 6
    e = run("XIC B3/0 TOF T4:0 0.001 4 0", scans=0, settings=Settings(scan_ms=1))
    assert [t[2] for t in steps(e, [1, 0, 0, 0, 0, 0], timer)] == [1, 1, 1, 1, 1, 0]


def test_ton_preset_and_accumulator_operands_initialise_the_element(run):
    e = run("XIC B3/0 TON T4:0 0.01 250 7")
    assert e.table.read("T4:0") == {"EN": 0, "TT": 0, "DN": 0, "PRE": 250, "ACC": 0}  # false rung resets ACC
    e = run("TON T4:0 0.01 5 7")
    assert timer(e) == (1, 0, 1, 7)  # ACC already past PRE: done at once


@pytest.mark.parametrize("mnemonic", ["TON", "RTO"])
def test_ton_and_rto_time_on_when_the_preset_of_a_done_timer_is_raised(run, mnemonic):
    e = run(f"{mnemonic} T4:0 0.01 2 0", scans=4)
    assert timer(e) == (1, 0, 1, 2)
    e.table.write("T4:0.PRE", 4)
    seen = scans(e, 3, timer)
    assert seen == [(1, 1, 0, 3), (1, 0, 1, 4), (1, 0, 1, 4)]


def test_ton_negative_preset_faults_with_code_34(run):
    e = run("TON T4:0 1.0 -5 0")
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_NEGATIVE_TIMER == 34
    assert e.table.read("S:12") == 34 and "PRE=-5" in e.fault.message
    assert e.fault.instruction.startswith("TON T4:0")
    e = run("XIC B3/0 TON T4:0 1.0 10 0", values={"T4:0.ACC": -1})
    assert e.fault.code == 34


def test_tof_scan_by_scan_and_retrigger(run):
    e = run("XIC B3/0 TOF T4:0 0.01 3 0", scans=0)
    seen = steps(e, [0, 1, 1, 0, 0, 0, 0, 0], timer)
    assert seen == [(0, 0, 0, 0), (1, 0, 1, 0), (1, 0, 1, 0), (0, 1, 1, 0), (0, 1, 1, 1), (0, 1, 1, 2),
                    (0, 0, 0, 3), (0, 0, 0, 3)]
    # true again while timing: ACC back to 0, DN stays on
    e = run("XIC B3/0 TOF T4:0 0.01 3 0", scans=0)
    assert steps(e, [1, 0, 0, 1], timer)[-1] == (1, 0, 1, 0)


def test_rto_retains_acc_while_false_until_res(run):
    e = run("XIC B3/0 RTO T4:0 0.01 5 0\nXIC B3/1 RES T4:0", scans=0)
    seen = steps(e, [1, 1, 1, 0, 0, 1, 1, 1, 1, 0], timer)
    assert seen == [(1, 1, 0, 0), (1, 1, 0, 1), (1, 1, 0, 2), (0, 0, 0, 2), (0, 0, 0, 2),
                    (1, 1, 0, 2), (1, 1, 0, 3), (1, 1, 0, 4), (1, 0, 1, 5), (0, 0, 1, 5)]
    e.table.write("B3/1", 1)
    e.scan()
    assert timer(e) == (0, 0, 0, 0)


def test_rto_seconds_base(run):
    e = run("XIC B3/0 RTO T4:0 1.0 1 0", scans=0, settings=Settings(scan_ms=500))
    assert [t[3] for t in steps(e, [1, 1, 0, 1, 1], timer)] == [0, 0, 0, 0, 1]


# -- counters ------------------------------------------------------------------------------------


def counter(e, addr: str = "C5:0") -> tuple:
    c = e.table.read(addr)
    return c["CU"], c["CD"], c["DN"], c["OV"], c["UN"], c["ACC"]


def test_ctu_counts_false_to_true_transitions(run):
    e = run("XIC B3/0 CTU C5:0 2 0", scans=0)
    seen = steps(e, [1, 1, 0, 1, 0, 1], counter)
    assert seen == [(1, 0, 0, 0, 0, 1), (1, 0, 0, 0, 0, 1), (0, 0, 0, 0, 0, 1), (1, 0, 1, 0, 0, 2),
                    (0, 0, 1, 0, 0, 2), (1, 0, 1, 0, 0, 3)]


def test_ctu_wraps_at_32767_and_sets_ov(run):
    e = run("XIC B3/0 CTU C5:0 10 32766", scans=0)
    seen = steps(e, [1, 0, 1, 0, 1], counter)
    assert seen[1] == (0, 0, 1, 0, 0, 32767)
    assert seen[2] == (1, 0, 0, 1, 0, -32768)  # DN off: ACC < PRE again
    assert seen[4] == (1, 0, 0, 1, 0, -32767)


def test_ctd_counts_down_and_wraps_at_minus_32768_setting_un(run):
    e = run("XIC B3/0 CTD C5:0 0 1", scans=0)
    assert [c[5] for c in steps(e, [1, 0, 1, 0, 1], counter)] == [0, 0, -1, -1, -2]
    assert counter(e)[2] == 0
    e = run("XIC B3/0 CTD C5:0 0 -32767", scans=0)
    seen = steps(e, [1, 0, 1], counter)
    assert seen[0] == (0, 1, 0, 0, 0, -32768)
    assert seen[2] == (0, 1, 1, 0, 1, 32767)


def test_ctu_and_ctd_on_one_counter_undo_each_others_wrap(run):
    # PLC-5: OV is cleared when a CTD brings an overflowed count back below +32767 (and UN likewise).
    e = run("XIC B3/0 CTU C5:0 0 32767\nXIC B3/1 CTD C5:0 0 32767", scans=0)
    e.table.write("B3/0", 1)
    e.scan()
    assert counter(e) == (1, 0, 0, 1, 0, -32768)
    e.table.write("B3/1", 1)
    e.scan()
    assert counter(e) == (1, 1, 1, 0, 0, 32767)


def test_res_clears_timer_counter_and_control(run):
    e = run("XIC B3/0 RES T4:0\nXIC B3/0 RES C5:0\nXIC B3/0 RES R6:0",
            values={"T4:0": {"EN": 1, "DN": 1, "PRE": 9, "ACC": 9}, "C5:0": {"CU": 1, "OV": 1, "DN": 1, "PRE": 4, "ACC": 5},
                    "R6:0": {"EN": 1, "DN": 1, "LEN": 5, "POS": 3}})
    assert e.table.read("T4:0.ACC") == 9  # false rung: nothing
    e.table.write("B3/0", 1)
    e.scan()
    assert e.table.read("T4:0") == {"EN": 0, "TT": 0, "DN": 0, "PRE": 9, "ACC": 0}
    assert e.table.read("C5:0") == {"CU": 0, "CD": 0, "DN": 0, "OV": 0, "UN": 0, "PRE": 4, "ACC": 0}
    r = e.table.read("R6:0")
    assert (r["EN"], r["DN"], r["LEN"], r["POS"]) == (0, 0, 5, 0)


def test_res_restarts_a_ton(run):
    e = run("TON T4:0 0.01 5 0\nXIC B3/0 RES T4:0", scans=3)
    assert timer(e) == (1, 1, 0, 2)
    seen = steps(e, [1, 0, 0], timer)
    assert seen == [(0, 0, 0, 0), (1, 1, 0, 0), (1, 1, 0, 1)]


# -- compare -------------------------------------------------------------------------------------

COMPARES = [
    ("EQU", 5, 5, 1), ("EQU", 5, 6, 0), ("NEQ", 5, 6, 1), ("NEQ", -1, -1, 0),
    ("LES", -2, 1, 1), ("LES", 1, 1, 0), ("LEQ", 1, 1, 1), ("LEQ", 2, 1, 0),
    ("GRT", 2, 1, 1), ("GRT", 1, 1, 0), ("GEQ", 1, 1, 1), ("GEQ", 0, 1, 0),
]


@pytest.mark.parametrize("mnemonic,a,b,out", COMPARES)
def test_equ_neq_les_leq_grt_geq(run, mnemonic, a, b, out):
    e = run(f"{mnemonic} N7:0 N7:1 OTE O:0/0\n{mnemonic} N7:0 {b} OTE O:0/1", values={"N7:0": a, "N7:1": b})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (out, out)


@pytest.mark.parametrize("mnemonic", ["EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ"])
def test_compare_false_rung_in_stays_false(run, mnemonic):
    e = run(f"XIC B3/0 {mnemonic} 1 1 OTE O:0/0\nXIC B3/0 {mnemonic} 1 2 OTE O:0/1", values={"O:0": -1})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (0, 0)


def test_equ_mixes_floats_and_integers_by_value(run):
    e = run("EQU F8:0 N7:0 OTE O:0/0\nLES F8:1 N7:0 OTE O:0/1\nGRT F8:1 1 OTE O:0/2",
            values={"F8:0": 2.0, "F8:1": 1.5, "N7:0": 2})
    assert [e.table.read(f"O:0/{k}") for k in range(3)] == [1, 1, 1]


@pytest.mark.parametrize("low,test,high,out", [
    (0, 5, 10, 1), (0, 0, 10, 1), (0, 10, 10, 1), (0, 11, 10, 0), (0, -1, 10, 0),
    # low > high: true outside the band (high, low), limits included
    (10, 5, 0, 0), (10, 10, 0, 1), (10, 0, 0, 1), (10, 11, 0, 1), (10, -3, 0, 1),
])
def test_lim(run, low, test, high, out):
    e = run("LIM N7:0 N7:1 N7:2 OTE O:0/0", values={"N7:0": low, "N7:1": test, "N7:2": high})
    assert e.table.read("O:0/0") == out


@pytest.mark.parametrize("source,out", [(0x1212, 1), (0x7F12, 1), (0x1213, 0)])
def test_meq(run, source, out):
    e = run("MEQ N7:0 0x00FF 0x0012 OTE O:0/0", values={"N7:0": source})
    assert e.table.read("O:0/0") == out


@pytest.mark.parametrize("value,out", [(10, 1), (11, 1), (9, 0)])
def test_cmp(run, value, out):
    e = run('CMP "N7:1 >= 10" OTE O:0/0\nCMP "N7:1 * 2 <> N7:1 + 10" OTE O:0/1', values={"N7:1": value})
    assert e.table.read("O:0/0") == out
    assert e.table.read("O:0/1") == int(value != 10)


def test_cmp_expression_divides_with_rounding(run):
    e = run('CMP "7 | 2 = 4" OTE O:0/0\nCMP "-7 | 2 = -4" OTE O:0/1\nXIC B3/0 CMP "1 = 1" OTE O:0/2')
    assert [e.table.read(f"O:0/{k}") for k in range(3)] == [1, 1, 0]


# -- math ----------------------------------------------------------------------------------------


def test_add(run):
    e = run("ADD 2 3 N7:0\nADD F8:0 N7:0 F8:1\nADD 1.5 N7:0 N7:1", values={"F8:0": 1.5})
    assert (e.table.read("N7:0"), e.table.read("F8:1"), e.table.read("N7:1")) == (5, 6.5, 6)  # 6.5: half to even


@pytest.mark.parametrize("a,b,result,flag", [(2, 3, 5, ""), (-3, 3, 0, "CZ"), (-5, 2, -3, "S"), (-1, -1, -2, "CS")])
def test_add_sets_the_arithmetic_flags(run, a, b, result, flag):
    e = run(f"ADD {a} {b} N7:0")
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (result, flag, set())


@pytest.mark.parametrize("overflow,result,flag", [("clamp", 32767, "V"), ("wrap", -32768, "VS")])
def test_add_overflow_clamps_or_wraps_and_sets_the_minor_fault(run, overflow, result, flag):
    e = run("MOV 0 N7:5\nADD 32767 1 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e)) == (result, flag)
    assert minor_bits(e) == {"overflow"} and e.mode is Mode.RUN
    assert (e.table.read("S:102"), e.table.read("S:103"), e.table.read("S:104")) == (S.MINOR_CODE_OVERFLOW, 2, 1)


def test_overflow_sets_plc5_minor_fault_s10_14_not_s17(run):
    # PLC-5 status file (1785-6.5.14 appendix B): S:10 bit 14 is "arithmetic overflow".
    e = run("ADD 32767 1 N7:0")
    assert (e.table.read("S:10"), e.table.read("S:17")) == (1 << 14, 0)
    e = run("MUL 300 300 N7:0\nDIV 1 0 N7:1")
    assert e.table.read("S:10/14") == 1 and e.table.read("S:17") == 1 << S.MINOR_DIV_ZERO_BIT


# -- one rule for integer constants: decimal is a value, hex 0x8000..0xFFFF a bit pattern ---------


@pytest.mark.parametrize("overflow,decimal", [("clamp", 32767), ("wrap", -25536)])
def test_mov_decimal_40000_overflows_like_70000(run, overflow, decimal):
    e = run("MOV 40000 N7:0\nMOV 0x9C40 N7:1", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (decimal, -25536)
    e = run("MOV 40000 N7:0", settings=Settings(overflow=overflow))
    assert "V" in flags(e) and minor_bits(e) == {"overflow"}
    e = run("MOV 70000 N7:0", settings=Settings(overflow=overflow))
    assert e.table.read("N7:0") == (32767 if overflow == "clamp" else 70000 - 65536) and "V" in flags(e)
    e = run("MOV 0xFFFF N7:0\nMOV 65535 F8:0")
    assert (e.table.read("N7:0"), e.table.read("F8:0"), flags(e)) == (-1, 65535.0, "")


@pytest.mark.parametrize("text,column,message", [
    ("AND N7:0 40000 N7:1", 10, "AND operand 2 (b): 40000 does not fit a 16-bit word (decimal -32768..32767); "
                                "for the 16-bit pattern write 0x9C40"),
    ("MEQ N7:0 65535 N7:1 OTE B3/0", 10, "MEQ operand 2 (mask): 65535 does not fit a 16-bit word (decimal "
                                         "-32768..32767); for the 16-bit pattern write 0xFFFF"),
    ("AND N7:0 70000 N7:1", 10, "AND operand 2 (b): 70000 does not fit a 16-bit word (decimal -32768..32767)"),
    ("DATA N7 3 = 1 40000 3\nNOP", 1, "DATA N7: 40000 does not fit a 16-bit word (decimal -32768..32767); "
                                      "for the 16-bit pattern write 0x9C40"),
])
def test_a_decimal_constant_a_word_cannot_hold_is_a_located_error(text, column, message):
    from softplc_lite.ladder import ProgramErrors, load_text

    with pytest.raises(ProgramErrors) as info:
        load_text(text, source="demo.lad")
    assert str(info.value.errors[0]) == f"demo.lad:1:{column}: {message}"


def test_hex_bit_patterns_go_where_a_word_goes(run):
    e = run("DATA N7 3 = 1 0x9C40 0xFFFF\nAND N7:1 0xFF00 N7:2\nMEQ N7:1 0x8000 0x8000 OTE B3/0")
    assert [e.table.read(f"N7:{k}") for k in range(3)] == [1, -25536, -25600] and e.table.read("B3/0") == 1


def test_constant_fits_says_what_a_store_will_do():
    from softplc_lite.datatable import parse_address
    from softplc_lite.ladder.ast import Const
    from softplc_lite.ladder.validate import constant_fits

    n7, f8 = parse_address("N7:0"), parse_address("F8:0")
    assert constant_fits(Const(40000), n7) == "40000 cannot fit N7:0, it will be stored as 32767 with overflow"
    assert constant_fits(Const(-40000), n7) == "-40000 cannot fit N7:0, it will be stored as -32768 with overflow"
    wrapped = constant_fits(Const(40000), n7, "wrap")
    assert wrapped == "40000 cannot fit N7:0, it will be stored as -25536 with overflow"
    assert constant_fits(Const(40000, hex=True), n7) is None
    assert constant_fits(Const(32767), n7) is None and constant_fits(Const(40000), f8) is None
    assert constant_fits(Const(1.5), n7) is None


def test_fmt_prints_hex_constants_in_hex():
    from softplc_lite.ladder import load_text
    from softplc_lite.ladder.fmt import format_program
    from softplc_lite.ladder.parser import parse_program

    text = "MOV 0xFFFF N7:0\nAND N7:0 0x00ff N7:1\nMOV 40000 N7:2\nMOV -0x10 N7:3\n"
    printed = format_program(parse_program(text))
    assert "MOV 0xFFFF N7:0" in printed and "AND N7:0 0xFF N7:1" in printed
    assert "MOV 40000 N7:2" in printed and "MOV -16 N7:3" in printed
    assert "MOV 0xFFFF N7:0" in format_program(load_text(text))  # validated: holds -1, still printed as written
    assert parse_program(printed) == parse_program(text)


def test_add_false_rung_leaves_dest_and_flags(run):
    e = run("XIC B3/0 ADD 32767 1 N7:0", values={"N7:0": 9})
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (9, "", set())


@pytest.mark.parametrize("overflow,result,flag", [("clamp", -32768, "VS"), ("wrap", 32767, "V")])
def test_sub(run, overflow, result, flag):
    e = run("SUB 2 5 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e)) == (-3, "CS")  # borrow
    e = run("SUB -32768 1 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (result, flag, {"overflow"})
    e = run("SUB F8:0 0.25 F8:0", values={"F8:0": 1.0})
    assert e.table.read("F8:0") == 0.75


@pytest.mark.parametrize("overflow,result", [("clamp", 32767), ("wrap", 90000 - 65536)])
def test_mul(run, overflow, result):
    e = run("MUL 6 -7 N7:0\nMUL 2.5 2 F8:0")
    assert (e.table.read("N7:0"), e.table.read("F8:0")) == (-42, 5.0)
    e = run("MUL 300 300 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (result, "V", {"overflow"})


def test_mul_float_overflow_gives_infinity(run):
    e = run("MUL F8:0 F8:0 F8:1", values={"F8:0": 1e30})
    assert e.table.read("F8:1") == math.inf and flags(e) == "V" and minor_bits(e) == {"overflow"}


@pytest.mark.parametrize("a,b,result", [(7, 2, 4), (-7, 2, -4), (7, -2, -4), (5, 2, 3), (9, 4, 2), (1, 3, 0), (6, 3, 2)])
def test_div_integers_round_half_away_from_zero(run, a, b, result):
    e = run(f"DIV {a} {b} N7:0")
    assert e.table.read("N7:0") == result
    assert flags(e) == ("Z" if result == 0 else "S" if result < 0 else "")


def test_div_floats(run):
    e = run("DIV 7.0 2 F8:0\nDIV F8:1 4 N7:0\nDIV 7 2 F8:2", values={"F8:1": 10.0})
    assert (e.table.read("F8:0"), e.table.read("N7:0")) == (3.5, 2)  # a float 2.5: half to even
    assert e.table.read("F8:2") == 4.0  # integer operands: rounded integer quotient (softplc choice)


@pytest.mark.parametrize("overflow", ["clamp", "wrap"])
@pytest.mark.parametrize("a,result,flag", [(5, 32767, "V"), (-5, -32768, "VS"), (0, 32767, "V")])
def test_div_by_zero_default_is_an_overflow(run, overflow, a, result, flag):
    e = run(f"DIV {a} N7:1 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e)) == (result, flag)
    assert minor_bits(e) == {"overflow", "div0"} and e.mode is Mode.RUN


def test_div_by_zero_into_a_float_stores_infinity(run):
    e = run("DIV 5.0 0 F8:0\nDIV -5 0 F8:1")
    assert (e.table.read("F8:0"), e.table.read("F8:1")) == (math.inf, -math.inf)
    assert flags(e) == "VS" and minor_bits(e) == {"overflow", "div0"}


def test_div_by_zero_fault_setting_is_a_major_fault(run):
    e = run("MOV 1 N7:1\nDIV 5 N7:2 N7:0", settings=Settings(divide_by_zero="fault"))
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_DIV_ZERO
    assert (e.fault.file, e.fault.rung) == (2, 1) and e.fault.instruction.startswith("DIV 5 N7:2 N7:0")
    assert e.table.read("S:12") == S.FAULT_DIV_ZERO and e.table.read("N7:0") == 0


@pytest.mark.parametrize("a,b,result", [(7, 3, 1), (-7, 3, -1), (7, -3, 1), (6, 3, 0)])
def test_mod_remainder_has_the_sign_of_the_dividend(run, a, b, result):
    e = run(f"MOD {a} {b} N7:0")
    assert e.table.read("N7:0") == result


def test_mod_floats_and_by_zero(run):
    e = run("MOD 7.5 2 F8:0\nMOD 5 0 N7:0")
    assert (e.table.read("F8:0"), e.table.read("N7:0")) == (1.5, 32767)
    assert minor_bits(e) == {"overflow", "div0"}
    e = run("MOD F8:0 2 F8:1", values={"F8:0": math.inf})  # no remainder of infinity: NaN, overflow
    assert math.isnan(e.table.read("F8:1")) and e.mode is Mode.RUN and "V" in flags(e)


@pytest.mark.parametrize("overflow,result,flag", [("clamp", 32767, "V"), ("wrap", -32768, "VS")])
def test_neg(run, overflow, result, flag):
    e = run("NEG 5 N7:0\nNEG F8:0 F8:1", values={"F8:0": -2.5})
    assert (e.table.read("N7:0"), e.table.read("F8:1"), flags(e)) == (-5, 2.5, "")
    e = run("NEG -32768 N7:0", settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (result, flag, {"overflow"})


# SLC 500 / MicroLogix NEG (SLC 500 HHT manual 1747-PT1 ch. 20, MicroLogix 1000 user manual):
# carry is cleared if the source is 0 or the result overflows, otherwise set.
@pytest.mark.parametrize("source,result,flag", [(5, -5, "CS"), (-7, 7, "C"), (0, 0, "Z"), (32767, -32767, "CS"),
                                                (-32768, 32767, "V")])
def test_neg_sets_carry_unless_the_source_is_0_or_it_overflows(run, source, result, flag):
    e = run("NEG N7:1 N7:0", values={"N7:1": source, "S:0": 1})
    assert (e.table.read("N7:0"), flags(e)) == (result, flag)


def test_abs(run):
    e = run("ABS -5 N7:0\nABS F8:0 F8:1\nABS 7 N7:1", values={"F8:0": -2.5})
    assert (e.table.read("N7:0"), e.table.read("F8:1"), e.table.read("N7:1")) == (5, 2.5, 7)
    e = run("ABS -32768 N7:0")
    assert (e.table.read("N7:0"), flags(e)) == (32767, "V")


def test_sqr(run):
    e = run("SQR 16 N7:0\nSQR 10 N7:1\nSQR 2 F8:0\nSQR -16 N7:2\nSQR 0 N7:3")
    assert [e.table.read(f"N7:{k}") for k in range(4)] == [4, 3, 4, 0]  # negative: root of |x|
    assert e.table.read("F8:0") == pytest.approx(1.4142135)
    assert flags(e) == "Z"


def test_cpt(run):
    e = run('CPT N7:0 "N7:1 * 2 + 5"\nCPT N7:2 "N7:1 ** 2 - SQR(16) + ABS(-3)"\nCPT F8:0 "N7:1 | 4"\n'
            'CPT F8:1 "F8:2 * 2"\nCPT N7:3 "(N7:1 AND 6) XOR 1"\nCPT N7:4 "NOT 0"',
            values={"N7:1": 10, "F8:2": 1.25})
    assert [e.table.read(f"N7:{k}") for k in (0, 2, 3, 4)] == [25, 99, 3, -1]
    assert (e.table.read("F8:0"), e.table.read("F8:1")) == (3.0, 2.5)  # 10 | 4 = 2.5 rounds to 3


def test_cpt_overflow_and_divide_by_zero(run):
    e = run('CPT N7:0 "N7:1 * 10000"', values={"N7:1": 10})
    assert (e.table.read("N7:0"), flags(e)) == (32767, "V")
    e = run('CPT N7:0 "N7:1 | N7:2 + 1"', values={"N7:1": 10}, settings=Settings(divide_by_zero="fault"))
    assert e.fault.code == S.FAULT_DIV_ZERO and "CPT" in e.fault.instruction


def test_cpt_results_without_a_real_value_overflow(run):
    e = run('CPT N7:0 "N7:1 ** 0.5"\nCPT F8:0 "N7:1 ** 0.5"\nCMP "N7:1 ** 0.5 > 1" OTE O:0/0\nCPT N7:2 "10 ** 400"',
            values={"N7:1": -8, "O:0/0": 1})
    assert e.fault is None and e.table.read("N7:0") == 0 and math.isnan(e.table.read("F8:0"))
    assert (e.table.read("O:0/0"), e.table.read("N7:2"), flags(e)) == (0, 32767, "V")


def test_clr(run):
    e = run("CLR N7:0\nCLR F8:0\nXIC B3/0 CLR N7:1", values={"N7:0": 5, "F8:0": 2.5, "N7:1": 5})
    assert (e.table.read("N7:0"), e.table.read("F8:0"), e.table.read("N7:1"), flags(e)) == (0, 0.0, 5, "Z")


def test_and(run):
    e = run("AND 0x0F0F 0x00FF N7:0\nAND -1 N7:2 N7:1", values={"N7:2": 0x7FFF})
    assert (e.table.read("N7:0"), e.table.read("N7:1"), flags(e)) == (0x000F, 0x7FFF, "")
    e = run("AND 0x0F00 0x00F0 N7:0")
    assert (e.table.read("N7:0"), flags(e)) == (0, "Z")


def test_or(run):
    e = run("OR 0x0F00 0x00F0 N7:0\nOR 0x8000 0 N7:1")
    assert (e.table.read("N7:0"), e.table.read("N7:1"), flags(e)) == (0x0FF0, -32768, "S")


def test_xor(run):
    e = run("XOR 0xFF 0x0F N7:0")
    assert (e.table.read("N7:0"), flags(e)) == (0xF0, "")
    e = run("XOR N7:1 N7:1 N7:0", values={"N7:1": 1234})
    assert (e.table.read("N7:0"), flags(e)) == (0, "Z")


def test_not(run):
    e = run("NOT 0 N7:0\nNOT 0x00FF N7:1")
    assert (e.table.read("N7:0"), e.table.read("N7:1"), flags(e)) == (-1, -256, "S")


# -- move and file -------------------------------------------------------------------------------


@pytest.mark.parametrize("source,result", [("3.7", 4), ("2.5", 2), ("-2.5", -2), ("3.5", 4), ("-3.2", -3), ("0.49", 0)])
def test_mov_float_to_integer_rounds_half_to_even(run, source, result):
    e = run(f"MOV {source} N7:0")
    assert e.table.read("N7:0") == result


def test_mov(run):
    e = run("MOV N7:1 F8:0\nMOV -5 N7:2\nMOV 0x8000 N7:3", values={"N7:1": 4})
    assert (e.table.read("F8:0"), e.table.read("N7:2"), e.table.read("N7:3"), flags(e)) == (4.0, -5, -32768, "S")
    e = run("MOV 0 N7:0", values={"N7:0": 3})
    assert (e.table.read("N7:0"), flags(e)) == (0, "Z")


@pytest.mark.parametrize("value,overflow,result,flag", [
    (40000.0, "clamp", 32767, "V"), (40000.0, "wrap", 40000 - 65536, "VS"), (-1e9, "clamp", -32768, "VS"),
    # infinity has no low 16 bits: the extreme of its sign in both modes; NaN stores 0
    (math.inf, "wrap", 32767, "V"), (-math.inf, "clamp", -32768, "VS"), (math.nan, "clamp", 0, "VZ"),
])
def test_mov_float_out_of_integer_range_overflows(run, value, overflow, result, flag):
    e = run("MOV F8:0 N7:0", values={"F8:0": value}, settings=Settings(overflow=overflow))
    assert (e.table.read("N7:0"), flags(e), minor_bits(e)) == (result, flag, {"overflow"})


def test_mvm(run):
    e = run("MVM 0x1234 0x00FF N7:0\nXIC B3/0 MVM 0 -1 N7:1", values={"N7:0": 0x5678, "N7:1": 7})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (0x5634, 7)


def test_cop(run):
    e = run("COP #N7:0 #N7:10 3", values={"N7:0": 1, "N7:1": 2, "N7:2": 3, "N7:3": 4, "N7:13": 0})
    assert [e.table.read(f"N7:{k}") for k in range(10, 14)] == [1, 2, 3, 0]
    e = run("COP #N7:0 #N7:1 3", values={"N7:0": 1, "N7:1": 2, "N7:2": 3, "N7:3": 4})
    assert [e.table.read(f"N7:{k}") for k in range(4)] == [1, 1, 2, 3]  # overlapping: source read whole first
    e = run("COP #F8:0 #F8:2 2", values={"F8:0": 1.5, "F8:1": -2.0})
    assert (e.table.read("F8:2"), e.table.read("F8:3")) == (1.5, -2.0)


def test_cop_between_float_and_word_files_copies_memory(run):
    e = run("COP #F8:0 #N7:0 2\nCOP #N7:0 #F8:5 1", values={"F8:0": 1.5})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (0, 0x3FC0)  # float32 1.5, low word first
    assert e.table.read("F8:5") == 1.5


def test_cop_block_past_the_end_faults(run):
    e = run("COP #N7:[N7:0] #N7:10 3", values={"N7:0": 11, "N7:12": 0})
    assert e.fault.code == S.FAULT_BLOCK_RANGE and "COP" in e.fault.instruction


def test_fll(run):
    e = run("FLL 7 #N7:0 3\nFLL 2.5 #N7:5 2\nFLL N7:9 #F8:0 2\nXIC B3/0 FLL 1 #N7:10 1",
            values={"N7:3": 9, "N7:9": 4, "N7:10": 5})
    assert [e.table.read(f"N7:{k}") for k in (0, 1, 2, 3, 5, 6, 10)] == [7, 7, 7, 9, 2, 2, 5]  # 2.5: half to even
    assert (e.table.read("F8:0"), e.table.read("F8:1")) == (4.0, 4.0)


def test_fll_out_of_range_value_is_clamped_or_wrapped(run):
    e = run("FLL 40000.0 #N7:0 2")
    assert e.table.read("N7:1") == 32767
    e = run("FLL 40000.0 #N7:0 2", settings=Settings(overflow="wrap"))
    assert e.table.read("N7:1") == 40000 - 65536


@pytest.mark.parametrize("value,result", [(math.inf, 32767), (-math.inf, -32768), (math.nan, 0)])
def test_fll_non_finite_float_into_integers(run, value, result):
    e = run("FLL F8:0 #N7:0 2", values={"F8:0": value})
    assert (e.table.read("N7:1"), e.fault) == (result, None)


def test_fll_indirect_block_past_the_end_faults(run):
    e = run("FLL 0 #N7:[N7:0] 5", values={"N7:0": 10, "N7:19": 0})
    assert e.mode is Mode.RUN
    e = run("FLL 0 #N7:[N7:0] 5", values={"N7:0": 18, "N7:19": 0})
    assert e.fault.code == S.FAULT_BLOCK_RANGE


def test_btd(run):
    e = run("BTD 0x00F0 4 N7:0 8 4\nBTD 0x0005 0 N7:1 1 3", values={"N7:0": 0x0001, "N7:1": -1})
    assert e.table.read("N7:0") == 0x0F01
    assert e.table.read("N7:1") == -5  # 0xFFFF with bits 1..3 <- 0b101: 0xFFFB
    # bits past the end of the destination word are lost (no wrap into the next word)
    e = run("BTD -1 0 N7:0 12 8", values={"N7:1": 0})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (-4096, 0)


# -- program control -----------------------------------------------------------------------------


@pytest.mark.parametrize("jump,n0", [(1, 0), (0, 1)])
def test_jmp_skips_rungs_to_its_label(run, jump, n0):
    e = run("XIC B3/0 JMP 5\nMOV 1 N7:0\nLBL 5 MOV 2 N7:1", values={"B3/0": jump})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (n0, 2)


def test_jmp_backward_loop_runs_until_its_condition_fails(run):
    e = run("LBL 1 ADD N7:0 1 N7:0\nLES N7:0 10 JMP 1")
    assert e.table.read("N7:0") == 10 and e.mode is Mode.RUN


def test_jmp_backward_forever_faults_by_watchdog(run):
    e = run("LBL 1 ADD N7:0 1 N7:0\nJMP 1", settings=Settings(watchdog_ms=20))
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_WATCHDOG
    assert e.table.read("S:11") >> S.MAJOR_WATCHDOG_BIT & 1 and e.table.read("S:12") == S.FAULT_WATCHDOG
    assert e.fault.file == 2 and "JMP" in e.fault.message


def test_lbl_rung_runs_its_own_logic(run):
    e = run("LBL 3 XIC B3/0 OTE O:0/0\nLBL 4 OTE O:0/1", values={"B3/0": 1})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (1, 1)


SUBROUTINE = """\
JSR 3
MOV N7:0 N7:1
XIC B3/1 JSR 4
FILE 3
SBR
ADD N7:0 1 N7:0
XIC B3/0 RET
ADD N7:0 10 N7:0
FILE 4
SBR
MOV 99 N7:2
"""


@pytest.mark.parametrize("ret,n0", [(1, 1), (0, 11)])
def test_jsr_sbr_ret(run, ret, n0):
    e = run(SUBROUTINE, values={"B3/0": ret})
    assert (e.table.read("N7:0"), e.table.read("N7:1"), e.table.read("N7:2")) == (n0, n0, 0)
    e.table.write("B3/1", 1)
    e.scan()
    assert e.table.read("N7:2") == 99


def test_sbr_and_ret_in_a_nested_call(run):
    e = run("JSR 3\nFILE 3\nSBR\nJSR 4\nADD N7:0 1 N7:0\nFILE 4\nSBR\nRET\nMOV 5 N7:0")
    assert e.table.read("N7:0") == 1 and e.mode is Mode.RUN


def test_ret_unconditional_ends_the_subroutine(run):
    e = run("JSR 3\nFILE 3\nSBR\nRET\nMOV 5 N7:0")
    assert e.table.read("N7:0") == 0


def test_jsr_nesting_too_deep_faults_with_code_30(run):
    e = run("JSR 3\nFILE 3\nADD N7:0 1 N7:0\nJSR 3")
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_JSR_NESTING == 30
    assert e.table.read("N7:0") == Settings().jsr_depth
    assert e.fault.file == 3 and e.fault.rung == 1 and "JSR 3" in e.fault.message
    assert "program file 3, rung 1" in str(e.fault)


def test_mcr_zone_de_energizes_ote_and_leaves_latches(run):
    text = "XIC B3/0 MCR\nXIC B3/1 OTE O:0/0\nXIC B3/1 OTL O:0/1\nXIC B3/1 TON T4:0 0.01 9 0\nMCR\nXIC B3/1 OTE O:0/2"
    e = run(text, scans=3, values={"B3/0": 1, "B3/1": 1})
    assert [e.table.read(f"O:0/{k}") for k in range(3)] == [1, 1, 1] and timer(e)[3] == 2
    e.table.write("B3/0", 0)
    e.scan()
    assert [e.table.read(f"O:0/{k}") for k in range(3)] == [0, 1, 1]  # OTE off, OTL kept, after the zone: on
    assert timer(e) == (0, 0, 0, 0)  # a TON in a false zone resets


def test_afi(run):
    e = run("AFI OTE O:0/0\nBST AFI NXB XIC B3/0 BND OTE O:0/1", values={"O:0/0": 1, "B3/0": 1})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (0, 1)


@pytest.mark.parametrize("end,n0", [(1, 0), (0, 1)])
def test_tnd(run, end, n0):
    e = run("MOV 7 N7:1\nXIC B3/0 TND\nMOV 1 N7:0", values={"B3/0": end})
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (n0, 7)


def test_tnd_inside_a_subroutine_ends_the_whole_scan(run):
    e = run("JSR 3\nMOV 1 N7:0\nFILE 3\nSBR\nXIC B3/0 TND\nMOV 2 N7:1", values={"B3/0": 1})
    assert (e.table.read("N7:0"), e.table.read("N7:1"), e.fault) == (0, 0, None)


# -- run-time faults -----------------------------------------------------------------------------


def test_indirect_address_out_of_range_faults_with_code_20(run):
    e = run("MOV 1 N7:1\nMOV N7:[N7:0] N7:1", values={"N7:0": 50})
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_INDIRECT_RANGE == 20
    assert (e.fault.file, e.fault.rung) == (2, 1)
    assert e.fault.instruction.startswith("MOV N7:[N7:0] N7:1")
    text = str(e.fault)
    assert "program file 2, rung 1" in text and "MOV N7:[N7:0] N7:1" in text and "element 50" in text
    assert (e.table.read("S:12"), e.table.read("S:13"), e.table.read("S:14")) == (20, 2, 1)
    assert e.table.read("S:11") >> S.MAJOR_RUNTIME_BIT & 1


def test_indexed_bit_in_a_contact_out_of_range_faults_too(run):
    e = run("XIC B3/[N7:0] OTE O:0/0", values={"N7:0": 500})
    assert e.fault.code == 20 and e.fault.instruction.startswith("XIC")


def test_indirect_file_number_naming_no_file_faults_with_code_24(run):
    e = run("MOV N[N7:0]:0 N7:1", values={"N7:0": 99})
    assert e.fault.code == S.FAULT_INDIRECT_FILE == 24 and "N99" in e.fault.message


@pytest.mark.parametrize("index,code", [(1, None), (5, 20)])
def test_indexed_address_uses_the_index_register_s24(run, index, code):
    e = run("MOV #N7:0 N7:2", values={"S:24": index, "N7:1": 42})
    assert (e.fault.code if e.fault else None) == code
    assert e.table.read("N7:2") == (42 if code is None else 0)


# -- strings -------------------------------------------------------------------------------------


# SLC 500 ACI (1747-RM001, ASCII instructions): skip to the first digit, commas allowed, a sign
# right before the first digit counts; no digit: nothing stored; out of range: overflow and 32767.
@pytest.mark.parametrize("text,value,errors,flag", [
    ("42", 42, set(), ""), ("  -123abc", -123, set(), "S"), ("+7", 7, set(), ""),
    ("T=123", 123, set(), ""), ("1,234", 1234, set(), ""), ("-1,234,5", -12345, set(), "S"),
    ("T=-45 degrees", -45, set(), "S"), ("- 5", 5, set(), ""), ("x9y8", 9, set(), ""), ("007", 7, set(), ""),
    ("abc", 5, {"string"}, "C"), ("", 5, {"string"}, "C"), ("-", 5, {"string"}, "C"), (",,", 5, {"string"}, "C"),
    ("99999", 32767, {"overflow", "string"}, "V"), ("-40000", -32768, {"overflow", "string"}, "VS"),
    ("32,767", 32767, set(), ""), ("-32768", -32768, set(), "S"), ("0", 0, set(), "Z")])
def test_aci(run, text, value, errors, flag):
    # S:0/0 carry is set beforehand: an ACI that finds no digit leaves S:0 (and the destination) alone.
    e = run("ACI ST9:0 N7:0", values={"ST9:0": text, "N7:0": 5, "S:0": 1})
    assert (e.table.read("N7:0"), minor_bits(e), flags(e)) == (value, errors, flag)
    if errors:
        assert e.table.read("S:102") == (S.MINOR_CODE_OVERFLOW if "overflow" in errors else S.MINOR_CODE_STRING)


def test_aci_out_of_range_is_32767_in_both_overflow_modes(run):
    e = run("ACI ST9:0 N7:0", values={"ST9:0": "70000"}, settings=Settings(overflow="wrap"))
    assert e.table.read("N7:0") == 32767 and flags(e) == "V"


def test_aci_into_a_float(run):
    e = run("ACI ST9:0 F8:0", values={"ST9:0": "12"})
    assert e.table.read("F8:0") == 12.0


def test_aic(run):
    e = run("AIC 123 ST9:0\nAIC -5 ST9:1\nAIC N7:0 ST9:2\nXIC B3/0 AIC 1 ST9:3", values={"N7:0": -32768, "ST9:3": "x"})
    assert [e.table.read(f"ST9:{k}") for k in range(4)] == ["123", "-5", "-32768", "x"]
    assert e.table.read("ST9:0.LEN") == 3


def test_acn(run):
    e = run("ACN ST9:0 ST9:1 ST9:2", values={"ST9:0": "abc", "ST9:1": "def"})
    assert e.table.read("ST9:2") == "abcdef" and minor_bits(e) == set()


def test_acn_longer_than_82_characters_is_cut_and_flagged(run):
    e = run("ACN ST9:0 ST9:1 ST9:2", values={"ST9:0": "a" * 50, "ST9:1": "b" * 50})
    assert e.table.read("ST9:2") == "a" * 50 + "b" * 32 and minor_bits(e) == {"string"}


@pytest.mark.parametrize("index,count,result,errors", [(7, 5, "world", set()), (1, 5, "Hello", set()),
                                                       (11, 1, "d", set()), (1, 0, "", set()),
                                                       (0, 3, "old", {"string"}), (10, 5, "old", {"string"}),
                                                       (1, -1, "old", {"string"})])
def test_aex(run, index, count, result, errors):
    e = run(f"AEX ST9:0 {index} {count} ST9:1", values={"ST9:0": "Hello world", "ST9:1": "old"})
    assert e.table.read("ST9:1") == result and minor_bits(e) == errors


# AB order (1747-RM001 ASC): Source = the string searched for, Index, String Search = the string
# examined, Result. Not found: 0. Index outside the examined string or an empty source: the string
# error and the result unchanged.
@pytest.mark.parametrize("index,search,result,errors", [(1, "o", 5, set()), (6, "o", 8, set()), (1, "world", 7, set()),
                                                        (11, "d", 11, set()), (1, "z", 0, set()), (9, "o", 0, set()),
                                                        (1, "Hello world!", 0, set()),
                                                        (0, "o", 99, {"string"}), (12, "o", 99, {"string"}),
                                                        (1, "", 99, {"string"})])
def test_asc(run, index, search, result, errors):
    e = run(f"ASC ST9:1 {index} ST9:0 N7:0", values={"ST9:0": "Hello world", "ST9:1": search, "N7:0": 99})
    assert e.table.read("N7:0") == result and minor_bits(e) == errors


def test_asc_neutral_text_takes_the_same_ab_operand_order(run):
    e = run('ASC(ST9:1,1,ST9:0,N7:0);', values={"ST9:0": "T=123", "ST9:1": "="})
    assert e.table.read("N7:0") == 2


@pytest.mark.parametrize("a,b,out", [("abc", "abc", 1), ("abc", "abd", 0), ("abc", "abcd", 0), ("", "", 1),
                                     ("ABC", "abc", 0)])
def test_asr(run, a, b, out):
    e = run("ASR ST9:0 ST9:1 OTE O:0/0\nXIC B3/0 ASR ST9:0 ST9:0 OTE O:0/1", values={"ST9:0": a, "ST9:1": b})
    assert (e.table.read("O:0/0"), e.table.read("O:0/1")) == (out, 0)


# -- both rung syntaxes --------------------------------------------------------------------------


def test_neutral_text_runs_like_mnemonic(run):
    values = {"B3/0": 1, "B3/1": 1, "B3/2": 1, "N7:1": 10}
    a = run('XIC B3/0 BST XIO B3/1 NXB XIC B3/2 BND OTE O:0/0\nCPT N7:0 "N7:1 * 2 + 5"', values=values)
    b = run("XIC(B3/0)[XIO(B3/1),XIC(B3/2)]OTE(O:0/0);\nCPT(N7:0, N7:1 * 2 + 5);", values=values)
    assert a.table == b.table and a.table.read("O:0/0") == 1 and a.table.read("N7:0") == 25


def test_a_minor_fault_after_a_jsr_in_the_same_rung_names_the_callers_rung(run):
    # The JSR's subroutine ran rungs of file 3; the overflow after it is in file 2, rung 1.
    e = run("MOV 1 N7:1\nJSR 3 ADD 32767 N7:1 N7:0\nFILE 3\nSBR\nMOV 2 N7:2\nMOV 3 N7:3\n")
    assert e.table.read("S:10/14") == 1
    assert (e.table.read("S:103"), e.table.read("S:104")) == (2, 1)
