"""A float stored into an integer rounds to the nearest integer, an exact half
to the even one, as AB documents REAL to integer conversion (1756-RM003,
appendix A Common Attributes, Data Conversions, "REAL to an Integer"), on
both executors and through every instruction that stores a float into a
word or a long; DIV's (and SCL's) integer quotient keeps its own rule
(docs/instructions.md, "Common rules")."""

from __future__ import annotations

import math
import struct
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softplc_lite.datatable import DataTable
from softplc_lite.datatable.errors import DataTableError
from softplc_lite.datatable.jsonio import load_text as load_json
from softplc_lite.ladder import Engine, Mode, Settings, load_text, run_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.rounding import FLOAT32_MAX, round_half_even

from helpers.cli import softplc_here
from helpers.words import signed

EXECUTORS = ("compiled", "reference")

# 1756-RM003's table (REAL -> DINT), then more halves, the ends of the word range and past them.
AB_TABLE = [(-2.5, -2), (-1.6, -2), (-1.5, -2), (-1.4, -1), (1.4, 1), (1.5, 2), (1.6, 2), (2.5, 2)]
HALVES = [(0.5, 0), (-0.5, 0), (3.5, 4), (-3.5, -4), (4.5, 4), (-4.5, -4), (1000.5, 1000), (1001.5, 1002),
          (0.49999997, 0), (0.50000006, 1), (32766.5, 32766), (-32767.5, -32768), (-32768.5, -32768)]
BEYOND = [(32767.5, 32768), (-32769.5, -32770), (40000.5, 40000), (65535.5, 65536)]
CASES = AB_TABLE + HALVES + BEYOND


def f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


def reference_round(v: float) -> int:
    """The rule worked out with exact fractions: the float32 value, then the
    nearest integer, a tie to the even one."""
    x = Fraction(f32(v)) if abs(v) <= FLOAT32_MAX else Fraction(v)
    low = math.floor(x)
    rest = x - low
    if rest > Fraction(1, 2) or (rest == Fraction(1, 2) and low % 2):
        return low + 1
    return low


def stored(n: int, overflow: str = "clamp") -> tuple[int, bool]:
    """An integer result in a word, per the overflow setting, and whether it overflowed."""
    if -32768 <= n <= 32767:
        return n, False
    if overflow == "clamp":
        return (32767 if n > 0 else -32768), True
    return signed(n), True


def bcd(n: int) -> int:
    """TOD's result for 0..9999, as the signed word holding the pattern; 0 (overflow) outside."""
    if not 0 <= n <= 9999:
        return 0
    v = int(str(n), 16)
    return signed(v)


def overflowed(e: Engine) -> bool:
    return bool(e.table.read("S:0") >> S.OVERFLOW & 1)


def minor_overflow(e: Engine) -> bool:
    return bool(e.table.read(f"S:{S.PLC5_MINOR_FAULT_BITS}") >> S.MINOR_OVERFLOW_BIT & 1)


# -- the helper: the AB table and a property against the exact rule --------------------------------


@pytest.mark.parametrize("value,result", AB_TABLE + HALVES + BEYOND)
def test_round_half_even_follows_the_ab_table(value, result):
    assert round_half_even(value) == result


def test_a_double_result_rounds_as_its_float32_value():
    # 0.1 (float32) * 25 is 2.5000000373 in double, 2.5 in float32 (what the PLC computes): 2
    product = f32(0.1) * 25
    assert product != 2.5 and f32(product) == 2.5
    assert round_half_even(product) == 2
    # beyond the float32 range the double is kept: an integer already, it overflows any word
    assert round_half_even(1e39) == int(1e39)


halves = st.integers(-(2 ** 25), 2 ** 25).map(lambda k: k / 2)
quarters = st.integers(-(2 ** 24), 2 ** 24).map(lambda k: k / 4)
float32s = st.floats(width=32, allow_nan=False, allow_infinity=False)
doubles = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=2000, deadline=None)
@given(st.one_of(halves, quarters, float32s, doubles))
def test_round_half_even_matches_the_exact_rule(v):
    assert round_half_even(v) == reference_round(v)


