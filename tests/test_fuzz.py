"""Fuzzing softplc in the default suite: a few dozen inputs of every kind.

The generators are tests/helpers/fuzz_inputs.py, the oracle tests/helpers/fuzz_oracle.py;
tools/fuzz.py runs the same for minutes in several processes
(docs/fuzzing.md). Here every input kind gets a bounded, derandomized run
(the same inputs on every machine, no example database), with the profile
``MUST_PASS``: input classes still being fixed (``fuzz_inputs.KNOWN_OPEN``) are
left out, so a failure here is a new regression, not a known bug. The
campaign (``tools/fuzz.py``, profile ``all``) is where the open classes
show.

Every command goes through ``softplc_lite.cli.main`` in-process; a few cases
also run as the real ``softplc`` command.
"""

from __future__ import annotations

import re
import tempfile
import time
from pathlib import Path

from helpers import fuzz_inputs as fi
from helpers import fuzz_oracle as fo
import pytest
from helpers.fuzz_inputs import KINDS, MUST_PASS, Case, cases
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

# Examples per kind: together about 30-60 s on a CI machine.
EXAMPLES = {
    "ladder": 45, "toml": 30, "datatable_json": 30, "load_json": 30, "modules_lst": 25, "comgenius_lst": 35,
    "modbmast_xml": 20, "cli_args": 40, "trace": 20, "snapshot_file": 40, "snapshot_app": 25, "address": 40,
    "watch": 25,
    # Files that are not what their name promises, damaged state, signals, a live Modbus TCP server:
    # together about 20 s (a signals case is a real run of 1-2 s, a modbus_tcp case a few hundred requests).
    "special_files": 20, "state_damage": 12, "signals": 3, "modbus_tcp": 2,
}

# Findings the product has for inputs the MUST_PASS profile draws, each a
# known bug, tolerated here by signature until it is fixed; none is known.
TOLERATED: dict[str, str] = {}


COMMAND_TIMEOUT = 20.0


def open_findings(findings: list[fo.Finding]) -> list[fo.Finding]:
    return [f for f in findings if not any(re.search(p, f.signature) for p in TOLERATED)]


def run_case(case: Case, runner=fo.run_main) -> list[fo.Finding]:
    with tempfile.TemporaryDirectory(prefix="softplc-fuzz-") as d:
        findings, _ = fo.check_case(case, Path(d), COMMAND_TIMEOUT, runner)
        return open_findings(findings)


def _report(case: Case, findings: list[fo.Finding]) -> str:
    return f"{case.kind} ({case.note}):\n" + "\n".join(str(f) for f in findings)


@pytest.mark.parametrize("kind", KINDS)
def test_fuzz(kind):
    @settings(max_examples=EXAMPLES[kind], deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much])
    @given(cases([kind], MUST_PASS))
    def fuzz(case):
        findings = run_case(case)
        assert not findings, _report(case, findings)

    fuzz()


# -- the real command, for a few cases ---------------------------------------------------------


