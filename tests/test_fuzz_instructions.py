"""Fuzzing the bound instructions (ladder/instr/): random
programs of NOP END BSL BSR FFL FFU LFL LFU SQO SQI SQL SQC FAL FSC AVE STD
SRT TOD FRD DDV XPY SIN COS TAN ASN ACS ATN LN LOG SCL SCP SWP DCD ENC PID,
with JSR/SBR/RET parameters, D/A/L files, SLC I/O addresses and symbol
members, with operands the validator accepts (direct, indirect, ``#``
indexed, constants at the edges of their range) and random initial values
(negative, 32767/-32768, NaN and infinite floats, huge L values).

Each program runs for several scans on both executors, its rung conditions
toggled by B3:0 bits written before each scan. Asserted:

- no exception escapes (load, bind, scan) and no major fault 255;
- after every scan the two data tables are identical
  (``datatable.jsonio.dumps``) and so are the modes and fault records;
- ``fmt`` in both styles prints text that parses back to the same program.

The default run is deterministic (``derandomize``) and takes well under 30 s.
To search harder::

    FUZZ_INSTR_EXAMPLES=5000 python -m pytest -q -p no:cacheprovider --timeout 0 tests/test_fuzz_instructions.py -k agree

(``FUZZ_INSTR_SEED=n`` draws another deterministic set; ``FUZZ_INSTR_SEED=random``
draws a fresh one each run; ``--timeout 0`` lifts pytest-timeout's 120 s per test.)
"""

from __future__ import annotations

import math
import os
import random
import re

from hypothesis import HealthCheck, given, note, seed, settings
from hypothesis import strategies as st

from softplc_lite.datatable import DataTable, snapshot
from softplc_lite.datatable.jsonio import dumps, table_from_json
from softplc_lite.ladder import Engine, Mode, Settings, check
from softplc_lite.ladder.fmt import format_program
from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.semantics import signed16

EXAMPLES = int(os.environ.get("FUZZ_INSTR_EXAMPLES", "300"))
_SEED = os.environ.get("FUZZ_INSTR_SEED", "0")
SCANS = 8
INTERNAL = 255

# The files a program works on, with their sizes: small, so that blocks,
# indexes and positions reach past the end (faults 20 and 202) now and then.
DATA = {"N7": 40, "N9": 4, "F8": 24, "L10": 16, "D11": 8, "A12": 8, "B3": 16, "T4": 6, "C5": 6, "R6": 8,
        "ST13": 2}
SYMBOLS = ("SYMBOL Tmr T4:1\nSYMBOL Ctl R6:2\nSYMBOL Levels N7:10\nSYMBOL Flags B3:2\nSYMBOL Cnt C5:1\n"
           "SYMBOL Temp F8:3\nSYMBOL Slot I:1.0\nSYMBOL Lamps O:2.1\nSYMBOL Old I:12\nSYMBOL Big L10:2\n")

WORD_EDGES = (0, 1, -1, 2, 3, 7, 15, 16, 255, 4095, 9999, 10000, 32767, -32768, -32767, 0x7FFF)
FLOAT_EDGES = (0.0, -0.0, 0.5, -0.5, 2.5, -2.5, 1e-30, 3.4e38, -3.4e38, 1e10, math.pi)

_ints = st.one_of(st.sampled_from(WORD_EDGES), st.integers(-5, 40), st.integers(-32768, 32767))


def _element(draw, size: int) -> int:
    # Mostly inside the file, sometimes at its last element.
    return draw(st.one_of(st.integers(0, size - 1), st.just(size - 1), st.integers(0, 3)))


def _index_word(draw) -> str:
    """An indirect element: N9:k, whose value the initial table sets (mostly small)."""
    return f"N9:{draw(st.integers(0, 3))}"


def word_address(draw, dest: bool = False) -> str:
    choice = draw(st.integers(0, 15))
    if choice <= 4:
        return f"N7:{_element(draw, DATA['N7'])}"
    if choice == 5:
        return f"N7:[{_index_word(draw)}]"
    if choice == 6:
        return f"#N7:{draw(st.integers(0, 30))}"
    if choice == 7:
        return f"B3:{_element(draw, DATA['B3'])}"
    if choice == 8:
        return f"D11:{_element(draw, DATA['D11'])}"
    if choice == 9:
        return f"A12:{_element(draw, DATA['A12'])}"
    if choice == 10:
        return draw(st.sampled_from([f"T4:{draw(st.integers(0, 5))}.ACC", f"C5:{draw(st.integers(0, 5))}.PRE",
                                     "Tmr.ACC", "Cnt.PRE"]))
    if choice == 11:
        return draw(st.sampled_from(["Levels", "Levels[3]", "Levels[12]"]))
    if choice == 12:
        return draw(st.sampled_from(["I:1.0", "O:2.1", "I:0", "O:3.2", "O:0", "Slot", "Lamps[31]", "Old[1]"]))
    if choice == 13:
        return f"N[N9:{draw(st.integers(0, 3))}]:{draw(st.integers(0, 3))}" if not dest else "N7:1"
    if choice == 14 and not dest:
        return draw(st.sampled_from(["S:0", "S:24", "S:106", "S:107", "S:1"]))
    return f"N7:{draw(st.integers(0, 5))}"


