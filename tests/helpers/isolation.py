"""What keeps the suite to itself (docs/testing.md, "Isolation"): nothing a
test run does may land inside the repository, so the suite can run from a
checkout beside a user's running PLC and on several workers at once.

* softplc's cache (``SOFTPLC_CACHE_DIR``, docs/cli.md "Cache") is kept
  beside the run's bytecode cache, outside the repository and the user's
  home.
* Hypothesis keeps its caches beside the bytecode cache (its default is
  ``.hypothesis/`` in the working directory), handed to xdist workers and
  to pytest runs the tests start through ``HYPOTHESIS_STORAGE_DIRECTORY``,
  with no example database. Its per-example deadline is
  off suite-wide (profile "softplc"): on cores shared with another worker
  it would time the machine's load, not the code.
* The session hooks list the repository tree before and after the run and
  fail the run, naming each path, when anything appeared in it. They act in
  the process that runs the session: the xdist controller, whose session
  starts before any worker and finishes after the last one, so the check
  sees every test of every worker once. Bytecode caches (``__pycache__``)
  are the interpreter's, not a test's, and are not counted; nor is a new
  source file (.py, .md) in a directory that was there: that is a
  developer's edit made while the suite ran, and no test writes either;
  nor a new file in an app's state directory (``.softplc/``) that was
  there: a PLC running from the checkout saves its snapshot there every
  100 ms (the suite runs beside it), and a test that writes an app's state
  in place makes that directory in a fresh checkout.

conftest.py imports the hooks, which pytest finds there by name.
"""

from __future__ import annotations

import atexit
import compileall
import hashlib
import os
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir

ROOT = Path(__file__).resolve().parents[2]
SKIPPED = {".git", "__pycache__"}
SOURCES = (".py", ".md")
STATE_DIR = ".softplc"


def hypothesis_setup() -> None:
    """After bytecode_setup: hypothesis's directory is kept beside the
    bytecode cache, so the constants it reads out of every test module's
    source at collection (1.5 s a process) are read once per change, not
    in every worker of every run. Its example database is off: a test runs
    once a run, so a failing example saved for a replay would only be
    replayed by a later run, which should find its own."""
    home = os.environ.get("HYPOTHESIS_STORAGE_DIRECTORY")
    if not home:
        home = os.path.join(os.environ["PYTHONPYCACHEPREFIX"], "hypothesis")
        os.environ["HYPOTHESIS_STORAGE_DIRECTORY"] = home
    set_hypothesis_home_dir(home)
    settings.register_profile("softplc", deadline=None, database=None)
    settings.load_profile("softplc")  # --hypothesis-profile, applied later, still wins


def bytecode_setup() -> None:
    """Compiled modules are cached outside the repository, in one directory
    of this user's for this checkout, handed to workers and to every
    ``softplc`` the tests start through ``PYTHONPYCACHEPREFIX``: the suite
    starts the real command hundreds of times, and an environment that says
    PYTHONDONTWRITEBYTECODE would make each start compile the whole package
    again (about 0.2 s each) and every run rewrite each test module's
    asserts again. Python checks a cached module against its source, so a
    stale cache costs a compile, never a wrong result; a directory another
    user owns is never used (its bytecode would run as ours)."""
    prefix = os.environ.get("PYTHONPYCACHEPREFIX")
    chosen_here = not prefix  # else a worker of this run, or a run this suite started
    if chosen_here:
        key = hashlib.sha256(f"{ROOT}|{sys.version}".encode()).hexdigest()[:12]
        prefix = os.path.join(tempfile.gettempdir(), f"softplc-pycache-{os.getuid()}-{key}")
        try:
            os.makedirs(prefix, mode=0o700, exist_ok=True)
            mine = os.stat(prefix).st_uid == os.getuid() and not os.path.islink(prefix)
        except OSError:
            mine = False
        if not mine:
            prefix = tempfile.mkdtemp(prefix="softplc-pycache-")
            atexit.register(shutil.rmtree, prefix, ignore_errors=True)
        os.environ["PYTHONPYCACHEPREFIX"] = prefix
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    sys.pycache_prefix = prefix
    sys.dont_write_bytecode = False
    if chosen_here:
        _seed(prefix)
    # softplc's own cache (the parser's tables, usercache.py) beside it, never the user's ~/.cache
    os.environ.setdefault("SOFTPLC_CACHE_DIR", os.path.join(prefix, "softplc-cache"))


def _seed(prefix: str) -> None:
    """A new cache starts with the byte code the standard library and the
    test tools were installed with (their ``__pycache__``), which a cache
    prefix makes Python ignore, and with softplc's own modules compiled:
    without it each worker of a first run, and each command the first tests
    start, compiled all of them again (9 s of a worker's start). Once per
    cache (the file SEEDED); a file that cannot be copied is left for Python
    to compile. Called with ``sys.pycache_prefix`` set to ``prefix``."""
    marker = os.path.join(prefix, "SEEDED")
    if os.path.exists(marker):
        return
    tag = sys.implementation.cache_tag
    for pyc in _installed_byte_code(tag):
        # DIR/__pycache__/NAME.TAG.pyc is PREFIX/DIR/NAME.TAG.pyc in the prefix's tree
        target = os.path.join(prefix, str(pyc.parent.parent).lstrip(os.sep), pyc.name)
        try:
            os.makedirs(os.path.dirname(target), exist_ok=True)
            if not os.path.exists(target):
                shutil.copyfile(pyc, target)
        except OSError:
            continue
    # softplc's own modules too, once, before the workers and the first commands all compile them at once
    compileall.compile_dir(str(ROOT / "softplc_lite"), quiet=1, workers=0)  # 0: one process a core
    Path(marker).write_text("")


