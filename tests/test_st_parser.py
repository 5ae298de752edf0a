"""The Logix Structured Text parser: PM007's grammar into typed nodes at
their places in the export, every syntax error located and listed at once."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.logix.load import read_export
from softplc_lite.logix.model import ExportError, Line
from softplc_lite.st import ast as A
from softplc_lite.st.parser import StError, StErrors, parse_routine

PUBLIC = Path(__file__).parent / "fixtures" / "logix" / "public"


def one(text: str):
    [statement] = parse_routine(text, "r.st")
    return statement


def expr(text: str):
    return one(f"x := {text};").value


def shape(e) -> str:
    """An expression with every operation bracketed, to read precedence."""
    if isinstance(e, A.BinOp):
        return f"({shape(e.left)} {e.op} {shape(e.right)})"
    if isinstance(e, A.UnaryOp):
        return f"({e.op} {shape(e.operand)})"
    if isinstance(e, A.Const):
        return repr(e.value)
    if isinstance(e, A.FunctionCall):
        return f"{e.name}({', '.join(shape(a) for a in e.args)})"
    return e.text


# -- precedence (PM007: **; - NOT; * / MOD; + -; < <= > >=; = <>; & AND; XOR; OR)


@pytest.mark.parametrize("text, expected", [
    ("-2 ** 2", "(- (2 ** 2))"),
    ("2 ** 3 ** 2", "((2 ** 3) ** 2)"),
    ("2 ** -1", "(2 ** (- 1))"),
    ("NOT a ** b", "(NOT (a ** b))"),
    ("-a * b", "((- a) * b)"),
    ("a + b * c", "(a + (b * c))"),
    ("a - b MOD c / d", "(a - ((b MOD c) / d))"),
    ("a + b < c - d", "((a + b) < (c - d))"),
    ("a < b = c >= d", "((a < b) = (c >= d))"),
    ("a = b AND c <> d", "((a = b) AND (c <> d))"),
    ("a & b XOR c AND d", "((a AND b) XOR (c AND d))"),
    ("a XOR b OR c XOR d", "((a XOR b) OR (c XOR d))"),
    ("a OR b AND NOT c", "(a OR (b AND (NOT c)))"),
    ("(a OR b) AND c", "((a OR b) AND c)"),
    ("a - b - c", "((a - b) - c)"),
    ("ABS(a - b) * 2", "(ABS((a - b)) * 2)"),
    ("a mod b", "(a MOD b)"),
])
def test_precedence(text, expected):
    assert shape(expr(text)) == expected


def test_constants():
    assert [shape(expr(t)) for t in ("16#FF", "2#1010", "8#17", "2#0000_1111", "1.5e3", "0.25", ".5", "7")] == \
        ["255", "10", "15", "15", "1500.0", "0.25", "0.5", "7"]
    assert expr("1.5e3").kind == "REAL" and expr("16#FF").kind == "INT"
    s = expr("'it$'s $$5'")
    assert (s.kind, s.value) == ("STRING", "it$'s $$5")


# -- statements


def test_assignments_retentive_and_not():
    a, b = parse_routine("Out := In;\nHeld [:=] 1;", "r.st")
    assert (a.retentive, b.retentive) == (True, False)
    assert b.target.text == "Held" and b.pos == A.Pos("r.st", 2, 1)


def test_if_elsif_else():
    s = one("IF a THEN x := 1; ELSIF b THEN x := 2; y := 3; ELSIF c THEN ELSE x := 4; END_IF;")
    assert isinstance(s, A.If)
    assert [shape(c) for c, _ in s.branches] == ["a", "b", "c"]
    assert [len(body) for _, body in s.branches] == [1, 2, 0]
    assert len(s.else_) == 1
    assert one("if a then end_if").else_ is None


def test_case_lists_ranges_and_else():
    s = one("CASE State OF 1: x := 1; 2, 4..6, -3: x := 2; 10..20: ELSE x := 0; END_CASE;")
    assert isinstance(s, A.Case) and shape(s.selector) == "State"
    labels = [[(l.low.value, l.high.value) if isinstance(l, A.CaseRange) else l.value for l in arm.labels]
              for arm in s.arms]
    assert labels == [[1], [2, (4, 6), -3], [(10, 20)]]
    assert [len(arm.body) for arm in s.arms] == [1, 1, 0]
    assert len(s.else_) == 1


def test_loops_exit_return():
    f, w, r = parse_routine(
        "FOR i := 0 TO 10 BY 2 DO IF a[i] THEN EXIT; END_IF; END_FOR;\n"
        "WHILE n > 0 DO n := n - 1; END_WHILE;\n"
        "REPEAT n := n + 1; UNTIL n >= 5 END_REPEAT;", "r.st")
    assert isinstance(f, A.For) and f.var.text == "i" and shape(f.step) == "2"
    assert isinstance(f.body[0].branches[0][1][0], A.Exit)
    assert one("FOR i := 1 TO n DO END_FOR;").step is None
    assert isinstance(w, A.While) and shape(w.cond) == "(n > 0)" and len(w.body) == 1
    assert isinstance(r, A.Repeat) and shape(r.until) == "(n >= 5)"
    assert isinstance(one("RETURN;"), A.Return)


def test_calls():
    t, j, aoi, gsv = parse_routine("TONR(MyTimer);\nJSR(Sub, 0);\nMyAoi(Inst, a, b + 1);\n"
                                   "GSV(WallClockTime, , LocalDateTime, d[0]);", "r.st")
    assert (t.name, [a.text for a in t.args]) == ("TONR", ["MyTimer"])
    assert j.name == "JSR" and shape(j.args[1]) == "0"
    assert aoi.name == "MyAoi" and shape(aoi.args[2]) == "(b + 1)"
    assert gsv.args[1] is None and len(gsv.args) == 4
    assert isinstance(expr("SQRT(a) + LN(b)"), A.BinOp)
    assert one("Reset();").args == ()


def test_keywords_any_case_and_names_that_start_like_keywords():
    s = one("If Ifx Then Order := Done oR Total; eLsE Byte := 1; End_If;")
    assert shape(s.branches[0][0]) == "Ifx" and shape(s.branches[0][1][0].value) == "(Done OR Total)"


# -- tags


def test_tag_paths():
    t = one("Tank.Level := Arr[i + 1].5 + Local:1:I.Data.0 + Word.[n] + M[1, j].Member.7 + %ofMaximum;")
    assert t.target == A.TagRef("Tank.Level", "Tank", (A.Member("Level"),))
    refs = []
    e = t.value
    while isinstance(e, A.BinOp):
        refs.append(e.right)
        e = e.left
    refs.append(e)
    texts = [r.text for r in reversed(refs)]
    assert texts == ["Arr[i+1].5", "Local:1:I.Data.0", "Word.[n]", "M[1,j].Member.7", "%ofMaximum"]
    arr, module, word, matrix, _ = reversed(refs)
    assert isinstance(arr.selectors[0], A.Index) and arr.selectors[1] == A.Bit(5)
    assert module.base == "Local:1:I" and module.selectors == (A.Member("Data"), A.Bit(0))
    assert isinstance(word.selectors[0], A.BitIndex)
    assert len(matrix.selectors[0].indices) == 2


def test_comments_of_each_form():
    text = "// a line\nx := 1; (* paren\n y := 2; *) z := /* slash */ 3; // end\n/* all\nof it */"
    a, b = parse_routine(text, "r.st")
    assert (a.target.text, b.target.text, b.value.value) == ("x", "z", 3)
    assert b.pos == A.Pos("r.st", 3, 13)


# -- positions and errors


def test_positions_come_from_the_export_lines():
    lines = [Line(1, "x := 1;", A.Pos("p.L5X", 40, 9)), Line(2, "  y := z +;", A.Pos("p.L5X", 41, 9))]
    errors: list[StError] = []
    [x] = parse_routine(lines, "p.L5X", errors=errors)
    assert x.pos == A.Pos("p.L5X", 40, 9)
    assert [str(e) for e in errors] == ["p.L5X:41:19: unexpected ';'; expected '(', '-', NOT, a module tag, "
                                        "a name, a number, a string or an enumeration word (%ofMaximum)"]
    [y] = parse_routine([(7, "y := 2;")], "r.st")
    assert y.pos == A.Pos("r.st", 7, 1)


def test_every_error_at_once_with_line_and_column():
    text = ("x := 1 +;\n"        # 10
            "y := 2;\n"          # 11
            "z := 3 @ 4;\n"      # 12
            "IF a THEN\n"        # 13
            "  f(1, 2;\n"        # 14
            "  w := (5;\n"       # 15
            "END_IF;\n"          # 16
            "v := 1\n")          # 17
    with pytest.raises(StErrors) as caught:
        parse_routine(text, "r.st", first_line=10)
    got = [(e.pos.line, e.pos.column, e.message) for e in caught.value.errors]
    assert got == [
        (10, 9, "unexpected ';'; expected '(', '-', NOT, a module tag, a name, a number, a string "
                "or an enumeration word (%ofMaximum)"),
        (12, 8, "unexpected character '@'"),
        (14, 9, "unexpected ';'; expected ')', ',' or an operator"),
        (15, 10, "unexpected ';'; expected ')' or an operator"),
        (17, 7, "unexpected end of routine; expected ';' or an operator"),
    ]
    report = caught.value.errors[1].report()
    assert report.splitlines()[1:] == ["z := 3 @ 4;", "       ^"]


def test_unclosed_blocks_and_comments():
    with pytest.raises(StErrors) as caught:
        parse_routine("IF a THEN\n  x := 1;\n", "r.st")
    [e] = caught.value.errors
    assert (e.pos.line, e.message.split(";")[0]) == (2, "unexpected end of routine")
    assert "END_IF" in e.message
    with pytest.raises(StErrors) as caught:
        parse_routine("x := 1;\n  (* never\nclosed", "r.st")
    assert [(e.pos.line, e.pos.column, e.message) for e in caught.value.errors] == \
        [(2, 3, "comment '(*' is never closed")]


@pytest.mark.parametrize("text, where", [
    ("IF a = THEN\n  y := 2;\n  z := 3 +;\nEND_IF;\nq := 1;", [(1, 8), (3, 11)]),
    ("WHILE DO\n  y := ;\nEND_WHILE;", [(1, 7), (2, 8)]),
    ("FOR i = 1 TO 5 DO\n  y := 2;\nEND_FOR;", [(1, 7)]),
    ("CASE x y OF 1: y := 1; END_CASE;", [(1, 8)]),
    ("IF a THEN x := 1; ELSIF b c THEN y := 1; ELSE z := 1; END_IF;", [(1, 27)]),
])
def test_an_error_in_a_block_head_leaves_its_body_and_end_alone(text, where):
    errors: list[StError] = []
    parse_routine(text, "r.st", errors=errors)
    assert [(e.pos.line, e.pos.column) for e in errors] == where


def test_errors_list_keeps_what_parsed():
    errors: list[StError] = []
    statements = parse_routine("a := 1;\nb := ;\nc := 3;", "r.st", errors=errors)
    assert [s.target.text for s in statements] == ["a", "c"]
    assert [e.pos.line for e in errors] == [2]


def test_long_routines_and_deep_nesting_give_no_traceback():
    assert len(parse_routine("x := 1;\n" * 3000, "r.st")) == 3000
    for text in ("x := " + " + ".join(["a"] * 3000) + ";", "IF a THEN " * 600 + "x := 1;" + " END_IF;" * 600):
        with pytest.raises(StErrors) as caught:
            parse_routine(text, "r.st")
        assert [str(e) for e in caught.value.errors] == ["r.st:1:1: an expression or block nested too deeply to read"]


def test_empty_routine():
    assert parse_routine("", "r.st") == [] and parse_routine("// only a comment\n;", "r.st") == []


# -- the public exports' ST routines


def st_routines():
    for path in sorted(PUBLIC.rglob("*")):
        if path.suffix.lower() not in (".l5x", ".l5k"):
            continue
        try:
            project = read_export(path)
        except ExportError:
            continue
        owners = list(project.programs) + list(project.add_on_instructions)
        for owner in owners:
            for routine in owner.routines:
                if routine.kind == "ST" and not routine.encoded:
                    yield path, routine


def test_every_public_st_routine_parses():
    routines = list(st_routines())
    assert len(routines) >= 10
    failed = []
    for path, routine in routines:
        errors: list[StError] = []
        statements = parse_routine(routine.lines, str(path), errors=errors)
        if errors:
            failed.append(errors[0].report())
        elif any(line.text.strip() and not line.text.strip().startswith(("//", "(*", "/*")) for line in routine.lines):
            assert statements, routine.name
    assert failed == []
