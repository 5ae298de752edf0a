"""Runtimes as separate processes (``softplc run APP --realtime``), for the
tests where two PLCs talk to each other or where clients' threads must not
share an interpreter with the scan they judge: started, stopped with
SIGTERM (which prints their --print values and the late scans), and what
they printed read back."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from helpers.modbtcps_apps import LIMIT_S


class Runtime:
    """``softplc run APP --realtime`` until ``stop``: (stdout, stderr)."""

    def __init__(self, app: Path, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "softplc_lite", "run", str(app), "--realtime",
                                      "--fresh", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)

    def stop(self) -> tuple[str, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            out, err = self.proc.communicate(timeout=LIMIT_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
        assert self.proc.returncode == 0, err
        return out, err


def prints(addresses: list[str]) -> list[str]:
    return [arg for a in addresses for arg in ("--print", a)]


def printed(stdout: str) -> dict[str, str]:
    return dict(line.split(" = ", 1) for line in stdout.splitlines() if " = " in line)


def late_scans(stderr: str) -> tuple[int, int]:
    m = re.search(r": (\d+) late scans? of (\d+),", stderr)
    assert m, stderr
    return int(m.group(1)), int(m.group(2))


def wait_for_a_client(port: int) -> None:
    """Until a connection to 127.0.0.1:``port`` is established (Linux's
    /proc/net/tcp; elsewhere at once)."""
    table = Path("/proc/net/tcp")
    deadline = time.monotonic() + LIMIT_S
    while table.exists() and time.monotonic() < deadline:
        rows = [line.split() for line in table.read_text().splitlines()[1:]]
        if any(row[2] == f"0100007F:{port:04X}" and row[3] == "01" for row in rows):  # remote, ESTABLISHED
            return
        time.sleep(0.05)
