"""The console script's entry (softplc_lite/console.py): Ctrl-C ends the
process quietly from its first lines until main() takes the signals over,
including the line the console script runs between its import and main();
a program that imports the CLI (softplc_lite.cli) keeps Python's own
Ctrl-C."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

PROBE = """
import signal, sys
import {module}
handler = signal.getsignal(signal.SIGINT)
print("default" if handler is signal.default_int_handler else handler.__module__ + "." + handler.__name__)
"""


def handler_after_importing(module: str) -> str:
    p = subprocess.run([sys.executable, "-c", PROBE.format(module=module)], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout.strip()


def test_the_console_entry_leaves_ctrl_c_ending_the_process_until_main():
    assert handler_after_importing("softplc_lite.console") == "softplc_lite.interrupt._quit"


def test_a_program_importing_the_cli_keeps_pythons_ctrl_c():
    assert handler_after_importing("softplc_lite.cli") == "default"


def test_the_console_script_and_python_m_enter_through_it():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts == {"softplc": "softplc_lite.console:main"}
    assert "from .console import main" in (ROOT / "softplc_lite" / "__main__.py").read_text()