def dest_address(draw) -> str:
    choice = draw(st.integers(0, 9))
    if choice <= 1:
        return f"F8:{_element(draw, DATA['F8'])}"
    if choice == 2:
        return f"L10:{_element(draw, DATA['L10'])}"
    if choice == 3:
        return draw(st.sampled_from(["Temp", f"F8:[{_index_word(draw)}]", f"L10:[{_index_word(draw)}]", "#F8:2",
                                     "Big", "Big[3]", "#L10:1"]))
    return word_address(draw, dest=True)


def bit_address(draw) -> str:
    choice = draw(st.integers(0, 8))
    if choice <= 2:
        return f"B3/{draw(st.integers(0, DATA['B3'] * 16 - 1))}"
    if choice == 3:
        return f"N7:{_element(draw, 8)}/{draw(st.integers(0, 15))}"
    if choice == 4:
        return draw(st.sampled_from(["I:1.0/3", "O:2.1/15", "I:0/0", "I:12/17", "O:0/5"]))
    if choice == 5:
        return draw(st.sampled_from(["Tmr/DN", "Tmr.EN", "Ctl/UL", "Ctl.DN", "Cnt/DN", "Flags/3", "Levels[2]/15",
                                     "R6:0/UL", "R6:1/EN", "T4:0/DN", "Slot/8", "Slot[1]/15", "Lamps/9", "Old/17",
                                     "Old[8]/7"]))
    if choice == 6:
        return f"B3/[{_index_word(draw)}]"
    if choice == 7:
        return f"N7:[{_index_word(draw)}]/{draw(st.integers(0, 15))}"
    return f"B3:{draw(st.integers(0, 3))}/{draw(st.integers(0, 15))}"


def int_constant(draw) -> str:
    v = draw(_ints)
    if draw(st.integers(0, 5)) == 0:
        return draw(st.sampled_from(["0x8000", "0xFFFF", "0x00FF", "0x0F0F", "0x7FFF"]))
    return str(v)


def int_source(draw) -> str:
    return int_constant(draw) if draw(st.booleans()) else word_address(draw)


def source(draw) -> str:
    """K.SOURCE: a number (int or float) or a word, float or long address."""
    choice = draw(st.integers(0, 5))
    if choice == 0:
        return repr(draw(st.sampled_from(FLOAT_EDGES))) if draw(st.booleans()) else \
            repr(draw(st.floats(-1e6, 1e6, allow_nan=False, width=32)))
    if choice == 1:
        return int_constant(draw)
    if choice == 2:
        return str(draw(st.sampled_from([40000, 65535, 70000, -40000, 100000])))
    return dest_address(draw)


def control(draw) -> str:
    choice = draw(st.integers(0, 6))
    if choice == 0:
        return "Ctl"
    if choice == 1:
        return f"R6:[{_index_word(draw)}]"
    return f"R6:{draw(st.integers(0, DATA['R6'] - 1))}"


def word_file(draw) -> str:
    choice = draw(st.integers(0, 7))
    if choice <= 2:
        return f"#N7:{draw(st.integers(0, 36))}"
    if choice == 3:
        return f"#B3:{draw(st.integers(0, DATA['B3'] - 1))}"
    if choice == 4:
        return f"#D11:{draw(st.integers(0, 4))}"
    if choice == 5:
        return f"#N7:[{_index_word(draw)}]"
    if choice == 6:
        return draw(st.sampled_from(["#A12:0", "#I:1.0", "#O:0", "#N7:10", "#N7:0"]))
    return f"#N7:{draw(st.integers(0, 3))}"


def numeric_file(draw) -> str:
    choice = draw(st.integers(0, 5))
    if choice == 0:
        return f"#F8:{draw(st.integers(0, 20))}"
    if choice == 1:
        return f"#L10:{draw(st.integers(0, 12))}"
    return word_file(draw)


