"""The size limits of docs/language.md ("Limits"): a quoted string of at
most MAX_LITERAL_CHARS characters and a rung of at most MAX_RUNG_ELEMENTS
elements, checked while the text is parsed, and nesting (MAX_NESTING,
MAX_SIGNS) checked on the text before it is parsed. A 10 MB literal or rung is
refused promptly, located, quoted short, in bounded memory (the real
``softplc`` in a subprocess, its peak memory read from the kernel); one
just within the limits checks and runs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from softplc_lite.ladder.limits import MAX_LITERAL_CHARS, MAX_NESTING, MAX_RUNG_ELEMENTS

ROOT = Path(__file__).resolve().parent.parent
TEN_MB = 10_000_000
# The peak memory a refusal may take. softplc takes about 45 MB to start and
# 60-90 MB to refuse each 10 MB text below; unbounded, a 10 MB literal took
# 5.6 GB and a 10 MB rung over 6 GB (the address space cap below stops such a
# run at AS_CAP instead, so the test fails without exhausting the machine).
PEAK_BOUND_MB = 250
AS_CAP = 3 << 30


# A small Python caps the address space and starts softplc as its own child,
# then writes the child's peak (ru_maxrss) to a file. Linux counts a new
# process's peak from the memory of the process that started it (fork copies
# it; exec records the old image's peak), so softplc started straight from a
# long pytest worker would count the worker's hundreds of MB as its own.
CAPPED = """
import os, resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
pid = os.posix_spawn(sys.executable, [sys.executable, "-m", "softplc_lite", *sys.argv[2:]], os.environ)
_, status, usage = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(str(usage.ru_maxrss))
code = os.waitstatus_to_exitcode(status)
sys.exit(code if code >= 0 else 128 - code)
""".format(cap=AS_CAP)


def softplc_measured(tmp_path: Path, *args: str, timeout: float = 120) -> tuple[int, str, str, float, float]:
    """Run softplc; (exit status, stdout, stderr, peak memory in MB, seconds)."""
    out, err, peak = tmp_path / "out.txt", tmp_path / "err.txt", tmp_path / "peak.txt"
    start = time.monotonic()
    with out.open("wb") as o, err.open("wb") as e:
        proc = subprocess.Popen([sys.executable, "-c", CAPPED, str(peak), *args], cwd=tmp_path, stdout=o, stderr=e,
                                start_new_session=True)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            pytest.fail(f"softplc {' '.join(args)} took more than {timeout} s")
    seconds = time.monotonic() - start
    return (proc.returncode, out.read_text(), err.read_text(errors="replace"), int(peak.read_text()) / 1024,
            seconds)


def app_with(tmp_path: Path, text: str) -> Path:
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.lad").write_text(text, encoding="utf-8")
    return app


RUNG_TOO_LARGE = f"more than {MAX_RUNG_ELEMENTS:,} elements"


@pytest.mark.parametrize("text, where, says", [
    ('DATA ST9 1 = "' + "A" * TEN_MB + '"\nXIC B3/0 OTE B3/1\n', "main.lad:1:14",
     f'DATA ST9: quoted string "AAAAAAAAAAAAAAAAAAAA..." ({TEN_MB:,} characters) is longer than '
     f"{MAX_LITERAL_CHARS:,} characters"),
    ('CPT N7:0 "' + "N7:1 + " * (TEN_MB // 7) + '1"\n', "main.lad:1:10",
     f'quoted string "N7:1 + N7:1 + N7:1 +..." ({TEN_MB // 7 * 7 + 1:,} characters) is longer than'),
    # the 10,001st element: the name of the 5,000th OTE (mnemonic), the operand of the 5,000th (neutral,
    # where an operand is counted before its instruction)
    ("XIC B3/0 " + "OTE B3/1 " * (TEN_MB // 9) + "\n", f"main.lad:1:{9 + 9 * 4999 + 1}:",
     RUNG_TOO_LARGE),
    ("XIC(B3/0)" + "OTE(B3/1)" * (TEN_MB // 9) + ";\n", f"main.lad:1:{9 + 9 * 4999 + 5}:",
     RUNG_TOO_LARGE),
    ("CPT(N7:0," + "N7:1+" * (TEN_MB // 5) + "1);\n", "main.lad:1:",
     RUNG_TOO_LARGE),
    ("DATA N7 10 = " + "1 " * (TEN_MB // 2) + "\n", "main.lad:1:", RUNG_TOO_LARGE),
    # nesting the parser would hold on its stack before any limit could look at it
    # (CPT's own "(" is the first one open)
    ("CPT(N7:0," + "(" * (TEN_MB // 2) + "N7:1" + ")" * (TEN_MB // 2) + ");\n", f"main.lad:1:{9 + MAX_NESTING}:",
     f"parentheses and brackets nested more than {MAX_NESTING:,} deep"),
    ("XIC(B3/0)" + "[" * (TEN_MB // 2) + "OTE(B3/1)" + "]" * (TEN_MB // 2) + ";\n",
     f"main.lad:1:{10 + MAX_NESTING}:", f"parentheses and brackets nested more than {MAX_NESTING:,} deep"),
    ("CPT(N7:0," + "-" * TEN_MB + "N7:1);\n", "main.lad:1:10:",
     f"{TEN_MB:,} signs or NOTs in a row: an expression nested more than 64 levels deep"),
], ids=["DATA string", "CPT expression", "mnemonic rung", "neutral rung", "neutral expression", "DATA values",
        "parentheses", "brackets", "signs"])
def test_ten_megabytes_in_one_literal_or_rung_are_refused_promptly_in_bounded_memory(request, tmp_path, text, where,
                                                                                     says):
    app = app_with(tmp_path, text)
    commands = [("check", str(app))]
    # run loads a program as check does (app.load_app); it is run too for the texts that once
    # exhausted memory in both, a 10 MB literal and a 10 MB rung, and the others refuse in that same load
    if request.node.callspec.id in ("DATA string", "mnemonic rung", "neutral rung"):
        commands.append(("run", str(app), "--fresh", "--scans", "1"))
    for command in commands:
        code, out, err, peak_mb, seconds = softplc_measured(tmp_path, *command)
        assert code == 1, (command, err[-2000:])
        first = err.splitlines()[0]
        assert first.startswith("app/main.lad:") and where in first and says in first, (command, first)
        assert len(err) < 1000  # quoted short, never the text itself
        assert peak_mb < PEAK_BOUND_MB, (command, peak_mb)
        assert seconds < 60, (command, seconds)


def _elements(count: int, neutral: bool) -> str:
    """A rung of exactly ``count`` elements (even): XIC B3/0 and OTEs."""
    if neutral:
        return "XIC(B3/0)" + "OTE(B3/1)" * (count // 2 - 1) + ";\n"
    return "XIC B3/0 " + "OTE B3/1 " * (count // 2 - 1) + "\n"


@pytest.mark.parametrize("neutral", [False, True], ids=["mnemonic", "neutral"])
def test_a_rung_at_the_limit_runs_and_one_element_more_is_refused(tmp_path, neutral):
    app = app_with(tmp_path, "MOV 7 N7:0\n" + _elements(MAX_RUNG_ELEMENTS, neutral) + "MOV 8 N7:1\n")
    code, out, err, _, _ = softplc_measured(tmp_path, "run", str(app), "--fresh", "--scans", "1",
                                            "--set", "B3/0=1", "--print", "B3/1", "--print", "N7:1")
    assert code == 0, err[-2000:]
    assert out == "B3/1 = 1\nN7:1 = 8\n"
    over = tmp_path / "over"
    over.mkdir()
    (over / "main.lad").write_text("MOV 7 N7:0\n" + _elements(MAX_RUNG_ELEMENTS + 2, neutral))
    code, _, err, _, _ = softplc_measured(tmp_path, "check", str(over))
    # the element past the limit: the last OTE's name (mnemonic) or its operand (neutral: an operand
    # is counted before its instruction)
    last = len(_elements(MAX_RUNG_ELEMENTS + 2, neutral)) - len("OTE B3/1 \n" if not neutral else "OTE(B3/1);\n")
    column = last + (1 if not neutral else len("OTE(") + 1)
    assert code == 1 and err.startswith(f"over/main.lad:2:{column}: {RUNG_TOO_LARGE}"), err


def test_a_literal_at_the_limit_works_and_one_character_more_is_refused(tmp_path):
    expression = "N7:1 + 5"
    at_limit = expression + " " * (MAX_LITERAL_CHARS - len(expression))
    app = app_with(tmp_path, f'CPT N7:0 "{at_limit}"\n')
    code, out, err, _, _ = softplc_measured(tmp_path, "run", str(app), "--fresh", "--scans", "1",
                                            "--set", "N7:1=2", "--print", "N7:0")
    assert code == 0 and out == "N7:0 = 7\n", err
    (app / "main.lad").write_text(f'CPT N7:0 "{at_limit} "\n')
    code, _, err, _, _ = softplc_measured(tmp_path, "check", str(app))
    assert code == 1 and err.startswith(
        f'app/main.lad:1:10: quoted string "N7:1 + 5            ..." ({MAX_LITERAL_CHARS + 1:,} characters) '
        f"is longer than {MAX_LITERAL_CHARS:,} characters"), err


def test_quoted_expressions_count_into_their_rung(tmp_path):
    # each CPT: the instruction, its destination, and 400 operands and 399 operators = 801 elements
    # (50 sums of 8 in parentheses: 56 levels deep, within the depth limit)
    expression = " + ".join(["(" + " + ".join(["N7:1"] * 8) + ")"] * 50)
    rung = "XIC B3/0 " + f'CPT N7:0 "{expression}" ' * 13  # 2 + 13 * 801 = 10,415 elements
    app = app_with(tmp_path, rung + "\n")
    code, _, err, _, _ = softplc_measured(tmp_path, "check", str(app))
    assert code == 1 and RUNG_TOO_LARGE in err and "main.lad:1:" in err, err


def test_a_program_of_many_large_rungs_compiles_in_blocks_of_bounded_size(tmp_path):
    # 12 rungs of MAX_RUNG_ELEMENTS: 60,000 instructions, compiled as blocks
    # of about 10,000 (blocks.INSTRUCTIONS_BUDGET), not one function.
    app = app_with(tmp_path, _elements(MAX_RUNG_ELEMENTS, neutral=False) * 12)
    code, out, err, peak_mb, _ = softplc_measured(tmp_path, "run", str(app), "--fresh", "--scans", "1",
                                                  "--set", "B3/0=1", "--print", "B3/1")
    assert code == 0 and out == "B3/1 = 1\n", err[-2000:]
    assert peak_mb < 300, peak_mb


def test_a_ten_megabyte_string_in_a_data_table_json_file_is_refused_in_bounded_memory(tmp_path):
    # The same per-character cost in the JSON reader's scan for long numbers
    # and deep nesting (datatable/jsonio.py): 1.2 GB for this file, unbounded.
    (tmp_path / "big.json").write_text('{"N7": [1, 2], "ST9": ["' + "A" * TEN_MB + '"]}')
    code, _, err, peak_mb, seconds = softplc_measured(tmp_path, "datatable", "big.json", "--print", "N7:1")
    assert code == 1 and err == (f"error: big.json: ST9[0]: a {TEN_MB}-character string does not fit ST9:0: "
                                 "at most 82 characters\n"), err[-2000:]
    assert peak_mb < PEAK_BOUND_MB and seconds < 60, (peak_mb, seconds)
