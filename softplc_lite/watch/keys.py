"""The keys of the interactive watch view, for ``softplc watch --help``.

The one table of keys is terminal.py's ``KEYS`` (label, what it does),
made from the ``BINDINGS`` the Controller dispatches from. A terminal.py
without that table (before it was added) still has its keys listed:
``TODAY`` holds the keys its Controller handled then, and can go once
terminal.py's table is in (tests/test_cli_usage.py checks whichever is used
against the Controller).
"""

from __future__ import annotations

# (label, the Controller's key values, what it does): the keys before terminal.py had its table
TODAY: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("n, space", ("n", " "), "one scan forward (from history when stepped back)"),
    ("r", ("r",), "run: scan continuously"),
    ("p", ("p",), "pause"),
    ("+ / -", ("+", "-"), "run faster / slower"),
    ("up/down, k/j", ("up", "k", "down", "j"), "select the rung above / below"),
    ("PgUp/PgDn", ("pgup", "pgdown"), "ten rungs up / down"),
    ("f", ("f",), "show the next program file"),
    ("b", ("b",), "toggle a breakpoint on the selected rung"),
    ("Backspace", ("\x7f", "\x08"), "one scan back in the history"),
    ("g", ("g",), "go to a rung (asks for its number)"),
    ("F", ("F",), "force a bit: ADDR=1 or ADDR=0"),
    ("U", ("U",), "remove the force on ADDR"),
    ("M", ("M",), "change mode: program, run or test"),
    ("q", ("q",), "quit (saves the retentive data table)"),
)


def key_rows() -> tuple[tuple[str, str], ...]:
    """(label, what it does) of every key of the view."""
    from . import terminal

    table = getattr(terminal, "KEYS", None)
    return tuple(table) if table else tuple((label, meaning) for label, _, meaning in TODAY)


def keys_help() -> str:
    """The keys as text for ``--help``: one key a line."""
    rows = key_rows()
    width = max(len(label) for label, _ in rows)
    return "\n".join(f"  {label.ljust(width)}  {meaning}" for label, meaning in rows)
