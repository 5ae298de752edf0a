"""JSR, SBR and RET parameters that are not one number (logix/subroutines.py,
docs/logix.md "Subroutines with parameters"): a BOOL, a STRING, a
user-defined structure and an array passed by value in and out, from two
call sites with different arguments, on both executors (1756-RM003, "Jump to
Subroutine (JSR), Subroutine (SBR), Return (RET)")."""

from __future__ import annotations

import pytest

from helpers.logix_l5x import Prog, Task, write_l5x
from softplc_lite.app import load_app
from softplc_lite.runner import Runner, RunOptions

EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])
PT = """<DataType Name="Pt" Family="NoFamily" Class="User"><Members>
<Member Name="ZZZZZZZZZZPt0" DataType="SINT" Dimension="0" Radix="Decimal" Hidden="true" ExternalAccess="Read/Write"/>
<Member Name="On" DataType="BIT" Dimension="0" Radix="Decimal" Hidden="false" Target="ZZZZZZZZZZPt0" BitNumber="0"
 ExternalAccess="Read/Write"/>
<Member Name="X" DataType="REAL" Dimension="0" Radix="Float" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="H" DataType="DINT" Dimension="3" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>"""


def start(path, executor: str) -> Runner:
    return Runner(load_app(path), RunOptions(executor=executor, fresh=True, save_state=False), log=lambda m: None)


def tag(r: Runner, path: str):
    return r.engine.table.read(str(r.app.logix.directory.resolve(path).address))


def set_tag(r: Runner, path: str, value) -> None:
    r.engine.table.write(str(r.app.logix.directory.resolve(path).address), value)


def export(tmp_path, main, routines, tags, local):
    return write_l5x(tmp_path / "params.L5X", tags, [Prog("P", {"Main": main, **routines}, main="Main", tags=local)],
                     [Task("T", ["P"])], data_types=PT)


@EXECUTORS
def test_a_bool_input_and_a_bool_return_from_two_call_sites(tmp_path, executor):
    # Invert(b) returns NOT b; called with A into NotA and with B into NotB, and a DINT rides along.
    path = export(tmp_path, ["JSR(Invert,2,A,5,NotA,Count);", "JSR(Invert,2,B,7,NotB,Count2);"],
                  {"Invert": ["SBR(In,K);", "XIC(In)RET(0,K);", "RET(1,K);"]},
                  [("A", "BOOL"), ("B", "BOOL"), ("NotA", "BOOL"), ("NotB", "BOOL"), ("Count", "DINT"),
                   ("Count2", "DINT")], [("In", "BOOL"), ("K", "DINT")])
    r = start(path, executor)
    assert r.app.warnings == []
    set_tag(r, "A", 1)
    r.run(1)
    assert r.engine.fault is None
    assert (tag(r, "NotA"), tag(r, "NotB"), tag(r, "Count"), tag(r, "Count2")) == (0, 1, 5, 7)
    set_tag(r, "A", 0)
    set_tag(r, "B", 1)
    r.run(1)
    assert (tag(r, "NotA"), tag(r, "NotB"), tag(r, "Program:P.In")) == (1, 0, 1)


@EXECUTORS
def test_a_string_input_is_copied_whole(tmp_path, executor):
    path = export(tmp_path, ["JSR(Greet,1,Name1,Out1);", "JSR(Greet,1,Name2,Out2);"],
                  {"Greet": ["SBR(Who);", "CONCAT(Hello,Who,Said);", "RET(Said);"]},
                  [("Name1", "STRING"), ("Name2", "STRING"), ("Out1", "STRING"), ("Out2", "STRING"),
                   ("Hello", "STRING")], [("Who", "STRING"), ("Said", "STRING")])
    r = start(path, executor)
    assert r.app.warnings == []
    set_tag(r, "Hello", "hi ")
    set_tag(r, "Name1", "ann")
    set_tag(r, "Name2", "bob")
    r.run(1)
    assert r.engine.fault is None
    assert (tag(r, "Out1"), tag(r, "Out2"), tag(r, "Program:P.Who")) == ("hi ann", "hi bob", "bob")


