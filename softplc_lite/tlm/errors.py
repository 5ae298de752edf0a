"""Errors of plug-in modules: loading them and reading their config files."""

from __future__ import annotations

from ..errors import LocatedError


class ModuleError(LocatedError):
    """A problem with a TLM or its config: where it is and what was expected.

    ``path`` is the file (MODULES.LST, COMGENIUS.LST, ...), ``line`` and
    ``column`` are 1-based (0 when not known)."""
