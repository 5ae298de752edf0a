"""COP, CPS, FLL, the string instructions, SIZE, string compares and moves,
and GSV/SSV through an export's rungs (logix/copy.py, strings.py,
system.py), on both executors: what each rung becomes, the cases 1756-RM003
gives, and what is not run said as a warning."""

from __future__ import annotations

import struct

import pytest

from softplc_lite.app import AppError, load_app
from softplc_lite.runner import RunOptions, Runner

from helpers.logix_l5x import Prog, Task, write_l5x, read_tag, write_tag, export_runner

EXECUTORS = pytest.mark.parametrize("executor", ["compiled", "reference"])
TYPES = """<DataType Name="Pt" Family="NoFamily" Class="User"><Members>
<Member Name="ZZZZZZZZZZPt0" DataType="SINT" Dimension="0" Radix="Decimal" Hidden="true" ExternalAccess="Read/Write"/>
<Member Name="On" DataType="BIT" Dimension="0" Radix="Decimal" Hidden="false" Target="ZZZZZZZZZZPt0" BitNumber="0"
 ExternalAccess="Read/Write"/>
<Member Name="X" DataType="REAL" Dimension="0" Radix="Float" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="H" DataType="DINT" Dimension="3" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="Name" DataType="STRING" Dimension="0" Radix="NullType" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>
<DataType Name="Stamp" Family="NoFamily" Class="User"><Members>
{STAMP}
</Members></DataType>
<DataType Name="STRING8" Family="StringFamily" Class="User"><Members>
<Member Name="LEN" DataType="DINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>
<Member Name="DATA" DataType="SINT" Dimension="8" Radix="ASCII" Hidden="false" ExternalAccess="Read/Write"/>
</Members></DataType>"""
TYPES = TYPES.replace("{STAMP}", "\n".join(
    f'<Member Name="{m}" DataType="DINT" Dimension="0" Radix="Decimal" Hidden="false" ExternalAccess="Read/Write"/>'
    for m in ("Note", "Yr", "Mo", "Da", "Hr", "Min", "Sec", "uSec")))
TAGS = [("A", "DINT[5]"), ("B", "DINT[5]"), ("I", "INT[4]"), ("R", "REAL[3]"), ("P", "Pt[3]"), ("Q", "Pt[3]"),
        ("One", "Pt"), ("S1", "STRING"), ("S2", "STRING"), ("S3", "STRING"), ("Short", "STRING8"),
        ("Names", "STRING[3]"), ("N", "DINT"), ("N2", "DINT"), ("F", "REAL"), ("DT", "DINT[7]"), ("Us", "LINT"),
        ("Flag", "BOOL"), ("Flag3", "BOOL"), ("k", "DINT"), ("Grid", "INT[2,3]"), ("T1", "TIMER"),
        ("T2", "TIMER"), ("Zero", "DINT"), ("Flag2", "DINT"), ("When", "Stamp"),
        ("Msg", "MESSAGE")]


