"""The ``softplc`` command (docs/cli.md): the parser built from the
subcommands (``commands/``, one module each), and ``main``, which runs the
one chosen and turns what escapes it into an exit code (commands/common.py
lists them) and one line of message, never a traceback."""

from __future__ import annotations

import argparse
import signal
import sys
from typing import Sequence

from . import __version__
from .app import AppError
from .commands import COMMANDS
from .commands.common import (  # noqa: F401 (the exit codes: importable from the command's module)
    DOCS, EXIT_ERROR, EXIT_FAULT, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK, EXIT_REPLAY, EXIT_USAGE,
    handle_signals,
)
from .datatable import DataTableError
from .errors import FileAccessError, LocatedError, file_error
from .interrupt import loaded, quit_until_handled, stop_as_interrupt
from .ladder.errors import LadderError

COMMAND_NAMES = tuple(command.NAME for command in COMMANDS)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="softplc",
        description="A soft PLC: text ladder logic on an emulated PLC-5/SoftPLC data table.",
        epilog=f"Each COMMAND has its own --help. Exit codes, time and signals: {DOCS}; "
               "the engine and softplc run: docs/engine.md; the watch view: docs/watch.md.",
    )
    p.add_argument("--version", action="version", version=f"softplc_lite {__version__}",
                   help="print the version and exit")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", help="what to do (each has its own --help)")
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """The softplc command. With ``argv`` None (the process's own command
    line: the console script, python -m) it owns the process's signals to
    the end: once the command is done, Ctrl-C and SIGTERM are ignored until
    the process exits, so no signal turns a finished command's exit status
    into a signal's. With ``argv`` (a program or a test calling it), the
    caller's handlers are restored at the end."""
    try:
        if argv is None:  # the process's own command: Ctrl-C or SIGTERM end it at once until it
            quit_until_handled()  # takes them over (a run once it scans, the view once it opens)
        else:
            loaded()  # the caller's process: Ctrl-C is a KeyboardInterrupt, caught below
        return _main(argv)
    except KeyboardInterrupt:  # while the arguments are read (the commands catch their own)
        return EXIT_INTERRUPTED
    finally:
        if argv is None:
            handle_signals({signal.SIGINT: signal.SIG_IGN, signal.SIGTERM: signal.SIG_IGN})


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_usage(sys.stderr)
        names = f"{', '.join(COMMAND_NAMES[:-1])} or {COMMAND_NAMES[-1]}"
        print(f"softplc: error: a COMMAND is needed: {names}; softplc --help says what each does ({DOCS})",
              file=sys.stderr)
        return EXIT_USAGE
    previous = {}
    if args.command in ("run", "watch"):  # they end cleanly on Ctrl-C: SIGTERM (kill, systemd) too
        previous = handle_signals({signal.SIGTERM: stop_as_interrupt}) if argv is not None else {}
        sigint = signal.getsignal(signal.SIGINT)
        if sigint is not None and previous:  # None: not installed from Python, left alone
            previous[signal.SIGINT] = sigint  # the run ignores it once its scanning ends
    try:
        return _dispatch(args)
    finally:
        if argv is not None:
            handle_signals({sig: handler for sig, handler in previous.items() if handler is not None})


def _dispatch(args: argparse.Namespace) -> int:
    try:
        return args.func(args)
    except (DataTableError, AppError, LadderError, LocatedError) as e:
        text = e.report() if isinstance(e, (LadderError, LocatedError)) else str(e)
        print(f"error: {text}" if not isinstance(e, AppError) else text, file=sys.stderr)
        return EXIT_ERROR
    except OSError as e:
        print(f"error: {e if isinstance(e, FileAccessError) else file_error(e, action='open')}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except (Exception, RecursionError, MemoryError) as e:  # a bug: one line, never a traceback
        text = str(e)
        text = text if len(text) <= 300 else text[:300] + "..."
        print(f"softplc: internal error: {type(e).__name__}: {text} (a bug in softplc; please report it "
              f"with the command that caused it)", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