# -- every store of a float into an integer, on both executors -------------------------------------

STORES = """DATA L9 2
MOV F8:0 N7:0
CPT N7:1 "F8:0 * 1"
ADD F8:0 0 N7:2
SCP F8:0 0.0 1.0 0.0 1.0 N7:3
TOD F8:0 N7:4
CPT N7:5 "F8:0 OR 0"
DIV F8:0 1 N7:6
AVE #F8:0 N7:7 R6:0 2 0
JSR 3 1 F8:0 N7:9
FLL F8:0 #N7:10 2
MOV F8:0 L9:0
SUB F8:0 0.0 N7:12
FILE 3
SBR N7:8
RET F8:0
"""
# destination -> what it holds for a rounded value n (before overflow)
WORD_DESTS = ["N7:0", "N7:1", "N7:2", "N7:3", "N7:6", "N7:7", "N7:8", "N7:9", "N7:10", "N7:11", "N7:12"]


@pytest.mark.parametrize("overflow", ["clamp", "wrap"])
@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("value,result", CASES)
def test_every_float_store_rounds_half_to_even(executor, overflow, value, result):
    e = run_text(STORES, executor=executor, settings=Settings(overflow=overflow),
                 values={"F8:0": value, "F8:1": value})
    assert e.fault is None and e.mode is Mode.RUN
    word, _ = stored(result, overflow)
    got = {a: e.table.read(a) for a in WORD_DESTS}
    assert got == dict.fromkeys(WORD_DESTS, word), f"{value} -> {result}"
    assert e.table.read("N7:4") == bcd(result)  # TOD
    assert e.table.read("N7:5") == stored(result, overflow)[0]  # a bitwise operand: rounded first
    assert e.table.read("L9:0") == result  # a long holds them all


@pytest.mark.parametrize("overflow", ["clamp", "wrap"])
@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("value,result", CASES)
def test_overflow_after_rounding_is_unchanged(executor, overflow, value, result):
    """The rounded value is what overflows: V (S:0/1) and the minor fault S:10/14,
    then clamp or the low 16 bits. -32768.5 rounds to -32768 and fits."""
    e = run_text("MOV F8:0 N7:0", executor=executor, settings=Settings(overflow=overflow), values={"F8:0": value})
    word, over = stored(result, overflow)
    assert e.table.read("N7:0") == word
    assert (overflowed(e), minor_overflow(e)) == (over, over)
    assert e.table.read("S:0") >> S.ZERO & 1 == (word == 0)
    assert e.table.read("S:0") >> S.SIGN & 1 == (word < 0)


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("setout,cv", [(30, 1228), (70, 2866), (50, 2048), (10, 410), (90, 3686)])
def test_pid_output_rounds_half_to_even(executor, setout, cv):
    # Set output (word 0 bit 4): CV = word 10 % of 4095, 30 % = 1228.5 -> 1228, 70 % = 2866.5 -> 2866
    e = run_text(f"DATA N10 23 = 16 0 0 0 0 0 0 0 0 0 {setout} 100 0 10\nPID N10:0 N11:0 0 N11:1",
                 executor=executor)
    assert e.fault is None
    assert e.table.read("N11:1") == cv == round_half_even(setout * 4095 / 100)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_integer_division_keeps_its_own_rule(executor):
    """DIV of two integers (and CPT's |, SCL) rounds its quotient half away from zero;
    a float operand makes it a float result, which converts half to even."""
    e = run_text('DIV 5 2 N7:0\nDIV -5 2 N7:1\nCPT N7:2 "5 | 2"\nSCL 5 5000 0 N7:3\nDIV 5.0 2 N7:4\n'
                 'DIV F8:0 2 N7:5\nCPT N7:6 "F8:0 | 2"', executor=executor, values={"F8:0": 5.0})
    assert [e.table.read(f"N7:{k}") for k in range(7)] == [3, -3, 3, 3, 2, 2, 2]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_fal_and_cpt_functions_round_half_to_even(executor):
    e = run_text('FAL R6:0 2 0 ALL #N7:10 "#F8:0 * 1"\nCPT N7:0 "FRD(F8:0)"\nCPT N7:1 "TOD(F8:1)"\n'
                 'CPT N7:2 "NOT F8:1"\nCPT N7:3 "F8:0 XOR 0"',
                 executor=executor, values={"F8:0": 18.5, "F8:1": 2.5})
    assert [e.table.read(f"N7:{k}") for k in (10, 11)] == [18, 2]
    # FRD(18) reads 0x0012 as BCD: 12; TOD(2) = 0x0002; NOT 2 = -3
    assert [e.table.read(f"N7:{k}") for k in range(4)] == [12, 2, -3, 18]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_cop_copies_a_float_s_bits_without_rounding(executor):
    e = run_text("COP #F8:0 #N7:0 2", executor=executor, values={"F8:0": 2.5})
    assert [e.table.read("N7:0"), e.table.read("N7:1")] == [0, 0x4020]  # 2.5 = 0x40200000, low word first


