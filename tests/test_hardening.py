"""Inputs that must not reach the user as a Python traceback, a wrong
fault or a check/run disagreement. Each case runs the real CLI entry
point (``softplc_lite.cli.main``) in-process, and a few run the real
``softplc`` command, and require a located error or a clean run."""

from __future__ import annotations

import pytest

from softplc_lite import cli
from softplc_lite.commands import check as check_command
from softplc_lite.ladder.limits import MAX_BRANCH_DEPTH, MAX_EXPRESSION_DEPTH
from softplc_lite.ladder.semantics import MAX_JSR_DEPTH

from helpers.cli import softplc
from helpers.apps import make_app


def short(value) -> str:
    """A test id for a parameter that may be thousands of characters long."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:30]}..{len(text)}"


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    """``softplc ARGS`` in this process: exit code, stdout, stderr. An
    exception escaping main() fails the test with its traceback."""
    try:
        code = cli.main(list(args))
    except SystemExit as e:  # argparse usage errors
        code = e.code
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert "internal error" not in out + err
    return code, out, err


HUGE = "9" * 5000


# -- 1. literals past Python's 4,300-digit limit ---------------------------------------

@pytest.mark.parametrize("lad, where, says", [
    (f"MOV {HUGE} N7:0\n", "main.lad:1:5", "out of range"),
    (f"MOV 0x{'F' * 3600} N7:0\n", "main.lad:1:5", "out of range"),
    (f"MOV 1 N7:{HUGE}\n", "main.lad:1:10", "element number 99999999...(5000 digits) out of range"),
    (f"MOV 1 N{HUGE}:0\n", "main.lad:1:8", "out of range"),
    (f"DATA N7 {HUGE}\nMOV 1 N7:0\n", "main.lad:1:9", "size 999999999999... (5000 digits) is out of range"),
    (f"FILE {HUGE}\nMOV 1 N7:0\n", "main.lad:1:6", "program file number"),
    (f"DATA N7 2 = 1 {HUGE}\nMOV 1 N7:0\n", "main.lad:1:15", "out of range"),
    # a quoted expression this long is past the literal limit first (docs/language.md, Limits)
    ('CPT N7:0 "N7:1 + ' + HUGE + '"\n', "main.lad:1:10", "(5,007 characters) is longer than 4,096 characters"),
    ('CPT N7:0 "N7:1 + ' + "9" * 4000 + '"\n', "main.lad:1:18", "out of range"),
    ("MOV 1e999 F8:0\n", "main.lad:1:5", "number 1e999 is out of range"),
    ('MOV 1 N7:0\nCPT N7:0 "1e999"\n', "main.lad:2:11", "number 1e999 is out of range"),  # a bare-number expression
    ("MOV(-1e39,F8:0);\n", "main.lad:1:6", "out of range"),
], ids=short)
def test_huge_and_overflowing_literals_are_located_check_errors(tmp_path, capsys, lad, where, says):
    app = make_app(tmp_path / "app", lad)
    for command in ("check", "run", "fmt"):
        code, _, err = run_cli(capsys, command, str(app))
        assert code == cli.EXIT_ERROR, (command, err)
        assert where in err and says in err, (command, err)
        assert len(err) < 2000  # the number is quoted short, not in full


def test_literals_at_the_top_of_the_range_run_and_format_back(tmp_path, capsys):
    app = make_app(tmp_path / "app", "MOV 3.4e38 F8:0\nMOV 1e-999 F8:1\nMOV 123456789012345678901234567890 F8:2\n"
                             "MOV -10000000000.0 F8:3\nCPT F8:4 \"1.5e30 * 2.0\"\n")
    code, out, _ = run_cli(capsys, "run", str(app), "--fresh", "--scans", "1", "--print", "F8:0", "--print", "F8:1")
    assert code == 0 and out.splitlines() == ["F8:0 = 3.4e+38", "F8:1 = 0.0"]  # 7 significant digits (JSON keeps them exact)
    for style in ("mnemonic", "neutral"):
        code, text, _ = run_cli(capsys, "fmt", "--style", style, str(app))
        again = tmp_path / f"again-{style}.lad"
        again.write_text(text)
        code2, text2, _ = run_cli(capsys, "fmt", "--style", style, str(again))
        assert code == code2 == 0 and text2 == text


@pytest.mark.parametrize("doc, says", [
    ('{"N7": [' + HUGE + "]}", "datatable.json:1:9: number 999999999999... has 5000 digits"),
    ("[" * 100_000 + "]" * 100_000, "datatable.json:1:101: nested more than 100 levels deep"),
    (b'{"N7": ["\xff"]}', "datatable.json:1:10: byte 0xff is not UTF-8 text"),
    ('{"N' + HUGE + '": [1]}', "expected a file name such as N7"),
], ids=short)
def test_bad_datatable_json_is_a_located_error_in_check_run_and_load(tmp_path, capsys, doc, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:0\n", datatable_json=doc)
    for args in (("check", str(app)), ("run", str(app), "--scans", "1"),
                 ("run", str(app), "--fresh", "--scans", "1", "--load", str(app / "datatable.json"))):
        code, _, err = run_cli(capsys, *args)
        assert code == cli.EXIT_ERROR and says in err, (args, err)


@pytest.mark.parametrize("value, says", [
    (HUGE, "--set N7:0: the value at 1:1: number 999999999999... has 5000 digits"),
    ("[" * 5000 + "]" * 5000, "nested more than 100 levels deep"),
], ids=short)
def test_bad_set_values(tmp_path, capsys, value, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:1\n")
    code, _, err = run_cli(capsys, "run", str(app), "--fresh", "--scans", "1", "--set", f"N7:0={value}")
    assert code == cli.EXIT_ERROR and says in err


# -- 1. nesting: documented limits, enforced by check, safe below them -----------------

def _branches(depth: int, neutral: bool = False) -> str:
    if neutral:
        return "XIC(B3/0)" + "[XIC(B3/3)," * depth + "XIC(B3/1)" + "]" * depth + "OTE(B3/2);"
    return "XIC B3/0 " + "BST XIC B3/3 NXB " * depth + "XIC B3/1 " + "BND " * depth + "OTE B3/2"


@pytest.mark.parametrize("neutral", [False, True])
@pytest.mark.parametrize("depth", [MAX_BRANCH_DEPTH + 1, 600, 1500])  # deeper is past the rung size limit too
def test_branches_nested_past_the_limit_are_a_check_error(tmp_path, capsys, depth, neutral):
    app = make_app(tmp_path / "app", _branches(depth, neutral) + "\n")
    for command in ("check", "run", "fmt"):
        code, _, err = run_cli(capsys, command, str(app))
        assert code == cli.EXIT_ERROR
        assert f"branches nested more than {MAX_BRANCH_DEPTH} levels deep" in err and "main.lad:1:" in err


@pytest.mark.parametrize("expression", [
    "NOT " * 99 + "N7:1",  # 99 chained NOTs
    " + ".join(["N7:1"] * 200),  # a 200-term sum
    "ABS(" * 199 + "N7:1" + ")" * 199,  # 199 nested function calls
    "(" * 150 + "-" * 0 + "N7:1" + " * 2)" * 150,
], ids=short)
def test_expressions_past_the_limit_are_a_check_error(tmp_path, capsys, expression):
    app = make_app(tmp_path / "app", f'CPT N7:0 "{expression}"\n')
    code, _, err = run_cli(capsys, "check", str(app))
    assert code == cli.EXIT_ERROR and f"the limit is {MAX_EXPRESSION_DEPTH}" in err and "main.lad:1:" in err
    code, _, err = run_cli(capsys, "run", str(app), "--scans", "1")
    assert code == cli.EXIT_ERROR


def test_every_stage_works_at_exactly_the_limits(tmp_path, capsys):
    """Branches MAX_BRANCH_DEPTH deep (both syntaxes), expressions
    MAX_EXPRESSION_DEPTH deep (CPT and CMP), and JSR recursion to jsr_depth
    = MAX_JSR_DEPTH from a subroutine holding them: check, both executors,
    fmt in both styles (parsing back), the watch snapshot."""
    chain = "ABS(" * (MAX_EXPRESSION_DEPTH - 1) + "N7:1" + ")" * (MAX_EXPRESSION_DEPTH - 1)
    rungs = [
        _branches(MAX_BRANCH_DEPTH), _branches(MAX_BRANCH_DEPTH, neutral=True),
        f'CPT N7:0 "{chain} + 1"',
        'CPT N7:2 "' + " + ".join(["N7:1"] * (MAX_EXPRESSION_DEPTH + 1)) + '"',
        f'CMP "{chain} > 0" OTE B3/5',
        "JSR 3", "FILE 3", _branches(MAX_BRANCH_DEPTH), f'CPT N7:3 "{chain} + 2"', "JSR 3",
    ]
    app = make_app(tmp_path / "app", "\n".join(rungs) + "\n", softplc_toml=f"[scan]\njsr_depth = {MAX_JSR_DEPTH}\n")
    code, out, _ = run_cli(capsys, "check", str(app))
    assert code == 0, out
    for executor in ("compiled", "reference"):
        code, out, err = run_cli(capsys, "run", str(app), "--fresh", "--scans", "2", "--executor", executor,
                                 "--set", "N7:1=-5", "--print", "N7:0", "--print", "N7:2", "--print", "S:12")
        # the subroutine recurses until the documented fault 30, never Python's recursion limit
        assert code == cli.EXIT_FAULT and "major fault 30" in err and f"more than {MAX_JSR_DEPTH} deep" in err
        assert out.splitlines() == ["N7:0 = 6", f"N7:2 = {-5 * (MAX_EXPRESSION_DEPTH + 1)}", "S:12 = 30"]
    for style in ("mnemonic", "neutral"):
        code, text, _ = run_cli(capsys, "fmt", "--style", style, str(app))
        back = tmp_path / f"back-{style}.lad"
        back.write_text(text)
        assert run_cli(capsys, "fmt", "--style", style, str(back))[1] == text
    snap = tmp_path / "view.txt"
    code, _, err = run_cli(capsys, "watch", str(app), "--fresh", "--snapshot", str(snap), "--scans", "1")
    assert code in (0, cli.EXIT_FAULT), err
    assert "JSR" in snap.read_text()


# -- 1. config files -----------------------------------------------------------------------

@pytest.mark.parametrize("toml, says", [
    ("[scan]\nwatchdog_ms = 40000\n", "softplc.toml:2: [scan] watchdog_ms = 40000; expected an integer from 1 to 32767"),
    ("[scan]\nscan_ms = -1\n", "softplc.toml:2: [scan] scan_ms = -1; expected an integer from 0 to 32767"),
    (f"[scan]\njsr_depth = {10 ** 6}\n", f"expected an integer from 1 to {MAX_JSR_DEPTH}"),
    (f"[scan]\nscan_ms = {HUGE}\n", "softplc.toml:2: a number too long to be any setting"),
    ("[retentive]\nsave_ms = 1.5\n", "softplc.toml:2: [retentive] save_ms = 1.5; expected an integer"),
    (b"[scan]\nscan_ms = 5 # \xff\xfe\n", "softplc.toml:2:15: byte 0xff is not UTF-8 text"),
], ids=short)
def test_settings_out_of_range_or_not_utf8_are_located_errors(tmp_path, capsys, toml, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:0\n", softplc_toml=toml)
    for command in ("check", "run"):
        code, _, err = run_cli(capsys, command, str(app))
        assert code == cli.EXIT_ERROR and says in err, err


def test_every_settings_problem_is_listed_at_once(tmp_path, capsys):
    toml = "[scan]\nscan_ms = 5\njsr_depth = 0\nfoo = 1\n[bar]\nx = 1\n[retentive]\nsave_ms = -5\n"
    app = make_app(tmp_path / "app", "MOV 1 N7:0\nBAD N7:0\n", softplc_toml=toml)
    code, _, err = run_cli(capsys, "check", str(app))
    lines = [line for line in err.splitlines() if "softplc.toml:" in line or "main.lad:" in line]
    assert code == cli.EXIT_ERROR and "5 problems found" in err
    assert [line.split(": ")[0].rsplit("/", 1)[-1] for line in lines] == [
        "softplc.toml:3", "softplc.toml:4", "softplc.toml:5", "softplc.toml:8", "main.lad:2:1"]


@pytest.mark.parametrize("args, says", [
    (("--realtime", "--scan-ms", "99999999999999999999"), "argument --scan-ms: expected an integer from 0 to 32767"),
    (("--scan-ms", "-5"), "argument --scan-ms: expected an integer from 0 to 32767, not '-5'"),
    (("--scan-ms", "abc"), "argument --scan-ms"),
    (("--scans", "-1"), "argument --scans: expected an integer 0 or more"),
], ids=short)
def test_cli_values_out_of_range_are_usage_errors(tmp_path, capsys, args, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:0\n")
    code, _, err = run_cli(capsys, "run", str(app), "--scans", "1", *args)
    assert code == cli.EXIT_USAGE and says in err


# -- 3. internal errors and wrong faults -------------------------------------------------

def test_a_program_with_no_rungs_scans_as_an_empty_plc(tmp_path, capsys):
    app = make_app(tmp_path / "app", "// nothing yet\n")
    assert run_cli(capsys, "check", str(app))[0] == 0
    code, out, _ = run_cli(capsys, "run", str(app), "--fresh", "--scans", "5", "--print", "S:100", "--print", "S:12")
    assert code == 0 and out.splitlines() == ["S:100 = 5", "S:12 = 0"]


def test_jsr_depth_is_bounded_where_the_engine_can_honour_it(tmp_path, capsys):
    app = make_app(tmp_path / "app", "JSR 3\nFILE 3\nJSR 3\n", softplc_toml="[scan]\njsr_depth = 100000\n")
    code, _, err = run_cli(capsys, "run", str(app), "--scans", "1")
    assert code == cli.EXIT_ERROR and f"jsr_depth = 100000; expected an integer from 1 to {MAX_JSR_DEPTH}" in err


@pytest.mark.parametrize("lad, toml, says", [
    ("DATA N9 3\nDATA ST9 3\nMOV 1 N9:0\n", None, "main.lad:2:1: file number 9 is already N9; ST9 cannot also exist"),
    ("MOV 1 N9:0\nMOV 1.5 F9:0\n", None, "main.lad:2:1:"),
    ('DATA ST9 1 = "\U0001F600"\nMOV 1 N7:0\n', None, "main.lad:1:1: DATA ST9 value 1: U+1F600 does not fit ST9:0"),
    ("DATA N7 3\nMOV 1 N7:0\n", '[display]\nstatus = { a = "N7:50" }\n',
     "softplc.toml:2: [display] status 'a': N7:50: element 50 is past the end of N7 (3 elements)"),
], ids=short)
def test_what_run_refuses_check_reports_first_located(tmp_path, capsys, lad, toml, says):
    files = {"softplc_toml": toml} if toml else {}
    app = make_app(tmp_path / "app", lad, **files)
    code, _, err = run_cli(capsys, "check", str(app))
    assert code == cli.EXIT_ERROR and says in err, err
    code, _, err = run_cli(capsys, "run", str(app), "--scans", "1")
    assert code == cli.EXIT_ERROR and says in err, err


def test_a_format_width_cannot_allocate_more_than_its_destination(tmp_path, capsys):
    """%999999999d once built a 1 GB string for an 82-character STRING."""
    app = make_app(tmp_path / "app", "DATA N7 3 = 5 32767 1\nSTRPRINT ST10:0 1 N7:0\nSTRPRINT ST10:1 2 N7:0 N7:0 N7:0\n"
                             "STRPRINT ST10:2 3 N7:1 N7:2\n",
                   MODULES_LST="COMGENIUS\n",
                   COMGENIUS_LST='[STRINGS]\n1 "%999999999d"\n2 "%32767d|%32767d|%32767d"\n3 "%-*d|"\n')
    code, out, err = run_cli(capsys, "check", str(app))
    assert code == 0 and "a width or precision is at most 32767" in err  # a warning, located
    code, out, _ = run_cli(capsys, "run", str(app), "--fresh", "--scans", "1", "--print", "ST10:0",
                           "--print", "ST10:1", "--print", "ST10:2", "--print", "S:102")
    assert code == 0
    assert out.splitlines() == ['ST10:0 = ""', f'ST10:1 = "{" " * 82}"', f'ST10:2 = "1{" " * 81}"', "S:102 = 5"]


def test_printf_render_stops_at_its_limit():
    from softplc_lite.tlm.comgenius.params import ValueParam
    from softplc_lite.tlm.comgenius.printf import compile_print

    fmt = compile_print("%32767d%32767d%d")
    full = fmt.render([ValueParam(1), ValueParam(2), ValueParam(3)])
    assert len(full) == 2 * 32767 + 1
    assert fmt.render([ValueParam(1), ValueParam(2), ValueParam(3)], 82) == full[:83]


# -- the real command, and the last-resort handler --------------------------------------------

def test_the_real_command_reports_without_a_traceback(tmp_path):
    app = make_app(tmp_path / "app", f"MOV {HUGE} N7:0\n" + _branches(600) + "\n")
    # A process: a fresh interpreter, with Python's own limits on digits and recursion, and its real stderr.
    p = softplc("check", str(app))
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "main.lad:1:5: number" in p.stderr and "main.lad:2:" in p.stderr


def test_an_internal_error_is_one_line_and_exit_code_4(capsys, monkeypatch):
    """A bug (here: one planted where check loads the app) is reported as
    one line and exit code 4, never a traceback."""
    def broken(*args, **kwargs):
        raise ZeroDivisionError("planted")
    monkeypatch.setattr(check_command, "load_app", broken)
    code = cli.main(["check", "x"])
    err = capsys.readouterr().err
    assert code == cli.EXIT_INTERNAL == 4
    assert err.startswith("softplc: internal error: ZeroDivisionError: planted") and "Traceback" not in err


@pytest.mark.parametrize("files, args, says", [
    ({"MODULES_LST": "COMGENIUS\n", "COMGENIUS_LST": f"[DRIVER]\nRETRY_MS={HUGE}\n"}, (),
     "COMGENIUS.LST:2: [DRIVER]: RETRY_MS 999999999... (5000 digits) is too large"),
    ({"MODULES_LST": "COMGENIUS\n", "COMGENIUS_LST": "[PORTS]\n0, loop://, ISO-8859-1, 9600, 8, N, 1, 250\n"},
     ("--port", f"{HUGE}=loop://"), "--port"),
    ({"softplc_toml": f'[display]\nsummary = {{ a = "#N7:0 {HUGE}" }}\n'}, (), "softplc.toml"),
    ({"main.lad": b"MOV 1 N7:0\nMOV 2 N7:1 // caf\xe9\n"}, (), "main.lad:2:18: byte 0xe9 is not UTF-8 text"),
], ids=short)
def test_other_numbers_and_encodings_are_clear_errors(tmp_path, capsys, files, args, says):
    lad = files.pop("main.lad", "MOV 1 N7:0\n")
    app = make_app(tmp_path / "app", lad, **files)
    code, _, err = run_cli(capsys, "run", str(app), "--fresh", "--scans", "1", *args)
    assert code in (cli.EXIT_ERROR, cli.EXIT_USAGE) and says in err, err


def test_a_utf8_bom_is_accepted(tmp_path, capsys):
    app = make_app(tmp_path / "app", b"\xef\xbb\xbfMOV 1 N7:0\n", softplc_toml=b"\xef\xbb\xbf[scan]\nscan_ms = 5\n",
                   datatable_json=b'\xef\xbb\xbf{"N7": [0, 7]}')
    code, out, _ = run_cli(capsys, "run", str(app), "--fresh", "--scans", "1", "--print", "N7:1")
    assert code == 0 and out == "N7:1 = 7\n"


def test_a_huge_address_is_quoted_short(capsys):
    code, _, err = run_cli(capsys, "address", "N7:" + HUGE)
    assert code == cli.EXIT_ERROR and "(5003 characters)" in err and len(err) < 500


def test_a_break_when_condition_has_the_expression_limit_too(tmp_path, capsys):
    from softplc_lite.ladder.ast import Pos
    from softplc_lite.ladder.errors import LadderError
    from softplc_lite.ladder.parser import parse_expression

    with pytest.raises(LadderError, match=f"nested 501 levels deep; the limit is {MAX_EXPRESSION_DEPTH}"):
        parse_expression("NOT " * 500 + "N7:0 > 1", Pos("--break-when", 1, 1))
    assert parse_expression("(" * 5000 + "N7:0" + ")" * 5000 + " > 1", Pos("--break-when", 1, 1)).op == ">"


def test_every_problem_short_of_a_syntax_error_is_found_in_one_parse(tmp_path, monkeypatch):
    """A file of rungs each past a limit (or with a bad address or number)
    was parsed again after each problem: a 1 MB file of 1,000-deep branches
    took over a minute to check. Now one parse lists them all."""
    from softplc_lite import app as app_module
    from softplc_lite.ladder import parser

    rung = "XIC B3/0 " + "BST XIC B3/3 NXB " * 40 + "OTE B3/2 " + "BND " * 40
    text = (f"{rung}\nMOV 1 N7:x\nMOV 1e999 F8:0\nCPT N7:0 \"FOO(N7:1)\"\nSYMBOL S1 Q:9\n") * 10
    (tmp_path / "main.lad").write_text(text)
    calls = []
    real = parser._parse_tree
    monkeypatch.setattr(parser, "_parse_tree", lambda *a, **k: calls.append(a[2]) or real(*a, **k))
    _, errors = app_module.parse_files([tmp_path / "main.lad"], tmp_path)
    assert calls.count("start") == 1
    assert len(errors) == 50  # 5 a block, 10 blocks
    assert [e.pos.line for e in errors[:5]] == [1, 2, 3, 4, 5]
    assert "branches nested" in errors[0].message and "unknown function FOO()" in errors[3].message


def test_validate_refuses_trees_past_the_limits_built_through_the_library():
    """A program built as an AST (not parsed) is checked against the same
    limits before validation walks it."""
    from softplc_lite.ladder import check, parse_program
    from softplc_lite.ladder.ast import Branch, UnaryOp

    program = parse_program('XIC B3/0 OTE B3/1\nCPT N7:0 "N7:1 + 1"\n')
    first, second = program.files[2].rungs
    elements = first.elements
    for _ in range(3000):
        elements = [Branch([elements, [first.elements[0]]], first.pos)]
    first.elements[:] = elements
    cpt = second.elements[0]
    for _ in range(3000):
        cpt.operands[1] = UnaryOp("NEG", cpt.operands[1], second.pos)
    _, problems = check(program)
    assert [str(p) for p in problems] == [
        f"<program>:1:1: branches nested more than {MAX_BRANCH_DEPTH} levels deep (the limit is {MAX_BRANCH_DEPTH})",
        f"<program>:2:1: expression nested 3001 levels deep; the limit is {MAX_EXPRESSION_DEPTH} "
        "(split it over several CPT instructions)"]


# -- found by the fuzz harness (tools/fuzz.py) --------------------------------------------

@pytest.mark.parametrize("toml, says", [
    ("[scan]\nscan_ms = " + "[" * 1000 + "]" * 1000 + "\n", "softplc.toml:2: values nested too deeply"),
    ("[scan]\nscan_ms = { a = " * 1 + "{ b = " * 1000 + "1" + " }" * 1001 + "\n", "softplc.toml:2: values nested"),
    ("[scan\nx = 1\n", "softplc.toml:1:6: Expected ']' at the end of a table declaration"),
    ("[scan]\nscan_ms =", "softplc.toml:2: Invalid value"),  # "at end of document": its last line
    ("save_ms = 5\n[scan]\nscan_ms = 5\n", "softplc.toml:1: save_ms = ... is outside any section (under [retentive]?)"),
    ('[display]\nstatus = { x = "N7:" }\n', "softplc.toml:2: [display] x = 'N7:': bad address"),
], ids=short)
def test_every_softplc_toml_problem_is_located(tmp_path, capsys, toml, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:0\n", softplc_toml=toml)
    code, _, err = run_cli(capsys, "check", str(app))
    assert code == cli.EXIT_ERROR and says in err, err


@pytest.mark.parametrize("lad, style", [
    ("SYMBOL Temp N7:[N9:2]\nDATA N9 5 = 1 2 3 70 7\n\nFILE 2", "mnemonic"),  # an empty main file
    ("SYMBOL Temp N7:[N9:2]\nDATA N9 5 = 1 2 3 70 7\n\nFILE 2", "neutral"),
])
def test_fmt_is_a_fixed_point(tmp_path, capsys, lad, style):
    (tmp_path / "a.lad").write_text(lad)
    code, once, _ = run_cli(capsys, "fmt", "--style", style, str(tmp_path / "a.lad"))
    (tmp_path / "b.lad").write_text(once)
    code2, twice, _ = run_cli(capsys, "fmt", "--style", style, str(tmp_path / "b.lad"))
    assert code == code2 == 0 and twice == once


@pytest.mark.parametrize("lad, style", [
    ("XIC(B3/0)OTE(O:0/0);\n;\n", "mnemonic"),  # an empty rung
    ("XIC(B3/0)OTE(O:0/0);\n;\n", "neutral"),
    ("XIC B3/0 BST NXB XIC B3/1 BND OTE O:0/0\n", "neutral"),  # an empty branch leg
    ("XIC B3/0 OTE\n", "mnemonic"),  # an operand missing
])
def test_fmt_refuses_what_check_refuses_with_the_same_problems(tmp_path, capsys, lad, style):
    """fmt refuses invalid programs (exit 1), every problem as
    softplc check lists it; nothing is printed."""
    (tmp_path / "a.lad").write_text(lad)
    code, out, err = run_cli(capsys, "fmt", "--style", style, str(tmp_path / "a.lad"))
    check_code, _, check_err = run_cli(capsys, "check", str(tmp_path / "a.lad"))
    assert code == check_code == 1 and out == ""
    problems = [line for line in check_err.splitlines() if ":" in line and "problem" not in line]
    assert problems and all(p in err for p in problems) and "nothing formatted" in err


@pytest.mark.parametrize("lad, style, says", [
    ("FOO(N7:0);\n", "mnemonic", "a.lad:1:1: unknown instruction 'FOO'"),
    ('XIC "B3/0" OTE O:0/0\n', "neutral", "a.lad:1:5: XIC has a quoted string operand, which neutral text cannot write"),
])
def test_fmt_refuses_what_it_could_not_print_back(tmp_path, capsys, lad, style, says):
    (tmp_path / "a.lad").write_text(lad)
    code, out, err = run_cli(capsys, "fmt", "--style", style, str(tmp_path / "a.lad"))
    assert code == cli.EXIT_ERROR and out == "" and says in err


@pytest.mark.parametrize("url, says", [
    ("sim://x?device=nosuch", "COMGENIUS.LST:3: COMGENIUS port 0: unknown device kind 'nosuch'"),
    ("sim://x?device=modbus&turnaround_ms=abc", "turnaround_ms must be a number >= 0, not 'abc'"),
    ("sim://bad name", "bad link name"),
])
def test_check_refuses_the_sim_urls_run_would_refuse(tmp_path, capsys, url, says):
    app = make_app(tmp_path / "app", "MOV 1 N7:0\n", MODULES_LST="COMGENIUS\n",
                   COMGENIUS_LST=f"[DRIVER]\n[PORTS]\n0, {url}, ISO-8859-1, 9600, 8, N, 1, 100\n")
    for command in ("check", "run"):
        code, _, err = run_cli(capsys, command, str(app))
        assert code == cli.EXIT_ERROR and says in err, (command, err)
