"""What every ``softplc`` subcommand shares: the exit codes, the option
types, and how warnings, values and signals are handled.

Exit codes: 0 ok; 1 a program, config or data error (reported with
file:line:col, no traceback); 2 usage error (and ``test --fail-under``:
coverage below the figure, as coverage.py exits); 3 the PLC faulted; 4 an
internal error in softplc itself (a bug, reported in one line, never as a
traceback); 5 ``--replay``: the program's output differed from the
recording; 130 interrupted (outside a run's scan loop: Ctrl-C or SIGTERM
while ``run`` or ``watch`` scans ends the run cleanly, exit 0).
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from pathlib import Path

from ..datatable import DataTable, DataTableError
from ..datatable.display import format_read
from ..ladder.symbols import SymbolIndex, is_name, resolve_name

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_FAULT, EXIT_INTERNAL = 0, 1, 2, 3, 4
EXIT_REPLAY = 5  # --replay: the program wrote bytes other than the recording's
EXIT_INTERRUPTED = 130
DOCS = "docs/cli.md"

# --scans N: 0 or more (a top this far out reads as "0 or more" in int_in's messages).
SCANS_RANGE = range(0, 2 ** 63)


def int_in(valid: range, what: str):
    """An argparse type: an integer in ``valid``, else a usage error."""
    def parse(text: str) -> int:
        try:
            value = int(text) if len(text) <= 19 else None
        except ValueError:
            value = None
        if value is None or value not in valid:
            span = f"{valid.start} or more" if valid.stop > 10 ** 12 else f"from {valid.start} to {valid.stop - 1}"
            raise argparse.ArgumentTypeError(f"expected an integer {span}, not {text[:20]!r}")
        return value
    parse.__name__ = what  # argparse names the type in its messages
    return parse


def app_directory(text: str) -> Path | None:
    """An APP argument that must be an app's directory (a command that
    writes files into it); None, said on standard error, when it is not."""
    app = Path(text)
    if not app.is_dir():
        print(f"error: {text}: expected an app's directory", file=sys.stderr)
        return None
    return app


def print_warnings(warnings: list[str]) -> None:
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)


def print_values(table: DataTable, addresses: list[str], symbols=None) -> None:
    """``ADDR = value`` a line (``NAME (ADDR) = value`` for a symbol): what --print shows."""
    names = SymbolIndex(symbols)
    for text in addresses:
        a = resolve_name(text, names)
        name = f"{text} ({a})" if is_name(text.strip(), names) else str(a)
        print(f"{name} = {format_read(table, a)}")


def address_problems(option: str, table: DataTable, texts: list[str], symbols=None) -> list[str]:
    """What is wrong with each address (or symbol) given to ``option``, read
    from the table a run starts with: checked before scan 0."""
    names = SymbolIndex(symbols)
    problems = []
    for text in texts:
        try:
            format_read(table, resolve_name(text, names))
        except DataTableError as e:
            message = str(e)  # most name the address already: not twice
            named = message.startswith((text, repr(text)))
            problems.append(f"{option} {message}" if named else f"{option} {text}: {message}")
    return problems


def handle_signals(handlers: dict) -> dict:
    """Install signal handlers; the previous ones. Python lets only the main
    thread do it: elsewhere (main() called from a thread) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
