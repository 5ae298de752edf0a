"""Structured Text routines of a Logix export run as ladder rungs
(logix/st_routine.py, logix/st_expr.py, docs/logix.md "Structured Text"), on
both executors: hand-written exports in tmp_path, loaded as an app and run
by the runner as ``softplc run`` runs them."""

from __future__ import annotations

import pytest

from helpers.logix_l5x import Prog, Task, export_runner, read_tag, write_l5x, write_tag
from softplc_lite.app import AppError, load_app
from softplc_lite.ladder import status as S

EXECUTORS = ["compiled", "reference"]
TAGS = [("Count", "DINT"), ("Big", "BOOL"), ("Flag", "BOOL"), ("Sel", "DINT"), ("Sum", "DINT"), ("i", "DINT"),
        ("Arr", "DINT[5]"), ("n", "DINT"), ("r", "REAL"), ("Out", "BOOL"), ("w", "INT"), ("s", "SINT")]


def st_export(tmp_path, st: str, tags=TAGS, main=None, extra=None, tasks=None):
    routines = {"Main": main or ["JSR(Calc,0);"], "Calc": st}
    routines.update(extra or {})
    return write_l5x(tmp_path / "st.L5X", tags, [Prog("MainProgram", routines)],
                     tasks or [Task("T", ["MainProgram"])])


def run_st(tmp_path, executor, st, scans=1, values=None, **kw):
    r = export_runner(st_export(tmp_path, st, **kw), executor)
    for path, value in (values or {}).items():
        write_tag(r, path, value)
    r.run(scans)
    return r


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("count,big,flag", [(7, 1, 0), (3, 0, 1), (1, 0, 0)])
def test_if_elsif_else_takes_the_first_arm_that_holds(tmp_path, executor, count, big, flag):
    st = ("IF Count > 5 THEN Big := 1; Flag := 0;\n"
          "ELSIF Count = 3 THEN Flag := TRUE; Big := FALSE;\n"
          "ELSE Big := 0; Flag := 0;\nEND_IF;")
    r = run_st(tmp_path, executor, st, values={"Count": count, "Flag": 1 - flag, "Big": 1 - big})
    assert (read_tag(r, "Big"), read_tag(r, "Flag")) == (big, flag)


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("count,sel", [(1, 10), (2, 20), (4, 20), (7, 40), (9, 40), (0, 99), (5, 99)])
def test_case_lists_and_ranges_and_else(tmp_path, executor, count, sel):
    st = "CASE Count OF\n 1: Sel := 10;\n 2..4: Sel := 20;\n 7, 8..9: Sel := 40;\nELSE Sel := 99;\nEND_CASE;"
    r = run_st(tmp_path, executor, st, values={"Count": count})
    assert read_tag(r, "Sel") == sel


@pytest.mark.parametrize("executor", EXECUTORS)
def test_case_reads_its_selector_once_though_an_arm_changes_it(tmp_path, executor):
    st = "CASE Count + 0 OF\n 1: Count := 2; Sel := 1;\n 2: Sel := 2;\nEND_CASE;"
    r = run_st(tmp_path, executor, st, values={"Count": 1})
    assert (read_tag(r, "Count"), read_tag(r, "Sel")) == (2, 1)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_for_by_while_repeat_and_exit(tmp_path, executor):
    st = ("Sum := 0;\nFOR i := 0 TO 4 DO Sum := Sum + Arr[i]; END_FOR;\n"
          "n := 0;\nFOR i := 10 TO 1 BY -3 DO n := n + 1; END_FOR;\n"  # 10, 7, 4, 1
          "Sel := 0;\nWHILE Sel < 100 DO Sel := Sel + 7; IF Sel > 50 THEN EXIT; END_IF; END_WHILE;\n"
          "Count := 0;\nREPEAT Count := Count + 1; UNTIL Count >= 3 END_REPEAT;")
    r = run_st(tmp_path, executor, st, values={f"Arr[{k}]": k * k for k in range(5)})
    assert (read_tag(r, "Sum"), read_tag(r, "n"), read_tag(r, "Sel"), read_tag(r, "Count")) == (30, 4, 56, 3)
    assert read_tag(r, "i") == -2  # the count stands one step past the end, as Logix leaves it


