"""An export file's bytes, read as every file softplc reads is
(softplc_lite/textfile.py: only a regular file, no more than its kind's
limit; docs/cli.md, "Input file limits"), a refusal as the one problem of
the export."""

from __future__ import annotations

import os

from ..errors import FileAccessError
from ..ladder.ast import Pos
from ..textfile import MiB, Limit, read_bytes
from .model import ExportError, Problem

# A softplc choice: the largest public exports gathered are 3.5 MB (27,000 rungs); reading one
# takes about 18 times its size in memory while the parts are built.
EXPORT = Limit("a Studio 5000 export (L5X, L5K)", 64 * MiB)


def read_export(path, source_name: str | None) -> tuple[bytes, str]:
    """The file's bytes and the source name its positions carry."""
    name = os.fspath(path)
    name = os.fsdecode(name) if isinstance(name, bytes) else name
    source = source_name or name
    try:
        return read_bytes(name, EXPORT), source
    except FileAccessError as e:
        raise ExportError([Problem(Pos(source, 0, 0), str(e))]) from None
