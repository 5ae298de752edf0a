"""The code cache is checked before it is trusted: a PLC never runs logic
other than its program. Every byte of a real cache flipped in turn (one bit
of it, every bit position met, then all eight), truncations, padding: each is refused before anything in it is
unmarshalled, the program is compiled from its text, runs exactly as it
does without a cache, and the cache is rewritten (docs/engine.md, "The code
cache")."""

from __future__ import annotations

import marshal
import os
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from softplc_lite.app import load_app
from softplc_lite.ladder import codecache
from softplc_lite.ladder.codecache import CodeCache
from softplc_lite.runner import RunOptions, Runner

from helpers.cli import softplc_here

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"
SCANS = 200  # the blinker: two blinks on simulated time
SHOWN = ("O:0/0", "C5:0.ACC", "T4:0.ACC", "T4:1.ACC", "B3/0")
# Header bytes whose change is not damage but another cache: the format and the key (a different
# program or softplc_lite); the cache is ignored as stale, without a warning.
QUIET = set(range(8, 10)) | set(range(20, 52))


@pytest.fixture
def blinker(tmp_path, monkeypatch):
    """A copy of programs/blinker run once (which writes its code cache):
    (app directory, cache key, the cache's bytes, what the run shows)."""
    app = tmp_path / "blinker"
    shutil.copytree(PROGRAMS / "blinker", app, ignore=shutil.ignore_patterns(".softplc"))
    monkeypatch.chdir(tmp_path)  # messages name the files from here, as the CLI's would
    values, loaded = run(app)
    assert loaded.code is None
    cache = app / ".softplc" / codecache.CACHE_FILE
    again, cached = run(app)
    assert cached.code is not None and again == values  # the cache is used, and runs the same
    return app, loaded.cache_key, cache.read_bytes(), values


def run(app: Path) -> tuple[dict, object]:
    """Load the app (through its cache when usable) and scan it SCANS times from its initial data."""
    loaded = load_app(app)
    runner = Runner(loaded, RunOptions(fresh=True, save_state=False), log=lambda message: None)
    runner.run(SCANS)
    runner.engine.close()
    return {a: runner.table.read(a) for a in SHOWN}, loaded


def flipped(blob: bytes, i: int) -> bytes:
    """``blob`` with one bit of byte ``i`` flipped (bit i mod 8: every bit position is met)."""
    out = bytearray(blob)
    out[i] ^= 1 << (i % 8)
    return bytes(out)


@pytest.fixture
def unmarshalled(monkeypatch):
    """Every payload the cache module unmarshals."""
    seen: list[bytes] = []

    def loads(data):
        seen.append(bytes(data))
        return marshal.loads(data)

    monkeypatch.setattr(codecache, "marshal", SimpleNamespace(loads=loads, dumps=marshal.dumps,
                                                              version=marshal.version))
    return seen


def test_every_flipped_byte_of_a_real_cache_is_refused_before_anything_is_unmarshalled(blinker, unmarshalled):
    app, key, good, _ = blinker
    path = app / ".softplc" / codecache.CACHE_FILE
    cache = CodeCache(path.parent)
    assert cache.load(key) is not None and len(unmarshalled) == 1  # the good one is used
    unmarshalled.clear()
    used, quiet, said = [], [], set()
    fd = os.open(path, os.O_RDWR)  # each byte changed in place and put back: quicker than a file a byte
    try:
        for i in range(len(good)):
            for bad in (flipped(good, i)[i], good[i] ^ 0xFF):  # one bit, then the whole byte
                os.pwrite(fd, bytes([bad]), i)
                if cache.load(key) is not None:
                    used.append(i)
                os.pwrite(fd, good[i:i + 1], i)
                if cache.problem is None:
                    quiet.append(i)
                else:
                    said.add(cache.problem)
    finally:
        os.close(fd)
    assert used == [], f"{len(used)} of {len(good)} damaged caches were used, the first at byte {used[0]}"
    assert unmarshalled == []
    assert said == {f"{path}: {why}; ignored, the program is compiled from its text and the cache rewritten"
                    for why in ("not a code cache this softplc_lite reads",
                                "damaged code cache (its digest does not match its contents)")}
    assert cache.load(key) is not None  # put back whole: used again
    assert set(quiet) == QUIET  # the format and the key: a stale cache, not a damaged one


def test_a_truncated_or_padded_cache_is_refused(blinker, unmarshalled):
    app, key, good, _ = blinker
    path = app / ".softplc" / codecache.CACHE_FILE
    cache = CodeCache(path.parent)
    # Every size within the header and the payload's start, then every 13th, and the last few.
    sizes = sorted(set(range(200)) | set(range(200, len(good), 13)) | set(range(len(good) - 5, len(good))))
    for size in sizes:
        path.write_bytes(good[:size])
        assert cache.load(key) is None and cache.problem is not None, size
    for extra in (b"\0", good[-1:], good):
        path.write_bytes(good + extra)
        assert cache.load(key) is None and "damaged code cache" in cache.problem
    assert unmarshalled == []


def test_a_damaged_cache_runs_the_real_program_as_without_a_cache_and_is_rewritten(blinker):
    """The whole path, in this process: the load, the warning, the scans, the rewrite."""
    app, key, good, values = blinker
    path = app / ".softplc" / codecache.CACHE_FILE
    payload = 84  # the header's size
    spots = [0, 7, 10, 13, 16, 52, 60, 83] + [payload + k * (len(good) - payload - 1) // 7 for k in range(8)]
    for i in spots:
        path.write_bytes(flipped(good, i))
        got, loaded = run(app)
        assert loaded.code is None, i  # compiled from the text
        assert got == values, i
        assert [w for w in loaded.warnings if "codecache.bin" in w] == [loaded.code_cache.problem], i
        assert path.read_bytes() == good, i  # rewritten whole, the same as the first run made


def test_the_cli_runs_the_real_program_from_a_damaged_cache_and_rewrites_it(tmp_path):
    shutil.copytree(PROGRAMS / "blinker", tmp_path / "blinker", ignore=shutil.ignore_patterns(".softplc"))

    args = ("run", "blinker", "--fresh", "--scans", "1000", "--print", "Lamp", "--print", "C5:0.ACC",
            "--print", "T4:1.ACC")
    first = softplc_here(*args, cwd=tmp_path)
    assert first.returncode == 0 and first.stdout == "Lamp (O:0/0) = 1\nC5:0.ACC = 10\nT4:1.ACC = 31\n", first
    path = tmp_path / "blinker" / ".softplc" / codecache.CACHE_FILE
    good = path.read_bytes()
    path.write_bytes(flipped(good, len(good) * 2 // 3))  # in the compiled code
    damaged = softplc_here(*args, cwd=tmp_path)
    assert damaged.returncode == 0, damaged.stderr
    assert damaged.stdout == first.stdout
    assert damaged.stderr == ("warning: blinker/.softplc/codecache.bin: damaged code cache (its digest does not "
                              "match its contents); ignored, the program is compiled from its text and the cache "
                              "rewritten\n")
    assert path.read_bytes() == good
