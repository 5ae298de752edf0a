"""Errors raised by the data table.

``AddressError`` is a problem with address *text* (found when a program or a
command line is read). ``DataTableError`` covers everything else: values of
the wrong kind or range, elements past the end of a file, bad JSON and bad
snapshots. Run-time trouble that a PLC reports through fault bits derives from
``AddressRangeError`` so the scan engine can catch exactly that.
"""

from __future__ import annotations


class DataTableError(Exception):
    """Something the data table refuses; the message says what and why."""


class AddressError(DataTableError):
    """Address text that cannot be parsed, quoted with what was expected.

    ``position`` is the 0-based offset of the problem inside ``text``;
    ``column`` is the same, 1-based, as editors count.
    """

    def __init__(self, text: str, position: int, reason: str) -> None:
        self.text = text
        self.position = max(0, min(position, len(text)))
        self.reason = reason
        shown = text if len(text) <= 60 else f"{text[:40]}...({len(text)} characters)"
        super().__init__(f"bad address '{shown}': {reason}")

    @property
    def column(self) -> int:
        return self.position + 1

    def context(self) -> str:
        """The address with a caret under the problem, like lark's get_context."""
        text, at = self.text, self.position
        if len(text) > 80:  # a window around the problem, not thousands of characters
            start = max(0, at - 40)
            text, at = ("..." if start else "") + text[start:start + 80] + ("..." if start + 80 < len(text) else ""), \
                at - start + (3 if start else 0)
        return f"{text}\n{' ' * at}^"


class AddressRangeError(DataTableError):
    """An address that parses but points outside the table (missing file,
    element past the end, indirect or indexed value out of range)."""


class ValueRangeError(DataTableError):
    """A value that does not fit the element it is written to."""


class BlockRangeError(AddressRangeError):
    """A block of consecutive words that runs past the end of its file."""


class SnapshotError(DataTableError):
    """A retentive snapshot that is missing, truncated or corrupted."""
