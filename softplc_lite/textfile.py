"""Reading the text files a user hands softplc: program, config, data.

Every reader goes through :func:`read_text`, so every file kind gives the
same answer to bytes that are not UTF-8: a :class:`LocatedError` naming the
file, the line and column of the first bad byte, and what was expected,
never a ``UnicodeDecodeError``. A UTF-8 byte-order mark (what Windows
editors write) is accepted and dropped.
"""

from __future__ import annotations

import os

from .errors import LocatedError


def decode_text(raw: bytes, path: str) -> str:
    """``raw`` as UTF-8 text (a leading BOM dropped); LocatedError at the
    first byte that is not UTF-8."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        start = e.start + (3 if raw.startswith(b"\xef\xbb\xbf") else 0)
        before = raw[:start]
        line = before.count(b"\n") + 1
        column = len(before) - (before.rfind(b"\n") + 1) + 1
        raise LocatedError(f"byte 0x{raw[start]:02x} is not UTF-8 text (the file must be saved as UTF-8)",
                           path, line, column) from None


def read_text(path: str | os.PathLike[str]) -> str:
    """The file's text; OSError as the OS reports it, LocatedError for bad encoding."""
    with open(path, "rb") as f:
        raw = f.read()
    return decode_text(raw, str(path))
