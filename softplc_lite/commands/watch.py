"""``softplc watch``: build the session from the command line, then either
render one snapshot (no terminal needed) or run the interactive view
(the watch package, docs/watch.md).

Before scan 0 the --watch and --trend addresses are read from the table the session
starts with: a bad one is an error (exit 1), nothing scanned or saved. A
snapshot reads the app's retentive state but leaves it as it was unless
``--save`` is given; ``--scans N`` is for a snapshot only (usage error
otherwise: the interactive view starts at scan 0, and ``n``/``r`` scan).
Ctrl-C and SIGTERM (raised as KeyboardInterrupt) quit as ``q`` does: the
final save, exit 0.

The view's modules (rich, termios) load only when the command runs or its
help is printed: every other command would load them for nothing (50 ms a
start)."""

from __future__ import annotations

import argparse
import sys

from ..app import SCAN_MS_RANGE, load_app
from ..interrupt import raise_on_interrupt
from ..runner import RunOptions
from ..watch.snapshot import SNAPSHOT_HEIGHT, SNAPSHOT_WIDTH, size_problem
from .common import DOCS, EXIT_ERROR, EXIT_USAGE, SCANS_RANGE, address_problems, int_in

NAME = "watch"


def add_parser(sub) -> argparse.ArgumentParser:
    w = sub.add_parser(
        NAME, help="step scans in a terminal view: rungs, power flow, values, ports",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="The online view of a running PLC in the terminal (docs/watch.md), or with --snapshot "
                    "one rendering of it to a file.")
    _keys_in_the_epilog(w)
    w.add_argument("app", metavar="APP", help="app directory, .lad file or Studio 5000 export (.L5X, .L5K)")
    w.add_argument("--watch", action="append", default=[], metavar="ADDR",
                   help="add ADDR (address or symbol) to the watch list (repeatable; checked before scan 0)")
    w.add_argument("--watch-file", metavar="FILE", help="a watch file: one address or symbol a line")
    w.add_argument("--trend", action="append", default=[], metavar="ADDR",
                   help="draw ADDR (address or symbol) in the trend panel (repeatable, at most 6; checked before "
                   "scan 0; docs/trends.md)")
    w.add_argument("--force", action="append", default=[], metavar="ADDR=0|1", help="force a bit on or off")
    w.add_argument("--break-when", action="append", default=[], metavar="EXPR",
                   help='stop running when EXPR becomes true, e.g. "N7:0 > 100" or R6:0/ER')
    w.add_argument("--realtime", action="store_true", help="use the wall clock instead of simulated time")
    w.add_argument("--scan-ms", type=int_in(SCAN_MS_RANGE, "--scan-ms"), metavar="MS",
                   help="simulated ms per scan (default from the app; 0..32767)")
    w.add_argument("--state", metavar="DIR", help="keep the retentive snapshot in DIR (default APP/.softplc)")
    w.add_argument("--fresh", action="store_true", help="ignore the retentive snapshot at start")
    w.add_argument("--set", action="append", default=[], metavar="ADDR=VALUE",
                   help="set ADDR to VALUE at start (as for run)")
    w.add_argument("--port", action="append", default=[], metavar="N=DEVICE", help="as for run")
    w.add_argument("--replay", metavar="TRACE", help="play every port back from a recorded TRACE file")
    w.add_argument("--scans", type=int_in(SCANS_RANGE, "--scans"), metavar="N",
                   help="with --snapshot: scans to run first (0 or more; default 0); refused without it")
    w.add_argument("--snapshot", metavar="FILE", help="render the view after --scans N scans to FILE "
                   "(.svg: an SVG picture; otherwise text) and exit; needs no terminal")
    w.add_argument("--save", action="store_true",
                   help="with --snapshot: save the retentive data table at the end, as a run does (without it "
                   "a snapshot leaves the app's state as it was; the interactive view always saves on quit)")
    w.add_argument("--width", type=int_in(SNAPSHOT_WIDTH, "--width"), default=100, metavar="COLS",
                   help="--snapshot width, 40..1000 (default 100)")
    w.add_argument("--height", type=int_in(SNAPSHOT_HEIGHT, "--height"), default=40, metavar="ROWS",
                   help="--snapshot height, 12..1000 (default 40)")
    w.set_defaults(func=run)
    return w


def _keys_in_the_epilog(parser: argparse.ArgumentParser) -> None:
    """``softplc watch --help`` ends with the view's keys, made when the help
    is printed: the key table comes from the view's terminal module."""
    format_help = parser.format_help

    def with_keys() -> str:
        from ..watch.keys import keys_help

        parser.epilog = (f"keys in the view:\n{keys_help()}\n\nCtrl-C or SIGTERM quit as q does (exit 0). "
                         f"See docs/watch.md and {DOCS}.")
        return format_help()

    parser.format_help = with_keys


def run(args: argparse.Namespace) -> int:
    from ..trends.series import TrendError
    from ..watch.session import WatchOptions, WatchSession
    from ..watch.snapshot import write_snapshot
    from ..watch.watchlist import WATCH_MAX, read_watch_file

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
    run_options = RunOptions(scan_ms=args.scan_ms, realtime=args.realtime, fresh=args.fresh, sets=tuple(args.set),
                             ports=tuple(args.port), replay=args.replay, save_state=save)
    # online: a snapshot renders once, so there is nothing to watch for
    options = WatchOptions(run=run_options, watch=tuple(watch), forces=tuple(args.force),
                           break_when=tuple(args.break_when), trend=tuple(args.trend), online=not snapshot)
    try:
        session = WatchSession(app, options)
    except TrendError as e:  # the session released what it opened; nothing scanned, nothing saved
        for problem in e.problems:
            print(f"error: {problem}", file=sys.stderr)
        return EXIT_ERROR
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
        from ..watch.screen import rung_view
        from ..watch.terminal import run_terminal

        return run_terminal(session, rung_view)
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: quit as q does (the finally saves)
        return 0
    finally:
        session.quit()