@EXECUTORS
def test_a_structure_input_and_return_copy_every_member(tmp_path, executor):
    # Twice(p) returns p with X doubled, H[2] plus one and On inverted.
    path = export(tmp_path, ["JSR(Twice,1,P1,Q1);", "JSR(Twice,1,P2,Q2);"],
                  {"Twice": ["SBR(Pin);", "COP(Pin,Pout,1);", "MUL(Pin.X,2.0,Pout.X);",
                             "ADD(Pin.H[2],1,Pout.H[2]);", "XIC(Pin.On)OTU(Pout.On);", "XIO(Pin.On)OTL(Pout.On);",
                             "RET(Pout);"]},
                  [("P1", "Pt"), ("P2", "Pt"), ("Q1", "Pt"), ("Q2", "Pt")], [("Pin", "Pt"), ("Pout", "Pt")])
    r = start(path, executor)
    assert r.app.warnings == []
    set_tag(r, "P1.X", 1.5)
    set_tag(r, "P1.H[0]", 11)
    set_tag(r, "P1.H[2]", 30)
    set_tag(r, "P1.On", 1)
    set_tag(r, "P2.X", -4.0)
    set_tag(r, "P2.H[1]", 22)
    r.run(1)
    assert r.engine.fault is None
    q1 = [tag(r, f"Q1.{m}") for m in ("X", "H[0]", "H[1]", "H[2]", "On")]
    q2 = [tag(r, f"Q2.{m}") for m in ("X", "H[0]", "H[1]", "H[2]", "On")]
    assert q1 == [3.0, 11, 0, 31, 0]
    assert q2 == [-8.0, 0, 22, 1, 1]


@EXECUTORS
def test_an_array_input_is_copied_whole_and_a_routine_ending_without_ret_returns_nothing(tmp_path, executor):
    path = export(tmp_path, ["JSR(Sum,1,Data,Total,Copy);"],
                  {"Sum": ["SBR(Vals);", "CPT(S,Vals[0]+Vals[1]+Vals[2]+Vals[3]);", "GRT(S,100)RET(S,Vals);"]},
                  [("Data", "DINT[4]"), ("Total", "DINT"), ("Copy", "DINT[4]")], [("Vals", "DINT[4]"), ("S", "DINT")])
    r = start(path, executor)
    assert r.app.warnings == []
    for k, v in enumerate((1, 2, 3, 4)):
        set_tag(r, f"Data[{k}]", v)
    r.run(1)
    assert r.engine.fault is None
    assert tag(r, "Program:P.S") == 10 and [tag(r, f"Program:P.Vals[{k}]") for k in range(4)] == [1, 2, 3, 4]
    assert tag(r, "Total") == 0 and [tag(r, f"Copy[{k}]") for k in range(4)] == [0, 0, 0, 0]  # no RET ran
    set_tag(r, "Data[3]", 400)
    r.run(1)
    assert tag(r, "Total") == 406 and [tag(r, f"Copy[{k}]") for k in range(4)] == [1, 2, 3, 400]


@EXECUTORS
def test_recursion_returns_each_call_its_callees_value(tmp_path, executor):
    # Down(0) is "*", Down(n) is Down(n-1) and one "*" more: each RET's string goes to the JSR returning.
    path = export(tmp_path, ["JSR(Down,1,3,Top);"],
                  {"Down": ["SBR(N);", "EQU(N,0)MOVE(Star,Text)RET(Text);",
                            "SUB(N,1,M)JSR(Down,1,M,Inner)CONCAT(Inner,Star,Text)RET(Text);"]},
                  [("Top", "STRING"), ("Star", "STRING")],
                  [("N", "DINT"), ("M", "DINT"), ("Inner", "STRING"), ("Text", "STRING")])
    r = start(path, executor)
    assert r.app.warnings == []
    set_tag(r, "Star", "*")
    r.run(1)
    assert r.engine.fault is None
    assert tag(r, "Top") == "****" and tag(r, "Program:P.Inner") == "***"


