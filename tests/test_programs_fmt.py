"""Every shipped app is as ``softplc fmt`` prints it: ``softplc fmt --check``
passes on each (a CI gate a user's own apps can copy), so the examples
teach the canonical form. fmt --check writes nothing; it runs on each app
as shipped, and once through the whole command (its arguments, its exit
status) on copies, both in this process."""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import pytest

from softplc_lite.commands.fmt import fmt_command

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
APPS = sorted(p.name for p in (ROOT / "programs").iterdir() if p.is_dir() and any(p.glob("*.lad")))


@pytest.mark.parametrize("name", APPS)
def test_each_shipped_app_passes_fmt_check(name):
    err = io.StringIO()
    code = fmt_command([str(ROOT / "programs" / name)], check=True, stdout=io.StringIO(), stderr=err)
    assert (code, err.getvalue()) == (0, ""), f"programs/{name}: run softplc fmt --write programs/{name}"


def test_the_command_agrees_on_copies(tmp_path):
    for name in APPS:
        shutil.copytree(ROOT / "programs" / name, tmp_path / name, ignore=shutil.ignore_patterns(".softplc"))
    p = softplc_here("fmt", "--check", *APPS, cwd=tmp_path)
    assert (p.returncode, p.stdout, p.stderr) == (0, "", "")
    assert len(APPS) >= 10
