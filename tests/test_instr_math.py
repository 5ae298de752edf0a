"""Math functions and conversions as instructions:
SIN COS TAN ASN ACS ATN LN LOG, XPY, DDV, SCL, SCP (ladder/instr/mathfn.py)
and TOD, FRD, SWP, DCD, ENC (ladder/instr/convert.py).

Every test runs on both executors through the ``run`` fixture; the
hypothesis tests at the end run random operands on both and compare the
whole tables. docs/instructions.md has the rules and their AB sources.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers.instr_helpers import flags
from helpers.words import signed
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Mode, Settings, run_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.errors import ProgramErrors
from softplc_lite.ladder.fmt import format_program
from softplc_lite.ladder.parser import parse_program

EXECUTORS = ("compiled", "reference")





def overflow_fault(e) -> bool:
    """The overflow minor fault: its code in S:102 and its bit."""
    return e.table.read("S:102") == S.MINOR_CODE_OVERFLOW


def f32(x: float) -> float:
    """x as a float file stores it."""
    from array import array
    return array("f", [x])[0]


# -- the eight functions ------------------------------------------------------------------

FUNCS = {"SIN": math.sin, "COS": math.cos, "TAN": math.tan, "ASN": math.asin, "ACS": math.acos,
         "ATN": math.atan, "LN": math.log, "LOG": math.log10}


@pytest.mark.parametrize("name", sorted(FUNCS))
def test_sin_cos_tan_asn_acs_atn_ln_log_compute_in_radians_into_floats(run, name):
    e = run(f"{name} F8:0 F8:1", values={"F8:0": 0.5})
    assert e.table.read("F8:1") == f32(FUNCS[name](f32(0.5)))
    assert not overflow_fault(e)
    assert "V" not in flags(e)


@pytest.mark.parametrize("name", sorted(FUNCS))
def test_sin_cos_tan_asn_acs_atn_ln_log_agree_with_cpt(run, name):
    e = run(f'{name} F8:0 F8:1\nCPT F8:2 "{name}(F8:0)"\n{name} N7:0 N7:1\nCPT N7:2 "{name}(N7:0)"',
            values={"F8:0": 0.75, "N7:0": 1})
    assert e.table.read("F8:1") == e.table.read("F8:2")
    assert e.table.read("N7:1") == e.table.read("N7:2")


def test_sin_cos_into_words_round_to_the_nearest_integer(run):
    # sin(2) = 0.909 -> 1; cos(2) = -0.416 -> 0; atan(-10) = -1.47 -> -1; ln(20) = 2.996 -> 3
    e = run("SIN 2 N7:0\nCOS 2 N7:1\nATN -10 N7:2\nLN 20 N7:3\nLOG 1000 N7:4")
    assert [e.table.read(f"N7:{k}") for k in range(5)] == [1, 0, -1, 3, 3]


def test_tan_flags_zero_and_sign(run):
    e = run("TAN 0 F8:0")
    assert e.table.read("F8:0") == 0.0 and flags(e) == "Z"
    e = run("TAN -0.5 F8:0")
    assert e.table.read("F8:0") < 0 and flags(e) == "S"


@pytest.mark.parametrize("text", ["ASN 2 F8:0", "ACS -1.5 F8:0", "LN 0 F8:0", "LN -3 F8:0", "LOG -1 F8:0"])
def test_asn_acs_ln_log_outside_their_domain_overflow_into_a_float(run, text):
    e = run(text)
    assert math.isnan(e.table.read("F8:0"))
    assert "V" in flags(e) and overflow_fault(e)


@pytest.mark.parametrize("text", ["ASN 2 N7:0", "LN 0 N7:0", "LOG -5 N7:0"])
def test_asn_ln_log_outside_their_domain_store_0_with_overflow_into_a_word(run, text):
    e = run(text, values={"N7:0": 99})
    assert e.table.read("N7:0") == 0
    assert "V" in flags(e) and overflow_fault(e)


def test_asn_acs_at_the_domain_edges_are_fine(run):
    e = run("ASN 1 F8:0\nACS -1 F8:1")
    assert e.table.read("F8:0") == f32(math.pi / 2) and e.table.read("F8:1") == f32(math.pi)
    assert not overflow_fault(e)


def test_sin_does_nothing_on_a_false_rung(run):
    e = run("XIC B3/0 SIN 1.0 F8:0", values={"F8:0": 7.0, "B3/0": 0})
    assert e.table.read("F8:0") == 7.0


# -- XPY -------------------------------------------------------------------------------

def test_xpy_raises_a_to_b(run):
    e = run("XPY 2 3 N7:0\nXPY 2 0.5 F8:0\nXPY N7:1 2 N7:2\nXPY 2 -1 F8:1", values={"N7:1": -3})
    assert e.table.read("N7:0") == 8
    assert e.table.read("F8:0") == f32(math.sqrt(2))
    assert e.table.read("N7:2") == 9
    assert e.table.read("F8:1") == 0.5


def test_xpy_negative_base_fractional_exponent_uses_the_absolute_base_and_overflows(run):
    e = run("XPY -8 0.5 F8:0")
    assert e.table.read("F8:0") == f32(math.sqrt(8))
    assert "V" in flags(e) and overflow_fault(e)


def test_xpy_negative_base_whole_exponent_is_fine(run):
    e = run("XPY -2 3 N7:0")
    assert e.table.read("N7:0") == -8 and flags(e) == "S" and not overflow_fault(e)


def test_xpy_result_too_large_overflows(run):
    e = run("XPY 2 20 N7:0")
    assert e.table.read("N7:0") == 32767 and "V" in flags(e) and overflow_fault(e)
    e = run("XPY 10 40 F8:0")
    assert e.table.read("F8:0") == math.inf and "V" in flags(e)
    e = run("XPY 0 -1 F8:0")
    assert "V" in flags(e)


def test_xpy_scp_frd_into_a_long_file_use_its_32_bit_range(run):
    e = run("XPY 2 20 L9:0\nSCP 5 0 10 0 100000 L9:1\nFRD 0x1234 L9:2")
    assert [e.table.read(f"L9:{k}") for k in range(3)] == [1048576, 50000, 1234]
    assert e.table.read("S:102") == 0


def test_xpy_agrees_with_cpt_power(run):
    e = run('XPY F8:0 F8:1 F8:2\nCPT F8:3 "F8:0 ** F8:1"', values={"F8:0": 1.7, "F8:1": 2.3})
    assert e.table.read("F8:2") == e.table.read("F8:3")


# -- DDV -------------------------------------------------------------------------------

def _math_register(value: int) -> dict:
    v = value & 0xFFFFFFFF
    lo, hi = v & 0xFFFF, v >> 16
    return {"S:106": signed(lo), "S:107": signed(hi)}


def test_ddv_divides_the_32_bit_math_register(run):
    e = run("DDV N7:0 N7:1", values={"N7:0": 9, **_math_register(45000)})
    assert e.table.read("N7:1") == 5000
    assert e.table.read("S:107") == 5000 and e.table.read("S:106") == 0  # unrounded quotient, remainder
    assert flags(e) == ""


def test_ddv_rounds_and_keeps_the_unrounded_quotient_and_remainder(run):
    e = run("DDV 4 N7:1", values=_math_register(100002))  # 25000.5
    assert e.table.read("N7:1") == 25001
    assert e.table.read("S:107") == 25000 and e.table.read("S:106") == 2


def test_ddv_negative_dividend(run):
    e = run("DDV 7 N7:1", values=_math_register(-100000))  # -14285.7
    assert e.table.read("N7:1") == -14286 and flags(e) == "S"
    assert e.table.read("S:107") == -14285 and e.table.read("S:106") == -5


def test_ddv_overflow_places_32767(run):
    e = run("DDV 2 N7:1", values=_math_register(-1000000))
    assert e.table.read("N7:1") == 32767 and "V" in flags(e) and overflow_fault(e)
    assert e.table.read("S:107") == _math_register(-1000000)["S:107"]  # register kept


def test_ddv_by_zero_follows_the_setting(run):
    e = run("DDV N7:0 N7:1", values={"N7:0": 0, **_math_register(10)})
    assert e.table.read("N7:1") == 32767 and "V" in flags(e)
    assert e.table.read("S:17") >> S.MINOR_DIV_ZERO_BIT & 1
    e = run("DDV 0 N7:1", values=_math_register(10), settings=Settings(divide_by_zero="fault"))
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_DIV_ZERO


# -- SCL -------------------------------------------------------------------------------

def test_scl_scales_by_rate_over_10000_plus_offset(run):
    e = run("SCL N7:0 25000 127 N7:1", values={"N7:0": 100})
    assert e.table.read("N7:1") == 377 and flags(e) == ""


def test_scl_rounds_the_product_half_away_from_zero(run):
    e = run("SCL 3 5000 0 N7:0\nSCL -3 5000 0 N7:1\nSCL 1 4999 0 N7:2")
    assert [e.table.read(f"N7:{k}") for k in range(3)] == [2, -2, 0]


def test_scl_overflow_before_the_offset_places_the_extreme_regardless_of_offset(run):
    e = run("SCL 32767 20000 -32768 N7:0")
    assert e.table.read("N7:0") == 32767 and "V" in flags(e) and overflow_fault(e)
    e = run("SCL -32768 20000 32767 N7:0")
    assert e.table.read("N7:0") == -32768 and "V" in flags(e)


def test_scl_overflow_after_the_offset(run):
    e = run("SCL 30000 10000 5000 N7:0")
    assert e.table.read("N7:0") == 32767 and "V" in flags(e)
    e = run("SCL -30000 10000 -5000 N7:0")
    assert e.table.read("N7:0") == -32768 and flags(e) == "VS"


def test_scl_zero_and_sign_flags(run):
    e = run("SCL 100 -10000 100 N7:0")
    assert e.table.read("N7:0") == 0 and flags(e) == "Z"


# -- SCP -------------------------------------------------------------------------------

def test_scp_scales_integers_and_rounds(run):
    e = run("SCP N7:0 0 32767 0 10000 N7:1", values={"N7:0": 100})
    assert e.table.read("N7:1") == 31  # 30.52
    e = run("SCP 6242 6242 31208 0 200 N7:1\nSCP 31208 6242 31208 0 200 N7:2")
    assert e.table.read("N7:1") == 0 and e.table.read("N7:2") == 200


def test_scp_floats_and_extrapolation(run):
    e = run("SCP F8:0 32.0 212.0 0.0 100.0 F8:1", values={"F8:0": -40.0})
    assert e.table.read("F8:1") == -40.0  # not clamped to the range
    e = run("SCP 50 0 100 F8:0 F8:1 F8:2", values={"F8:0": 1.5, "F8:1": 2.5})
    assert e.table.read("F8:2") == 2.0


def test_scp_overflow_into_a_word(run):
    e = run("SCP 32767 0 1 0 2 N7:0")
    assert e.table.read("N7:0") == 32767 and "V" in flags(e) and overflow_fault(e)


def test_scp_with_equal_input_limits_is_a_division_by_zero(run):
    e = run("SCP 5 10 10 0 100 N7:0")
    assert e.table.read("N7:0") == 32767 and "V" in flags(e)
    assert e.table.read("S:17") >> S.MINOR_DIV_ZERO_BIT & 1


# -- TOD, FRD --------------------------------------------------------------------------

def test_tod_converts_to_bcd(run):
    e = run("TOD N7:0 N7:1\nTOD 44 N7:2\nTOD 0 N7:3", values={"N7:0": 9760})
    assert e.table.read("N7:1") == -26784  # 0x9760, a negative word
    assert e.table.read("N7:2") == 0x44
    assert e.table.read("N7:3") == 0 and flags(e) == "Z"


def test_tod_sign_bit_always_resets(run):
    e = run("TOD 9760 N7:0")
    assert flags(e) == ""


def test_tod_into_a_bcd_file(run):
    e = run("TOD 1234 D9:0\nFRD D9:0 N7:0")
    assert e.table.read("D9:0") == 0x1234 and e.table.read("N7:0") == 1234


@pytest.mark.parametrize("value", [10000, -1, 32767])
def test_tod_outside_0_to_9999_overflows(run, value):
    e = run("TOD N7:0 N7:1", values={"N7:0": value, "N7:1": 5})
    assert e.table.read("N7:1") == 0
    assert "V" in flags(e) and "S" not in flags(e) and overflow_fault(e)


def test_frd_converts_from_bcd(run):
    e = run("FRD N7:0 N7:1\nFRD 0x9999 N7:2\nFRD 0x0037 F8:0", values={"N7:0": 0x0156})
    assert e.table.read("N7:1") == 156 and e.table.read("N7:2") == 9999
    assert e.table.read("F8:0") == 37.0


@pytest.mark.parametrize("value", [0x000A, 0x00F0, 0x1A00, -1])
def test_frd_of_a_non_bcd_nibble_overflows(run, value):
    e = run("FRD N7:0 N7:1", values={"N7:0": value, "N7:1": 5})
    assert e.table.read("N7:1") == 0 and "V" in flags(e) and overflow_fault(e)


def test_tod_and_frd_agree_with_cpt(run):
    e = run('TOD N7:0 N7:1\nCPT N7:2 "TOD(N7:0)"\nFRD N7:3 N7:4\nCPT N7:5 "FRD(N7:3)"',
            values={"N7:0": 4321, "N7:3": 0x0987})
    assert e.table.read("N7:1") == e.table.read("N7:2") == 0x4321
    assert e.table.read("N7:4") == e.table.read("N7:5") == 987


# -- SWP, DCD, ENC ---------------------------------------------------------------------

def test_swp_swaps_the_bytes_of_length_words(run):
    e = run("SWP #N7:1 2", values={"N7:0": 0x0102, "N7:1": 0x1234, "N7:2": 0x00FF, "N7:3": 0x0A0B})
    assert [e.table.read(f"N7:{k}") for k in range(4)] == [0x0102, 0x3412, -256, 0x0A0B]


def test_swp_leaves_the_flags_alone(run):
    e = run("MOV 0 N7:5\nSWP #N7:0 1", values={"N7:0": 0x0001})
    assert e.table.read("N7:0") == 0x0100 and flags(e) == "Z"


def test_swp_past_the_end_of_its_file_faults(run):
    e = run("SWP #N7:[N7:0] 4", values={"N7:0": 3, "N7:5": 0})  # N7:3..N7:6, N7 has 6 words
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_BLOCK_RANGE


def test_swp_grows_the_file_for_a_constant_length(run):
    e = run("SWP #B3:0 5")
    assert e.fault is None and e.table.file("B3").data.__len__() >= 5


def test_dcd_turns_on_one_bit(run):
    e = run("DCD N7:0 N7:1\nDCD 15 N7:2\nDCD 0x00F3 N7:3", values={"N7:0": 5, "N7:1": 0x7777})
    assert e.table.read("N7:1") == 32 and e.table.read("N7:2") == -32768 and e.table.read("N7:3") == 8


def test_enc_gives_the_lowest_bit_on(run):
    e = run("ENC N7:0 N7:1", values={"N7:0": 0x0400})
    assert e.table.read("N7:1") == 10 and flags(e) == ""
    e = run("ENC -32768 N7:1")
    assert e.table.read("N7:1") == 15 and flags(e) == ""


def test_enc_more_than_one_bit_sets_overflow_but_no_minor_fault(run):
    e = run("ENC 0x0030 N7:1")
    assert e.table.read("N7:1") == 4 and flags(e) == "V" and not overflow_fault(e)


def test_enc_of_zero_sets_zero(run):
    e = run("ENC 0 N7:1", values={"N7:1": 0x7FFF})
    assert e.table.read("N7:1") == 0 and flags(e) == "Z"


# -- syntax and validation --------------------------------------------------------------

RUNGS = [("SIN", "F8:0 F8:1"), ("COS", "F8:0 F8:2"), ("XPY", "F8:0 2 F8:3"), ("DDV", "N7:0 N7:1"),
         ("SCL", "N7:0 5000 3 N7:2"), ("SCP", "F8:0 0 1 0 100 N7:3"), ("TOD", "N7:0 N7:4"), ("FRD", "N7:4 N7:5"),
         ("SWP", "#N7:6 2"), ("DCD", "N7:0 N7:8"), ("ENC", "N7:8 N7:9"), ("LN", "F8:0 F8:4"), ("LOG", "F8:0 F8:5"),
         ("TAN", "F8:0 F8:6"), ("ASN", "F8:0 F8:7"), ("ACS", "F8:0 F8:8"), ("ATN", "F8:0 F8:9")]
NEUTRAL = "\n".join(f"XIC(B3/0){m}({ops.replace(' ', ',')});" for m, ops in RUNGS)
MNEMONIC = "\n".join(f"XIC B3/0 {m} {ops}" for m, ops in RUNGS)


def test_both_rung_syntaxes_give_the_same_program_for_sin_xpy_ddv_scl_scp_tod_frd_swp_dcd_enc():
    assert parse_program(NEUTRAL) == parse_program(MNEMONIC)
    for style in ("neutral", "mnemonic"):
        assert parse_program(format_program(parse_program(MNEMONIC), style)) == parse_program(MNEMONIC)


def test_both_rung_syntaxes_run_alike(run):
    values = {"F8:0": 0.25, "N7:0": 7, "N7:6": 0x0102, "N7:7": 0x0304, "B3/0": 1}
    a, b = run(NEUTRAL, values=values), run(MNEMONIC, values=values)
    assert [list(f.data) for f in a.table.files()] == [list(f.data) for f in b.table.files()]


@pytest.mark.parametrize("text, expected", [
    ("TOD 5 F8:0", "TOD operand 2 (dest) must be word address"),
    ("SWP #F8:0 2", "SWP operand 1 (source) must be word file address"),
    ("SWP #N7:0 0", "SWP operand 2 (length) must be in 1..1000"),
    ("SWP #N7:0 N7:1", "SWP operand 2 (length) must be a constant"),
    ("SCL 1.5 2 3 N7:0", "SCL operand 1 (source) must be integer or word address"),
    ("DDV F8:0 N7:0", "DDV operand 1 (source) must be integer or word address"),
    ("SIN T4:0 F8:0", "SIN operand 1 (source) must be number or word/float address"),
    ("XPY 2 3", "XPY takes 3 operands (XPY a b dest), got 2"),
])
def test_bad_operands_of_tod_swp_scl_ddv_sin_xpy_are_reported(text, expected):
    with pytest.raises(ProgramErrors) as info:
        run_text(text)
    assert expected in str(info.value)


# -- both executors on random operands ---------------------------------------------------

WORDS = st.integers(-32768, 32767)
FLOATS = st.floats(-1e6, 1e6, allow_nan=False, width=32)
PROGRAM = "\n".join([
    *[f"{name} F8:{k} F8:{10 + k}" for k, name in enumerate(FUNCS)],
    *[f"{name} N7:{k} N7:{10 + k}" for k, name in enumerate(FUNCS)],
    "XPY F8:0 F8:1 F8:20", "XPY N7:0 N7:1 N7:20",
    "DDV N7:2 N7:21", "SCL N7:3 N7:4 N7:5 N7:22", "SCP N7:0 N7:1 N7:2 N7:3 N7:4 N7:23",
    "SCP F8:0 F8:1 F8:2 F8:3 F8:4 F8:21",
    "TOD N7:6 N7:24", "FRD N7:7 N7:25", "SWP #N7:0 4", "DCD N7:1 N7:26", "ENC N7:2 N7:27",
])


def _run_both(values: dict, overflow: str):
    tables = []
    for executor in EXECUTORS:
        table = DataTable()
        for addr in ("F8:29", "N7:29", "S:107"):
            table.reference(addr)
        e = run_text(PROGRAM, scans=2, executor=executor, table=table, values=values,
                     settings=Settings(overflow=overflow))
        tables.append((e.mode, e.fault and e.fault.code, [list(f.data) for f in e.table.files()]))
    return tables


def _same(a, b) -> bool:
    if a[:2] != b[:2]:
        return False
    return all(len(x) == len(y) and all(u == v or (u != u and v != v) for u, v in zip(x, y))
               for x, y in zip(a[2], b[2]))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(words=st.lists(WORDS, min_size=8, max_size=8), floats=st.lists(FLOATS, min_size=8, max_size=8),
       register=st.tuples(WORDS, WORDS), overflow=st.sampled_from(["clamp", "wrap"]))
def test_sin_xpy_ddv_scl_scp_tod_frd_swp_dcd_enc_both_executors_agree_on_random_operands(words, floats, register,
                                                                                         overflow):
    values = {f"N7:{k}": v for k, v in enumerate(words)}
    values.update({f"F8:{k}": v for k, v in enumerate(floats)})
    values.update({"S:106": register[0], "S:107": register[1]})
    compiled, reference = _run_both(values, overflow)
    assert _same(compiled, reference)


@settings(max_examples=60, deadline=None)
@given(value=st.integers(0, 9999))
def test_tod_then_frd_round_trips(value):
    e = run_text("TOD N7:0 N7:1\nFRD N7:1 N7:2", values={"N7:0": value})
    assert e.table.read("N7:2") == value and e.table.read("N7:1") & 0xFFFF == int(str(value), 16)
