"""Where a problem is: shared by the config file tests (MODBMAST.XML, MODBTCPS.XML)."""

from __future__ import annotations


def locate(text: str, needle: str, nth: int = 1) -> tuple[int, int]:
    """(line, column), 1-based, of the ``nth`` occurrence of ``needle``."""
    i = -1
    for _ in range(nth):
        i = text.index(needle, i + 1)
    return text.count("\n", 0, i) + 1, i - (text.rfind("\n", 0, i) + 1) + 1


def where(problem) -> tuple[int, int]:
    return problem.line, problem.column
