"""A fresh install runs what the README says, as a new user meets it: a
virtual environment made with ``python -m venv`` and ``pip install -e`` of
this repository only (no test extras), then the README's first command and
every line of its "Try it" block, in order, from a copy of programs/.

Slow by nature: building the environment is a pip install (about 5 s here
with pip's cache warm; pip's cache is reused, never bypassed). It is built
once per test run, however many xdist workers run the tests: in the run's
shared base directory, under a file lock, by whichever worker comes first.
"""

from __future__ import annotations

import fcntl
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.cli_tmux import open_terminal
from helpers.readme import try_it_lines
from helpers.shipped_apps import copy_programs

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
INSTALL = "pip install -e ."  # the install of the README's first command, as the fixture runs it

# One worker runs this file's tests, so the one that does not build the
# environment does not sit idle on the lock while another worker builds it.
pytestmark = pytest.mark.xdist_group("fresh_install")


def first_command() -> tuple[str, list[str]]:
    """The README's first command, split at ``&&``: its install part and the softplc command after it."""
    block = re.search(r"```bash\n(.*?)```", README.read_text(encoding="utf-8"), re.DOTALL).group(1)
    install, _, command = block.splitlines()[0].partition(" && ")
    return install.strip(), shlex.split(command, comments=True)


@pytest.fixture(scope="session")
def fresh_venv(tmp_path_factory) -> Path:
    """A virtual environment with this repository installed the README's way."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):  # one environment for every worker of this run
        base = base.parent
    venv = base / "fresh-venv"
    with open(base / "fresh-venv.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # the first worker builds; the others wait here, then reuse it
        if not (venv / "built").exists():
            shutil.rmtree(venv, ignore_errors=True)  # what a failed attempt left
            made = subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], capture_output=True,
                                  text=True, timeout=120)
            if made.returncode != 0:
                pytest.skip(f"cannot create a virtual environment here: {made.stderr.strip()[-300:]}")
            # This interpreter's pip installs into the new environment (--python): the same pip a
            # user's venv gets, without ensurepip's copy (several seconds on this machine).
            # --no-compile: pip's byte-compiling of what it installs is never used here (the commands
            # below keep byte code in the run's PYTHONPYCACHEPREFIX); it changes nothing installed.
            installed = subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"),
                                        "install", "--no-compile", "-e", str(ROOT)],
                                       capture_output=True, text=True, timeout=600, env=_clean_env())
            assert installed.returncode == 0, installed.stdout[-2000:] + installed.stderr[-2000:]
            (venv / "built").write_text("")
    return venv


def _clean_env() -> dict[str, str]:
    """The environment a user's shell would give: nothing of this test run's Python path."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    # Byte code goes to the run's PYTHONPYCACHEPREFIX (tests/helpers/isolation.py), never into the repository,
    # and is reused by every command after the first.
    return env


@pytest.fixture
def programs(tmp_path) -> Path:
    """A copy of programs/ (the lines run in it; they write their state there)."""
    # programs/hmi_server serves 127.0.0.1:5020 as written; the copy serves a free port instead,
    # so the test passes beside a user's running PLC (or another test run) holding 5020.
    assert "hmi_server" in copy_programs(tmp_path)
    return tmp_path


@pytest.fixture(name="terminal")
def fixture_terminal(request):
    yield from open_terminal(request)


def run_softplc(venv: Path, argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    assert argv[0] == "softplc", argv
    return subprocess.run([str(venv / "bin" / "softplc"), *argv[1:]], cwd=cwd, capture_output=True, text=True,
                          timeout=120, env=_clean_env())


def test_the_readme_installs_with_pip_install_e_dot():
    install, command = first_command()
    assert install == INSTALL and command[:2] == ["softplc", "run"]


def test_the_readme_first_command_works_in_a_fresh_install(fresh_venv, programs):
    _, command = first_command()
    p = run_softplc(fresh_venv, command, programs)
    assert p.returncode == 0, (command, p.stderr)
    assert "Traceback" not in p.stderr + p.stdout
    assert "polls (C5:0.ACC) =" in p.stdout  # its counters, as the README says


def test_every_try_it_line_works_in_order_in_a_fresh_install(fresh_venv, programs, terminal):
    lines = try_it_lines()
    assert any("programs/hmi_server" in line for line in lines)  # MODBTCPS: pymodbus comes with the install
    for k, line in enumerate(lines):
        argv = shlex.split(line, comments=True)
        if argv[1] == "watch":  # in a real terminal, quit once its view is up, as tests/test_cli_readme.py does
            terminal.session = f"w{k}"
            softplc = shlex.quote(str(fresh_venv / "bin" / "softplc"))
            terminal.start(f"env -u PYTHONPATH {softplc} {shlex.join(argv[1:])}", cwd=programs)
            terminal.wait_for(r"PAUSED")
            terminal.keys("q")
            assert terminal.exit_status() == 0, (line, terminal.screen())
            continue
        p = run_softplc(fresh_venv, argv, programs)
        assert p.returncode == 0, (line, p.stderr)
        assert "Traceback" not in p.stderr + p.stdout, line
