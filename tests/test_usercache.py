"""softplc's cache directory (docs/cli.md, "Cache"): where it is, when it is
trusted, and that the parser's tables kept there change how fast softplc
starts, never what it does."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from softplc_lite.usercache import cache_dir

ROOT = Path(__file__).resolve().parent.parent
BLINKER = ROOT / "programs" / "blinker"


@pytest.fixture
def no_cache_env(monkeypatch):
    for name in ("SOFTPLC_CACHE_DIR", "XDG_CACHE_HOME"):
        monkeypatch.delenv(name, raising=False)
    return monkeypatch


def test_the_directory_is_the_setting_else_xdg_else_home(no_cache_env, tmp_path):
    no_cache_env.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / ".cache" / "softplc_lite"
    no_cache_env.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "softplc_lite"
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", str(tmp_path / "mine"))
    assert cache_dir() == tmp_path / "mine"
    assert (tmp_path / "mine").stat().st_mode & 0o777 == 0o700  # created for this user only


def test_an_empty_setting_or_a_relative_xdg_path_means_no_cache(no_cache_env, tmp_path):
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", "")
    assert cache_dir() is None
    no_cache_env.delenv("SOFTPLC_CACHE_DIR")
    no_cache_env.setenv("XDG_CACHE_HOME", "relative/cache")
    assert cache_dir() is None


def test_a_directory_others_may_write_or_a_link_is_not_trusted(no_cache_env, tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir(mode=0o777)
    shared.chmod(0o777)
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", str(shared))
    assert cache_dir() is None
    mine = tmp_path / "mine"
    mine.mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(mine)
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", str(tmp_path / "link"))
    assert cache_dir() is None
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", str(mine))
    assert cache_dir() == mine


def test_a_directory_that_cannot_be_made_means_no_cache(no_cache_env, tmp_path):
    (tmp_path / "file").write_text("")
    no_cache_env.setenv("SOFTPLC_CACHE_DIR", str(tmp_path / "file" / "cache"))
    assert cache_dir() is None


def check(cache: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, SOFTPLC_CACHE_DIR=cache)
    return subprocess.run([sys.executable, "-m", "softplc_lite", "check", str(BLINKER)], capture_output=True,
                          text=True, env=env, cwd=cwd, timeout=60)


def test_the_parser_tables_are_kept_reused_and_a_damaged_file_is_rebuilt(tmp_path):
    cache = tmp_path / "cache"
    first = check(str(cache), tmp_path)
    assert first.returncode == 0 and first.stderr == "", first.stderr
    kept = list(cache.iterdir())
    assert [p.name for p in kept] == [f"ladder-parser-{sys.version_info[0]}.{sys.version_info[1]}.lark"]
    whole = kept[0].read_bytes()
    again = check(str(cache), tmp_path)
    assert (again.returncode, again.stdout, again.stderr) == (0, first.stdout, "")
    assert kept[0].read_bytes() == whole  # loaded, not rewritten
    kept[0].write_bytes(whole[: len(whole) // 2])  # cut short, as a full disk leaves it
    damaged = check(str(cache), tmp_path)
    assert (damaged.returncode, damaged.stdout, damaged.stderr) == (0, first.stdout, "")
    rebuilt = kept[0].read_bytes()
    assert rebuilt.split(b"\n", 1)[0] == whole.split(b"\n", 1)[0] and len(rebuilt) > len(whole) // 2  # rewritten
    check(str(cache), tmp_path)
    assert kept[0].read_bytes() == rebuilt  # and loaded from then on
    none = check("", tmp_path)
    assert (none.returncode, none.stdout, none.stderr) == (0, first.stdout, "")
