"""JSR / SBR / RET with input and return parameters.

``JSR file inputs in... ret...``: the first ``inputs`` parameters go to the
addresses of the subroutine's SBR, the rest receive the values of the RET
that ends it (docs/instructions.md, JSR/SBR/RET). Every test runs on both
executors through the ``run`` fixture; the table-level comparison below holds
them to identical data tables.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.cli import main
from softplc_lite.datatable import DataTable
from softplc_lite.datatable.jsonio import dumps
from softplc_lite.ladder import Mode, Settings, check, load_text, parse_program, run_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.ast import address_refs, walk
from softplc_lite.ladder.fmt import format_program
from softplc_lite.ladder.instructions import MAX_PARAMETERS, lookup
from softplc_lite.watch.rungs import RungView


@pytest.fixture(params=["compiled", "reference"])
def run(request):
    """run(text, scans=1, values=None, **kw) -> Engine on one executor; every
    address in ``values`` is created first."""

    def _run(text: str, scans: int = 1, values: dict | None = None, **kw):
        table = DataTable()
        for address in values or {}:
            table.reference(address)
        return run_text(text, scans=scans, executor=request.param, table=table, values=values, **kw)

    return _run


def read(e, *addresses):
    return tuple(e.table.read(a) for a in addresses)


ADD_TWO = """\
JSR 3 2 N7:0 N7:1 N7:10
FILE 3
SBR N7:20 N7:21
ADD N7:20 N7:21 N7:22
RET N7:22
"""


def test_jsr_passes_words_in_and_ret_returns_a_word(run):
    e = run(ADD_TWO, values={"N7:0": 30, "N7:1": 12})
    assert read(e, "N7:20", "N7:21", "N7:22", "N7:10") == (30, 12, 42, 42)
    assert e.mode is Mode.RUN


def test_jsr_inputs_are_read_again_at_every_call(run):
    e = run(ADD_TWO, values={"N7:0": 1, "N7:1": 2})
    assert e.table.read("N7:10") == 3
    e.table.write("N7:1", 100)
    e.scan()
    assert e.table.read("N7:10") == 101


def test_jsr_on_a_false_rung_passes_nothing_and_returns_nothing(run):
    e = run("XIC B3/0 JSR 3 1 N7:0 N7:1\nFILE 3\nSBR N7:5\nRET 77", values={"N7:0": 9, "N7:1": 4})
    assert read(e, "N7:5", "N7:1") == (0, 4)


def test_sbr_floats_and_mixed_parameters_convert_as_mov(run):
    # float into an integer rounds half to even; an integer into a float is exact
    e = run("JSR 3 3 F8:0 N7:0 -2.5 F8:10 N7:10 N7:11\nFILE 3\nSBR N7:20 F8:20 N7:21\n"
            "RET N7:20 F8:20 N7:21",
            values={"F8:0": 2.5, "N7:0": -7})
    assert read(e, "N7:20", "F8:20", "N7:21") == (2, -7.0, -2)
    assert read(e, "F8:10", "N7:10", "N7:11") == (2.0, -7, -2)


def test_ret_float_into_an_integer_return_parameter_rounds(run):
    e = run("JSR 3 1 1.25 N7:1\nFILE 3\nSBR F8:0\nMUL F8:0 2 F8:1\nRET F8:1", values={"N7:1": 0})
    assert read(e, "F8:0", "F8:1", "N7:1") == (1.25, 2.5, 2)


@pytest.mark.parametrize("overflow,stored", [("clamp", 32767), ("wrap", -25536)])
def test_sbr_a_value_that_does_not_fit_overflows_as_mov_does(run, overflow, stored):
    e = run("JSR 3 1 F8:0\nFILE 3\nSBR N7:0", values={"F8:0": 40000.0}, settings=Settings(overflow=overflow))
    assert e.table.read("N7:0") == stored and e.mode is Mode.RUN
    assert e.table.read("S:0") >> S.OVERFLOW & 1
    assert e.table.read(f"S:{S.PLC5_MINOR_FAULT_BITS}") >> S.MINOR_OVERFLOW_BIT & 1
    # the minor fault is located where the value was received: the SBR, program file 3 rung 0
    assert (e.table.read(f"S:{S.MINOR_FAULT_FILE}"), e.table.read(f"S:{S.MINOR_FAULT_RUNG}")) == (3, 0)


def test_jsr_constants_as_input_parameters(run):
    e = run("JSR 3 3 5 -2 0.5 N7:9\nFILE 3\nSBR N7:0 N7:1 F8:0\nCPT F8:1 \"N7:0 * N7:1 + F8:0\"\nRET F8:1")
    assert read(e, "N7:0", "N7:1", "F8:0", "F8:1", "N7:9") == (5, -2, 0.5, -9.5, -10)


def test_jsr_indirect_input_sbr_and_return_addresses(run):
    # N7:50 points the input, N7:51 the SBR's destination, N7:52 the return: the
    # subroutine moves N7:52, and the return goes where it points after the RET.
    e = run("JSR 3 1 N10:[N7:50] N10:[N7:52]\nFILE 3\nSBR N11:[N7:51]\nMOV 6 N7:52\n"
            "ADD N11:[N7:51] 1 N7:0\nRET N7:0",
            values={"N10:9": 0, "N11:9": 0, "N7:50": 2, "N7:51": 4, "N7:52": 5, "N10:2": 41})
    assert read(e, "N11:4", "N7:0", "N10:6", "N10:5") == (41, 42, 42, 0)


def test_jsr_indirect_input_out_of_its_file_faults_20_at_the_jsr(run):
    e = run("MOV 1 N7:0\nJSR 3 1 N7:[N7:60] N7:1\nFILE 3\nSBR N7:2\nRET N7:2", values={"N7:60": 500})
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_INDIRECT_RANGE
    assert (e.fault.file, e.fault.rung) == (2, 1)
    assert e.fault.instruction.startswith("JSR 3 1 N7:[N7:60] N7:1 at ")


def test_ret_indirect_value_out_of_its_file_faults_20_at_the_ret(run):
    e = run("JSR 3 0 N7:1\nFILE 3\nMOV 0 N7:2\nRET N7:[N7:61]", values={"N7:61": 500})
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_INDIRECT_RANGE
    assert (e.fault.file, e.fault.rung) == (3, 1) and e.fault.instruction.startswith("RET N7:[N7:61] at ")


def test_sbr_indirect_destination_out_of_its_file_faults_20_at_the_sbr(run):
    e = run("JSR 3 1 5\nFILE 3\nSBR N7:[N7:62]\nMOV 1 N7:0", values={"N7:62": 500})
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_INDIRECT_RANGE
    assert (e.fault.file, e.fault.rung) == (3, 0) and e.fault.instruction.startswith("SBR N7:[N7:62] at ")
    assert e.table.read("N7:0") == 0


def test_sbr_inputs_are_all_read_before_any_is_written(run):
    # a swap: SBR's first address is JSR's second input and the other way round
    e = run("JSR 3 2 N7:0 N7:1\nFILE 3\nSBR N7:1 N7:0", values={"N7:0": 1, "N7:1": 2})
    assert read(e, "N7:0", "N7:1") == (2, 1)


def test_ret_values_are_all_read_before_any_return_is_written(run):
    e = run("JSR 3 0 N7:1 N7:0\nFILE 3\nRET N7:0 N7:1", values={"N7:0": 1, "N7:1": 2})
    assert read(e, "N7:0", "N7:1") == (2, 1)


def test_ret_without_values_leaves_the_return_parameters_unchanged(run):
    text = ("JSR 3 1 N7:0 N7:1\nFILE 3\nSBR N7:5\nXIC B3/0 RET\nXIC B3/1 RET 99\nRET N7:5")
    e = run(text, values={"N7:0": 4, "N7:1": -1, "B3/0": 1})
    assert e.table.read("N7:1") == -1  # the plain RET returned nothing
    e.table.write("B3/0", 0)
    e.scan()
    assert e.table.read("N7:1") == 4  # the last RET returned N7:5
    e.table.write("B3/1", 1)
    e.scan()
    assert e.table.read("N7:1") == 99


def test_ret_the_end_of_the_file_returns_nothing(run):
    e = run("JSR 3 1 7 N7:1\nFILE 3\nSBR N7:5\nXIC B3/0 RET N7:5", values={"N7:1": -1})
    assert read(e, "N7:5", "N7:1") == (7, -1)


def test_ret_values_to_a_jsr_without_return_parameters_are_dropped(run):
    e = run("JSR 3\nJSR 3 0 N7:1\nFILE 3\nADD N7:0 1 N7:0\nRET N7:0")
    assert read(e, "N7:0", "N7:1") == (2, 2)


def test_jsr_nested_calls_with_parameters(run):
    text = """\
