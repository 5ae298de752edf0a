"""A real terminal for tests: tmux runs a command (``softplc watch``),
``send-keys`` types, ``capture-pane`` reads the screen. Each test gets a
tmux server of its own (the ``tmux`` fixture), killed at the end; every
wait is bounded."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


class Tmux:
    """One tmux server of our own (-L socket), killed at the end."""

    def __init__(self, name: str) -> None:
        self.socket = f"softplc-test-{os.getpid()}-{name}"
        self.session = name

    def run(self, *args: str) -> str:
        out = subprocess.run(["tmux", "-L", self.socket, *args], capture_output=True, text=True, timeout=10,
                             check=False)
        return out.stdout

    def start(self, command: str, width: int = 100, height: int = 30) -> None:
        # COLUMNS/LINES (pytest's terminal may set them) would override the pane's size in rich
        env = f"cd {ROOT} && unset COLUMNS LINES; PYTHONPATH={ROOT} TERM=xterm-256color {command}"
        subprocess.run(["tmux", "-L", self.socket, "new-session", "-d", "-s", self.session, "-x", str(width),
                        "-y", str(height), env], check=True, timeout=10)

    def screen(self) -> str:
        return self.run("capture-pane", "-p", "-t", self.session)

    def keys(self, *keys: str) -> None:
        for k in keys:
            self.run("send-keys", "-t", self.session, k)

    def wait_for(self, text: str, seconds: float = 15.0) -> str:
        deadline = time.monotonic() + seconds
        screen = ""
        while time.monotonic() < deadline:
            screen = self.screen()
            if text in screen:
                return screen
            time.sleep(0.1)
        raise AssertionError(f"{text!r} not on screen after {seconds} s:\n{screen}")

    def wait_without(self, text: str, seconds: float = 15.0) -> str:
        """Wait (bounded) until ``text`` is gone from the screen."""
        deadline = time.monotonic() + seconds
        screen = self.screen()
        while text in screen and time.monotonic() < deadline:
            time.sleep(0.1)
            screen = self.screen()
        if text in screen:
            raise AssertionError(f"{text!r} still on screen after {seconds} s:\n{screen}")
        return screen

    def alive(self) -> bool:
        return subprocess.run(["tmux", "-L", self.socket, "has-session", "-t", self.session],
                              capture_output=True, timeout=10, check=False).returncode == 0

    def kill(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, timeout=10, check=False)
        # the server's socket file can outlive it: remove ours, so test runs leave nothing behind
        socket_dir = Path(os.environ.get("TMUX_TMPDIR", "/tmp")) / f"tmux-{os.getuid()}"
        (socket_dir / self.socket).unlink(missing_ok=True)

    def wait_gone(self, seconds: float = 10.0) -> bool:
        """Wait (bounded) for the command to end; True when it did."""
        deadline = time.monotonic() + seconds
        while self.alive() and time.monotonic() < deadline:
            time.sleep(0.1)
        return not self.alive()


@pytest.fixture
def tmux(request):
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (apt-get install -y tmux)")
    t = Tmux(request.node.name[:20].replace("[", "_").replace("]", "_"))
    yield t
    t.kill()