@pytest.mark.parametrize("executor", EXECUTORS)
def test_for_with_a_step_from_a_tag_counts_down_or_up(tmp_path, executor):
    st = "n := 0;\nFOR i := Count TO Sel BY Sum DO n := n + 1; END_FOR;"
    r = run_st(tmp_path, executor, st, values={"Count": 10, "Sel": 0, "Sum": -5})
    assert read_tag(r, "n") == 3  # 10, 5, 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_operators_precedence_functions_and_bool_logic(tmp_path, executor):
    st = ("Sum := 2 + 3 * 4 ** 2 - 10 MOD 4;\n"  # 2 + 48 - 2
          "r := SQRT(16.0) + ABS(-2) + TRUNC(2.7);\n"
          "Big := NOT (Count > 3) AND Flag OR Count = 9;\n"
          "n := (Count AND 16#0F) XOR 2#0101;\n"
          "Out := Flag & NOT Big;")
    r = run_st(tmp_path, executor, st, values={"Count": 0x3C, "Flag": 1})
    assert read_tag(r, "Sum") == 48
    assert read_tag(r, "r") == pytest.approx(8.0)
    assert read_tag(r, "Big") == 0 and read_tag(r, "Out") == 1
    assert read_tag(r, "n") == (0x3C & 0x0F) ^ 5


@pytest.mark.parametrize("executor", EXECUTORS)
def test_integer_overflow_wraps_and_sets_the_overflow_flag_as_cpt_does(tmp_path, executor):
    st = "Sum := Count + 1;\nFlag := S:V;\nw := Count;"
    r = run_st(tmp_path, executor, st, values={"Count": 2 ** 31 - 1})
    assert read_tag(r, "Sum") == -(2 ** 31) and read_tag(r, "Flag") == 1
    assert read_tag(r, "w") == -1  # the low 16 bits, as a DINT stored into an INT
    assert r.table.read(f"S:{S.PLC5_MINOR_FAULT_BITS}") >> S.MINOR_OVERFLOW_BIT & 1
    assert r.engine.fault is None


@pytest.mark.parametrize("executor", EXECUTORS)
def test_real_into_an_integer_rounds_half_to_even_and_integer_division_truncates(tmp_path, executor):
    st = "Sum := 2.5;\nn := 3.5;\nSel := 7 / 2;\ni := -7 / 2;"
    r = run_st(tmp_path, executor, st)
    assert [read_tag(r, t) for t in ("Sum", "n", "Sel", "i")] == [2, 4, 3, -3]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_lstb_assigns_a_bool_the_truth_of_an_expression(tmp_path, executor):
    r = run_st(tmp_path, executor, "Flag := Count * 2;\nBig := Count - 4;", values={"Count": 4})
    assert (read_tag(r, "Flag"), read_tag(r, "Big")) == (1, 0)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_bits_of_words_and_indexes_made_of_expressions(tmp_path, executor):
    st = "Arr[Count - 1] := 5;\nArr[Count].3 := 1;\nw.[Count] := 1;\nFlag := Arr[(Count + 1) MOD 5].0;"
    r = run_st(tmp_path, executor, st, values={"Count": 2, "Arr[3]": 3})
    assert read_tag(r, "Arr[1]") == 5 and read_tag(r, "Arr[2]") == 8 and read_tag(r, "w") == 4
    assert read_tag(r, "Flag") == 1


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_index_out_of_range_is_major_fault_20(tmp_path, executor):
    r = run_st(tmp_path, executor, "Arr[Count] := 1;", values={"Count": 5})
    assert r.engine.fault is not None and r.engine.fault.code == 20


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_loop_past_the_watchdog_is_a_major_fault_not_a_hang(tmp_path, executor):
    r = run_st(tmp_path, executor, "WHILE TRUE DO n := n + 1; END_WHILE;")
    assert r.engine.fault is not None and r.engine.fault.code == S.FAULT_WATCHDOG
    assert read_tag(r, "n") > 1000  # it did run, until the watchdog


