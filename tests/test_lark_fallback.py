"""When lark's internals are not as lalr_driver.py reads them (another lark
release: a name moved, a table laid out otherwise), parsing falls back to
lark's own parser for the rest of the process, silently, with the same
programs and the same located errors.

Each case runs in a process of its own: the fallback is process-wide, and
the lark objects the simulations alter are shared by the whole process."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

# Texts with errors: each must come out located (file:line:col) and worded
# as with the fast loop.
BAD = {
    "missing_paren.lad": "XIC B3/0 OTE B3/1\nXIC(B3/0 OTE(B3/1);\n",
    "bad_char.lad": "XIC B3/0\nOTE B3/1 @\n",
    "bad_address.lad": "XIC B3/0 OTE Q9:0/0\nXIC(B3/1)OTE(B3/2);\n",
    "unclosed_branch.lad": "XIC B3/0 BST XIC B3/1 NXB XIO B3/2 OTE O:0/0\n",
    "no_semicolon.lad": "XIC(B3/0)OTE(O:0/0)\n",
    "bad_expression.lad": 'CPT N7:0 "N7:1 + * 2"\n',
}

# Run in the child: ``mode`` says which internal goes missing, as a lark
# release that moved it would make it.
SCRIPT = r'''
import json, logging, sys
from pathlib import Path

mode, root, bad = sys.argv[1], Path(sys.argv[2]), json.loads(sys.argv[3])
records = []

class Keep(logging.Handler):
    def emit(self, record):
        records.append(record.getMessage())

logging.getLogger("softplc_lite").addHandler(Keep())
logging.getLogger("softplc_lite").setLevel(logging.DEBUG)

import lark.lexer

if mode == "import":  # an internal lalr_driver imports is gone
    saved = lark.lexer.UnlessCallback
    del lark.lexer.UnlessCallback
    from softplc_lite.ladder import parser
    lark.lexer.UnlessCallback = saved  # lark itself still has it: only lalr_driver's import failed
else:
    from softplc_lite.ladder import parser
from softplc_lite.ladder import lalr_driver
from softplc_lite.ladder.errors import LadderError
from softplc_lite.ladder.parser import parse_program, syntax_problems

if mode == "table":  # lark's Shift action is another object: the parse table reads otherwise
    lalr_driver.Shift = type("Shift", (), {})
elif mode == "rename":  # Scanner.fullmatch renamed, lark's own code following it: fails in the middle of a parse
    lark.lexer.Scanner.match_whole = lark.lexer.Scanner.fullmatch
    del lark.lexer.Scanner.fullmatch
    def call(self, t):
        res = self.scanner.match_whole(t.value)
        if res is not None:
            t.type = res
        return t
    lark.lexer.UnlessCallback.__call__ = call

runs = []  # how many parses the fast loop was asked for
if hasattr(lalr_driver, "FastLalr"):
    inner = lalr_driver.FastLalr._parse
    def counted(self, text, start):
        runs.append(1)
        return inner(self, text, start)
    lalr_driver.FastLalr._parse = counted

def problem(e):
    return f"{e.pos} {e.message} {e.context!r}"

def outcome(text, source):
    try:
        program = parse_program(text, source)
        result = repr([(n, f.name, [(r.pos, r.comment, repr(r.elements)) for r in f.rungs])
                       for n, f in sorted(program.files.items())]) + repr(program.data) + repr(program.symbols)
    except LadderError as e:
        result = "error " + problem(e)
    return [result, [problem(e) for e in syntax_problems(text, source)]]

texts = [(str(p.relative_to(root)), p.read_text()) for p in sorted(root.glob("programs/**/*.lad"))]
texts += list(bad.items())
# The second parse of a shipped program: the fallback stays for the rest of the process.
texts.append(texts[0])
out = {name: outcome(text, name) for name, text in texts}
json.dump({"outcomes": out, "parser": type(parser._fast_parser()).__name__, "fast_runs": len(runs),
           "debug": records}, sys.stdout)
'''


def run_child(mode: str, tmp_path: Path) -> dict:
    # byte code goes to the run's PYTHONPYCACHEPREFIX (tests/helpers/isolation.py), never into the repository
    proc = subprocess.run([sys.executable, "-c", SCRIPT, mode, str(ROOT), json.dumps(BAD)], capture_output=True,
                          text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""  # the fallback is silent
    return json.loads(proc.stdout)


@pytest.fixture(scope="module")
def with_fast_loop(tmp_path_factory) -> dict:
    found = run_child("none", tmp_path_factory.mktemp("fast"))
    assert found["parser"] == "FastLalr" and found["fast_runs"] > 0 and found["debug"] == []
    return found


@pytest.mark.parametrize("mode", ["import", "table", "rename"])
def test_a_missing_lark_internal_leaves_parsing_to_lark_with_the_same_results(mode, with_fast_loop, tmp_path):
    found = run_child(mode, tmp_path)
    assert found["outcomes"] == with_fast_loop["outcomes"]
    # Given up once, for the rest of the process: one debug line, at most one try of the loop.
    assert len(found["debug"]) == 1 and "fast parse loop is off" in found["debug"][0]
    if mode == "rename":
        assert found["parser"] == "FastLalr" and found["fast_runs"] == 1
    else:
        assert found["parser"] == "LarkOnly" and found["fast_runs"] == 0


def test_errors_stay_located_without_the_fast_loop(tmp_path):
    outcomes = run_child("rename", tmp_path)["outcomes"]
    expected = {
        "missing_paren.lad": "missing_paren.lad:2:10 unexpected 'OTE'",
        "bad_char.lad": "bad_char.lad:2:10 unexpected character '@'",
        "bad_address.lad": "bad_address.lad:1:14 unknown file type 'Q'",
        "unclosed_branch.lad": "unclosed_branch.lad:1:10 BST without a matching BND",
        "no_semicolon.lad": "no_semicolon.lad:1:19 unexpected end of file",
        "bad_expression.lad": "bad_expression.lad:1:18 unexpected '*'",
    }
    for name, start in expected.items():
        first, problems = outcomes[name]
        assert first.startswith("error " + start), (name, first)
        assert problems and problems[0].startswith(start), (name, problems)
