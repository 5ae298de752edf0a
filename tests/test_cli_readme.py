"""Every line of the README's "Try it" block works in the order written,
each in the state the lines before it left (a temp copy of programs/, so the
tree's own state is not touched, whose Modbus TCP server listens on a port
found free, so a PLC running here does not stand in the way). A ``softplc watch``
line runs in a real terminal (tmux), is quit with q once its view is up;
every other line is bounded (--scans, a --replay trace, or check/fmt) and
has a timeout."""

from __future__ import annotations

import shlex

import pytest
from helpers.cli import softplc
from helpers.cli_tmux import SOFTPLC, open_terminal
from helpers.readme import try_it_lines
from helpers.shipped_apps import copy_programs


@pytest.fixture(name="terminal")
def fixture_terminal(request):
    yield from open_terminal(request)


def test_the_try_it_block_is_what_this_test_runs():
    lines = try_it_lines()
    assert len(lines) >= 10 and all(line.startswith("softplc ") for line in lines)
    for line in lines:
        argv = shlex.split(line, comments=True)
        bounded = argv[1] in ("check", "fmt", "watch", "test") or "--scans" in argv or "--replay" in argv
        assert bounded, f"a README line that would run until stopped: {line}"


def test_every_try_it_line_works_in_order(tmp_path, terminal):
    copy_programs(tmp_path)
    for k, line in enumerate(try_it_lines()):
        argv = shlex.split(line, comments=True)
        if argv[1] == "watch":
            terminal.session = f"w{k}"
            terminal.start(f"{SOFTPLC} {shlex.join(argv[1:])}", cwd=tmp_path)
            terminal.wait_for(r"PAUSED")
            if "C5:1.ACC" in argv:  # after the Start=150 line: --fresh makes the polls good again
                terminal.keys("r")
                terminal.wait_for(r"C5:1\.ACC\W+[1-9]")  # good replies counted
            terminal.keys("q")
            assert terminal.exit_status() == 0, (line, terminal.screen())
            continue
        p = softplc(*argv[1:], cwd=tmp_path, timeout=120)
        assert p.returncode == 0, (line, p.stderr)
        assert "Traceback" not in p.stderr, line
