"""Errors of plug-in modules: loading them and reading their config files."""

from __future__ import annotations

from ..errors import LocatedError


class ModuleError(LocatedError):
    """A problem with a TLM or its config: where it is and what was expected.

    ``path`` is the file (MODULES.LST, COMGENIUS.LST, ...), ``line`` and
    ``column`` are 1-based (0 when not known)."""


class ModuleErrors(ModuleError):
    """Every problem found in a module's config file, reported together
    (one ``path:line:column: message`` line each)."""

    def __init__(self, problems: list[ModuleError]) -> None:
        self.problems = sorted(problems, key=lambda p: (p.path or "", p.line, p.column))
        first = self.problems[0]
        super().__init__(first.message, first.path, first.line, first.column)

    def report(self) -> str:
        return "\n".join(p.report() for p in self.problems)
