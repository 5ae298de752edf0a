"""Errors of the port layer: a trace file that cannot be read or written."""

from __future__ import annotations

from ..errors import LocatedError


class PortError(LocatedError):
    """A port layer problem with its file, line and column."""
