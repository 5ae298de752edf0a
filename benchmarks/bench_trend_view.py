"""Trend panel benchmark: what the watch view's trend panel costs a scan
and a redraw (docs/trends.md, "The trend panel").

    python benchmarks/bench_trend_view.py        # about 20 s

The app: programs/tank, fresh, simulated time, no state directory, the
trend Level, Valve and AtSetpoint (a word, a word, a bit) plus LevelF and
Percent (two floats), five series.

1. Per scan: ``WatchSession.scan()`` on two sessions of the same app, one
   with the trend open and one without, interleaved rounds
   (``_common.sample_rounds``, GC paused), ns per scan; and the panel's
   frame reads counted across the scans (they must be none: the panel reads
   the history when it is drawn).
2. Per redraw: the panel alone at 120 columns (14 lines) rendered into a
   rich Console (truecolor, ANSI, to an ``io.StringIO``): cold (every frame
   of the window read: the first draw, or after the series changed) and
   warm (10 scans since the last draw: what a redraw costs while running
   at 100 scans/s and 10 redraws/s); and the whole 120x40 screen with and
   without the panel.
3. The view running at full speed: ``ViewLoop.tick`` (terminal.py's loop
   without a terminal, the screen drawn into a 120x40 rich Console) with
   the trend open against without, interleaved windows of WINDOW_S:
   scans per wall second and redraws per second (the drawing budget keeps
   drawing to 4% of the wall time, so a slower draw means fewer redraws,
   not fewer scans).
"""

from __future__ import annotations

import io
import statistics
import time

import _common as C
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.screen import WatchScreen, rung_view
from softplc_lite.watch.session import SPEEDS, WatchOptions, WatchSession
from softplc_lite.watch.terminal import ViewLoop
from softplc_lite.watch.trendview import TrendPanel, panel_height

APP = C.REPO / "programs" / "tank"
TREND = ("Level", "Valve", "AtSetpoint", "LevelF", "Percent")
WIDTH, HEIGHT = 120, 40
WARMUP = 1500  # scans: the history full (1,000 frames), dropping the oldest as in a long session
ROUNDS = 11
SCANS = 2000  # a sample of the scan loop
WINDOW_S = 0.5  # of the view loop, per round


def _session(trend: tuple[str, ...]) -> WatchSession:
    app = load_app(APP)
    app.state_dir = None
    session = WatchSession(app, WatchOptions(run=RunOptions(fresh=True), trend=trend, online=False))
    for _ in range(WARMUP):
        session.scan()
    return session


def _console() -> Console:
    return Console(width=WIDTH, height=HEIGHT, file=io.StringIO(), color_system="truecolor", force_terminal=True,
                   legacy_windows=False)


def _timed(body, times: int) -> float:
    """The median ms of ``times`` calls."""
    samples = []
    for _ in range(times):
        t0 = time.perf_counter_ns()
        body()
        samples.append((time.perf_counter_ns() - t0) / 1e6)
    return statistics.median(samples)


def _view_loop(session: WatchSession):
    """(tick the loop for ``seconds``: scans/s and redraws/s) of a view loop at full speed."""
    console = _console()
    redraws = [0]

    def draw(screen):
        console.file.seek(0)
        console.file.truncate()
        console.print(screen)
        redraws[0] += 1

    loop = ViewLoop(session, WatchScreen(session, rung_view), draw)
    session.speed = len(SPEEDS) - 1
    session.start()

    def window(seconds: float) -> tuple[float, float]:
        s0, r0 = session.engine.scans, redraws[0]
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            loop.tick(None)
        wall = time.perf_counter() - t0
        return (session.engine.scans - s0) / wall, (redraws[0] - r0) / wall
    window(0.3)  # the first draws, rich's caches
    return window


def view_rounds() -> dict:
    """Scans and redraws per second of the view at full speed, with and without the trend."""
    sessions = {"trend": _session(TREND), "none": _session(())}
    windows = {name: _view_loop(s) for name, s in sessions.items()}
    per = {name: [] for name in windows}
    names = list(windows)
    for r in range(ROUNDS):
        for name in names[r % 2:] + names[:r % 2]:
            per[name].append(windows[name](WINDOW_S))
    for s in sessions.values():
        assert s.running, s.message
        s.quit()
    scans = {name: [w[0] for w in per[name]] for name in names}
    return {"view_scans_per_s_with_trend": round(C.median(scans["trend"])),
            "view_scans_per_s_without": round(C.median(scans["none"])),
            "view_ratio": round(C.ratio(scans, "trend", "none"), 3),
            "view_redraws_per_s_with_trend": round(C.median([w[1] for w in per["trend"]]), 2),
            "view_redraws_per_s_without": round(C.median([w[1] for w in per["none"]]), 2)}


def main() -> None:
    with_trend, without = _session(TREND), _session(())

    def scans(session):
        return lambda number: [session.scan() for _ in range(number)]

    reads = with_trend.trend_cache.reads
    samples = C.sample_rounds({"trend": scans(with_trend), "none": scans(without)}, {"trend": SCANS, "none": SCANS},
                              ROUNDS)
    scan_reads = with_trend.trend_cache.reads - reads
    ns_trend, ns_none = C.median(samples["trend"]), C.median(samples["none"])

    console = _console()
    height = panel_height(with_trend, WIDTH, HEIGHT)
    panel = TrendPanel(with_trend, height)

    def cold():
        with_trend.trend_cache.series = ()  # forget every frame read: the next draw reads its whole window
        console.print(panel)

    def warm():
        for _ in range(10):
            with_trend.scan()
        t0 = time.perf_counter_ns()
        console.print(panel)
        return time.perf_counter_ns() - t0

    cold_ms = _timed(cold, 21)
    before = with_trend.trend_cache.reads
    warm_ms = statistics.median(warm() for _ in range(21)) / 1e6
    warm_reads = (with_trend.trend_cache.reads - before) / 21
    window = len(with_trend.trend_cache.kept)
    screen_trend = WatchScreen(with_trend, rung_view, measured=False)
    screen_none = WatchScreen(without, rung_view, measured=False)
    full_trend = _timed(lambda: console.print(screen_trend), 21)
    full_none = _timed(lambda: console.print(screen_none), 21)
    figures = {
        "series": len(TREND), "scan_ns_with_trend": round(ns_trend), "scan_ns_without": round(ns_none),
        "scan_ratio": round(C.ratio(samples, "trend", "none"), 3), "frame_reads_while_scanning": scan_reads,
        "panel_lines": height, "window_scans": window, "panel_cold_ms": round(cold_ms, 2),
        "panel_warm_ms": round(warm_ms, 2), "frames_read_per_warm_redraw": warm_reads,
        "screen_ms_with_trend": round(full_trend, 2), "screen_ms_without": round(full_none, 2),
    }
    with_trend.quit()
    without.quit()
    figures.update(view_rounds())
    for name, value in figures.items():
        print(f"{name:28} {value}")
    print(f"results: {C.write_results('bench_trend_view', figures)}")


if __name__ == "__main__":
    main()
