"""The ``softplc`` command (docs/cli.md).

Exit codes: 0 ok; 1 a program, config or data error (reported with
file:line:col, no traceback); 2 usage error; 3 the PLC faulted; 4 an
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
import time
from pathlib import Path
from typing import Sequence

from . import __version__
from .app import SCAN_MS_RANGE, AppError, load_app
from .datatable import DataTable, DataTableError, parse_address
from .datatable import jsonio, snapshot
from .datatable.display import format_read
from .run_output import StatusLine
from .ladder.engine import Mode
from .ladder.errors import LadderError
from .fmtcmd import fmt_command
from .ladder.fmt import STYLES
from .ladder.symbols import SymbolIndex, is_symbol_text, resolve_name
from .runner import RunOptions, Runner
from .errors import FileAccessError, LocatedError, file_error
from .interrupt import loaded, quit_until_handled, stop_as_interrupt

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_FAULT, EXIT_INTERNAL = 0, 1, 2, 3, 4
EXIT_REPLAY = 5  # --replay: the program wrote bytes other than the recording's
EXIT_INTERRUPTED = 130
DOCS = "docs/cli.md"

# --scan-ms (SCAN_MS_RANGE, the range of softplc.toml's scan_ms): simulated ms
# per scan, or the --realtime period (0: free-running).
SCANS_RANGE = range(0, 2 ** 63)
# watch --snapshot sizes: a real terminal's at the low end; the top keeps a
# snapshot's memory and time bounded (1000x1000 takes about 1.3 s).
SNAPSHOT_WIDTH = range(40, 1001)
SNAPSHOT_HEIGHT = range(12, 1001)


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



def _cmd_address(args: argparse.Namespace) -> int:
    status = EXIT_OK
    print("address\tcanonical\tkind\taccess")  # the columns, tab-separated as the rows
    for text in args.text:
        try:
            a = parse_address(text)
        except DataTableError as e:
            print(f"error: {e}", file=sys.stderr)
            if hasattr(e, "context"):
                print("  " + e.context().replace("\n", "\n  "), file=sys.stderr)
            status = EXIT_ERROR
            continue
        direct = "direct" if a.is_direct else "indirect/indexed"
        print(f"{text}\t{a}\t{a.kind.value}\t{direct}")
    return status


def _cmd_datatable(args: argparse.Namespace) -> int:
    if not (args.load or args.print or args.dump or args.save):  # nothing to do: say what it is for
        args.parser.error("expected FILEs to load (datatable .json or snapshot files) and what to do with them "
                          "(--print ADDR, --dump, --save SNAPSHOT), e.g. "
                          "softplc datatable docs/examples/datatable.json --print N7:0")
    table = DataTable()
    for path in args.load:
        if path.endswith(".json"):
            jsonio.load_file(table, path)
        else:
            table.assign(snapshot.load(path))
    _print_values(table, args.print)
    if args.dump:
        sys.stdout.write(jsonio.dumps(table))
    if args.save:
        try:
            snapshot.save(table, args.save)
        except OSError as e:
            print(f"error: --save: {file_error(e, args.save, 'write')}", file=sys.stderr)
            return EXIT_ERROR
    return EXIT_OK


def _print_values(table: DataTable, addresses: list[str], symbols=None) -> None:
    names = SymbolIndex(symbols)
    for text in addresses:
        a = resolve_name(text, names)
        name = f"{text} ({a})" if is_symbol_text(text.strip()) else str(a)
        print(f"{name} = {format_read(table, a)}")


def run_realtime(args: argparse.Namespace) -> bool:
    """The clock of ``softplc run``: --realtime or --simulated when given;
    otherwise the wall clock for an unbounded run (no --scans, no --replay:
    a PLC that runs until stopped) and simulated time for a bounded one."""
    if args.realtime or args.simulated:
        return bool(args.realtime)
    return args.scans is None and args.replay is None


def _cmd_run(args: argparse.Namespace) -> int:
    app = load_app(args.app, args.state)
    _print_warnings(app.warnings)
    options = RunOptions(
        scan_ms=args.scan_ms, realtime=run_realtime(args), fresh=args.fresh,
        load=tuple(args.load or ()), sets=tuple(args.set), executor=args.executor,
        ports=tuple(args.port), record=args.record, replay=args.replay,
    )
    runner = Runner(app, options)
    problems = address_problems("--print", runner.table, args.print, app.program.symbols)
    if problems:  # before scan 0: nothing ran, nothing is saved
        runner.engine.close()
        for problem in problems:
            print(f"error: {problem}", file=sys.stderr)
        return EXIT_ERROR
    if args.online:
        from .program_watcher import ProgramWatcher

        watcher = ProgramWatcher(app)

        def online_edit(runner: Runner) -> None:
            edit = watcher.apply(runner.engine)
            if edit is not None:  # stderr: above the status line when rich's Live draws one
                print(edit.summary() if edit.accepted else edit.report(), file=sys.stderr)

        runner.between_scans.append(online_edit)
    try:
        _scan_until_the_end(runner, app, args)
    finally:
        runner.close()
    engine = runner.engine
    if engine.clock.realtime and engine.scans:
        # On the wall clock, whether the scan kept its period (a scan late by a whole period missed its
        # slot). On standard error, so that standard output stays the --print values a script reads;
        # before the final save, so that a save's error stays the last line.
        print(f"{app.name}: {runner.late_scans} late scan{'s' if runner.late_scans != 1 else ''} "
              f"of {engine.scans}, the latest start {runner.max_lateness_ms:.1f} ms after due", file=sys.stderr)
    storage_problems = runner.finish()  # the final save; a failure is reported, and the output still printed
    if args.dump:
        try:
            Path(args.dump).write_text(jsonio.dumps(runner.table), encoding="utf-8")
        except OSError as e:
            print(f"error: --dump: {file_error(e, args.dump, 'write')}", file=sys.stderr)
            storage_problems = storage_problems or [str(e)]
    if app.display:
        clock = "real" if engine.clock.realtime else "simulated"
        print(f"{app.name}: {engine.scans} scans, {engine.clock.now_ms / 1000:.2f} s {clock} time")
        for line in app.display.summary_lines(runner.table):
            print(line)
    _print_values(runner.table, args.print, app.program.symbols)
    if engine.mode is Mode.FAULTED:
        print(f"softplc: {app.name}: {engine.fault}", file=sys.stderr)
        return EXIT_FAULT
    if runner.replay_differences:
        count = runner.replay_differences
        print(f"softplc: {app.name}: --replay: the program's output differed from the recording "
              f"({count} difference{'s' if count != 1 else ''}, listed above)", file=sys.stderr)
        return EXIT_REPLAY
    return EXIT_ERROR if storage_problems else EXIT_OK


def _scan_until_the_end(runner: Runner, app, args: argparse.Namespace) -> None:
    """Scan until --scans, the end of a --replay trace, a major fault, or
    Ctrl-C/SIGTERM: either signal ends the run after the scan under way, so
    the final save holds a whole scan (a second one stops at once). Then
    both are ignored (main() restores them for a caller in the same
    process): a service manager that sends SIGTERM again must not cut the
    final save or the exit short."""
    def stop(signum, frame) -> None:
        if runner.stop_requested:
            raise KeyboardInterrupt
        runner.request_stop()

    _handle_signals({signal.SIGINT: stop, signal.SIGTERM: stop})
    try:
        _run_with_status(runner, app, args.scans, unbounded=args.scans is None and args.replay is None)
    finally:
        _handle_signals({signal.SIGTERM: signal.SIG_IGN, signal.SIGINT: signal.SIG_IGN})


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


def _run_with_status(runner: Runner, app, scans: int | None, unbounded: bool) -> None:
    """Run, with a status line redrawn on standard error while it is a
    terminal: for an app with [display] status items, and for every app
    while the run is unbounded (the scan, the scan rate, the sim/real time
    ratio). rich's Live redraws from its own thread a few times a second;
    the scan loop only refreshes the values, at most ten times a second, so
    drawing never slows scanning."""
    items = app.display.status
    if not (items or unbounded):
        runner.run(scans)
        return
    from rich.console import Console  # here: a run without a status line never loads rich (30 ms a start)
    from rich.live import Live

    console = Console(stderr=True)
    if not console.is_terminal:
        runner.run(scans)
        return
    line = StatusLine(app.name, items)
    start = time.monotonic()
    last = 0.0

    def refresh(engine) -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= 0.1:
            last = now
            line.update(engine.table, engine.scans, engine.clock.now_ms, engine.clock.realtime, now - start)
            servers = [s for m in engine.modules for s in m.network_servers()]
            line.clients = sum(s.clients for s in servers) if servers else None

    with Live(line, console=console, refresh_per_second=5, transient=False):
        runner.run(scans, on_scan=refresh)
        engine = runner.engine
        line.update(engine.table, engine.scans, engine.clock.now_ms, engine.clock.realtime,
                    time.monotonic() - start)


def _cmd_watch(args: argparse.Namespace) -> int:
    from .watch.cli import watch_command

    return watch_command(args)


def _cmd_check(args: argparse.Namespace) -> int:
    try:
        app = load_app(args.app, use_cache=False)  # check reads every text, whatever was cached
    except AppError as e:
        print(str(e), file=sys.stderr)
        count = len(e.errors) or 1
        print(f"{count} problem{'s' if count != 1 else ''} found", file=sys.stderr)
        return EXIT_ERROR
    _print_warnings(app.warnings)
    rungs = sum(len(f.rungs) for f in app.program.files.values())
    extra = "".join(f", module {m.name}" for m in app.modules)
    if app.warnings:
        extra += f", {len(app.warnings)} warning{'s' if len(app.warnings) != 1 else ''}"
    print(f"{app.name}: ok ({len(app.program.files)} program file{'s' if len(app.program.files) != 1 else ''}, "
          f"{rungs} rung{'s' if rungs != 1 else ''}{extra})")
    return EXIT_OK


def _print_warnings(warnings: list[str]) -> None:
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)


def _cmd_fmt(args: argparse.Namespace) -> int:
    return fmt_command(args.paths, args.style, check=args.check, write=args.write)


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

    r = sub.add_parser(
        "run", help="run an app (directory or .lad file) in RUN mode",
        description="Run an app in RUN mode until --scans N scans, the end of a --replay trace, Ctrl-C or "
                    "SIGTERM (both end cleanly: final save, --print/--dump output, exit 0).",
        epilog=f"Time: an unbounded run (no --scans, no --replay) follows the wall clock; a bounded one is on "
               f"simulated time; --realtime or --simulated says which. Exit codes: 0 ok, 1 error, 2 usage, "
               f"3 PLC fault, 4 internal error, 5 --replay output differed. See {DOCS} and docs/engine.md.")
    r.add_argument("app", metavar="APP", help="app directory or .lad file")
    r.add_argument("--scans", type=int_in(SCANS_RANGE, "--scans"), metavar="N",
                   help="stop after N scans (0 or more; default: until Ctrl-C or SIGTERM, or the end of the "
                   "--replay trace)")
    r.add_argument("--scan-ms", type=int_in(SCAN_MS_RANGE, "--scan-ms"), metavar="MS",
                   help="simulated ms per scan (default: the app's scan_ms, 10), or on the wall clock the scan "
                   "period (0 = free-running); 0..32767")
    clock = r.add_mutually_exclusive_group()
    clock.add_argument("--realtime", action="store_true",
                       help="use the wall clock (the default without --scans and --replay)")
    clock.add_argument("--simulated", action="store_true",
                       help="use simulated time, --scan-ms a scan (the default with --scans or --replay)")
    r.add_argument("--state", metavar="DIR", help="keep the retentive snapshot in DIR (default APP/.softplc)")
    r.add_argument("--fresh", action="store_true",
                   help="ignore the retentive snapshot at start (it is still saved while running)")
    r.add_argument("--load", action="append", metavar="FILE.json",
                   help="load data table values from FILE.json at start (repeatable)")
    r.add_argument("--dump", metavar="FILE.json", help="write the data table as JSON to FILE.json at the end")
    r.add_argument("--set", action="append", default=[], metavar="ADDR=VALUE",
                   help="set ADDR (address or symbol) to VALUE (JSON, or plain text) at start (repeatable)")
    r.add_argument("--print", action="append", default=[], metavar="ADDR",
                   help="print ADDR (address or symbol) at the end (repeatable; checked before scan 0)")
    r.add_argument("--online", action="store_true",
                   help="online program edit: watch the app's .lad files; a saved valid version replaces the "
                        "running program between two scans, the data table kept; errors are printed and "
                        "nothing changes (docs/engine.md, Online program edit)")
    r.add_argument("--executor", choices=("compiled", "reference"), default="compiled",
                   help="compiled fast path (default) or the reference interpreter")
    r.add_argument("--port", action="append", default=[], metavar="N=DEVICE",
                   help="open logical port N ([MODULE:]N) on DEVICE (a device path or pyserial URL) instead of "
                   "its [PORTS] field (repeatable; docs/serial.md)")
    r.add_argument("--record", metavar="TRACE", help="record every port's traffic to the TRACE file")
    r.add_argument("--replay", metavar="TRACE",
                   help="play every port back from a recorded TRACE file; stops at its end ('# scans: N' "
                   "comment, else the last recorded byte); exit 5 if the output differed")
    r.set_defaults(func=_cmd_run)

    w = sub.add_parser(
        "watch", help="step scans in a terminal view: rungs, power flow, values, ports",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="The online view of a running PLC in the terminal (docs/watch.md), or with --snapshot "
                    "one rendering of it to a file.")
    _keys_in_the_epilog(w)
    w.add_argument("app", metavar="APP", help="app directory or .lad file")
    w.add_argument("--watch", action="append", default=[], metavar="ADDR",
                   help="add ADDR (address or symbol) to the watch list (repeatable; checked before scan 0)")
    w.add_argument("--watch-file", metavar="FILE", help="a watch file: one address or symbol a line")
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
    w.set_defaults(func=_cmd_watch)

    c = sub.add_parser("check", help="parse and validate an app; list every problem",
                       description="Parse and validate an app; list every problem (exit 1), then RSLogix-style "
                                   "verify warnings (exit 0 with warnings only). See docs/language.md.")
    c.add_argument("app", metavar="APP", help="app directory or .lad file")
    c.set_defaults(func=_cmd_check)

    f = sub.add_parser("fmt", help="print, check or rewrite .lad programs canonically, keeping every comment",
                       description="Print each .lad file (an app directory: each of its .lad files; -: standard "
                                   "input) canonically, keeping every comment; what does not parse is refused "
                                   "(exit 1, every problem listed). See docs/language.md.")
    f.add_argument("paths", nargs="+", metavar="PATH", help=".lad file, app directory, or - for standard input")
    f.add_argument("--style", choices=STYLES, default="mnemonic",
                   help="mnemonic (XIC B3/0 OTE O:0/0; the default) or neutral text (XIC(B3/0)OTE(O:0/0);)")
    mode = f.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="print nothing; exit 1 naming each file that is not formatted (a CI gate)")
    mode.add_argument("--write", action="store_true",
                      help="rewrite each file that changes in place, atomically; nothing is written if a file "
                           "is refused")
    f.set_defaults(func=_cmd_fmt)

    a = sub.add_parser("address", help="parse data table addresses and print their canonical form",
                       description="Print each address's canonical form, value kind and whether it is direct "
                                   "(docs/datatable.md).")
    a.add_argument("text", nargs="+", metavar="ADDR", help="address text such as N7:0/3 or I:012/17")
    a.set_defaults(func=_cmd_address)

    d = sub.add_parser("datatable", help="load data table JSON or snapshots, print values, dump, save",
                       description="Load data table files in order, then print values, dump JSON or save a "
                                   "snapshot (docs/datatable.md).",
                       epilog="example: softplc datatable docs/examples/datatable.json --print ST9:0")
    d.add_argument("load", nargs="*", metavar="FILE",
                   help="datatable .json or a snapshot file, loaded in order (none: an empty table)")
    d.add_argument("--print", action="append", default=[], metavar="ADDR", help="print a value (repeatable)")
    d.add_argument("--dump", action="store_true", help="write the table as JSON to stdout")
    d.add_argument("--save", metavar="SNAPSHOT", help="save the table as a retentive snapshot")
    d.set_defaults(func=_cmd_datatable, parser=d)
    return p


def _keys_in_the_epilog(parser: argparse.ArgumentParser) -> None:
    """``softplc watch --help`` ends with the view's keys, made when the help
    is printed: the key table comes from the view's terminal module (rich,
    termios), which every other command would otherwise load for nothing
    (50 ms a start)."""
    format_help = parser.format_help

    def with_keys() -> str:
        from .watch.keys import keys_help

        parser.epilog = (f"keys in the view:\n{keys_help()}\n\nCtrl-C or SIGTERM quit as q does (exit 0). "
                         f"See docs/watch.md and {DOCS}.")
        return format_help()

    parser.format_help = with_keys


def _handle_signals(handlers: dict) -> dict:
    """Install signal handlers; the previous ones. Python lets only the main
    thread do it: elsewhere (main() called from a thread) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}


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
            _handle_signals({signal.SIGINT: signal.SIG_IGN, signal.SIGTERM: signal.SIG_IGN})


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_usage(sys.stderr)
        print(f"softplc: error: a COMMAND is needed: run, watch, check, fmt, address or datatable; "
              f"softplc --help says what each does ({DOCS})", file=sys.stderr)
        return EXIT_USAGE
    previous = {}
    if args.command in ("run", "watch"):  # they end cleanly on Ctrl-C: SIGTERM (kill, systemd) too
        previous = _handle_signals({signal.SIGTERM: stop_as_interrupt}) if argv is not None else {}
        sigint = signal.getsignal(signal.SIGINT)
        if sigint is not None and previous:  # None: not installed from Python, left alone
            previous[signal.SIGINT] = sigint  # the run ignores it once its scanning ends
    try:
        return _dispatch(args)
    finally:
        if argv is not None:
            _handle_signals({sig: handler for sig, handler in previous.items() if handler is not None})


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