JSR 3 1 N7:0 N7:1
FILE 3
SBR N7:10
MUL N7:10 2 N7:11
JSR 4 2 N7:11 3 N7:12
RET N7:12
FILE 4
SBR N7:20 N7:21
ADD N7:20 N7:21 N7:22
RET N7:22
"""
    e = run(text, values={"N7:0": 5})
    assert read(e, "N7:11", "N7:12", "N7:1") == (10, 13, 13)


FACTORIAL = """\
JSR 3 1 N7:0 N7:1
FILE 3
// n! = n * (n - 1)!, each level keeping its n in N10:[depth]
SBR N7:10
ADD N7:11 1 N7:11
MOV N7:10 N10:[N7:11]
LEQ N7:10 1 BST SUB N7:11 1 N7:11 NXB RET 1 BND
SUB N7:10 1 N7:12
JSR 3 1 N7:12 N7:13
MUL N10:[N7:11] N7:13 N7:14
SUB N7:11 1 N7:11
RET N7:14
"""


def test_jsr_recursion_with_parameters(run):
    e = run(FACTORIAL, values={"N7:0": 6, "N10:9": 0})
    assert e.mode is Mode.RUN and read(e, "N7:1", "N7:11") == (720, 0)


def test_jsr_recursion_deeper_than_jsr_depth_faults_30(run):
    e = run(FACTORIAL, values={"N7:0": 6, "N10:9": 0}, settings=Settings(jsr_depth=4))
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_JSR_NESTING
    assert (e.fault.file, e.fault.rung) == (3, 5) and "nested more than 4 deep" in e.fault.message
    assert e.table.read("N7:1") == 0  # no return reached the main file
    e6 = run(FACTORIAL, values={"N7:0": 4, "N10:9": 0}, settings=Settings(jsr_depth=4))
    assert e6.mode is Mode.RUN and e6.table.read("N7:1") == 24


def test_tnd_in_a_subroutine_with_parameters_ends_the_scan_without_returning(run):
    e = run("JSR 3 1 N7:0 N7:1\nMOV 1 N7:2\nFILE 3\nSBR N7:5\nXIC B3/0 TND\nRET N7:5",
            values={"N7:0": 8, "N7:1": -1, "B3/0": 1})
    assert read(e, "N7:5", "N7:1", "N7:2") == (8, -1, 0) and e.mode is Mode.RUN


def test_jsr_ret_inside_a_branch_leg(run):
    e = run("JSR 3 0 N7:1\nFILE 3\nBST XIC B3/0 RET 5 NXB XIO B3/0 RET 6 BND", values={"B3/0": 1})
    assert e.table.read("N7:1") == 5
    e.table.write("B3/0", 0)
    e.scan()
    assert e.table.read("N7:1") == 6


def test_jsr_most_parameters(run):
    n = MAX_PARAMETERS
    ins = " ".join(f"N7:{k}" for k in range(n))
    rets = " ".join(f"N9:{k}" for k in range(n))
    sbr = " ".join(f"N10:{k}" for k in range(n))
    values = {f"N7:{k}": k * 3 for k in range(n)}
    e = run(f"JSR 3 {n} {ins} {rets}\nFILE 3\nSBR {sbr}\nRET {sbr}", values=values)
    assert [e.table.read(f"N9:{k}") for k in range(n)] == [k * 3 for k in range(n)]


@pytest.mark.parametrize("text", [ADD_TWO, FACTORIAL, "JSR 3 3 F8:0 N7:0 -2.5 F8:10 N7:10 N7:11\nFILE 3\n"
                                  "SBR N7:20 F8:20 N7:21\nRET N7:20 F8:20 N7:21"])
def test_jsr_both_executors_give_identical_tables(text):
    values = {"N7:0": 5, "N7:1": 7, "F8:0": 2.5, "N10:9": 0}
    tables = []
    for executor in ("compiled", "reference"):
        table = DataTable()
        for address in values:
            table.reference(address)
        e = run_text(text, scans=3, executor=executor, table=table, values=values)
        assert e.mode is Mode.RUN
        tables.append(dumps(e.table))
    assert tables[0] == tables[1]


NEUTRAL_ADD_TWO = "JSR(3,2,N7:0,N7:1,N7:10);\nFILE 3\nSBR(N7:20,N7:21);\nADD(N7:20,N7:21,N7:22);\nRET(N7:22);\n"


def test_jsr_sbr_ret_in_neutral_text_run_as_in_mnemonic_text(run):
    a = run(ADD_TWO, values={"N7:0": 30, "N7:1": 12})
    b = run(NEUTRAL_ADD_TWO, values={"N7:0": 30, "N7:1": 12})
    assert dumps(a.table) == dumps(b.table) and b.table.read("N7:10") == 42
    mixed = run("JSR(3,1,-4.5,F8:0);\nFILE 3\nSBR F8:1\nRET(F8:1);")
    assert mixed.table.read("F8:0") == -4.5


def _strip(program):
    """A program's rungs as text-independent tuples (positions dropped)."""
    return {n: [format_program_rung(r) for r in f.rungs] for n, f in program.files.items()}


