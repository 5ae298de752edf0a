"""The error every config and data file reader raises: where and what.

``LocatedError(message, path, line, column)`` reports as
``path:line:column: message`` (line and column 1-based, left out when 0).
Module configs (tlm.errors.ModuleError) and port traces
(ports.errors.PortError) derive from it; the CLI prints any of them without
a traceback.
"""

from __future__ import annotations


class LocatedError(Exception):
    """A problem in a file: where it is and what was expected."""

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
