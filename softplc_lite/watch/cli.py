"""``softplc watch``: build the session from the command line, then either
render one snapshot (no terminal needed) or run the interactive view.

Before scan 0 the --watch addresses are read from the table the session
starts with: a bad one is an error (exit 1), nothing scanned or saved. A
snapshot reads the app's retentive state but leaves it as it was unless
``--save`` is given; ``--scans N`` is for a snapshot only (usage error
otherwise: the interactive view starts at scan 0, and ``n``/``r`` scan).
Ctrl-C and SIGTERM (raised as KeyboardInterrupt) quit as ``q`` does: the
final save, exit 0."""

from __future__ import annotations

import io
import sys

from rich.console import Console

from ..app import load_app
from ..interrupt import raise_on_interrupt
from ..cli import (
    EXIT_ERROR,
    EXIT_USAGE,
    SNAPSHOT_HEIGHT,  # the ranges the argument parser checks too
    SNAPSHOT_WIDTH,
    address_problems,
)
from ..runner import RunOptions
from .screen import WatchScreen, rung_view
from .session import WatchOptions, WatchSession
from .watchlist import WATCH_MAX, read_watch_file


def watch_command(args) -> int:
    snapshot = args.snapshot
    scans = args.scans
    if scans is not None and not snapshot:
        print("softplc watch: error: --scans N needs --snapshot FILE (the view starts at scan 0; "
              "press n to step or r to run)", file=sys.stderr)
        return EXIT_USAGE
    scans = scans or 0
    problem = size_problem(args.width, args.height) or (scans < 0 and "--scans: expected 0 or more")
    if problem:  # the parser checks these: for callers that build ``args`` themselves
        print(f"softplc watch: error: {problem}", file=sys.stderr)
        return EXIT_USAGE
    # The app first: a missing app or a program with errors is the problem to fix, whatever the terminal
    # (the same error and exit code as softplc run's).
    app = load_app(args.app, args.state)
    if not snapshot and not (sys.stdin.isatty() and sys.stdout.isatty()):
        print("softplc watch: needs a terminal (standard input and output are not one here); "
              "render the view to a file instead: softplc watch APP --scans N --snapshot view.txt "
              "(or view.svg)", file=sys.stderr)
        return EXIT_USAGE
    watch = list(args.watch)
    if args.watch_file:
        watch += read_watch_file(args.watch_file, app.program.symbols, room=max(0, WATCH_MAX - len(watch)))
    save = not snapshot or getattr(args, "save", False)
    run = RunOptions(scan_ms=args.scan_ms, realtime=args.realtime, fresh=args.fresh, sets=tuple(args.set),
                     ports=tuple(args.port), replay=args.replay, save_state=save)
    options = WatchOptions(run=run, watch=tuple(watch), forces=tuple(args.force), break_when=tuple(args.break_when),
                           online=not snapshot)  # a snapshot renders once: nothing to watch
    session = WatchSession(app, options)
    problems = address_problems("--watch", session.engine.table, list(args.watch), app.program.symbols) + \
        address_problems(f"--watch-file {args.watch_file}:", session.engine.table, watch[len(args.watch):],
                         app.program.symbols)
    if problems:  # before scan 0: nothing scanned, nothing saved
        session.engine.close()
        for problem in problems:
            print(f"error: {problem}", file=sys.stderr)
        return EXIT_ERROR
    raise_on_interrupt()  # from here Ctrl-C and SIGTERM quit as q does, saving
    try:
        if snapshot:
            for _ in range(scans):
                session.scan()
                if session.last_hit is not None:
                    break
            write_snapshot(session, snapshot, args.width, args.height)
            return 0
        from .terminal import run_terminal

        return run_terminal(session, rung_view)
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: quit as q does (the finally saves)
        return 0
    finally:
        session.quit()


def size_problem(width: int, height: int) -> str | None:
    """What is wrong with a snapshot size, None when it is in range."""
    for name, value, valid in (("--width", width, SNAPSHOT_WIDTH), ("--height", height, SNAPSHOT_HEIGHT)):
        if value not in valid:
            return f"{name}: expected an integer from {valid.start} to {valid.stop - 1}, not {value}"
    return None


def render(session: WatchSession, width: int, height: int, measured: bool = False) -> Console:
    """The view of ``session`` at ``width`` x ``height``, recorded (export it
    with ``export_text()`` or ``save_svg()``). The status bar shows the
    status file's scan times (S:8, S:9) unless ``measured``: on simulated
    time a snapshot is then the same on every machine. The size must be in
    SNAPSHOT_WIDTH x SNAPSHOT_HEIGHT (ValueError otherwise)."""
    problem = size_problem(width, height)
    if problem:
        raise ValueError(problem)
    console = Console(width=width, height=height, record=True, color_system="truecolor", force_terminal=True,
                      file=io.StringIO(), legacy_windows=False)
    console.print(WatchScreen(session, rung_view, measured=measured))
    return console


def write_snapshot(session: WatchSession, path: str, width: int, height: int) -> None:
    console = render(session, width, height)
    if path.lower().endswith(".svg"):
        console.save_svg(path, title=f"softplc watch {session.app.name}")
    else:
        console.save_text(path)