def format_program_rung(rung):
    from softplc_lite.ladder.fmt import format_rung

    return format_rung(rung, "neutral")


@pytest.mark.parametrize("text", [ADD_TWO, NEUTRAL_ADD_TWO, FACTORIAL])
@pytest.mark.parametrize("style", ["mnemonic", "neutral"])
def test_jsr_fmt_round_trip(text, style):
    program = parse_program(text)
    printed = format_program(program, style)
    again = parse_program(printed)
    assert _strip(again) == _strip(program)
    assert format_program(again, style) == printed


def test_jsr_sbr_ret_fmt_prints_parameters_in_both_styles(tmp_path, capsys):
    (tmp_path / "main.lad").write_text(ADD_TWO.replace("JSR 3 2 N7:0 N7:1 N7:10", "JSR 3 2 N7:0 -5 N7:10"))
    assert main(["fmt", str(tmp_path / "main.lad")]) == 0
    out = capsys.readouterr().out
    assert "JSR 3 2 N7:0 -5 N7:10\n" in out and "SBR N7:20 N7:21\n" in out and "RET N7:22\n" in out
    assert main(["fmt", "--style", "neutral", str(tmp_path / "main.lad")]) == 0
    out = capsys.readouterr().out
    assert "JSR(3,2,N7:0,-5,N7:10);\n" in out and "SBR(N7:20,N7:21);\n" in out and "RET(N7:22);\n" in out