def length(draw, hi: int = 1000) -> str:
    return str(draw(st.one_of(st.integers(1, 6), st.sampled_from([1, 2, 16, 17, 40, hi]), st.integers(1, hi))))


def position(draw, n: int) -> str:
    return str(draw(st.one_of(st.integers(0, min(n, 6)), st.sampled_from([0, n, 1000]))))


# A product of 40 L words: past the float range when they are large.
_HUGE_PRODUCT = "(" + " * ".join("(" + " * ".join(f"L10:{k}" for k in range(8)) + ")" for _ in range(5)) + ")"


def expression(draw, compare: bool = False) -> str:
    def term(depth: int) -> str:
        choice = draw(st.integers(0, 9 if depth < 2 else 4))
        if choice == 0:
            return f"#N7:{draw(st.integers(0, 20))}"
        if choice == 1:
            return f"#F8:{draw(st.integers(0, 10))}"
        if choice == 2:
            return draw(st.sampled_from(["0", "1", "-1", "32767", "2.5", "0.0", "100000", "#L10:0", "L10:3",
                                         _HUGE_PRODUCT, "(F8:1 ** 200.0)", "1e38"]))
        if choice == 3:
            return word_address(draw)
        if choice == 4:
            return f"F8:{draw(st.integers(0, 10))}"
        if choice in (5, 6):
            op = draw(st.sampled_from(["+", "-", "*", "|", "MOD", "**", "AND", "OR", "XOR"]))
            return f"({term(depth + 1)} {op} {term(depth + 1)})"
        if choice == 7:
            fn = draw(st.sampled_from(["SQR", "ABS", "FRD", "TOD", "LN", "SIN", "DEG", "RAD", "ATN"]))
            return f"{fn}({term(depth + 1)})"
        if choice == 8:
            return f"-{term(depth + 1)}"
        return f"NOT {term(depth + 1)}"
    text = term(0)
    if compare:
        text = f"{text} {draw(st.sampled_from(['=', '<>', '<', '<=', '>', '>=']))} {term(1)}"
    return f'"{text}"'


# -- the instructions ---------------------------------------------------------------------


def _bit_shift(draw, m):
    n = draw(st.one_of(st.integers(1, 40), st.sampled_from([1, 15, 16, 17, 32, 33, 16000])))
    return f"{m} {word_file(draw)} {control(draw)} {bit_address(draw)} {n}"


def _stack(draw, m):
    n = int(length(draw, 40 if draw(st.integers(0, 9)) else 1000))
    ctl, p = control(draw), position(draw, n)
    if m in ("FFL", "LFL"):
        return f"{m} {int_source(draw)} {word_file(draw)} {ctl} {n} {p}"
    return f"{m} {word_file(draw)} {word_address(draw, dest=True)} {ctl} {n} {p}"


def _seq_operand(draw, dest: bool = False):
    if not dest and draw(st.integers(0, 2)) == 0:
        return int_constant(draw)
    if draw(st.integers(0, 2)) == 0:
        return f"#N7:{draw(st.integers(0, 30))}"
    return word_address(draw, dest=dest)


def _sequencer(draw, m):
    n = int(length(draw, 40 if draw(st.integers(0, 9)) else 1000))
    ctl, p = control(draw), position(draw, n)
    f = word_file(draw)
    if m == "SQO":
        return f"{m} {f} {_seq_operand(draw)} {_seq_operand(draw, dest=True)} {ctl} {n} {p}"
    if m in ("SQI", "SQC"):
        return f"{m} {f} {_seq_operand(draw)} {_seq_operand(draw)} {ctl} {n} {p}"
    return f"{m} {f} {_seq_operand(draw)} {ctl} {n} {p}"


