"""Add-On Instructions run (logix/aoi.py, ladder/instr/logix_aoi.py;
docs/logix.md "Add-On Instructions"), on both executors: an AOI with Input,
Output and InOut parameters and a local TIMER called with two instances,
EnableIn false, an EnableInFalse routine, nested calls, a variable index in an
InOut argument; errors at the call located and said at once; a
source-protected AOI a warning; the fixtures that hold AOIs load."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.runner import RunOptions, Runner

from helpers.cli import softplc_here
from helpers.logix_aoi import Aoi, Param, write_aoi_l5x
from helpers.logix_l5x import Prog, Task, read_tag, write_tag, export_runner

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "logix"
EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])
TIMER_30 = ('<Structure DataType="TIMER">\n<DataValueMember Name="PRE" DataType="DINT" Radix="Decimal" Value="30"/>\n'
            "</Structure>")

# Out = In * Gain; the caller's Count (InOut) counts the runs; Done is the local TIMER's DN (30 ms).
SCALE = Aoi("Scale", [Param("In", "REAL", "Input"), Param("Gain", "REAL", "Input", required=False, default="2.0"),
                      Param("Out", "REAL", "Output"), Param("Count", "DINT", "InOut"),
                      Param("Done", "BOOL", "Output")],
            {"Logic": ["MUL(In,Gain,Out);", "ADD(Count,1,Count);", "TON(Delay,?,?);", "XIC(Delay.DN)OTE(Done);",
                       "ADD(Runs,1,Runs);"]},
            [("Delay", "TIMER", TIMER_30), ("Runs", "DINT", None)])
SCALE_TAGS = [("S1", "Scale"), ("S2", "Scale"), ("Go1", "BOOL"), ("Go2", "BOOL"), ("In1", "REAL"), ("Out1", "REAL"),
              ("Out2", "REAL"), ("Cnt1", "DINT"), ("Cnt2", "DINT"), ("Done1", "BOOL"), ("Done2", "BOOL"),
              ("Eo1", "BOOL"), ("Eo2", "BOOL")]
SCALE_RUNGS = ["XIC(Go1)Scale(S1,In1,Out1,Cnt1,Done1)OTE(Eo1);", "XIC(Go2)Scale(S2,5.0,Out2,Cnt2,Done2)OTE(Eo2);"]


def runner(tmp_path, aois, tags, rungs, executor) -> Runner:
    path = write_aoi_l5x(tmp_path / "aoi.L5X", aois, tags, [Prog("P", {"Main": rungs})], [Task("T", ["P"])])
    return export_runner(path, executor)




@EXECUTORS
def test_two_instances_run_the_logic_each_with_its_own_data(tmp_path, executor):
    r = runner(tmp_path, [SCALE], SCALE_TAGS, SCALE_RUNGS, executor)
    assert read_tag(r, "S1.Gain") == 2.0 and read_tag(r, "S2.Delay.PRE") == 30  # the AOI's defaults
    write_tag(r, "In1", 1.5)
    write_tag(r, "Go1", 1)
    write_tag(r, "Go2", 1)
    r.run(1)
    assert read_tag(r, "Out1") == 3.0 and read_tag(r, "Out2") == 10.0  # In * Gain, the constant 5.0 for S2
    assert read_tag(r, "S1.In") == 1.5 and read_tag(r, "S1.Out") == 3.0
    assert read_tag(r, "Cnt1") == 1 and read_tag(r, "Cnt2") == 1 and read_tag(r, "Eo1") == 1 and read_tag(r, "S1.EnableOut") == 1
    write_tag(r, "S2.Gain", 3.0)  # an instance's member, set from outside: S2 alone changes
    write_tag(r, "Go1", 0)
    r.run(5)
    assert read_tag(r, "Out2") == 15.0 and read_tag(r, "Out1") == 3.0
    assert read_tag(r, "Cnt1") == 1 and read_tag(r, "Cnt2") == 6 and read_tag(r, "S1.Runs") == 1 and read_tag(r, "S2.Runs") == 6
    assert read_tag(r, "Done2") == 1 and read_tag(r, "S2.Delay.DN") == 1 and read_tag(r, "Done1") == 0  # 30 ms of 10 ms scans
    r.close()


@EXECUTORS
def test_enablein_false_skips_the_logic_clears_enableout_and_copies_nothing(tmp_path, executor):
    r = runner(tmp_path, [SCALE], SCALE_TAGS, SCALE_RUNGS, executor)
    write_tag(r, "Go1", 1)
    write_tag(r, "In1", 2.0)
    r.run(4)
    assert read_tag(r, "Done1") == 1 and read_tag(r, "S1.Delay.ACC") == 30
    write_tag(r, "Go1", 0)
    write_tag(r, "In1", 7.0)
    r.run(2)
    assert read_tag(r, "S1.EnableIn") == 0 and read_tag(r, "S1.EnableOut") == 0 and read_tag(r, "Eo1") == 0
    assert read_tag(r, "Cnt1") == 4 and read_tag(r, "S1.In") == 2.0 and read_tag(r, "Out1") == 4.0
    assert read_tag(r, "Done1") == 1 and read_tag(r, "S1.Delay.ACC") == 30  # the TON inside is not scanned false
    r.close()


@EXECUTORS
def test_an_enableinfalse_routine_runs_when_the_rung_is_false(tmp_path, executor):
    hold = Aoi("Hold", [Param("In", "DINT", "Input"), Param("Out", "DINT", "Output")],
               {"Logic": ["ADD(In,100,Out);"], "EnableInFalse": ["MOV(In,Out)ADD(Falses,1,Falses);"]},
               [("Falses", "DINT", None)])
    r = runner(tmp_path, [hold], [("H", "Hold"), ("Go", "BOOL"), ("X", "DINT"), ("Y", "DINT"), ("Eo", "BOOL")],
               ["XIC(Go)Hold(H,X,Y)OTE(Eo);"], executor)
    write_tag(r, "X", 5)
    r.run(2)
    assert read_tag(r, "Y") == 5 and read_tag(r, "H.Falses") == 2 and read_tag(r, "Eo") == 0
    write_tag(r, "Go", 1)
    r.run(1)
    assert read_tag(r, "Y") == 105 and read_tag(r, "H.Falses") == 2 and read_tag(r, "Eo") == 1
    r.close()


TWICE = Aoi("Twice", [Param("X", "DINT", "Input"), Param("Y", "DINT", "Output")], {"Logic": ["MUL(X,2,Y);"]})
BUMP = Aoi("Bump", [Param("V", "DINT", "InOut")], {"Logic": ["ADD(V,1,V);"]})
# B = 4 * A through two calls of an inner instance; Acc (InOut) gets B added, and is passed on to Bump's InOut.
QUAD = Aoi("Quad", [Param("A", "DINT", "Input"), Param("B", "DINT", "Output"), Param("Acc", "DINT", "InOut")],
           {"Logic": ["Twice(T,A,Mid)Twice(T,Mid,B);", "ADD(Acc,B,Acc)Bump(Bp,Acc);"]},
           [("T", "Twice", None), ("Mid", "DINT", None), ("Bp", "Bump", None)])


@EXECUTORS
def test_nested_calls_and_a_variable_index_bound_at_the_call(tmp_path, executor):
    r = runner(tmp_path, [QUAD, TWICE, BUMP],  # QUAD first: its local types are made after it
               [("Q", "Quad"), ("Res", "DINT"), ("Accs", "DINT[3]"), ("I", "DINT")],
               ["Quad(Q,3,Res,Accs[I]);"], executor)
    write_tag(r, "I", 1)
    r.run(2)
    assert read_tag(r, "Res") == 12 and read_tag(r, "Q.Mid") == 6 and read_tag(r, "Q.T.Y") == 12
    assert [read_tag(r, f"Accs[{k}]") for k in range(3)] == [0, 26, 0]  # (12 + 1) twice
    write_tag(r, "I", 2)
    r.run(1)
    assert [read_tag(r, f"Accs[{k}]") for k in range(3)] == [0, 26, 13]
    write_tag(r, "I", 3)  # past the array: Logix faults an out-of-range subscript (major fault type 4, code 20)
    r.run(1)
    assert r.engine.mode.name == "FAULTED"
    r.close()


def test_errors_at_the_call_are_located_and_said_at_once(tmp_path):
    rungs = ["Scale(S1,In1,Out1,Cnt1);", "Scale(S1,In1,Out1,5,Done1);", "Scale(In1,In1,Out1,Out1,Done1);",
             "Scale(S1,In1,3,Cnt1,Done1);", "Scaler(S1);"]
    path = write_aoi_l5x(tmp_path / "bad.L5X", [SCALE], SCALE_TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])])
    with pytest.raises(AppError) as info:
        load_app(path)
    reports = [str(e) for e in info.value.errors]
    lines = path.read_text().splitlines()

    def at(text: str, column_of: str) -> str:
        line = next(k for k, ln in enumerate(lines, 1) if text in ln)
        return f"{path}:{line}:{lines[line - 1].index(column_of) + 1}"

    assert len(reports) == 5, reports
    assert reports[0].startswith(at(rungs[0], "Scale")) and "routine P.Main: rung 0: Scale takes 5 operands" in \
        reports[0] and "found 4" in reports[0]
    assert reports[1].startswith(at(rungs[1], "5,"))
    assert "Count: an InOut parameter is passed by reference" in reports[1]
    assert reports[2].startswith(at(rungs[2], "In1")) and "instance 'In1': expected a tag of type Scale" in reports[2]
    assert reports[3].startswith(at(rungs[2], "Out1,Done1")) and "Count: expected a DINT tag" in reports[3]
    assert reports[4].startswith(at(rungs[3], "3,")) and "expected a tag to receive" in reports[4]
    p = softplc_here("check", str(path))
    assert p.returncode == 1 and "Traceback" not in p.stderr


def test_an_aoi_that_calls_itself_is_an_error(tmp_path):
    loop = Aoi("Loop", [Param("V", "DINT", "InOut")], {"Logic": ["Loop(Me,V);"]}, [("Me", "DINT", None)])
    path = write_aoi_l5x(tmp_path / "loop.L5X", [loop], [("L1", "Loop"), ("V", "DINT")],
                         [Prog("P", {"Main": ["Loop(L1,V);"]})], [Task("T", ["P"])])
    with pytest.raises(AppError) as info:
        load_app(path)
    assert "loop.L5X:20:10: routine Loop.Logic: rung 0: Loop: an Add-On Instruction may not call itself (Loop -> " \
           "Loop)" in str(info.value)


def test_a_source_protected_aoi_is_a_warning_and_its_calls_are_not_run(tmp_path):
    secret = Aoi("Secret", [Param("In", "DINT", "Input")], {}, encoded=True)
    path = write_aoi_l5x(tmp_path / "secret.L5X", [secret], [("K", "Secret"), ("Ran", "BOOL")],
                         [Prog("P", {"Main": ["Secret(K,5)OTE(Ran);", "OTE(Ran);", "Secrets(K,5);"]})],
                         [Task("T", ["P"])])
    app = load_app(path)
    warnings = "\n".join(app.warnings)
    assert "rung 0: Secret: source protected: its logic cannot be read; the rung is not run" in warnings
    assert "rung 2: SECRETS: not an instruction softplc_lite runs yet" in warnings  # neither instruction nor AOI
    r = Runner(app, RunOptions(fresh=True, save_state=False))
    r.run(1)
    assert read_tag(r, "Ran") == 1 and read_tag(r, "K.In") == 0  # the instance is laid out; rung 1 ran
    r.close()


@pytest.mark.parametrize("name", ["whole_controller.L5X", "whole_controller.L5K"])
def test_the_fixture_limiter_runs(tmp_path, name):
    shutil.copy(FIXTURES / name, tmp_path / name)
    p = softplc_here("run", str(tmp_path / name), "--scans", "2", "--executor", "reference", "--print", "Levels[0]",
                     "--print", "Lim1.Out", "--print", "Lim1.EnableOut")
    assert p.returncode == 0, p.stderr
    assert "Limiter" not in p.stderr  # no warning about the AOI, its tag or its call
    assert p.stdout.splitlines()[0].endswith("= 25") and p.stdout.splitlines()[2].endswith("= 1")


def test_the_public_duty_cycle_aois_load_and_their_types_are_held(tmp_path):
    src = FIXTURES / "public" / "Alex-OPTIM__rslogix5000-aois" / "DUTY_CYCLE.L5X"
    app = load_app(shutil.copy(src, tmp_path / "DUTY_CYCLE.L5X"))
    assert not [w for w in app.warnings if "Add-On Instruction" in w]
    types = app.program.symbols.directory.types
    assert [m.name for m in types.get("BOOLS_2_DINT").visible_members()] == ["EnableIn", "EnableOut", "DINT_OUT"]
    # no rung calls them: their logic is checked in files of their own, DUTY_CYCLE's calls to the other two too
    names = sorted(f.name for f in app.program.files.values() if "(" in (f.name or ""))
    assert "DUTY_CYCLE.Logic(not called)" in names and len(names) >= 3


# -- LAIN and LAOUT on the ladder (ladder/instr/logix_aoi.py), each executor (the engine fixture) ------------
# L9:0/0 is EnableIn, L9:0/1 EnableOut; file 3 the Logic (doubles L9:1 into L9:2), file 4 an EnableInFalse routine.
CALL = ("DATA L9 4\nXIC B3/0 LAIN L9:0/0 L9:0/1 {flags} N7:0 L9:1 BST XIC L9:0/0 JSR 3 NXB XIO L9:0/0 JSR 4 BND "
        "LAOUT L9:0/0 L9:0/1 {flags} L9:2 N7:1 OTE B3/1\nFILE 3\nMUL L9:1 2 L9:2\nXIC B3/2 OTU L9:0/1\n"
        "FILE 4\nADD L9:3 1 L9:3\n")


def test_lain_laout_copy_in_run_the_logic_copy_out_and_pass_enableout(engine):
    e = engine(CALL.format(flags=0), {"N7:0": 21, "B3/0": 1})
    e.scan()
    assert e.table.read("L9:0") == 3 and e.table.read("N7:1") == 42 and e.table.read("B3/1") == 1
    assert e.table.read("L9:3") == 0  # the second leg's routine runs only with EnableIn false
    e.table.write("B3/2", 1)  # the Logic clears EnableOut: the rung-out follows it
    e.scan()
    assert e.table.read("L9:0") == 1 and e.table.read("B3/1") == 0 and e.table.read("N7:1") == 42


def test_lain_laout_with_enablein_false_clear_enableout_and_copy_only_for_an_enableinfalse_routine(engine):
    e = engine(CALL.format(flags=0), {"N7:0": 21, "L9:0": 3, "N7:1": 5})
    e.scan()
    assert e.table.read("L9:0") == 0 and e.table.read("L9:1") == 0 and e.table.read("N7:1") == 5
    assert e.table.read("B3/1") == 0 and e.table.read("L9:3") == 1  # the XIO leg ran file 4
    e = engine(CALL.format(flags=1), {"N7:0": 21, "L9:2": 8})
    e.scan()
    assert e.table.read("L9:1") == 21 and e.table.read("N7:1") == 8 and e.table.read("B3/1") == 0


def test_an_instance_in_l5k_data_packs_its_bools_first_and_nests_its_timer_array(tmp_path):
    seq = Aoi("Seq", [Param("In", "DINT", "Input")], {"Logic": ["MOV(In,Last);"]},
              [("Tmrs", "TIMER[2]", None), ("Flag", "BOOL", None), ("Last", "DINT", None)])
    path = write_aoi_l5x(tmp_path / "seq.L5X", [seq], [("Q", "Seq")], [Prog("P", {"Main": ["Seq(Q,3);"]})],
                         [Task("T", ["P"])])
    # as Studio writes an instance's L5K data: the BOOLs' DINT (EnableIn bit 0, Flag bit 2), In, Tmrs, Last
    text = path.read_text().replace('<Tag Name="Q" TagType="Base" DataType="Seq" Constant="false" '
                                    'ExternalAccess="Read/Write"/>',
                                    '<Tag Name="Q" TagType="Base" DataType="Seq" Constant="false" ExternalAccess='
                                    '"Read/Write">\n<Data Format="L5K">\n<![CDATA[[5,7,[[0,100,0],[0,200,0]],9]]]>\n'
                                    '</Data>\n</Tag>')
    path.write_text(text)
    r = export_runner(path)
    assert [read_tag(r, p) for p in ("Q.EnableIn", "Q.EnableOut", "Q.Flag", "Q.In", "Q.Tmrs[1].PRE", "Q.Last")] == \
        [1, 0, 1, 7, 200, 9]
    r.run(1)
    assert read_tag(r, "Q.Last") == 3 and read_tag(r, "Q.EnableOut") == 1
    r.close()


@EXECUTORS
def test_a_user_defined_type_may_hold_an_aoi_instance_and_an_aoi_a_local_of_such_a_type(tmp_path, executor):
    cell = ('<DataTypes>\n<DataType Name="Cell" Family="NoFamily" Class="User">\n<Members>\n'
            '<Member Name="Doubler" DataType="Twice" Dimension="0" Radix="NullType" Hidden="false" '
            'ExternalAccess="Read/Write"/>\n<Member Name="Count" DataType="DINT" Dimension="0" Radix="Decimal" '
            'Hidden="false" ExternalAccess="Read/Write"/>\n</Members>\n</DataType>\n</DataTypes>')
    keeper = Aoi("Keeper", [Param("X", "DINT", "Input")], {"Logic": ["Twice(Inner.Doubler,X,Inner.Count);"]},
                 [("Inner", "Cell", None)])
    path = write_aoi_l5x(tmp_path / "cell.L5X", [keeper, TWICE], [("C", "Cell"), ("K", "Keeper")],
                         [Prog("P", {"Main": ["Twice(C.Doubler,21,C.Count);", "Keeper(K,4);"]})], [Task("T", ["P"])])
    path.write_text(re.sub(r"<DataTypes(/>|>\s*</DataTypes>)", cell, path.read_text(), count=1))
    r = export_runner(path, executor)
    r.run(1)
    assert read_tag(r, "C.Count") == 42 and read_tag(r, "C.Doubler.Y") == 42 and read_tag(r, "K.Inner.Count") == 8
    r.close()


def test_an_aoi_no_rung_calls_has_its_logic_checked(tmp_path):
    lone = Aoi("Lone", [Param("In", "DINT", "Input"), Param("Buf", "DINT[4]", "InOut")],
               {"Logic": ["MOV(In,Buf[2]);", "MOV(In,Nowhere);", "MOV(Buf[In],Last);"]}, [("Last", "DINT", None)])
    path = write_aoi_l5x(tmp_path / "lone.L5X", [lone], [], [Prog("P", {"Main": ["NOP();"]})], [Task("T", ["P"])])
    with pytest.raises(AppError) as info:
        load_app(path)
    line = next(k for k, ln in enumerate(path.read_text().splitlines(), 1) if "MOV(In,Nowhere)" in ln)
    assert str(info.value).startswith(f"{path}:{line}:") and "routine Lone.Logic: rung 1: MOV operand 'Nowhere': " \
        "unknown tag 'Nowhere': the logic of Add-On Instruction Lone names only its parameters and local tags" \
        in str(info.value)
    assert len(info.value.errors) == 1  # its other rungs are right: the InOut array, an index by a parameter


@EXECUTORS
@pytest.mark.parametrize("modes,first", [(None, 101), ([], 1)])
def test_a_prescan_routine_runs_in_the_first_scan_when_the_export_says_so(tmp_path, executor, modes, first):
    prime = Aoi("Prime", [Param("Out", "DINT", "Output")],
                {"Logic": ["ADD(Count,1,Count)MOV(Count,Out);"], "Prescan": ["MOV(100,Count);"]},
                [("Count", "DINT", None)], scan_modes=modes)
    r = runner(tmp_path, [prime], [("P1", "Prime"), ("Out", "DINT")], ["Prime(P1,Out);"], executor)
    r.run(1)
    assert read_tag(r, "Out") == first
    r.run(2)
    assert read_tag(r, "Out") == first + 2  # once, in the first scan only
    r.close()


def test_an_export_without_enablein_and_enableout_parameters_still_has_them(tmp_path):
    bare = Aoi("Bare", [Param("X", "DINT", "Input")], {"Logic": ["MOV(X,Y);"]}, [("Y", "DINT", None)])
    path = write_aoi_l5x(tmp_path / "bare.L5X", [bare], [("B", "Bare"), ("Go", "BOOL")],
                         [Prog("P", {"Main": ["Bare(B,6)OTE(Go);"]})], [Task("T", ["P"])])
    text = path.read_text()
    path.write_text("\n".join(ln for ln in text.splitlines() if 'Name="Enable' not in ln))
    r = export_runner(path)
    r.run(1)
    assert read_tag(r, "B.Y") == 6 and read_tag(r, "B.EnableOut") == 1 and read_tag(r, "Go") == 1
    r.close()
