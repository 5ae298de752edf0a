"""Errors of the ladder pipeline, each pointing at source text."""

from __future__ import annotations

from .ast import Pos


class LadderError(Exception):
    """A problem in a program, with where it is: ``file:line:col: message``."""

    def __init__(self, pos: Pos, message: str, context: str | None = None) -> None:
        self.pos = pos
        self.message = message
        self.context = context
        super().__init__(f"{pos}: {message}")

    def report(self) -> str:
        """The message, plus the source line with a caret when known."""
        text = str(self)
        if self.context:
            text += "\n" + self.context.rstrip("\n")
        return text


class ProgramErrors(Exception):
    """Every problem found in a program (check lists them all)."""

    def __init__(self, errors: list[LadderError]) -> None:
        self.errors = errors
        super().__init__("\n".join(e.report() for e in errors))
