"""``softplc watch``: build the session from the command line, then either
render one snapshot (no terminal needed) or run the interactive view."""

from __future__ import annotations

import io
import sys

from rich.console import Console

from ..app import load_app
from ..runner import RunOptions
from .screen import WatchScreen, rung_view
from .session import WatchOptions, WatchSession
from .watchlist import read_watch_file

EXIT_USAGE = 2


def watch_command(args) -> int:
    snapshot = args.snapshot
    if not snapshot and not (sys.stdin.isatty() and sys.stdout.isatty()):
        print("softplc watch: needs a terminal (standard input and output are not one here); "
              "render the view to a file instead: softplc watch APP --scans N --snapshot view.txt "
              "(or view.svg)", file=sys.stderr)
        return EXIT_USAGE
    if args.scans < 0 or args.width < 40 or args.height < 12:
        raise SystemExit("softplc watch: error: --scans must be 0 or more, --width at least 40, --height at least 12")
    app = load_app(args.app, args.state)
    watch = list(args.watch) + (read_watch_file(args.watch_file) if args.watch_file else [])
    run = RunOptions(scan_ms=args.scan_ms, realtime=args.realtime, fresh=args.fresh, sets=tuple(args.set),
                     ports=tuple(args.port), replay=args.replay)
    options = WatchOptions(run=run, watch=tuple(watch), forces=tuple(args.force), break_when=tuple(args.break_when))
    session = WatchSession(app, options)
    try:
        if snapshot:
            for _ in range(args.scans):
                session.scan()
                if session.last_hit is not None:
                    break
            write_snapshot(session, snapshot, args.width, args.height)
            return 0
        from .terminal import run_terminal

        return run_terminal(session, rung_view)
    finally:
        session.quit()


def render(session: WatchSession, width: int, height: int, measured: bool = False) -> Console:
    """The view of ``session`` at ``width`` x ``height``, recorded (export it
    with ``export_text()`` or ``save_svg()``). The status bar shows the
    status file's scan times (S:8, S:9) unless ``measured``: on simulated
    time a snapshot is then the same on every machine."""
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