@pytest.mark.parametrize("executor", EXECUTORS)
def test_return_leaves_the_routine(tmp_path, executor):
    r = run_st(tmp_path, executor, "n := 1;\nIF Flag THEN RETURN; END_IF;\nn := 2;", values={"Flag": 1})
    assert read_tag(r, "n") == 1


@pytest.mark.parametrize("executor", EXECUTORS)
def test_non_retentive_assignment_follows_its_expression_and_clears_on_the_first_scan(tmp_path, executor):
    st = "IF Count > 0 THEN Out [:=] Flag; Sum [:=] 7; END_IF;"
    r = run_st(tmp_path, executor, st, values={"Count": 0, "Out": 1, "Sum": 3})
    assert (read_tag(r, "Out"), read_tag(r, "Sum")) == (0, 0)  # cleared, though the IF did not run
    write_tag(r, "Count", 1)
    write_tag(r, "Flag", 1)
    r.run(1)
    assert (read_tag(r, "Out"), read_tag(r, "Sum")) == (1, 7)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_jsr_from_ladder_to_st_and_from_st_to_ladder(tmp_path, executor):
    extra = {"Ladder": ["ADD(n,10,n);"]}
    r = run_st(tmp_path, executor, "Count := Count + 1;\nJSR(Ladder, 0);", extra=extra, scans=3)
    assert (read_tag(r, "Count"), read_tag(r, "n")) == (3, 30)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_st_main_routine_runs_in_a_periodic_task(tmp_path, executor):
    path = write_l5x(tmp_path / "t.L5X", TAGS, [Prog("Fast", {"Main": "Count := Count + 1;"}),
                                                 Prog("Cont", {"Main": "n := n + 1;"})],
                     [Task("Cyclic", ["Fast"], kind="PERIODIC", rate_ms=50), Task("T", ["Cont"])])
    r = export_runner(path, executor)
    r.run(100)  # 10 ms scans
    assert (read_tag(r, "Count"), read_tag(r, "n")) == (20, 100)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_string_instructions_and_string_assignment(tmp_path, executor):
    tags = TAGS + [("a", "STRING"), ("b", "STRING"), ("c", "STRING")]
    r = export_runner(st_export(tmp_path, "b := a;\nCONCAT(a, b, c);\nSIZE(Arr, 0, n);", tags=tags), executor)
    r.run(1)
    assert read_tag(r, "n") == 5


def test_errors_are_all_located_in_the_export_at_once(tmp_path):
    st = ("Count := Nope + 1;\n"
          "IF Count > THEN n := 1; END_IF;\n"
          "Arr := 3;\n"
          "TON(Timer1, ?, ?);\n"
          "EXIT;\n"
          "r := FOO(2);")
    path = st_export(tmp_path, st)
    with pytest.raises(AppError) as info:
        load_app(path)
    text = str(info.value)
    lines = [ln for ln in text.splitlines() if ln.startswith(str(path))]
    assert len(lines) >= 6, text
    assert "unknown tag 'Nope'" in text and "expected" in text
    assert "Arr is a DINT array" in text and "TON is a ladder instruction" in text
    assert "EXIT outside" in text and "FOO: not a function" in text
    # each names the routine and its place: the line of the export where the statement is
    first = lines[0].split(":")
    assert int(first[1]) > 1 and int(first[2]) >= 1