def runner(tmp_path, rungs, executor="compiled") -> Runner:
    path = write_l5x(tmp_path / "x.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])], data_types=TYPES)
    return export_runner(path, executor)




def warnings_of(tmp_path, rungs) -> str:
    path = write_l5x(tmp_path / "w.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])], data_types=TYPES)
    return "\n".join(load_app(path).warnings)


def errors_of(tmp_path, rungs) -> list[str]:
    path = write_l5x(tmp_path / "e.L5X", TAGS, [Prog("P", {"Main": rungs})], [Task("T", ["P"])], data_types=TYPES)
    with pytest.raises(AppError) as info:
        load_app(path)
    return [str(e) for e in info.value.errors]


# -- COP, CPS, FLL ---------------------------------------------------------------------------

@EXECUTORS
@pytest.mark.parametrize("mnemonic", ["COP", "CPS"])
def test_cop_and_cps_of_whole_arrays_stop_at_the_destination_end(tmp_path, executor, mnemonic):
    r = runner(tmp_path, [f"{mnemonic}(A,B,10);", f"{mnemonic}(A[1],A[0],4);"], executor)
    for k in range(5):
        write_tag(r, f"A[{k}]", k + 1)
    r.run(1)
    assert [read_tag(r, f"B[{k}]") for k in range(5)] == [1, 2, 3, 4, 5] and r.engine.fault is None
    assert [read_tag(r, f"A[{k}]") for k in range(5)] == [2, 3, 4, 5, 5]  # overlapping: as a move
    r.close()


@EXECUTORS
def test_cop_between_types_copies_logix_bytes(tmp_path, executor):
    r = runner(tmp_path, ["COP(R[0],A[3],2);", "COP(A[0],I[0],2);"], executor)
    write_tag(r, "R[0]", 1.5)
    write_tag(r, "A[0]", 0x00020001)
    r.run(1)
    assert read_tag(r, "A[3]") == 0x3FC00000 and read_tag(r, "A[4]") == 0  # R[1] is 0.0
    assert [read_tag(r, "I[0]"), read_tag(r, "I[1]")] == [1, 2]  # a DINT's low INT first
    r.close()


@EXECUTORS
def test_cop_of_structures_copies_every_member_bools_arrays_and_strings(tmp_path, executor):
    r = runner(tmp_path, ["COP(P[0],Q[1],5);", "COP(P[1],One,1);", "COP(T1,T2,1);"], executor)
    write_tag(r, "P[0].X", 3.25)
    write_tag(r, "P[0].H[2]", 9)
    write_tag(r, "P[0].On", 1)
    write_tag(r, "P[0].Name", "feed")
    write_tag(r, "P[1].H[0]", 5)
    write_tag(r, "Q[2].X", 7.0)
    write_tag(r, "T1.PRE", 1500)
    r.run(1)
    assert (read_tag(r, "Q[1].X"), read_tag(r, "Q[1].H[2]"), read_tag(r, "Q[1].On"), read_tag(r, "Q[1].Name")) == (3.25, 9, 1, "feed")
    assert read_tag(r, "Q[2].H[0]") == 5 and read_tag(r, "Q[2].X") == 0.0  # P[1] into Q[2]; then the end of Q
    assert read_tag(r, "Q[0].X") == 0.0 and read_tag(r, "One.H[0]") == 5 and read_tag(r, "T2.PRE") == 1500
    r.close()


@EXECUTORS
def test_cop_with_an_index_tag_and_a_length_tag(tmp_path, executor):
    r = runner(tmp_path, ["COP(A[k],B[N],N2);", "COP(P[k],Q[0],1);"], executor)
    for k in range(5):
        write_tag(r, f"A[{k}]", 10 + k)
    write_tag(r, "k", 2)
    write_tag(r, "N", 1)
    write_tag(r, "N2", 2)
    write_tag(r, "P[2].H[1]", 8)
    r.run(1)
    assert [read_tag(r, f"B[{k}]") for k in range(5)] == [0, 12, 13, 0, 0] and read_tag(r, "Q[0].H[1]") == 8
    write_tag(r, "k", 3)
    write_tag(r, "N", 7)  # the destination index past the array: major fault 20 as for any subscript
    r.run(1)
    assert r.engine.fault is not None and r.engine.fault.code == 20
    r.close()


@EXECUTORS
def test_fll_converts_with_logix_rules_and_clears_structures(tmp_path, executor):
    r = runner(tmp_path, ["FLL(70000,I[1],10);", "FLL(2.5,A[0],2);", "FLL(0,P[1],2);", "FLL(F,R,3);"], executor)
    write_tag(r, "P[1].X", 1.0)
    write_tag(r, "P[2].Name", "x")
    write_tag(r, "P[0].H[0]", 4)
    write_tag(r, "F", -1.25)
    r.run(1)
    assert [read_tag(r, f"I[{k}]") for k in range(4)] == [0, 4464, 4464, 4464]  # low 16 bits of 70000, to the end
    assert [read_tag(r, "A[0]"), read_tag(r, "A[1]")] == [2, 2]  # half to even
    assert read_tag(r, "P[1].X") == 0.0 and read_tag(r, "P[2].Name") == "" and read_tag(r, "P[0].H[0]") == 4
    assert [read_tag(r, f"R[{k}]") for k in range(3)] == [-1.25] * 3
    r.close()


def test_cop_and_fll_that_softplc_lite_does_not_run_are_warnings(tmp_path):
    warnings = warnings_of(tmp_path, ["COP(P[0],A[0],1);", "FLL(5,P[0],1);", "COP(S1,A[0],1);", "COP(Flag,N,1);",
                                      "FLL(S1,A[0],2);", "FLL(5,Names[0],2);"])
    assert "rung 0: COP: a copy from a Pt into a DINT copies Logix's byte layout" in warnings
    assert "rung 1: FLL: a FLL of a number into Pt structures" in warnings
    assert "rung 2: COP: a copy from a STRING into a DINT" in warnings
    assert "rung 3: COP: Flag is a BOOL" in warnings
    assert "rung 4: FLL: a FLL of a string into DINT" in warnings and "rung 5: FLL: a FLL of a number into STRING" \
        in warnings
    assert warnings.count("the rung is not run") == 6


@EXECUTORS
def test_fll_of_a_string_or_of_0_into_strings(tmp_path, executor):
    r = runner(tmp_path, ["FLL(S1,Names[1],5);", "FLL(0,S2,1);"], executor)
    write_tag(r, "S1", "idle")
    write_tag(r, "S2", "x")
    r.run(1)
    assert [read_tag(r, f"Names[{k}]") for k in range(3)] == ["", "idle", "idle"] and read_tag(r, "S2") == ""
    r.close()


def test_question_marks_string_literals_and_message_members_are_warnings(tmp_path):
    warnings = warnings_of(tmp_path, ["COP(?,?,1);", "MOVE('hello',S1);", "CONCAT(Msg.LocalElement,S1,S2);",
                                      "CONCAT(Msg.Path,S1,S2);"])
    assert "rung 0: COP operand '?': an operand left as ?" in warnings
    assert "rung 1: MOVE operand \"'hello'\": a string literal is not yet taken by softplc_lite" in warnings
    assert "rung 2: CONCAT operand 'Msg.LocalElement': LocalElement of a MESSAGE is not held by softplc_lite" \
        in warnings
    assert "rung 3" not in warnings  # a MESSAGE's Path is a STRING softplc_lite holds


def test_cop_with_a_wrong_operand_is_a_located_error(tmp_path):
    errors = errors_of(tmp_path, ["COP(A,Nope,2);", "FLL(1,A[0]);"])
    assert "rung 0: COP operand 'Nope': unknown tag 'Nope'" in errors[0]
    assert "rung 1: FLL takes 3 operands, found 2" in errors[1]


# -- strings ---------------------------------------------------------------------------------

@EXECUTORS
def test_concat_mid_find_insert_delete_upper_lower_on_tags(tmp_path, executor):
    r = runner(tmp_path, ["CONCAT(S1,S2,S3);", "MID(S3,3,2,Names[0]);", "FIND(S3,S2,1,N);",
                          "INSERT(S1,S2,2,Names[1]);", "DELETE(S3,2,1,Names[2]);", "UPPER(S3,S1);",
                          "LOWER(S1,S2);", "CONCAT(S3,S3,Short);"], executor)
    write_tag(r, "S1", "Ab")
    write_tag(r, "S2", "Cd")
    r.run(1)
    assert read_tag(r, "S3") == "AbCd" and read_tag(r, "Names[0]") == "bCd" and read_tag(r, "N") == 3
    assert read_tag(r, "Names[1]") == "ACdb" and read_tag(r, "Names[2]") == "Cd"
    assert read_tag(r, "S1") == "ABCD" and read_tag(r, "S2") == "abcd"
    assert read_tag(r, "Short") == "AbCdAbCd"  # 8 characters: a STRING8 holds them
    r.close()


@EXECUTORS
def test_concat_past_a_string_types_size_truncates_with_the_minor_fault(tmp_path, executor):
    r = runner(tmp_path, ["CONCAT(S1,S1,Short);"], executor)
    write_tag(r, "S1", "12345")
    r.run(1)
    assert read_tag(r, "Short") == "12345123" and read_tag(r, "S:MINOR") == 0  # S:MINOR is S:10/14, the overflow bit
    assert r.table.read("S:17/2") == 1
    r.close()


@EXECUTORS
def test_dtos_stod_rtos_stor(tmp_path, executor):
    r = runner(tmp_path, ["DTOS(N,S1);", "STOD(S1,N2);", "RTOS(F,S2);", "STOR(S2,R[0]);", "STOD(S3,k);"], executor)
    write_tag(r, "N", -1234567)
    write_tag(r, "F", 0.1)
    write_tag(r, "S3", "Tank 12")
    r.run(1)
    assert read_tag(r, "S1") == "-1234567" and read_tag(r, "N2") == -1234567
    assert read_tag(r, "S2") == "0.1" and abs(read_tag(r, "R[0]") - 0.1) < 1e-7 and read_tag(r, "k") == 12
    r.close()


@EXECUTORS
def test_size_of_arrays_by_dimension(tmp_path, executor):
    r = runner(tmp_path, ["SIZE(A,0,N);", "SIZE(Grid,1,N2);", "SIZE(P[0].H,0,k);"], executor)
    r.run(1)
    assert (read_tag(r, "N"), read_tag(r, "N2"), read_tag(r, "k")) == (5, 3, 3)
    r.close()


@EXECUTORS
def test_size_of_an_arrays_first_element_as_exports_write_it(tmp_path, executor):
    r = runner(tmp_path, ["SIZE(A[0],0,N);", "SIZE(Grid[0,0],1,N2);", "SIZE(P[k].H[0],0,k);"], executor)
    r.run(1)
    assert (read_tag(r, "N"), read_tag(r, "N2"), read_tag(r, "k")) == (5, 3, 3)
    r.close()


def test_size_of_a_dimension_the_array_does_not_have_is_a_located_error(tmp_path):
    errors = errors_of(tmp_path, ["SIZE(A,1,N);", "SIZE(N,0,k);"])
    assert "SIZE operand '1': expected the dimension to vary as a number from 0 to 0" in errors[0]
    assert "SIZE operand 'N': expected an array, found DINT" in errors[1]


@EXECUTORS
@pytest.mark.parametrize("mnemonic, out", [("EQU", 0), ("NEQ", 1), ("LES", 1), ("GRT", 0), ("LEQ", 1), ("GEQ", 0),
                                           ("EQ", 0), ("LT", 1)])
def test_equ_neq_les_grt_leq_geq_compare_strings(tmp_path, executor, mnemonic, out):
    r = runner(tmp_path, [f"{mnemonic}(S1,S2)OTE(Flag);", "EQU(S1,S1)EQU(N,0)OTE(Flag3);"], executor)
    write_tag(r, "S1", "AB")
    write_tag(r, "S2", "AC")
    r.run(1)
    assert read_tag(r, "Flag") == out and read_tag(r, "Flag3") == 1
    r.close()


@EXECUTORS
def test_mov_and_move_of_a_string(tmp_path, executor):
    r = runner(tmp_path, ["MOV(S1,S2);", "MOVE(S1,Names[2]);", "MOV(5,N);"], executor)
    write_tag(r, "S1", "hello")
    r.run(1)
    assert read_tag(r, "S2") == "hello" and read_tag(r, "Names[2]") == "hello" and read_tag(r, "N") == 5
    r.close()


@EXECUTORS
def test_cop_and_mov_of_a_string_into_a_smaller_string_type_cut_it_to_fit(tmp_path, executor):
    r = runner(tmp_path, ["COP(S1,Short,1);", "MOV(S1,S3);", "MOV(Short,S2);"], executor)
    write_tag(r, "S1", "0123456789")
    r.run(1)
    assert read_tag(r, "Short") == "01234567" and read_tag(r, "S3") == "0123456789" and read_tag(r, "S2") == "01234567"
    assert read_tag(r, "Short.LEN") == 8
    r.close()


def test_a_string_instruction_on_a_number_is_a_located_error(tmp_path):
    errors = errors_of(tmp_path, ["CONCAT(S1,N,S2);", "EQU(S1,N)OTE(Flag);"])
    assert "CONCAT operand 'N': expected a string, found DINT" in errors[0]
    assert "EQU operand 'N': expected a string, found DINT" in errors[1]


# -- GSV, SSV --------------------------------------------------------------------------------

@EXECUTORS
def test_gsv_and_ssv_of_the_wall_clock(tmp_path, executor):
    r = runner(tmp_path, ["XIC(Flag)SSV(WallClockTime,,DateTime,DT);", "GSV(WallClockTime,,CurrentValue,Us);",
                          "GSV(WALLCLOCKTIME,,DATETIME,DT[0]);"], executor)
    for k, v in enumerate((2030, 1, 2, 3, 4, 5, 0)):
        write_tag(r, f"DT[{k}]", v)
    write_tag(r, "Flag", 1)
    r.run(1)
    assert read_tag(r, "Us") == 1893553445_000_000  # 2030-01-02 03:04:05 UTC
    write_tag(r, "Flag", 0)
    r.run(10)
    assert [read_tag(r, f"DT[{k}]") for k in range(7)] == [2030, 1, 2, 3, 4, 5, 100_000]
    r.close()


@EXECUTORS
def test_gsv_of_task_program_and_fault_log_and_ssv_of_a_programs_disable_flag(tmp_path, executor):
    r = runner(tmp_path, ["GSV(Task,T,LastScanTime,N);", "GSV(Program,THIS,MaxScanTime,N2);",
                          "GSV(Program,P,DisableFlag,k);", "CONCAT(S1,S1,Short);",
                          "GSV(FaultLog,,MinorFaultBits,A[0]);", "SSV(FaultLog,,MinorFaultBits,Zero);",
                          "GSV(FaultLog,,MinorFaultBits,A[1]);", "XIC(Flag)SSV(Program,THIS,DisableFlag,Flag2);"],
               executor)
    write_tag(r, "S1", "123456")
    r.run(2)
    assert (read_tag(r, "N"), read_tag(r, "N2"), read_tag(r, "k")) == (10_000, 10_000, 0)  # 10 ms simulated scans, in µs
    assert [read_tag(r, "A[0]"), read_tag(r, "A[1]")] == [16, 0]
    write_tag(r, "Flag", 1)
    write_tag(r, "Flag2", 1)
    r.run(1)
    assert read_tag(r, "Program:P.DisableFlag") == 1
    write_tag(r, "N", 0)
    r.run(1)
    assert read_tag(r, "N") == 0  # the program is disabled
    r.close()


@EXECUTORS
def test_gsv_and_ssv_of_a_date_time_into_a_structures_dints_and_a_real_gets_the_bytes(tmp_path, executor):
    r = runner(tmp_path, ["XIC(Flag)SSV(WallClockTime,,DateTime,When.Yr);", "GSV(WallClockTime,,DateTime,When.Yr);",
                          "GSV(Task,T,LastScanTime,F);"], executor)
    for member, v in zip(("Yr", "Mo", "Da", "Hr", "Min", "Sec", "uSec"), (2031, 12, 31, 23, 59, 59, 990_000)):
        write_tag(r, f"When.{member}", v)
    write_tag(r, "When.Note", 77)
    write_tag(r, "Flag", 1)
    r.run(1)
    write_tag(r, "Flag", 0)
    r.run(1)
    assert [read_tag(r, f"When.{m}") for m in ("Yr", "Mo", "Da", "Hr", "Min", "Sec", "uSec")] == [2032, 1, 1, 0, 0, 0,
                                                                                              0]
    assert read_tag(r, "When.Note") == 77
    assert read_tag(r, "F") == struct.unpack("f", struct.pack("i", 10_000))[0]  # the DINT's bytes, not 10000.0
    r.close()


@EXECUTORS
def test_gsv_of_a_tasks_priority_rate_and_watchdog_gives_the_exports(tmp_path, executor):
    r = runner(tmp_path, ["GSV(Task,T,Priority,N);", "GSV(TASK,T,WATCHDOG,N2);", "GSV(Task,T,Rate,k);"], executor)
    r.run(1)
    assert (read_tag(r, "N"), read_tag(r, "N2"), read_tag(r, "k")) == (10, 500_000, 0)  # a continuous task has no Rate
    r.close()


def test_gsv_of_what_softplc_lite_does_not_hold_is_a_warning(tmp_path):
    warnings = warnings_of(tmp_path, ["GSV(Module,Rack,EntryStatus,N);", "SSV(Axis,Servo,HomeSpeed,F);",
                                      "SSV(Task,T,Priority,N);"])
    assert "rung 2: SSV: SSV of Task.Priority is not applied by softplc_lite" in warnings
    assert "rung 0: GSV: Module.EntryStatus is not an attribute softplc_lite holds" in warnings
    assert "rung 1: SSV: Axis.HomeSpeed is not an attribute softplc_lite holds" in warnings


def test_gsv_into_a_too_small_destination_is_a_located_error(tmp_path):
    errors = errors_of(tmp_path, ["GSV(WallClockTime,,DateTime,DT[3]);", "GSV(Task,T,LastScanTime,Flag);"])
    assert "takes 7 DINTs: expected an array with 7 elements from here" in errors[0]
    assert "expected a DINT, found BOOL" in errors[1]


def test_the_watch_view_shows_string_compares_and_copies_by_logix_name(tmp_path):
    from softplc_lite.watch.session import WatchOptions, WatchSession
    from softplc_lite.watch.snapshot import render

    path = write_l5x(tmp_path / "v.L5X", TAGS, [Prog("P", {"Main": ["NEQ(S1,S2)CONCAT(S1,S2,S3);",
                                                                    "COP(A,B,5)BXOR(N,16#FF,N);"]})],
                     [Task("T", ["P"])], data_types=TYPES)
    s = WatchSession(load_app(path, tmp_path / "state"), WatchOptions(run=RunOptions(fresh=True), online=False))
    try:
        s.engine.table.write(s.app.program.symbols.resolve_path("S1"), "ab")
        s.scan()
        text = render(s, 140, 30).export_text()
    finally:
        s.quit()
    assert "+-NEQ" in text and "S1=\"ab\" <> S2" in text and "+-CONCAT" in text and "+-COP" in text
    assert "|A[0]=0 -> B[0]=0 length 5|" in text and "dest end" not in text
    assert "N=255 XOR 255 -> N=255" in text and "LSCMP" not in text and "LCOP" not in text
