"""Usage errors name only the rule broken (exit 2),
addresses are checked before scan 0 (exit 1, nothing run or saved), the
help texts, --version, softplc alone, softplc datatable alone, and the
watch options' rules at the command line (--snapshot leaves the retentive state alone unless
--save; --scans needs --snapshot). The command run by cli.main in the
test's process, on real files: each test checks what it prints, returns and
writes."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from helpers.cli import ROOT, softplc_here
from softplc_lite import __version__
from softplc_lite.cli import build_parser
from softplc_lite.watch import terminal
from softplc_lite.watch.keys import key_rows

def motor(tmp_path: Path) -> Path:
    app = tmp_path / "motor"
    shutil.copytree(ROOT / "programs" / "motor", app, ignore=shutil.ignore_patterns(".softplc"))
    return app


# -- usage errors: exit 2, the one rule broken --------------------------------------------------

@pytest.mark.parametrize("args,message", [
    (("run", "programs/motor", "--scans", "-5"), "softplc run: error: argument --scans: expected an integer 0 or more, not '-5'"),
    (("run", "programs/motor", "--scans=-5"), "softplc run: error: argument --scans: expected an integer 0 or more, not '-5'"),
    (("watch", "programs/motor", "--width", "20", "--snapshot", "x.txt"),
     "softplc watch: error: argument --width: expected an integer from 40 to 1000, not '20'"),
    (("run", "programs/motor", "--realtime", "--simulated"),
     "softplc run: error: argument --simulated: not allowed with argument --realtime"),
])
def test_usage_errors_name_only_the_rule_broken(args, message):
    p = softplc_here(*args)
    assert p.returncode == 2
    assert p.stderr.splitlines()[-1] == message  # one rule, on the last line under the usage
    assert "Traceback" not in p.stderr and p.stdout == ""


def test_softplc_alone_prints_usage_and_exits_2():
    p = softplc_here()
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.startswith("usage: softplc ")
    assert "a COMMAND is needed: run, watch, check, test, fmt, address, datatable, opcua-cert or opcua-user" in p.stderr


def test_version():
    p = softplc_here("--version")
    assert (p.returncode, p.stdout) == (0, f"softplc_lite {__version__}\n")


def test_datatable_alone_explains_itself():
    p = softplc_here("datatable")
    assert p.returncode == 2
    assert p.stderr.startswith("usage: softplc datatable")
    assert "expected FILEs to load" in p.stderr and "softplc datatable docs/examples/datatable.json" in p.stderr


# -- checked before scan 0 ------------------------------------------------------------------------

def test_a_bad_print_address_stops_before_scan_0(tmp_path):
    app = motor(tmp_path)
    p = softplc_here("run", str(app), "--scans", "5", "--print", "Motor", "--print", "N7:999", "--print", "Nope")
    assert p.returncode == 1 and p.stdout == ""
    assert p.stderr.splitlines() == [
        "error: --print N7:999: element 999 is past the end of N7 (1 element)",
        "error: --print 'Nope': Nope is neither an address nor a program symbol",
    ]
    assert not (app / ".softplc" / "datatable.snap").exists()  # no scan ran, nothing was saved


def test_a_bad_watch_address_stops_before_scan_0(tmp_path):
    app = motor(tmp_path)
    out = tmp_path / "view.txt"
    p = softplc_here("watch", str(app), "--watch", "N99:0", "--scans", "3", "--snapshot", str(out), "--save")
    assert p.returncode == 1
    assert p.stderr == "error: --watch N99:0: there is no data file N99\n"
    assert not out.exists() and not (app / ".softplc" / "datatable.snap").exists()


def test_a_bad_display_address_stops_before_scan_0_with_its_line(tmp_path):
    app = motor(tmp_path)
    (app / "softplc.toml").write_text('# shown by softplc run\n[display]\nsummary = { far = "N7:50" }\n')
    p = softplc_here("run", str(app), "--scans", "5")
    assert p.returncode == 1 and p.stdout == ""
    assert re.search(r"softplc.toml:3: \[display\] summary 'far': .*past the end of N7", p.stderr), p.stderr
    assert not (app / ".softplc" / "datatable.snap").exists()


# -- watch at the CLI level -------------------------------------------------------------------------

def test_watch_snapshot_leaves_the_retentive_state_unless_save(tmp_path):
    app = motor(tmp_path)
    snap = app / ".softplc" / "datatable.snap"
    assert softplc_here("run", str(app), "--scans", "1", "--set", "N7:0=5").returncode == 0
    before = snap.read_bytes()
    view = tmp_path / "view.txt"
    p = softplc_here("watch", str(app), "--scans", "3", "--set", "N7:0=77", "--snapshot", str(view))
    assert p.returncode == 0 and view.exists(), p.stderr
    assert snap.read_bytes() == before  # read at start, not written
    p = softplc_here("watch", str(app), "--scans", "3", "--set", "N7:0=77", "--snapshot", str(view), "--save")
    assert p.returncode == 0, p.stderr
    assert softplc_here("run", str(app), "--scans", "0", "--print", "N7:0").stdout == "N7:0 = 77\n"


def test_watch_scans_without_snapshot_is_refused():
    p = softplc_here("watch", "programs/motor", "--scans", "10")
    assert p.returncode == 2
    assert p.stderr == ("softplc watch: error: --scans N needs --snapshot FILE (the view starts at scan 0; "
                        "press n to step or r to run)\n")


# -- help ---------------------------------------------------------------------------------------------

def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return parser, action.choices


def test_every_argument_has_help_and_every_help_points_to_docs():
    parser, commands = _subparsers()
    for name, sub in [("softplc", parser), *commands.items()]:
        for action in sub._actions:
            assert action.help, f"{name} {action.option_strings or action.dest} has no help text"
    for name in ("run", "watch", "check", "address", "datatable"):
        p = softplc_here(name, "--help")
        assert p.returncode == 0 and re.search(r"docs/\w+\.md", p.stdout), (name, p.stdout)
    assert "docs/cli.md" in softplc_here("--help").stdout


def test_watch_help_lists_every_key_of_the_table():
    text = softplc_here("watch", "--help").stdout
    assert "keys in the view:" in text
    rows = key_rows()
    assert len(rows) == len(terminal.BINDINGS) >= 20
    for label, meaning in rows:
        assert re.search(rf"^  {re.escape(label)} +{re.escape(meaning)}$", text, re.MULTILINE), label


def test_the_help_lists_the_keys_the_controller_handles():
    # the Controller dispatches from the table the help shows: every row has its method
    assert key_rows() == tuple((b.label, b.help) for b in terminal.BINDINGS)
    missing = [b.action for b in terminal.BINDINGS if not callable(getattr(terminal.Controller, f"_do_{b.action}", None))]
    assert not missing, missing


def test_the_package_version_is_the_distributions():
    # the code cache's key uses the package's __version__ (ladder/codecache.py)
    import tomllib

    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["version"] == __version__
