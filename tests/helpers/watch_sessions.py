"""Watch sessions over one-file apps made in a test's directory: the
``session`` fixtures of the watch session tests."""

from __future__ import annotations

import itertools
import os
import time
from pathlib import Path

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.session import WatchOptions, WatchSession


def sessions(tmp_path: Path, program: str, files: dict[str, str] | None = None):
    """A generator for a fixture: yields ``make(text=program, **watch_options)``,
    which writes an app (main.lad and ``files``) and opens a fresh session
    on it; every session made is quit at the end."""
    made: list[WatchSession] = []
    tried = itertools.count()  # a session refused by its options made its directory too

    def make(text: str = program, **kw) -> WatchSession:
        k = next(tried)
        d = tmp_path / f"app{k}"
        d.mkdir()
        (d / "main.lad").write_text(text)
        for name, content in (files or {}).items():
            (d / name).write_text(content)
        app = load_app(d, state_dir=tmp_path / f"state{k}")
        s = WatchSession(app, WatchOptions(run=RunOptions(fresh=True), **kw))
        made.append(s)
        return s
    yield make
    for s in made:
        s.quit()


def scan_to_break(session: WatchSession, limit: int):
    """Scan ``session`` until a breakpoint stops it (what ``scan`` returns
    then), or ``limit`` scans: None."""
    for _ in range(limit):
        hit = session.scan()
        if hit is not None:
            return hit
    return None


def save_edit(session: WatchSession, path: Path, text: str, wait_s: float = 10.0) -> None:
    """Write ``text`` over ``path`` as an editor saves it (a later mtime) and
    poll ``session`` until its online edit is made (``session.last_edit``)."""
    before = path.stat().st_mtime_ns
    path.write_text(text, encoding="utf-8")
    os.utime(path, ns=(before, before + 10_000_000))
    deadline = time.monotonic() + wait_s
    while session.last_edit is None and time.monotonic() < deadline:
        session.poll_online()
        time.sleep(0.05)
