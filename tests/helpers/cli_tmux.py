"""A real terminal for the CLI tests: one tmux server of our own (``-L``
socket) running one shell command, its screen read with capture-pane, and
the command's exit status caught by the shell line around it. Every server
is killed at the end (the ``terminal`` fixture)."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers.tmux_helpers import ROOT, Tmux

SOFTPLC = f"{shlex.quote(sys.executable)} -m softplc_lite"


class Terminal(Tmux):
    """A Tmux whose pane runs one shell line and shows its exit status."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.socket = f"softplc-cli-{os.getpid()}-{name}"
        self.session = "t"
        self.tmux = self.run

    def start(self, command: str, cwd: Path = ROOT, width: int = 120, height: int = 30) -> None:
        """Run ``command`` (a shell line); when it ends the pane shows
        ``exit=N`` and stays open a while, so ``exit_status`` can read N."""
        line = (f"cd {shlex.quote(str(cwd))} && export PYTHONPATH={shlex.quote(str(ROOT))} TERM=xterm-256color; "
                f"{command}; echo exit=$?; sleep 60")
        subprocess.run(["tmux", "-L", self.socket, "new-session", "-d", "-s", self.session, "-x", str(width),
                        "-y", str(height), line], check=True, timeout=10)

    def wait_for(self, pattern: str, seconds: float = 20.0) -> re.Match:
        """Wait (bounded) for the regular expression ``pattern`` on the screen."""
        deadline = time.monotonic() + seconds
        while True:
            screen = self.screen()
            m = re.search(pattern, screen)
            if m:
                return m
            if time.monotonic() > deadline:
                raise AssertionError(f"{pattern!r} not on the screen after {seconds} s:\n{screen}")
            time.sleep(0.1)

    def exit_status(self, seconds: float = 30.0) -> int:
        return int(self.wait_for(r"exit=(\d+)", seconds).group(1))

    def command_pid(self, seconds: float = 10.0) -> int:
        """The pid of the softplc process the pane's shell started."""
        shell = int(self.tmux("display-message", "-p", "-t", self.session, "#{pane_pid}").strip())
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            out = subprocess.run(["ps", "-o", "pid=,args=", "--ppid", str(shell)], capture_output=True,
                                 text=True, timeout=10, check=False).stdout
            for row in out.splitlines():
                pid, _, args = row.strip().partition(" ")
                if "softplc_lite" in args:
                    return int(pid)
            time.sleep(0.1)
        raise AssertionError("the softplc process did not start")


def open_terminal(request):
    """For a fixture: a Terminal named after the test, killed after it
    (``@pytest.fixture(name="terminal")`` around ``yield from open_terminal(request)``)."""
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (apt-get install -y tmux)")
    t = Terminal(re.sub(r"\W", "", request.node.name)[-40:])
    yield t
    t.kill()
