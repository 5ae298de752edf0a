"""The keys of the interactive watch view, as one table.

``softplc watch --help`` lists them from here. The table is meant to be
the one place a key is described: the view's key handling
(terminal.py's ``Controller``) and any help overlay should read it rather
than keep a list of their own (tests/test_cli_help.py fails when a key the
Controller handles is missing here, or one described here is not handled).
"""

from __future__ import annotations

# (the key names a person presses, the Controller's key values, what it does)
KEYS: tuple[tuple[str, tuple[str, ...], str], ...] = (
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


def keys_help() -> str:
    """The key table as text for ``--help``: one key a line."""
    width = max(len(names) for names, _, _ in KEYS)
    return "\n".join(f"  {names.ljust(width)}  {meaning}" for names, _, meaning in KEYS)
