"""The examples in docs/ and the README are run: ``>>>`` lines as doctests,
``$ softplc ...`` lines in ```console blocks as real commands whose output
must match what the page shows."""

from __future__ import annotations

import doctest
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = sorted((ROOT / "docs").glob("*.md"))
PAGES = DOCS + [ROOT / "README.md"]


def _console_examples(page: Path):
    text = page.read_text(encoding="utf-8")
    for block in re.findall(r"```console\n(.*?)```", text, re.S):
        command, expected = None, []
        for line in block.splitlines():
            if line.startswith("$ "):
                if command:
                    yield command, expected
                command, expected = line[2:], []
            else:
                expected.append(line)
        if command:
            yield command, expected


CONSOLE = [
    pytest.param(cmd, out, id=f"{page.name}:{cmd[:50]}")
    for page in PAGES
    for cmd, out in _console_examples(page)
]


@pytest.mark.parametrize("page", [p for p in DOCS if ">>>" in p.read_text()], ids=lambda p: p.name)
def test_doctests_in_docs(page: Path):
    result = doctest.testfile(
        str(page), module_relative=False, optionflags=doctest.ELLIPSIS, verbose=False
    )
    assert result.attempted > 0
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {page.name}"


@pytest.mark.parametrize("command,expected", CONSOLE)
def test_console_examples(command: str, expected: list[str]):
    argv = shlex.split(command)
    assert argv[0] == "softplc", "console examples run the softplc command"
    proc = subprocess.run(
        [sys.executable, "-m", "softplc_lite", *argv[1:]],
        cwd=ROOT, capture_output=True, text=True, timeout=60,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == expected


def test_every_doc_page_has_a_tested_example():
    for page in DOCS:
        text = page.read_text()
        if page.name == "performance.md":
            continue  # figures, not examples
        assert ">>>" in text or "```console" in text, f"{page.name} has no tested example"


def test_example_json_in_the_doc_matches_the_file():
    doc = (ROOT / "docs" / "datatable.md").read_text()
    shown = re.search(r"`docs/examples/datatable.json`:\n\n```json\n(.*?)```", doc, re.S).group(1)
    assert shown == (ROOT / "docs" / "examples" / "datatable.json").read_text()