@pytest.mark.parametrize("kind", ["ladder", "comgenius_lst", "datatable_json", "address"])
def test_fuzz_as_the_softplc_command(kind):
    @settings(max_examples=1, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(cases([kind], MUST_PASS))
    def fuzz(case):
        findings = run_case(case, fo.run_command)
        assert not findings, _report(case, findings)

    fuzz()


# -- the oracle itself -----------------------------------------------------------------------------


def _case(**kw) -> Case:
    return Case("ladder", target="app/main.lad", **kw)


def _classes(result: fo.Result, case: Case | None = None) -> set[str]:
    return {f.cls for f in fo.judge(result, case or _case(), "/tmp/x")}


def test_oracle_sees_an_escaped_exception_a_traceback_and_odd_exit_codes():
    assert _classes(fo.Result(["run"], None, exception="KeyError: 'x'", traceback="...")) == {"exception"}
    assert _classes(fo.Result(["run"], 1, err="Traceback (most recent call last):\n  ...")) == {"exception"}
    assert _classes(fo.Result(["run"], 4, err="softplc: internal error: KeyError: 'x' (a bug)")) == {"internal-error"}
    assert _classes(fo.Result(["run"], 5)) == {"exit-code"}
    assert _classes(fo.Result(["run"], 130)) == {"exit-code"}
    assert _classes(fo.Result(["run"], 3, err="softplc: a: major fault 255: internal error: KeyError: 2")) == {"fault-255"}
    assert _classes(fo.Result(["run"], 0, out="\udcff")) == {"unencodable-output"}
    for code in (0, 2, 3):
        assert _classes(fo.Result(["run"], code, err="softplc: a: major fault 20: x")) == set()


def test_oracle_wants_path_and_line_in_errors_about_the_fuzzed_file():
    located = fo.Result(["check"], 1, err="/tmp/x/app/main.lad:3:7: unknown instruction 'XIX'")
    unlocated = fo.Result(["check"], 1, err="/tmp/x/app/main.lad: something is wrong")
    in_passing = fo.Result(["check"], 1, err="main.lad:1:1: add COMGENIUS to the app's main.lad")
    assert _classes(located) == set() and _classes(in_passing) == set()
    assert _classes(unlocated) == {"unlocated"}


def test_watchdog_ends_a_command_that_hangs(monkeypatch):
    import softplc_lite.cli

    def sleepy(argv):
        time.sleep(30)
        return 0

    monkeypatch.setattr(softplc_lite.cli, "main", sleepy)
    start = time.monotonic()
    r = fo.run_main(["run", "x"], timeout=0.5)
    assert r.hung and time.monotonic() - start < 5
    assert _classes(r) == {"hang"}


def test_run_main_catches_what_escapes_and_usage_exits(monkeypatch):
    import softplc_lite.cli

    def broken(argv):
        raise RecursionError("deep")

    monkeypatch.setattr(softplc_lite.cli, "main", broken)
    r = fo.run_main(["check", "x"])
    assert r.exception == "RecursionError: deep" and "broken" in r.traceback
    monkeypatch.undo()
    assert fo.run_main(["run"]).code == 2  # argparse: APP is missing
    assert fo.run_main(["check", "programs/blinker"]).code == 0


def _files_case(name: str, spec: str) -> Case:
    import random

    from helpers import fuzz_files

    return fuzz_files.special_case(name, spec, random.Random(0), fi.EVERYTHING)


def test_files_oracle_wants_a_special_input_refused_and_named(tmp_path):
    """A stand-in softplc that accepts a FIFO main.lad, then one that refuses it without naming it."""
    case = _files_case("main.lad", "fifo")
    accepts = lambda argv, timeout: fo.Result(argv, 0)  # noqa: E731
    findings, _ = fo.check_case(case, tmp_path / "a", runner=accepts)
    assert {f.cls for f in findings} == {"not-refused"}
    unnamed = lambda argv, timeout: fo.Result(argv, 1, err="error: cannot read a file: No such file or directory")  # noqa: E731
    findings, _ = fo.check_case(case, tmp_path / "b", runner=unnamed)
    assert {f.cls for f in findings} == {"unnamed", "raw-errno"}
    findings, _ = fo.check_case(case, tmp_path / "c")  # the real one
    assert findings == []


def test_files_oracle_sees_a_code_cache_that_changes_the_logic(tmp_path):
    """A stand-in for a run that loads a damaged cache: its table is not the one the run without a cache makes."""
    case = _files_case("codecache.bin", "empty")
    runs = []

    def runner(argv, timeout):
        r = fo.run_main(argv, timeout)
        runs.append(argv)
        if len(runs) == 3:  # prepare, reference, then the run on the damaged cache
            Path(argv[argv.index("--dump") + 1]).write_text('{"N7": [1]}')
        return r

    findings, _ = fo.check_case(case, tmp_path, runner=runner)
    assert {f.cls for f in findings} == {"cache-other-logic"}


def test_special_files_cover_every_file_softplc_reads_and_every_special():
    from helpers import fuzz_files

    assert set(fuzz_files.SPECIALS) == {"fifo", "devzero", "dangling", "loop", "dir", "sparse", "empty"}
    targets = {t[1].split("/")[-1] for t in fuzz_files.TARGETS.values()}
    assert {"main.lad", "softplc.toml", "MODULES.LST", "COMGENIUS.LST", "MODBMAST.XML", "MODBTCPS.XML", "datatable.json",
            "load.json", "replay.trace", "t.snap", "t.json", "watch.txt", "datatable.snap", "datatable.snap.prev",
            "codecache.bin"} <= targets


def test_fmt_property_sees_text_that_does_not_parse_back(tmp_path):
    """fmt_roundtrip on a stand-in for fmt whose output never parses."""
    lad = tmp_path / "app" / "main.lad"
    lad.parent.mkdir()
    lad.write_text("XIC B3/0 OTE O:0/0\n")
    findings: list[fo.Finding] = []

    def do(argv, located=True):
        if argv[1] == str(lad):
            return fo.Result(argv, 0, out="XIC B3/0 BND\n")
        return fo.run_main(argv)

    fo.fmt_roundtrip(lad, "mnemonic", do, findings, _case())
    assert [f.cls for f in findings] == ["fmt-reparse"]


@given(cases(profile=fi.EVERYTHING))
@settings(max_examples=60, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
def test_every_case_survives_json_and_names_real_commands(case):
    """What the campaign saves (case.json) gives the same case back."""
    again = Case.from_json(case.to_json())
    assert again == case
    assert case.kind in KINDS
    for argv in case.commands:
        assert argv[0] in {"run", "check", "fmt", "watch", "address", "datatable"}


def test_profiles_keep_the_known_classes_out_of_the_default_suite():
    assert fi.KNOWN_OPEN <= set(fi.FEATURES)
    assert not any(MUST_PASS.allows(f) for f in fi.KNOWN_OPEN)
    assert all(fi.EVERYTHING.allows(f) for f in fi.FEATURES)


@given(st.integers(0, 2 ** 32 - 1))
@settings(max_examples=30, deadline=None, derandomize=True, database=None)
def test_small_int_numbers_stay_under_the_digit_limit(n):
    """The numbers generators hold as Python ints (SMALL_INTS) can be ints."""
    import random

    rnd = random.Random(n)
    for _ in range(20):
        text = fi.interesting_number(rnd, fi.SMALL_INTS)
        assert len(text) <= 4302, text[:40]
        assert "e999" not in text


def test_the_campaign_lists_every_kind():
    """tools/fuzz.py --help names every kind --kinds takes."""
    import subprocess
    import sys

    tool = Path(__file__).resolve().parents[1] / "tools" / "fuzz.py"
    text = " ".join(subprocess.run([sys.executable, str(tool), "--help"], capture_output=True, text=True,
                                   check=True).stdout.split())
    assert all(kind in text for kind in KINDS), [k for k in KINDS if k not in text]
