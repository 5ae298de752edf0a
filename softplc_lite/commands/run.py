"""``softplc run``: run an app in RUN mode until --scans N scans, the end of
a --replay trace, a major fault, Ctrl-C or SIGTERM; then the final save and
the --print/--dump output (docs/cli.md, docs/engine.md)."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from contextlib import nullcontext
from pathlib import Path

from ..app import SCAN_MS_RANGE, load_app
from ..datatable import jsonio
from ..errors import file_error
from ..ladder.host import Mode
from ..run_output import StatusLine
from ..runner import RunOptions, Runner
from .common import (DOCS, EXIT_ERROR, EXIT_FAULT, EXIT_OK, EXIT_REPLAY, SCANS_RANGE, address_problems,
                     handle_signals, int_in, print_values, print_warnings)

NAME = "run"


def add_parser(sub) -> argparse.ArgumentParser:
    r = sub.add_parser(
        NAME, help="run an app (directory or .lad file) in RUN mode",
        description="Run an app in RUN mode until --scans N scans, the end of a --replay trace, Ctrl-C or "
                    "SIGTERM (both end cleanly: final save, --print/--dump output, exit 0).",
        epilog=f"Time: an unbounded run (no --scans, no --replay) follows the wall clock; a bounded one is on "
               f"simulated time; --realtime or --simulated says which. Exit codes: 0 ok, 1 error, 2 usage, "
               f"3 PLC fault, 4 internal error, 5 --replay output differed. See {DOCS} and docs/engine.md.")
    r.add_argument("app", metavar="APP", help="app directory, .lad file, or Studio 5000 export (.L5X, .L5K)")
    r.add_argument("--scans", type=int_in(SCANS_RANGE, "--scans"), metavar="N",
                   help="stop after N scans (0 or more; default: until Ctrl-C or SIGTERM, or the end of the "
                   "--replay trace)")
    # SCAN_MS_RANGE is the range of softplc.toml's scan_ms: simulated ms per scan, or the --realtime period
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
    r.add_argument("--trend", action="append", default=[], metavar="ADDR",
                   help="record ADDR (an address or symbol) every scan to --trend-file (repeatable, at most "
                   "20; docs/trends.md)")
    r.add_argument("--trend-file", metavar="FILE", help="write the --trend addresses to FILE: .csv (a row a scan) "
                   "or .vcd (a value change dump for GTKWave and other waveform viewers)")
    r.add_argument("--trend-on-change", action="store_true",
                   help="record a scan only when a --trend value changed")
    r.add_argument("--replay", metavar="TRACE",
                   help="play every port back from a recorded TRACE file; stops at its end ('# scans: N' "
                   "comment, else the last recorded byte); exit 5 if the output differed")
    r.set_defaults(func=run)
    return r


def _trend_recorder(runner: Runner, app, args: argparse.Namespace):
    """(the Recorder of --trend/--trend-file, added to the runner's
    after-scan hooks; or None and the problems, every one)."""
    from ..trends.background import BackgroundRecorder
    from ..trends.record import TrendFileError, format_of
    from ..trends.series import TrendError, resolve_series

    problems = []
    if not args.trend:
        problems.append("--trend-file: name the addresses to record with --trend ADDR (repeatable)")
    if not args.trend_file:
        problems.append("--trend: name the file to record to with --trend-file FILE.csv or FILE.vcd (softplc watch "
                        "--trend draws them instead)")
    series = []
    try:
        series = resolve_series(args.trend, runner.table, app.program.symbols)
    except TrendError as e:
        problems += e.problems
    if args.trend_file:
        try:
            format_of(args.trend_file)
        except TrendFileError as e:
            problems.append(str(e))
    if problems:
        return None, problems
    clock = "wall clock" if runner.engine.clock.realtime else "simulated"
    try:
        recorder = BackgroundRecorder(runner.table, series, args.trend_file, app.name, clock, args.trend_on_change,
                                      follow=runner.engine.clock.realtime)
    except TrendFileError as e:
        return None, [str(e)]
    runner.after_scan.append(recorder.hook())
    return recorder, []


def run_realtime(args: argparse.Namespace) -> bool:
    """The clock of ``softplc run``: --realtime or --simulated when given;
    otherwise the wall clock for an unbounded run (no --scans, no --replay:
    a PLC that runs until stopped) and simulated time for a bounded one."""
    if args.realtime or args.simulated:
        return bool(args.realtime)
    return args.scans is None and args.replay is None


def run(args: argparse.Namespace) -> int:
    app = load_app(args.app, args.state)
    print_warnings(app.warnings)
    options = RunOptions(
        scan_ms=args.scan_ms, realtime=run_realtime(args), fresh=args.fresh,
        load=tuple(args.load or ()), sets=tuple(args.set), executor=args.executor,
        ports=tuple(args.port), record=args.record, replay=args.replay,
    )
    runner = Runner(app, options)
    problems = address_problems("--print", runner.table, args.print, app.program.symbols)
    recorder = None
    if not problems and (args.trend or args.trend_file):
        recorder, problems = _trend_recorder(runner, app, args)
    if problems:  # before scan 0: nothing ran, nothing is saved
        runner.engine.close()
        for problem in problems:
            print(f"error: {problem}", file=sys.stderr)
        return EXIT_ERROR
    if args.online:
        from ..program_watcher import ProgramWatcher

        watcher = ProgramWatcher(app)

        def online_edit(runner: Runner) -> None:
            edit = watcher.poll()
            if edit is None:
                return
            with recorder.detached() if recorder is not None else nullcontext():  # the edit may grow a file
                edit = watcher.install(runner.engine, edit)
            # stderr: above the status line when rich's Live draws one
            print(edit.summary() if edit.accepted else edit.report(), file=sys.stderr)

        runner.between_scans.append(online_edit)
    trend_problem = None
    try:
        _scan_until_the_end(runner, app, args)
    finally:
        runner.close()
        if recorder is not None:
            trend_problem = _close_recorder(recorder)
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
    print_values(runner.table, args.print, app.program.symbols)
    if engine.mode is Mode.FAULTED:
        print(f"softplc: {app.name}: {engine.fault}", file=sys.stderr)
        return EXIT_FAULT
    if runner.replay_differences:
        count = runner.replay_differences
        print(f"softplc: {app.name}: --replay: the program's output differed from the recording "
              f"({count} difference{'s' if count != 1 else ''}, listed above)", file=sys.stderr)
        return EXIT_REPLAY
    if trend_problem is not None:
        print(f"error: {trend_problem}", file=sys.stderr)
    return EXIT_ERROR if storage_problems or trend_problem else EXIT_OK


def _close_recorder(recorder) -> str | None:
    """Finish the trend file; what went wrong writing it, or None."""
    from ..trends.record import TrendFileError

    try:
        recorder.close()
    except TrendFileError as e:
        return str(e)
    return None


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

    handle_signals({signal.SIGINT: stop, signal.SIGTERM: stop})
    try:
        _run_with_status(runner, app, args.scans, unbounded=args.scans is None and args.replay is None)
    finally:
        handle_signals({signal.SIGTERM: signal.SIG_IGN, signal.SIGINT: signal.SIG_IGN})


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