def _errors(text: str) -> list[str]:
    _, errors = check(parse_program(text, source="p.lad"))
    return [str(e) for e in errors]


@pytest.mark.parametrize("text,message", [
    ("JSR 3 2 N7:0 N7:1\nFILE 3\nSBR N7:5",
     "p.lad:1:7: JSR passes 2 input parameters to program file 3, but its SBR at p.lad:3:1 receives 1"),
    ("JSR 3 1 N7:0\nFILE 3\nSBR N7:5 N7:6",
     "p.lad:1:7: JSR passes 1 input parameter to program file 3, but its SBR at p.lad:3:1 receives 2"),
    ("JSR 3 1 N7:0\nFILE 3\nSBR\nMOV 1 N7:1",
     "p.lad:1:7: JSR passes 1 input parameter to program file 3, but it has no SBR with parameters"),
    ("JSR 3\nFILE 3\nSBR N7:5",
     "p.lad:1:1: JSR passes 0 input parameters to program file 3, but its SBR at p.lad:3:1 receives 1"),
    ("JSR 3 3 N7:0 N7:1\nFILE 3\nSBR N7:5",
     "p.lad:1:7: JSR passes 3 input parameters but lists 2 parameters"),
    ("JSR 3 41 N7:0\nFILE 3\nSBR",
     "p.lad:1:7: JSR operand 2 (inputs) must be in 0..40, not the constant 41"),
    ("JSR 3 0 N7:0 5\nFILE 3\nRET 1 2",
     "p.lad:1:14: JSR operand 4 (return parameter) must be a word or float address, not the constant 5"),
    ("JSR 3 0 N7:0\nFILE 3\nMOV 1 N7:1",
     "p.lad:1:1: JSR expects 1 return parameter from program file 3, which has no RET with values"),
    ("JSR 3 0 N7:0 N7:1\nFILE 3\nRET 1",
     "p.lad:1:1: JSR expects 2 return parameters from program file 3, but the RET at p.lad:3:1 returns 1"),
    ("JSR 3\nFILE 3\nMOV 1 N7:0\nSBR N7:5",
     "p.lad:4:1: an SBR with parameters must be the first instruction of the first rung of a subroutine "
     "file (3..999): a JSR passes its inputs there"),
    ("SBR N7:0",
     "p.lad:1:1: an SBR with parameters must be the first instruction of the first rung of a subroutine "
     "file (3..999): a JSR passes its inputs there"),
    ("JSR 3 1 B3/0\nFILE 3\nSBR N7:0",
     "p.lad:1:9: JSR operand 3 (parameter) must be number or word/float address, not B3/0 (a bit)"),
    ("JSR 3 1 5\nFILE 3\nSBR 5",
     "p.lad:3:5: SBR operand 1 (parameter) must be word or float address, not the constant 5"),
    ("JSR 3 0 N7:0\nFILE 3\nRET ST9:0",
     "p.lad:3:5: RET operand 1 (value) must be number or word/float address, not ST9:0 (a string)"),
])
def test_jsr_sbr_ret_check_errors_are_located(text, message):
    assert message in _errors(text)