@EXECUTORS
def test_a_parameter_of_another_kind_is_a_warning_and_the_call_is_not_run(tmp_path, executor):
    path = export(tmp_path, ["JSR(Take,1,N);", "ADD(Count,1,Count);", "JSR(Pt1,1,N);", "JSR(Num,1,F);"],
                  {"Take": ["SBR(B);", "ADD(Count,100,Count);"], "Pt1": ["SBR(Pin);", "ADD(Count,100,Count);"],
                   "Num": ["SBR(D);", "ADD(Count,100,Count);"]},
                  [("Count", "DINT"), ("N", "DINT"), ("F", "BOOL")], [("B", "BOOL"), ("Pin", "Pt"), ("D", "DINT")])
    r = start(path, executor)
    warnings = "\n".join(r.app.warnings)
    assert "rung 0: JSR parameter 'N': a DINT passed to a BOOL parameter" in warnings
    assert "rung 2: JSR parameter 'N': a DINT passed to a Pt parameter: the types must match" in warnings
    assert "rung 3: JSR parameter 'F': a BOOL where the routine's SBR or RET has a number" in warnings
    r.run(2)
    assert tag(r, "Count") == 2  # the rest runs


def test_an_aoi_input_that_is_a_string_is_said_as_logix_allows_only_atomic_ones(tmp_path):
    # Studio 5000 makes no such AOI (1756-PM010): the call is a warning, not run; the rest runs.
    from helpers.logix_aoi import Aoi, Param, write_aoi_l5x

    named = Aoi("Named", [Param("Who", "STRING", "Input"), Param("N", "DINT", "Output")], {"Logic": ["MOV(1,N);"]})
    path = write_aoi_l5x(tmp_path / "aoi.L5X", [named], [("K", "Named"), ("S", "STRING"), ("Out", "DINT"),
                                                         ("Ran", "DINT")],
                         [Prog("P", {"Main": ["Named(K,S,Out);", "ADD(Ran,1,Ran);"]})], [Task("T", ["P"])])
    r = start(path, "compiled")
    warnings = "\n".join(r.app.warnings)
    assert "Named: its Input parameter Who is a STRING: Logix passes Input and Output parameters of atomic " \
           "types only (1756-PM010" in warnings
    r.run(1)
    assert tag(r, "Ran") == 1 and tag(r, "Out") == 0


@EXECUTORS
def test_an_argument_indexed_at_run_time_is_the_element_of_the_call_and_past_the_end_faults(tmp_path, executor):
    path = export(tmp_path, ["JSR(Twice,1,Pts[I],Qs[I]);"],
                  {"Twice": ["SBR(Pin);", "COP(Pin,Pout,1);", "MUL(Pin.X,2.0,Pout.X);", "RET(Pout);"]},
                  [("Pts", "Pt[3]"), ("Qs", "Pt[3]"), ("I", "DINT")], [("Pin", "Pt"), ("Pout", "Pt")])
    r = start(path, executor)
    assert r.app.warnings == []
    set_tag(r, "Pts[1].X", 2.5)
    set_tag(r, "Pts[2].X", 7.0)
    set_tag(r, "I", 1)
    r.run(1)
    set_tag(r, "I", 2)
    r.run(1)
    assert r.engine.fault is None
    assert [tag(r, f"Qs[{k}].X") for k in range(3)] == [0.0, 5.0, 14.0]
    set_tag(r, "I", 3)  # past Pt[3]: Logix's major fault type 4, code 20; the ladder's file end
    r.run(1)
    assert r.engine.fault is not None and r.engine.fault.code == 20
