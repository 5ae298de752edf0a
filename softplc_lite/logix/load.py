"""An export file (``.L5X`` or ``.L5K``) read and made into a ladder program:
every problem of the reading and of the making listed at once, each at its
place in the file."""

from __future__ import annotations

from pathlib import Path

from .model import ExportError, Problem, Project
from .project import LogixProgram, build_program

SUFFIXES = (".l5x", ".l5k")


def is_export(path: str | Path) -> bool:
    return Path(path).suffix.lower() in SUFFIXES


def read_export(path: str | Path, source_name: str | None = None) -> Project:
    """The export's Project; ExportError lists every problem of the file."""
    name = source_name or str(path)
    if Path(path).suffix.lower() == ".l5k":
        from .l5k import read_l5k
        return read_l5k(path, name)
    from .l5x import read_l5x
    return read_l5x(path, name)


def load_export(path: str | Path, source_name: str | None = None) -> LogixProgram:
    """The export's ladder program (not yet validated); ExportError lists
    every problem of the file, reading and making together."""
    project = read_export(path, source_name)
    result = build_program(project)
    if result.problems:
        raise ExportError(sorted(result.problems, key=_order))
    return result


def _order(p: Problem):
    return (p.pos.line, p.pos.column)