def test_jsr_check_errors_each_once():
    # one wrong count: one error, not one per consequence
    assert len(_errors("JSR 3 41 N7:0\nFILE 3\nSBR")) == 1
    assert len(_errors("JSR 3 3 N7:0 N7:1\nFILE 3\nSBR N7:5")) == 1


def test_jsr_operand_count_message_shows_the_repeated_operand():
    spec = lookup("JSR")
    assert spec.signature() == "JSR file [inputs] [parameter...]"
    assert lookup("SBR").signature() == "SBR [parameter...]" and lookup("RET").signature() == "RET [value...]"
    too_many = "RET " + " ".join(["1"] * (MAX_PARAMETERS + 1)) + "\n"
    assert _errors(too_many) == [f"p.lad:1:1: RET takes 0..{MAX_PARAMETERS} operands (RET [value...]), "
                                 f"got {MAX_PARAMETERS + 1}"]


def test_jsr_softplc_check_lists_every_problem_located(tmp_path, capsys):
    (tmp_path / "main.lad").write_text("JSR 3 2 N7:0 N7:1\nJSR 3 1 N7:0 5\nFILE 3\nSBR N7:5\nRET N7:5 N7:6\n")
    assert main(["check", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    where = tmp_path / "main.lad"
    assert f"{where}:1:7: JSR passes 2 input parameters to program file 3, but its SBR at {where}:4:1 receives 1" in err
    assert f"{where}:2:14: JSR operand 4 (return parameter) must be a word or float address, not the constant 5" in err
    assert f"{where}:2:1: JSR expects 1 return parameter from program file 3, but the RET at {where}:5:1 returns 2" in err
    assert "3 problems found" in err and "Traceback" not in err


def test_jsr_with_parameters_in_the_watch_view():
    program = load_text(ADD_TWO)
    table = DataTable()
    for ins in walk(program.main.rungs[0].elements):
        for op in ins.operands:
            for ref in address_refs(op):
                table.reference(ref.address)
    table.write("N7:0", 30)
    console = Console(width=100, record=True, color_system=None, file=io.StringIO())
    console.print(RungView(program.main.rungs[0], 0, table, symbols=program.symbols))
    text = console.export_text()
    assert "JSR" in text and "N7:0" in text and "N7:10" in text and "30" in text


@pytest.mark.parametrize("app", ["subroutines", "modbus_slave"])
def test_jsr_programs_with_parameterless_subroutines_still_load(app):
    loaded = load_app(Path(__file__).resolve().parent.parent / "programs" / app)
    assert any(ins.mnemonic == "JSR" for f in loaded.program.files.values() for r in f.rungs
               for ins in walk(r.elements))


def test_jsr_symbols_and_structure_members_as_parameters(run):
    text = ("SYMBOL Level N7:0\nSYMBOL Result F8:3\nJSR 3 2 Level T4:0.ACC Result\nFILE 3\n"
            "SBR N10:0 C5:0.PRE\nCPT F8:0 \"N10:0 / C5:0.PRE\"\nRET F8:0")
    e = run(text, values={"N7:0": 9, "T4:0.ACC": 4})
    assert read(e, "N10:0", "C5:0.PRE", "F8:3") == (9, 4, 2.0)  # 9 / 4 on words: a word result, rounded


def test_jsr_a_ninth_nested_call_faults_with_slc_depth_eight(run):
    # SLC 5/02 and later nest eight levels (1747-RM001, Nesting Subroutine Files)
    text = "JSR 3 1 0\nFILE 3\nSBR N7:0\nADD N7:0 1 N7:0\nLES N7:0 N7:1 JSR 3 1 N7:0"
    ok = run(text, values={"N7:1": 8}, settings=Settings(jsr_depth=8))
    assert ok.mode is Mode.RUN and ok.table.read("N7:0") == 8
    over = run(text, values={"N7:1": 9}, settings=Settings(jsr_depth=8))
    assert over.mode is Mode.FAULTED and over.fault.code == S.FAULT_JSR_NESTING and over.table.read("N7:0") == 8


def test_jsr_and_ret_compiled_code_names_only_allowed_names():
    # the compiled path hands the JSR and the RET to the engine through one bound list, _calls
    from helpers.generated_code import ALLOWED, names_in

    from softplc_lite.ladder import Engine

    engine = Engine(load_text(ADD_TWO + "XIC B3/0 RET 5\n"))
    for number in (2, 3):
        source = engine.files[number][0].source
        assert not [n for n in names_in(source) if not ALLOWED.match(n)]
    assert "_jsr(3, _calls[0])" in engine.files[2][0].source
    assert "return _calls[0]" in engine.files[3][0].source and "return _calls[1]" in engine.files[3][0].source