def _installed_byte_code(tag: str) -> list[Path]:
    """The byte code files of the standard library and of the distributions
    the test extra brings (softplc_lite[test] and what they require)."""
    from importlib.metadata import PackageNotFoundError, distribution
    from packaging.requirements import Requirement

    found: list[Path] = []
    stdlib = sysconfig.get_paths()["stdlib"]
    for root, dirs, files in os.walk(stdlib):
        dirs[:] = [d for d in dirs if d != "site-packages"]
        if os.path.basename(root) == "__pycache__":
            found += [Path(root, f) for f in files if f.endswith(f".{tag}.pyc")]
    seen: set[str] = set()
    todo = [("softplc_lite", "test")]
    while todo:
        name, extra = todo.pop()
        try:
            dist = distribution(name)
        except PackageNotFoundError:
            continue
        if dist.metadata["Name"].lower() in seen:
            continue
        seen.add(dist.metadata["Name"].lower())
        found += [Path(f.locate()) for f in dist.files or () if f.name.endswith(f".{tag}.pyc")]
        for text in dist.requires or ():
            req = Requirement(text)
            if req.marker is None or req.marker.evaluate({"extra": extra}):
                todo.append((req.name, ""))
    return found


def signals_setup() -> None:
    """Ctrl-C as a terminal gives it. A run started in the background of a
    non-interactive shell, or under nohup, begins with SIGINT ignored, and
    every process it starts would inherit that: the signal tests would wait
    for softplc processes that cannot hear their Ctrl-C. A Python handler,
    unlike an ignored signal, is not inherited across exec."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def repo_listing(root: Path = ROOT) -> set[str]:
    """Every file and directory under ``root`` (relative, '/' after a
    directory), without .git and bytecode caches."""
    found: set[str] = set()
    for top, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in SKIPPED]
        rel = Path(top).relative_to(root)
        found.update(f"{(rel / d).as_posix()}/" for d in dirs)
        found.update((rel / f).as_posix() for f in files)
    return found


# The ports a PLC on the same machine would hold: programs/hmi_server's
# 127.0.0.1:5020, and 44818 (EtherNet/IP). The whole run happens while
# another process listens on them, so a test that binds one of them (or
# runs a shipped app on its own port) fails here, not on a user's machine.
HELD_PORTS = (5020, 44818)
HOLDER_ENV = "SOFTPLC_TEST_PORT_HOLDER"
HOLDER = """
import socket, sys
held = []
for port in map(int, sys.argv[1:]):
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", port))
        s.listen()
        held.append(s)
    except OSError:  # already taken (a PLC running on this machine): held either way
        s.close()
print("holding", flush=True)
sys.stdin.read()  # until the run closes it, or ends
"""


def hold_ports() -> subprocess.Popen:
    """A process that listens on HELD_PORTS (where free) until its standard
    input closes; its pid in HOLDER_ENV for the workers and the check."""
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, *map(str, HELD_PORTS)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    if holder.stdout.readline() != "holding\n":
        raise RuntimeError("the process holding ports 5020 and 44818 for the run did not start")
    os.environ[HOLDER_ENV] = str(holder.pid)
    return holder


def _controller(session: pytest.Session) -> bool:
    return not hasattr(session.config, "workerinput")


_BEFORE = pytest.StashKey[set]()
_APPEARED = pytest.StashKey[list]()


_HOLDER = pytest.StashKey[subprocess.Popen]()


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session: pytest.Session) -> None:
    if _controller(session):
        session.config.stash[_BEFORE] = repo_listing()
        session.config.stash[_HOLDER] = hold_ports()  # before any worker starts


@pytest.hookimpl(trylast=True)
def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    holder = session.config.stash.get(_HOLDER, None)
    if holder is not None:
        holder.stdin.close()
        holder.wait(30)
    before = session.config.stash.get(_BEFORE, None)
    if before is None:
        return
    def elsewhere(path: str) -> bool:
        """A developer's new source file, or a running PLC's save."""
        parent = path.rpartition("/")[0]
        known = not parent or f"{parent}/" in before
        return known and (path.endswith(SOURCES) or f"/{STATE_DIR}/" in f"/{path}")

    appeared = sorted(p for p in repo_listing() - before if not elsewhere(p))
    if appeared:
        session.config.stash[_APPEARED] = appeared
        if session.exitstatus == pytest.ExitCode.OK:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    appeared = config.stash.get(_APPEARED, [])
    if appeared:
        shown = appeared[:20] + ([f"... and {len(appeared) - 20} more"] if len(appeared) > 20 else [])
        terminalreporter.section("written inside the repository", sep="=", red=True, bold=True)
        terminalreporter.write_line("The run wrote inside the repository tree; a test must write only in its "
                                    "tmp_path (docs/testing.md, \"Isolation\"). New paths:")
        for path in shown:
            terminalreporter.write_line(f"  {path}")
