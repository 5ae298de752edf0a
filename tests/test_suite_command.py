"""The README's test command is the one CI runs, and it runs every test
exactly once: the tests marked ``alone`` by themselves, the rest on every
core (docs/testing.md)."""

from __future__ import annotations

import shlex
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def readme_test_command() -> str:
    block = (ROOT / "README.md").read_text(encoding="utf-8").split("```bash\n", 1)[1].split("```", 1)[0]
    (line,) = [line for line in block.splitlines() if "pytest" in line]
    return line


def test_ci_runs_the_readme_test_command_verbatim():
    lines = [line for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines() if line.strip()]
    assert lines[-1] == readme_test_command()


def test_the_command_runs_the_alone_tests_apart_and_everything_else_in_parallel():
    steps = [shlex.split(step) for step in readme_test_command().split("&&")]
    assert steps[0][:3] == ["pip", "install", "-e"]
    runs = {}
    for argv in steps[1:]:
        assert argv[:3] == ["python", "-m", "pytest"], argv
        runs[argv[argv.index("-m", 3) + 1]] = argv
    assert set(runs) == {"not alone", "alone"}  # together: every test, each once
    assert "-n" in runs["not alone"] and "-n" not in runs["alone"]
    docs = (ROOT / "docs" / "testing.md").read_text(encoding="utf-8")
    assert readme_test_command() in docs