# -- float32 semantics: a result into a word is the F element's value, rounded --------------------

# the same result straight into a word, and into an F element then MOVed
PAIR = ('CPT N7:0 "F8:0 * F8:1"\nCPT F8:2 "F8:0 * F8:1"\nMOV F8:2 N7:1\n'
        'ADD F8:0 F8:1 N7:2\nADD F8:0 F8:1 F8:3\nMOV F8:3 N7:3')
_engines: dict[str, Engine] = {}


def _engine(executor: str) -> Engine:
    if executor not in _engines:
        e = Engine(load_text(PAIR, source="pair"), executor=executor)
        e.set_mode(Mode.RUN)
        _engines[executor] = e
    return _engines[executor]


@settings(max_examples=300, deadline=None)
@given(a=st.one_of(float32s, quarters).filter(lambda v: abs(v) < 1e4),
       b=st.one_of(float32s, st.sampled_from([0.1, 0.5, 2.5, 25.0, 3.0])).filter(lambda v: abs(v) < 1e4))
def test_a_word_destination_holds_what_mov_of_the_float_result_gives(a, b):
    a, b = f32(a), f32(b)
    for executor in EXECUTORS:
        e = _engine(executor)
        e.table.write("F8:0", a)
        e.table.write("F8:1", b)
        e.scan()
        assert e.table.read("N7:0") == e.table.read("N7:1"), executor  # CPT straight vs via F8:2
        assert e.table.read("N7:2") == e.table.read("N7:3"), executor  # ADD straight vs via F8:3
        assert e.table.read("N7:0") == stored(reference_round(a * b))[0]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_float32_product_that_is_a_half_rounds_to_even(executor):
    e = run_text('CPT N7:0 "F8:0 * 25"', executor=executor, values={"F8:0": 0.1})
    assert e.table.read("N7:0") == 2  # 0.1f * 25 = 2.5 in float32


# -- the data table refuses a float for an integer: no second rounding rule ------------------------


def test_the_data_table_refuses_a_float_for_an_integer_element():
    t = DataTable()
    t.write("N7:0", 7)
    for value in (2.5, 2.0):
        with pytest.raises(DataTableError):
            t.write("N7:0", value)
    assert t.read("N7:0") == 7
    with pytest.raises(DataTableError):
        load_json(t, '{"N7": [2.5]}')
    assert t.read("N7:0") == 7


def test_a_real_app_rounds_a_set_float_half_to_even(tmp_path):
    """The whole pipeline: an app's program loaded by `softplc run`, a float set
    from the command line, the integer printed."""
    app = tmp_path / "conv"
    app.mkdir()
    (app / "main.lad").write_text("MOV F8:0 N7:0\nCPT N7:1 \"F8:0 * 3\"\nSCP F8:0 0.0 1.0 0.0 -1.0 N7:2\n")
    for executor in EXECUTORS:
        out = softplc_here("run", str(app), "--fresh", "--scans", "1", "--executor", executor, "--set", "F8:0=2.5",
                           "--print", "N7:0", "--print", "N7:1", "--print", "N7:2", cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        assert out.stdout.splitlines()[-3:] == ["N7:0 = 2", "N7:1 = 8", "N7:2 = -2"], out.stdout