def _mode(draw, n: int) -> str:
    return draw(st.sampled_from(["ALL", "INC", "all", "Inc", "1", str(n), str(max(1, n // 2))]))


def _file_math(draw, m):
    n = int(length(draw, 30 if draw(st.integers(0, 9)) else 1000))
    ctl, p, mode = control(draw), position(draw, n), _mode(draw, n)
    if m == "FAL":
        dest = draw(st.sampled_from([f"#N7:{draw(st.integers(0, 20))}", f"#F8:{draw(st.integers(0, 10))}",
                                     f"#L10:{draw(st.integers(0, 8))}", "N7:39", "F8:0", "#D11:0"]))
        return f"FAL {ctl} {n} {p} {mode} {dest} {expression(draw)}"
    return f"FSC {ctl} {n} {p} {mode} {expression(draw, compare=True)}"


def _statistic(draw, m):
    n = int(length(draw, 30 if draw(st.integers(0, 9)) else 1000))
    ctl, p = control(draw), position(draw, n)
    f = numeric_file(draw)
    if m == "SRT":
        return f"SRT {f} {ctl} {n} {p}"
    return f"{m} {f} {dest_address(draw)} {ctl} {n} {p}"


def _unary(draw, m):
    src = int_source(draw) if m in ("FRD", "DCD", "ENC", "DDV") else source(draw)
    dst = word_address(draw, dest=True) if m in ("TOD", "DCD", "ENC", "DDV") else dest_address(draw)
    return f"{m} {src} {dst}"


def _xpy(draw, m):
    return f"XPY {source(draw)} {source(draw)} {dest_address(draw)}"


def _scl(draw, m):
    return f"SCL {int_source(draw)} {int_source(draw)} {int_source(draw)} {word_address(draw, dest=True)}"


def _scp(draw, m):
    return "SCP " + " ".join(source(draw) for _ in range(5)) + f" {dest_address(draw)}"


def _swp(draw, m):
    return f"SWP {word_file(draw)} {length(draw, 40)}"


def _pid(draw, m):
    blk = draw(st.sampled_from(["N7:0", "N7:10", "N7:17", "N7:[N9:0]", "Levels"]))
    return f"PID {blk} {word_address(draw)} {int_source(draw)} {word_address(draw, dest=True)}"


def _plain(draw, m):
    return m


# The instructions outside ladder/instr/, on the wider operands (L, D and A files, SLC I/O
# addresses, symbol members and offsets): these have a compiler template and a separate
# interpreter rule, so the two executors can disagree.


def _integer_operand(draw, dest: bool = False) -> str:
    choice = draw(st.integers(0, 3))
    if choice == 0 and not dest:
        return int_constant(draw)
    if choice == 1:
        return draw(st.sampled_from([f"L10:{draw(st.integers(0, 15))}", f"L10:[{_index_word(draw)}]"]))
    return word_address(draw, dest=dest)


def _classic(draw, m):
    if m in ("ADD", "SUB", "MUL", "DIV", "MOD"):
        return f"{m} {source(draw)} {source(draw)} {dest_address(draw)}"
    if m in ("NEG", "ABS", "SQR", "MOV"):
        return f"{m} {source(draw)} {dest_address(draw)}"
    if m == "CLR":
        return f"CLR {dest_address(draw)}"
    if m == "CPT":
        return f"CPT {dest_address(draw)} {expression(draw)}"
    if m in ("AND", "OR", "XOR"):
        return f"{m} {_integer_operand(draw)} {_integer_operand(draw)} {_integer_operand(draw, dest=True)}"
    if m == "NOT":
        return f"NOT {_integer_operand(draw)} {_integer_operand(draw, dest=True)}"
    if m == "MVM":
        return f"MVM {int_source(draw)} {int_source(draw)} {word_address(draw, dest=True)}"
    if m == "COP":
        return f"COP {numeric_file(draw)} {numeric_file(draw)} {length(draw, 20)}"
    if m == "FLL":
        return f"FLL {source(draw)} {numeric_file(draw)} {length(draw, 20)}"
    if m == "BTD":
        return (f"BTD {int_source(draw)} {draw(st.integers(0, 15))} {word_address(draw, dest=True)} "
                f"{draw(st.integers(0, 15))} {draw(st.integers(1, 16))}")
    if m in ("EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ"):
        return f"{m} {source(draw)} {source(draw)}"
    if m == "LIM":
        return f"LIM {source(draw)} {source(draw)} {source(draw)}"
    if m == "MEQ":
        return f"MEQ {int_source(draw)} {int_source(draw)} {int_source(draw)}"
    if m == "CMP":
        return f"CMP {expression(draw, compare=True)}"
    if m in ("XIC", "XIO"):
        return f"{m} {bit_address(draw)}"
    if m in ("OTE", "OTL", "OTU"):
        return f"{m} {bit_address(draw)}"
    if m == "TON":
        return f"TON {draw(st.sampled_from(['Tmr', 'T4:0', 'T4:[N9:1]']))} 0.01 {draw(st.integers(0, 5))} 0"
    if m == "CTU":
        return f"CTU {draw(st.sampled_from(['Cnt', 'C5:0']))} {draw(st.sampled_from([2, 32767]))} 0"
    if m == "RES":
        return f"RES {draw(st.sampled_from(['Ctl', 'Tmr', 'Cnt', 'R6:0', 'R6:[N9:2]']))}"
    raise AssertionError(m)


CLASSIC = ("ADD", "SUB", "MUL", "DIV", "MOD", "NEG", "ABS", "SQR", "MOV", "CLR", "CPT", "AND", "OR", "XOR",
           "NOT", "MVM", "COP", "FLL", "BTD", "EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ", "LIM", "MEQ", "CMP",
           "XIC", "XIO", "OTE", "OTL", "OTU", "TON", "CTU", "RES")


INSTRUCTIONS = {
    "BSL": _bit_shift, "BSR": _bit_shift, "FFL": _stack, "FFU": _stack, "LFL": _stack, "LFU": _stack,
    "SQO": _sequencer, "SQI": _sequencer, "SQL": _sequencer, "SQC": _sequencer,
    "FAL": _file_math, "FSC": _file_math, "AVE": _statistic, "STD": _statistic, "SRT": _statistic,
    **{m: _unary for m in ("TOD", "FRD", "DDV", "SIN", "COS", "TAN", "ASN", "ACS", "ATN", "LN", "LOG", "DCD",
                           "ENC")},
    "XPY": _xpy, "SCL": _scl, "SCP": _scp, "SWP": _swp, "PID": _pid, "NOP": _plain, "END": _plain,
}
NEW = tuple(sorted(INSTRUCTIONS))
INSTRUCTIONS.update({m: _classic for m in CLASSIC})
# input instructions: an output follows them
INPUTS = ("SQI", "EQU", "NEQ", "LES", "LEQ", "GRT", "GEQ", "LIM", "MEQ", "CMP", "XIC", "XIO")


def condition(draw) -> str:
    choice = draw(st.integers(0, 5))
    if choice == 0:
        return ""
    if choice == 1:
        return f"XIO B3/{draw(st.integers(0, 3))} "
    if choice == 2:
        return f"BST XIC B3/{draw(st.integers(0, 3))} NXB XIC B3/{draw(st.integers(4, 7))} BND "
    return f"XIC B3/{draw(st.integers(0, 7))} "


def rung(draw) -> str:
    # mostly the new instructions; the older ones on the new operands now and then
    m = draw(st.sampled_from(NEW)) if draw(st.integers(0, 3)) else draw(st.sampled_from(CLASSIC))
    text = condition(draw) + INSTRUCTIONS[m](draw, m)
    if m in INPUTS:
        text += f" OTE B3:4/{draw(st.integers(0, 15))}"
    elif draw(st.integers(0, 4)) == 0:
        # a second instruction in series
        m2 = draw(st.sampled_from(NEW))
        if m2 not in INPUTS:
            text += " " + INSTRUCTIONS[m2](draw, m2)
    return text


def subroutine(draw) -> tuple[str, str]:
    """A JSR rung in the main file and a FILE 3 with SBR/RET parameters."""
    n_in = draw(st.integers(0, 3))
    n_out = draw(st.integers(0, 3))
    ins = [source(draw) for _ in range(n_in)]
    outs = [dest_address(draw) for _ in range(n_out)]
    call = f"{condition(draw)}JSR 3 {n_in} {' '.join(ins + outs)}".rstrip()
    body = ["FILE 3"]
    sbr = " ".join(dest_address(draw) for _ in range(n_in))
    body.append(f"SBR {sbr}".rstrip())
    for _ in range(draw(st.integers(0, 3))):
        body.append(rung(draw))
    if n_out:
        values = " ".join(source(draw) for _ in range(n_out))
        if draw(st.booleans()):
            body.append(f"XIC B3/{draw(st.integers(0, 3))} RET {values}")
        body.append(f"RET {values}")
    elif draw(st.booleans()):
        body.append("RET")
    return call, "\n".join(body)


@st.composite
def programs(draw) -> str:
    lines = [SYMBOLS.rstrip("\n")]
    lines += [f"DATA {name} {size}" for name, size in DATA.items()]
    for _ in range(draw(st.integers(1, 5))):
        lines.append(rung(draw))
    sub = None
    if draw(st.integers(0, 3)) == 0:
        call, sub = subroutine(draw)
        lines.append(call)
    if sub:
        lines.append(sub)
    return "\n".join(lines) + "\n"


_special_floats = st.sampled_from([math.nan, math.inf, -math.inf, 3.4028234663852886e38, -3.4e38, 0.0, -1.5, 1e-45])


@st.composite
def initial_values(draw) -> dict[str, object]:
    """Random initial words, mostly small so that indexes and LEN/POS stay useful."""
    values: dict[str, object] = {}
    for k in range(4):
        values[f"N9:{k}"] = draw(st.one_of(st.integers(0, 7), st.sampled_from([-1, 39, 40, 32767, -32768])))
    for k in range(draw(st.integers(0, 12))):
        addr = draw(st.sampled_from(
            [f"N7:{i}" for i in range(40)] + [f"B3:{i}" for i in range(16)] + [f"D11:{i}" for i in range(8)]
            + [f"A12:{i}" for i in range(8)] + ["S:106", "S:107", "S:24"]))
        values[addr] = draw(_ints)
    for k in range(draw(st.integers(0, 8))):
        values[f"F8:{draw(st.integers(0, 23))}"] = draw(st.one_of(_special_floats, st.floats(width=32)))
    for k in range(draw(st.integers(0, 6))):
        values[f"L10:{draw(st.integers(0, 15))}"] = draw(st.one_of(
            st.sampled_from([2 ** 31 - 1, -2 ** 31, 65536, -65537, 0]), st.integers(-2 ** 31, 2 ** 31 - 1)))
    for k in range(draw(st.integers(0, 6))):
        # control words: LEN, POS and status bits the program did not set
        r = draw(st.integers(0, DATA["R6"] - 1))
        member = draw(st.sampled_from(["LEN", "POS", "bits"]))
        if member == "bits":  # status bits a program (or a snapshot) left set
            values[f"R6:{r}"] = draw(st.integers(0, 0xFFFF)) & 0xFF00
        else:
            values[f"R6:{r}.{member}"] = draw(st.one_of(st.integers(-2, 20), st.sampled_from([-32768, 32767, 1000])))
    return values


def _dump(engine: Engine) -> str:
    return dumps(engine.table)


def _fault(engine: Engine):
    f = engine.fault
    return None if f is None else (f.code, f.file, f.rung, f.instruction, f.message)


def run_both(text: str, values: dict, seed: int, config: Settings, scans: int = SCANS) -> None:
    """The property: parse, fmt round trip, validate, run both executors."""
    program = parse_program(text, "<fuzz>")
    for style in ("mnemonic", "neutral"):
        printed = format_program(program, style)
        again = parse_program(printed, f"<{style}>")
        assert again == program, f"fmt --style {style} does not parse back to the same program:\n{printed}"
        assert format_program(again, style) == printed, f"fmt --style {style} is not a fixed point"
    resolved, errors = check(program)
    assert not errors, "the generator made a program the validator refuses:\n" + "\n".join(map(str, errors))
    rnd = random.Random(seed)
    bits = [rnd.getrandbits(16) for _ in range(scans)]
    engines = []
    for executor in ("compiled", "reference"):
        table = DataTable()
        for address in values:
            table.reference(address)
        engine = Engine(resolved, table=table, executor=executor, settings=Settings(**vars(config)))
        for address, value in values.items():
            if address.startswith(("F", "L")):
                engine.table.write(address, value)
            else:
                engine.table.write_word(address, value & 0xFFFF)
        engine.set_mode(Mode.RUN)
        engines.append(engine)
    compiled, reference = engines
    assert _dump(compiled) == _dump(reference), "tables differ before the first scan"
    for k in range(scans):
        for e in engines:
            e.table.file(3).data[0] = signed16(bits[k])
            e.scan()
        fc, fr = _fault(compiled), _fault(reference)
        assert fc is None or fc[0] != INTERNAL, f"scan {k}: compiled: {compiled.fault}"
        assert fr is None or fr[0] != INTERNAL, f"scan {k}: reference: {reference.fault}"
        assert fc == fr, f"scan {k}: faults differ:\ncompiled  {compiled.fault}\nreference {reference.fault}"
        assert compiled.mode is reference.mode, f"scan {k}: modes differ"
        dc, dr = _dump(compiled), _dump(reference)
        if dc != dr:
            diff = [f"compiled  {a}\nreference {b}" for a, b in zip(dc.splitlines(), dr.splitlines()) if a != b]
            raise AssertionError(f"scan {k}: tables differ\n" + "\n".join(diff[:6]))
        if compiled.mode is Mode.FAULTED:
            break
    # What the instructions left (NaN, L extremes, odd control words) saves and loads back.
    text = _dump(compiled)
    assert dumps(table_from_json(text)) == text, "the data table's JSON does not load back to itself"
    assert dumps(snapshot.decode(snapshot.encode(compiled.table))) == text, "the snapshot does not load back"


# The watchdog (fault 200) measures wall-clock time: on a loaded machine one executor's scan
# may pass 500 ms and the other's not, so it is set out of reach here.
configs = st.builds(Settings, overflow=st.sampled_from(["clamp", "wrap"]),
                    divide_by_zero=st.sampled_from(["overflow", "overflow", "fault"]), watchdog_ms=st.just(32767))

_settings = dict(max_examples=EXAMPLES, deadline=None, database=None,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                        HealthCheck.filter_too_much])
if _SEED == "0":
    _settings["derandomize"] = True  # CI: the same inputs every run


def _seeded(test):
    return seed(int(_SEED))(test) if _SEED not in ("0", "random") else test


@_seeded
@settings(**_settings)
@given(text=programs(), values=initial_values(), bits=st.integers(0, 2 ** 32 - 1), config=configs)
def test_new_instructions_agree_on_both_executors(text, values, bits, config):
    note(text)
    note(repr(values))
    run_both(text, values, bits, config)


# -- regressions: what the fuzzing found, each a behaviour on both executors ------------------

EXECUTORS = ("compiled", "reference")


def _run(text: str, values: dict, executor: str, scans: int = 1, **config) -> Engine:
    from softplc_lite.ladder import run_text

    return run_text(text, scans=scans, executor=executor, values=values, settings=Settings(**config))


import pytest  # noqa: E402 - the regressions below only


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("mnemonic", ["AVE", "STD"])
def test_ave_std_of_a_file_holding_both_infinities_overflow_with_er(executor, mnemonic):
    # math.fsum refuses inf + -inf (ValueError: major fault 255 before)
    e = _run(f"{mnemonic} #F8:0 F8:10 R6:0 3 0", {"F8:0": math.inf, "F8:1": -math.inf, "F8:2": 1.0}, executor)
    assert e.fault is None
    assert math.isnan(e.table.read("F8:10"))
    assert e.table.read("R6:0/ER") == 1 and e.table.read("R6:0/DN") == 0
    assert e.table.read("S:0/1") == 1 and e.table.read("S:10/14") == 1


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("words", [(-1, -1), (0, 0x7F80 - 0x10000 + 0x10000), (0, -128)])  # NaN, +inf, -inf
def test_pid_with_a_non_finite_integral_word_restarts_the_integral(executor, words):
    # words 17-18 (the integral, float32 low word first) written by the program: NaN or inf
    # (ValueError "cannot convert float NaN to integer": major fault 255 before)
    values = {"N10:2": 2000, "N10:3": 200, "N10:4": 50, "N10:13": 10, "N11:0": 1000,
              "N10:17": words[0], "N10:18": words[1]}
    e = _run("PID N10:0 N11:0 0 N11:1", values, executor)
    assert e.fault is None
    # as from a clean block: 2 x 1000 + 0.5 x 1000 x 0.1
    assert e.table.read("N11:1") == 2050


@pytest.mark.parametrize("executor", EXECUTORS)
def test_pid_with_a_nan_last_derivative_input_takes_no_derivative_that_update(executor):
    values = {"N10:2": 2000, "N10:3": 100, "N10:5": 100, "N10:13": 10, "N11:0": 1000}
    e = _run("PID N10:0 N11:0 0 N11:1", values, executor)
    e.table.write_word("N10:19", 0xFFFF)
    e.table.write_word("N10:20", 0xFFFF)  # NaN
    e.scan()
    assert e.fault is None
    assert e.table.read("N11:1") == 1000  # Kp E only: no integral, no derivative


_HUGE = "*".join(["(" + "*".join(["L10:0"] * 10) + ")"] * 5)  # (2**31 - 1) ** 50: past the float range


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("text", [
    f'CPT F8:0 "({_HUGE}) | 0.5"',
    f'CPT N7:0 "({_HUGE}) + F8:1"',
    f'CPT L10:1 "({_HUGE}) MOD 2.5"',
    f'FAL R6:0 1 0 ALL F8:0 "({_HUGE}) * 1.5"',
])
def test_an_integer_product_past_the_float_range_overflows(executor, text):
    # int too large to convert to float: major fault 255 before
    e = _run(text, {"L10:0": 2 ** 31 - 1}, executor)
    assert e.fault is None
    assert e.table.read("S:0/1") == 1 and e.table.read("S:10/14") == 1


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_huge_product_compares_as_infinity(executor):
    e = _run(f'CMP "({_HUGE}) > F8:1" OTE B3/0\nCMP "-1 * ({_HUGE}) < F8:1" OTE B3/1',
             {"L10:0": 2 ** 31 - 1, "F8:1": 3.4e38}, executor)
    assert (e.table.read("B3/0"), e.table.read("B3/1")) == (1, 1)


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_tod_of_an_infinite_or_nan_float_overflows(executor, value):
    # _int() made them 0, which TOD converted without V
    e = _run("TOD F8:0 N7:0\nCPT N7:1 \"TOD(F8:0)\"\nCPT N7:2 \"FRD(F8:0)\"",
             {"F8:0": value, "N7:0": 5, "N7:1": 5, "N7:2": 5}, executor)
    assert [e.table.read(f"N7:{k}") for k in range(3)] == [0, 0, 0]
    assert e.table.read("S:0/1") == 1 and e.table.read("S:10/14") == 1


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_bit_of_a_symbol_of_an_slc_io_address_is_decimal_as_in_the_address(executor):
    # SYMBOL Start I:1.0: Start/8 was refused as octal, Start/17 taken as bit 15 and printed I:40/17
    text = "SYMBOL Start I:1.0\nSYMBOL Lamp O:2.1\nXIC Start/8 OTE Lamp/15\nXIC I:1.0/9 OTE Lamp/9"
    e = _run(text, {"I:1.0/8": 1, "I:1.0/9": 1}, executor)
    assert e.table.read("O:2.1/15") == 1 and e.table.read("O:2.1/9") == 1


def test_a_bit_of_an_slc_symbol_past_15_is_refused_and_it_prints_in_slc_form():
    from softplc_lite.ladder.parser import parse_program
    from softplc_lite.ladder.symbols import SymbolIndex, resolve_name
    from softplc_lite.datatable import AddressError

    symbols = SymbolIndex(parse_program("SYMBOL Start I:1.0\nSYMBOL Old I:12").symbols)
    assert str(resolve_name("Start/8", symbols)) == "I:1.0/8"
    assert str(resolve_name("Old/17", symbols)) == "I:12/17"  # PLC-5 form: octal, as before
    with pytest.raises(AddressError, match="bit 16 is past bit 15"):
        resolve_name("Start/16", symbols)


def test_an_offset_past_the_last_slc_slot_is_refused_located():
    from softplc_lite.ladder.parser import parse_program

    _, errors = check(parse_program("SYMBOL Last I:30.31\nXIC Last[1] OTE O:0/0\nXIC Last[0]/3 OTE O:0/1"))
    assert [(e.pos.line, "past the last SLC slot 30" in e.message) for e in errors] == [(2, True)]


def test_an_slc_address_stepped_past_slot_30_prints_in_plc5_form_that_parses_back():
    from softplc_lite.datatable import parse_address

    a = parse_address("I:30.31/3").with_element(30 * 32 + 32)
    assert str(a) == "I:1740/3" and parse_address(str(a)) == a


@pytest.mark.parametrize("text", [
    "XIC Q7:0/3 OTE B3/0",
    "BSL #N7:0 R6:0 Q7:0/3 5",
    "SQO #N7:0 0 Q7:0 R6:0 4 0",
    "FAL R6:0 4 0 ALL #Q7:0 1",
    "CPT(N7:0, Q7:0 + 1);",
    "JSR 3 0 Q7:0\nFILE 3\nRET 1",
    "LBL Q7:0\nLBL Q8:0",
])
def test_a_bad_address_is_reported_once_not_again_as_the_constant_0(text):
    # the parser's stand-in for the refused operand drew a second error: "... must be bit address,
    # not the constant 0" (or a return parameter constant, a label 0 defined twice)
    from softplc_lite.ladder.parser import parse_program

    problems: list = []
    program = parse_program(text, "<t>", problems=problems)
    _, errors = check(program)
    assert len(problems) == len(re.findall(r"Q\d", text)) and errors == []


def test_the_compiler_multiplies_inline_unless_a_product_could_pass_the_float_range():
    # _x_mul costs a call per product: only where the operands' bits could add up to 2**1024
    from softplc_lite.ladder.ast import Pos
    from softplc_lite.ladder.expr import to_python
    from softplc_lite.ladder.parser import parse_expression

    def code(text):
        return to_python(parse_expression(text, Pos("<t>", 1, 1)), lambda ref: "x")
    assert "_x_mul" not in code("N7:1 * 3 + N7:2 * N7:3 * L10:0")
    assert "_x_mul" in code(_HUGE)
    assert "_x_mul" in code("(F8:0 OR 0) * 2")  # a float rounded to an integer may be 1024 bits
