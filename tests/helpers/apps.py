"""An app directory written by a test: the one factory the test files use
(``make_app``); a shipped app copied is helpers.shipped_apps.copy_app."""

from __future__ import annotations

from pathlib import Path


def make_app(directory: Path, ladder: str | bytes, **files: str | bytes) -> Path:
    """DIRECTORY (made if missing) as an app: ``main.lad`` holding LADDER and
    one file per keyword. A keyword names its file with ``_`` for the dot
    (``softplc_toml`` is softplc.toml, ``MODULES_LST`` is MODULES.LST); a
    name that holds a dot is the file's name as it is (``**{"notes.txt":
    ""}``). Text is written as UTF-8, bytes as they are (a file in another
    encoding, or one that is not text)."""
    directory.mkdir(parents=True, exist_ok=True)
    for name, content in {"main.lad": ladder, **files}.items():
        if "." not in name:
            stem, _, suffix = name.rpartition("_")
            name = f"{stem}.{suffix}" if stem else name
        data = content if isinstance(content, bytes) else content.encode("utf-8")
        (directory / name).write_bytes(data)
    return directory
