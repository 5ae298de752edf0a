"""A virtual null-modem for tests and benchmarks: two ptys joined by socat.

    with PtyPair(tmp_path) as pair:      # socat -d -d pty,raw,echo=0,link=A pty,raw,echo=0,link=B
        open(pair.a) ... open(pair.b)    # the two link paths, both existing
        pair.kill()                      # socat ends: both ptys (and links) vanish
        pair.restart()                   # a new socat, the SAME link paths

Lifetime is bounded three ways, so an aborted run cannot leave socat behind:

- ``kill()`` / leaving the ``with`` block / ``close()`` end socat (SIGTERM,
  then SIGKILL to its process group if it does not go) and reap it;
- socat runs under ``timeout LIFETIME_S`` (coreutils): it is killed after
  that many seconds whatever happens to this process;
- the ``timeout`` process gets ``PR_SET_PDEATHSIG`` = SIGTERM (Linux): when
  the process (thread) that started it dies, it receives SIGTERM, which it
  forwards to socat.

Only ``pytest.skip`` when socat is not installed (``require_socat()``);
outside pytest (benchmarks) a missing socat raises ``SocatMissing``.
Facts about ptys this relies on are in /work/shared/testing-notes.md: a pty
pair does not enforce the baud rate, and 8N1/8N2 are the only settings that
work on this kernel.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

LIFETIME_S = 120  # the outer bound of one socat's life (coreutils timeout)
START_S = 5.0  # how long to wait for both links to appear
STOP_S = 3.0  # how long to wait for socat to go after SIGTERM

_PR_SET_PDEATHSIG = 1


class SocatMissing(RuntimeError):
    """socat is not installed (apt-get install -y socat)."""


def socat_path() -> str | None:
    return shutil.which("socat")


def require_socat() -> str:
    """socat's path, or skip the calling test (pytest) when it is not installed."""
    path = socat_path()
    if path is None:
        import pytest

        pytest.skip("socat is not installed (apt-get install -y socat): no pty pair")
    return path


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except Exception:  # not Linux: the timeout still bounds the lifetime
        pass


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


def _alive(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def socat_processes(ancestor: int | None = None) -> list[int]:
    """Live socat processes descending from ``ancestor`` (default: this process)."""
    ancestor = os.getpid() if ancestor is None else ancestor
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            if (entry / "comm").read_text().strip() != "socat" or not _alive(int(entry.name)):
                continue
        except OSError:
            continue
        pid = int(entry.name)
        while pid > 1:  # walk up the parents
            try:
                pid = int((Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split())[1])
            except (OSError, IndexError, ValueError):
                break
            if pid == ancestor:
                found.append(int(entry.name))
                break
    return found


class PtyPair:
    """Two ptys joined by socat, at link paths ``a`` and ``b`` under ``directory``.

    ``directory`` defaults to a new temporary directory (removed by close()).
    The constructor starts socat and waits until both links exist; use it as a
    context manager or call close()."""

    def __init__(self, directory: str | os.PathLike | None = None, names: tuple[str, str] = ("ttyA", "ttyB"),
                 lifetime_s: float = LIFETIME_S, start: bool = True) -> None:
        self.socat = socat_path()
        if self.socat is None:
            raise SocatMissing("socat is not installed (apt-get install -y socat): no pty pair")
        self.timeout = shutil.which("timeout")
        self._own_dir = directory is None
        self.directory = Path(tempfile.mkdtemp(prefix="ptypair-") if directory is None else directory)
        self.a = str(self.directory / names[0])
        self.b = str(self.directory / names[1])
        self.log_path = self.directory / f"socat-{names[0]}-{names[1]}.log"
        self.lifetime_s = lifetime_s
        self.proc: subprocess.Popen | None = None
        self.socat_pid: int | None = None  # socat itself (a child of `timeout` when there is one)
        self.started: list[int] = []  # every pid this pair started, for the cleanup checks
        self.starts = 0
        if start:
            self.start()

    # -- context manager -------------------------------------------------------------------
    def __enter__(self) -> "PtyPair":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        state = f"socat pid {self.socat_pid}" if self.running else "stopped"
        return f"<PtyPair {self.a} <-> {self.b}, {state}>"

    @property
    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    # -- start, kill, restart ----------------------------------------------------------------
    def start(self) -> None:
        """Start socat and wait until both link paths exist."""
        if self.running:
            raise RuntimeError(f"{self!r} is already running")
        for link in (self.a, self.b):  # a stale link from a socat that was SIGKILLed
            if os.path.islink(link):
                os.unlink(link)
        cmd = [self.socat, "-d", "-d", f"pty,raw,echo=0,link={self.a}", f"pty,raw,echo=0,link={self.b}"]
        if self.timeout:
            cmd = [self.timeout, "-s", "TERM", "-k", "2", str(int(self.lifetime_s)), *cmd]
        with open(self.log_path, "ab") as log:
            self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                                         start_new_session=True, preexec_fn=_die_with_parent)
        self.started.append(self.proc.pid)
        self.starts += 1
        deadline = time.monotonic() + START_S
        while not (os.path.exists(self.a) and os.path.exists(self.b)):
            if self.proc.poll() is not None:
                self._reap()
                raise RuntimeError(f"socat exited with status {self.proc.returncode} before creating "
                                   f"{self.a} and {self.b}:\n{self.log()}")
            if time.monotonic() > deadline:
                self.kill()
                raise RuntimeError(f"socat did not create {self.a} and {self.b} within {START_S} s:\n{self.log()}")
            time.sleep(0.002)
        self.socat_pid = self.proc.pid
        if self.timeout:
            kids = _children(self.proc.pid)
            if kids:
                self.socat_pid = kids[0]
                self.started.append(kids[0])

    def kill(self) -> None:
        """End socat (the ptys vanish, socat removes the links); idempotent."""
        proc = self.proc
        if proc is None:
            return
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)  # `timeout` forwards it to socat
            try:
                proc.wait(STOP_S)
            except subprocess.TimeoutExpired:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait(STOP_S)
        self._reap()
        if self.socat_pid is not None and _alive(self.socat_pid):
            # socat outlived `timeout` (should not happen): end it directly.
            try:
                os.kill(self.socat_pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            deadline = time.monotonic() + STOP_S
            while _alive(self.socat_pid) and time.monotonic() < deadline:
                time.sleep(0.005)
        for link in (self.a, self.b):  # socat removes them on SIGTERM; not on SIGKILL
            if os.path.islink(link):
                os.unlink(link)
        self.proc = None

    def _reap(self) -> None:
        if self.proc is not None and self.proc.returncode is None:
            try:
                self.proc.wait(STOP_S)
            except subprocess.TimeoutExpired:
                pass

    def restart(self) -> None:
        """A new socat with the same link paths (the old one ended first if running)."""
        self.kill()
        self.start()

    def close(self) -> None:
        self.kill()
        if self._own_dir:
            shutil.rmtree(self.directory, ignore_errors=True)

    def log(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except OSError:
            return ""

    def leftovers(self) -> list[int]:
        """Processes this pair started that are still alive (should be none after close())."""
        return [pid for pid in self.started if _alive(pid)]
