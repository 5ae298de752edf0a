"""The examples in docs/ and the README are run: ``>>>`` lines as doctests,
``$ softplc ...`` lines in ```console blocks as real commands whose output
must match what the page shows, and exit 0 unless the output ends with an
``[exit N]`` line (the status it must exit with).

They run in a copy of programs/ and docs/examples/ in the test's temporary
directory (so the apps' state is written there, not in the repository),
where programs/hmi_server serves on a free port that stands for the page's
5020, and a page's /tmp/ paths stand for the temporary directory."""

from __future__ import annotations

import doctest
import re
import shlex
import shutil
from pathlib import Path

import pytest

from helpers.cli import softplc_here
from helpers.shipped_apps import SHIPPED_PORT, copy_programs

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


@pytest.fixture
def here(tmp_path, monkeypatch):
    """The working directory the examples run in; ``here(text)`` is a page's
    text as it reads there (its server port and /tmp/ paths replaced)."""
    ports = copy_programs(tmp_path)
    shutil.copytree(ROOT / "docs" / "examples", tmp_path / "docs" / "examples")
    monkeypatch.chdir(tmp_path)

    def as_here(text: str) -> str:
        return re.sub(rf"\b{SHIPPED_PORT}\b", str(ports["hmi_server"]), text).replace("/tmp/", f"{tmp_path}/")
    return as_here


@pytest.mark.parametrize("page", [p for p in DOCS if ">>>" in p.read_text()], ids=lambda p: p.name)
def test_doctests_in_docs(page: Path, here):
    test = doctest.DocTestParser().get_doctest(here(page.read_text(encoding="utf-8")), {"__name__": "__main__"},
                                               page.name, str(page), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS, verbose=False)
    runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.attempted > 0
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {page.name}"


@pytest.mark.parametrize("command,expected", CONSOLE)
def test_console_examples(command: str, expected: list[str], here, tmp_path):
    argv = shlex.split(here(command))
    assert argv[0] == "softplc", "console examples run the softplc command"
    status = re.fullmatch(r"\[exit (\d+)\]", expected[-1]) if expected else None
    if status:
        expected = expected[:-1]
    # the width a console without a terminal has, whatever the environment says
    proc = softplc_here(*argv[1:], cwd=tmp_path, env={"COLUMNS": "80"})  # test_cli_readme runs the command itself
    assert proc.returncode == (int(status.group(1)) if status else 0), proc.stderr
    assert proc.stdout.splitlines() == [here(line) for line in expected]


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
