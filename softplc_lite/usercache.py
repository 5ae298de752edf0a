"""The user's cache directory: what softplc can rebuild at any time but
would rather not rebuild on every start (the ladder parser's tables).

The directory is ``$SOFTPLC_CACHE_DIR`` when that is set (empty: no cache),
else ``$XDG_CACHE_HOME/softplc_lite``, else ``~/.cache/softplc_lite``, the
place the XDG base directory specification gives per-user caches. What is
kept there is loaded with pickle, so the directory is used only when it is
this user's own, not a link, and writable by no one else, as Python's own
bytecode cache relies on; otherwise, and on any error reading or writing
it, softplc builds what it needs and goes on (docs/cli.md, "Cache").
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

ENV = "SOFTPLC_CACHE_DIR"


def cache_dir() -> Path | None:
    """The cache directory, created if need be; None when there is none to trust."""
    chosen = os.environ.get(ENV)
    if chosen is not None:
        if not chosen:
            return None
        path = Path(chosen)
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        if not os.path.isabs(base):  # the specification says to ignore a relative path
            return None
        path = Path(base) / "softplc_lite"
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = os.lstat(path)
    except (OSError, RuntimeError):  # RuntimeError: no home directory to expand
        return None
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
        return None
    return path


def cached_file(name: str) -> Path | None:
    """The path of ``name`` in the cache directory, or None without one."""
    directory = cache_dir()
    return None if directory is None else directory / name
