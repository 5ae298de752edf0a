"""Running the ``softplc`` command from a test, the two ways a test needs.

- ``softplc(...)``: the real command, ``python -m softplc_lite`` in a process
  of its own. For what only a process shows: exit by signal, Ctrl-C and
  SIGTERM, the console script, a fresh interpreter's imports and caches,
  resource limits, bytes that are not UTF-8 on the command line.
- ``softplc_here(...)``: ``cli.main(argv)`` in the test's own process, its
  output captured. For what a command says and returns (messages, exit
  codes, files written): the same code path as the command after its
  arguments are read, without the ~0.2 s of CPU a new interpreter costs.

Both return a ``subprocess.CompletedProcess[str]`` (``returncode``,
``stdout``, ``stderr``), so a test changes from one to the other by name."""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def softplc(*args: str, cwd: Path | str = ROOT, timeout: float = 60, env: Mapping[str, str] | None = None,
            **kw) -> subprocess.CompletedProcess[str]:
    """``softplc ARGS`` as a process (``python -m softplc_lite``) in ``cwd``;
    ``kw`` goes to ``subprocess.run`` (``stdin``, ``input``, ``preexec_fn``...)."""
    kw.setdefault("text", True)
    return subprocess.run([sys.executable, "-m", "softplc_lite", *args], cwd=cwd, capture_output=True,
                          timeout=timeout, check=False, env=None if env is None else dict(env), **kw)


def softplc_here(*args: str, cwd: Path | str = ROOT, env: Mapping[str, str | None] | None = None,
                 stdin: str = "") -> subprocess.CompletedProcess[str]:
    """``softplc ARGS`` run by ``cli.main`` in this process, in ``cwd``, with
    ``env`` set (a None value unsets a variable) and ``stdin`` as its
    standard input; stdout and stderr captured. An exception escaping
    main() (a bug: the command prints one line for those) fails the test
    with its traceback."""
    from softplc_lite.cli import main

    out, err = io.StringIO(), io.StringIO()
    with _working_directory(cwd), _environment(env or {}), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err), _standard_input(stdin):
        try:
            code = main(list(args))
        except SystemExit as e:  # argparse: usage errors, --help, --version
            code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    return subprocess.CompletedProcess(["softplc", *args], code, out.getvalue(), err.getvalue())


@contextlib.contextmanager
def _working_directory(path: Path | str) -> Iterator[None]:
    before = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(before)


@contextlib.contextmanager
def _environment(changes: Mapping[str, str | None]) -> Iterator[None]:
    before = {name: os.environ.get(name) for name in changes}
    try:
        for name, value in changes.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextlib.contextmanager
def _standard_input(text: str) -> Iterator[None]:
    before = sys.stdin
    sys.stdin = io.TextIOWrapper(io.BytesIO(text.encode("utf-8")), encoding="utf-8")  # with .buffer, as a real one
    try:
        yield
    finally:
        sys.stdin = before