def test_what_is_not_run_is_a_warning_and_the_rest_runs(tmp_path):
    tags = TAGS + [("T1", "FBD_TIMER")]
    path = st_export(tmp_path, "MSG(Nothing);\nCount := Count + 1;", tags=tags)
    r = export_runner(path)
    r.run(2)
    assert read_tag(r, "Count") == 2
    said = [str(w) for w in r.app.logix.warnings]
    assert any("MSG" in w for w in said)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_bool_in_an_expression_is_0_or_1(tmp_path, executor):
    # BOOL tags are bits of words in the ladder: in ST's CMP and CPT they read as 0 or 1
    st = ("IF NOT Flag AND NOT Big THEN Out := 1; END_IF;\n"
          "n := Out * 10 + Flag - Big;\nSum := Out;\nr := Out + 0.5;\nIF Flag = Big THEN Sel := 7; END_IF;")
    r = run_st(tmp_path, executor, st, values={"Flag": 0, "Big": 0})
    assert [read_tag(r, t) for t in ("Out", "n", "Sum", "r", "Sel")] == [1, 10, 1, 1.5, 7]
    r = run_st(tmp_path, executor, st, values={"Flag": 1, "Big": 0, "Out": 0})
    assert [read_tag(r, t) for t in ("Out", "n", "Sum", "Sel")] == [0, 1, 0, 0]


def test_a_bool_in_a_ladder_expression_is_still_refused(tmp_path):
    path = write_l5x(tmp_path / "rll.L5X", TAGS, [Prog("MainProgram", {"Main": ["CPT(n,Flag+1);"]})],
                     [Task("T", ["MainProgram"])])
    with pytest.raises(AppError, match="is a bit; expressions take words"):
        load_app(path)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_bool_assignment_sets_and_clears_every_bit_of_a_word_the_sign_bit_too(tmp_path, executor):
    # BOOL tags share words: 16 of them fill one, the sixteenth its sign bit (and so on for SINT and DINT hosts)
    tags = [(f"b{k}", "BOOL") for k in range(16)] + [("w", "INT"), ("s", "SINT"), ("n", "DINT"), ("Count", "DINT")]
    st = "".join(f"b{k} := Count = 1;\n" for k in range(16)) + "w.15 := Count = 1;\ns.7 := Count = 1;\nn.31 := Count = 1;"
    r = run_st(tmp_path, executor, st, tags=tags, values={"Count": 1})
    assert [read_tag(r, f"b{k}") for k in range(16)] == [1] * 16 and r.engine.fault is None
    assert (read_tag(r, "w"), read_tag(r, "s"), read_tag(r, "n")) == (-32768, -128, -2 ** 31)
    write_tag(r, "Count", 0)
    r.run(1)
    assert [read_tag(r, f"b{k}") for k in range(16)] == [0] * 16 and r.engine.fault is None
    assert (read_tag(r, "w"), read_tag(r, "s"), read_tag(r, "n")) == (0, 0, 0)


def test_a_statement_not_run_inside_an_if_leaves_the_rest_of_the_routine_running(tmp_path):
    tags = TAGS + [("a", "STRING")]
    st = ("IF Count > 100 THEN n := 1;\nELSIF a = 3 THEN n := 2;\nEND_IF;\n"  # a STRING in an expression
          "IF Count > 1 THEN Sel := 5; IF a > 1 THEN Sum := 1; END_IF; Big := 1; END_IF;\n"
          "Count := Count + 1;")
    r = export_runner(st_export(tmp_path, st, tags=tags))
    r.run(3)
    assert (read_tag(r, "Count"), read_tag(r, "Sel"), read_tag(r, "Big"), read_tag(r, "n")) == (3, 5, 1, 0)
    warnings = [str(w) for w in r.app.logix.warnings]
    assert sum("the statement is not run" in w for w in warnings) == 2, warnings
    counts = r.app.logix.statements
    assert counts["not run"] == 2 and counts["errors"] == 0 and counts["total"] == counts["run"] + 2
