"""Errors of plug-in modules: loading them and reading their config files."""

from __future__ import annotations


class ModuleError(Exception):
    """A problem with a TLM or its config: where it is and what was expected.

    ``path`` is the file (MODULES.LST, COMGENIUS.LST, ...), ``line`` and
    ``column`` are 1-based (0 when not known)."""

    def __init__(self, message: str, path: str | None = None, line: int = 0, column: int = 0) -> None:
        self.message = message
        self.path = path
        self.line = line
        self.column = column
        super().__init__(self.report())

    def report(self) -> str:
        where = self.path or ""
        if self.line:
            where += f":{self.line}"
            if self.column:
                where += f":{self.column}"
        return f"{where}: {self.message}" if where else self.message
