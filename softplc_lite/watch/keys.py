"""The keys of the interactive watch view, for ``softplc watch --help``.

The one table of keys is terminal.py's ``KEYS`` (label, what it does),
made from the ``BINDINGS`` the Controller dispatches from.
"""

from __future__ import annotations


def key_rows() -> tuple[tuple[str, str], ...]:
    """(label, what it does) of every key of the view."""
    # terminal.py imports termios: only when the help is asked for
    from .terminal import KEYS

    return KEYS


def keys_help() -> str:
    """The keys as text for ``--help``: one key a line."""
    rows = key_rows()
    width = max(len(label) for label, _ in rows)
    return "\n".join(f"  {label.ljust(width)}  {meaning}" for label, meaning in rows)
