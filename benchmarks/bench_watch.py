"""Watch view benchmark: what ``softplc watch`` running at full
speed costs the scan loop, against ``softplc run``.

    python benchmarks/bench_watch.py             # about 25 s
    python benchmarks/bench_watch.py --profile   # and where the view's time goes (cProfile)

The app everywhere: programs/modbus_master as shipped but for ``T4:0.PRE=0``
(it polls back to back), fresh, simulated time (1 ms scans), no state
directory (nothing saved), compiled executor; its port 0 is the simulated
38400-baud wire to the simulated slave, so every scan does real work (the
COMSCANs match, the counters count, bytes move). Three loops, each on an
engine of its own:

1. ``run``: ``Runner.run(CHUNK)`` called again and again: ``softplc run``'s
   loop, free-running;
2. ``session``: ``WatchSession.scan()`` in a loop: a scan plus the view's
   per-scan work (history record, watch list sample, breakpoint check),
   nothing drawn;
3. ``view``: the interactive loop without a terminal:
   ``ViewLoop(session, WatchScreen(session, rung_view), draw).tick(None)``
   in a loop after ``session.start()`` at full speed
   (``session.speed = len(SPEEDS) - 1``), where ``draw`` renders the screen
   into a 120x40 rich Console (truecolor, ANSI) writing to an
   ``io.StringIO``, as a terminal would get it. Watch list: N11:0 and
   C5:1.ACC.

Method: every engine first runs WARMUP scans (more than the history's
1,000, so it records and drops frames as in a long session). Then ROUNDS
rounds; in each, every loop (the order rotates every round) runs for
WINDOW_S of wall time and its scans per second are taken from its scan
counter. Figures are medians over the rounds; a ratio is the median of the
per-round ratios, so a slow spell of the shared machine lands on both
sides. The garbage collector is left on: the history's allocations and the
collections they cause are part of the view's cost. The view's redraws are
counted and timed (ms per redraw, share of wall time spent drawing).
Target: the view costs at most 20% of ``run``'s scan throughput
(view / run >= 0.80). A miss is reported, not failed; the script exits 0.

The parts (``_common.sample_rounds``, GC paused, ns per call): one
``History.record``, one ``WatchList.sample`` (2 addresses), one
``Breakpoints.after_scan`` (none set), one draw.
"""

from __future__ import annotations

import cProfile
import io
import pstats
import sys
import time

import _common as C
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.watch.screen import WatchScreen, rung_view
from softplc_lite.watch.session import SPEEDS, WatchOptions, WatchSession
from softplc_lite.watch.terminal import REDRAW_HZ, ViewLoop

APP = C.REPO / "programs" / "modbus_master"
SETS = ("T4:0.PRE=0",)
WATCH = ("N11:0", "C5:1.ACC")
WIDTH, HEIGHT = 120, 40
WARMUP = 1500
WINDOW_S = 0.6
ROUNDS = 11
CHUNK = 200  # scans per Runner.run call (about 10 ms)
TARGET_RATIO = 0.80


def _app():
    app = load_app(APP)
    app.state_dir = None  # nothing saved, ever
    return app


def _options() -> RunOptions:
    return RunOptions(fresh=True, sets=SETS)


class Drawer:
    """``draw`` for the ViewLoop: the screen rendered as a 120x40 terminal
    would receive it (ANSI escapes into a StringIO, emptied every draw)."""

    def __init__(self) -> None:
        self.out = io.StringIO()
        self.console = Console(width=WIDTH, height=HEIGHT, file=self.out, force_terminal=True,
                               color_system="truecolor", legacy_windows=False)
        self.seconds = 0.0
        self.count = 0
        self.chars = 0

    def __call__(self, screen) -> None:
        t0 = time.perf_counter()
        self.out.seek(0)
        self.out.truncate()
        self.console.print(screen)
        self.seconds += time.perf_counter() - t0
        self.count += 1
        self.chars = self.out.tell()


class RunLoop:
    name = "run"

    def __init__(self) -> None:
        self.runner = Runner(_app(), _options())
        self.engine = self.runner.engine
        self.runner.run(WARMUP)

    def window(self, seconds: float) -> dict:
        engine, run = self.engine, self.runner.run
        s0 = engine.scans
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            run(CHUNK)
        wall = time.perf_counter() - t0
        return {"scans_per_s": (engine.scans - s0) / wall}


class SessionLoop:
    name = "session"

    def __init__(self) -> None:
        self.session = WatchSession(_app(), WatchOptions(run=_options(), watch=WATCH))
        self.engine = self.session.engine
        for _ in range(WARMUP):
            self.session.scan()

    def window(self, seconds: float) -> dict:
        engine, scan = self.engine, self.session.scan
        s0 = engine.scans
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            for _ in range(CHUNK):
                scan()
        wall = time.perf_counter() - t0
        return {"scans_per_s": (engine.scans - s0) / wall}


class ViewLoopCase:
    name = "view"

    def __init__(self) -> None:
        self.session = session = WatchSession(_app(), WatchOptions(run=_options(), watch=WATCH))
        self.engine = session.engine
        for _ in range(WARMUP):
            session.scan()
        self.drawer = Drawer()
        self.loop = ViewLoop(session, WatchScreen(session, rung_view), self.drawer)
        session.speed = len(SPEEDS) - 1  # full speed
        session.start()
        self.window(0.3)  # first draws, rich's caches

    def window(self, seconds: float) -> dict:
        engine, tick, d = self.engine, self.loop.tick, self.drawer
        s0, r0, draw0 = engine.scans, d.count, d.seconds
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            tick(None)
        wall = time.perf_counter() - t0
        assert self.session.running, self.session.message  # no fault, no breakpoint
        redraws = d.count - r0
        return {"scans_per_s": (engine.scans - s0) / wall, "redraws_per_s": redraws / wall,
                "ms_per_redraw": 1000 * (d.seconds - draw0) / max(redraws, 1),
                "drawing_share": (d.seconds - draw0) / wall}


def measure_loops() -> dict:
    cases = [RunLoop(), SessionLoop(), ViewLoopCase()]
    names = [c.name for c in cases]
    per: dict[str, list[dict]] = {n: [] for n in names}
    for r in range(ROUNDS):
        for case in cases[r % len(cases):] + cases[:r % len(cases)]:
            per[case.name].append(case.window(WINDOW_S))
    good = {}
    for case in cases:
        table = case.engine.table
        # every loop did the app's work: good replies, no timeout, exception or garbage
        good[case.name] = table.read("C5:1.ACC")
        assert good[case.name] > 0 and not any(table.read(f"C5:{k}.ACC") for k in (2, 3, 4)), case.name
        if hasattr(case, "session"):
            case.session.quit()
        else:
            case.engine.close()
    sps = {n: [w["scans_per_s"] for w in per[n]] for n in names}
    view = per["view"]
    return {
        "good_replies": good,
        "scans_per_s": {n: round(C.median(sps[n])) for n in names},
        "scans_per_s_min_max": {n: [round(min(sps[n])), round(max(sps[n]))] for n in names},
        "ratio_view_over_run": round(C.ratio(sps, "view", "run"), 3),
        "ratio_session_over_run": round(C.ratio(sps, "session", "run"), 3),
        "ratio_view_over_session": round(C.ratio(sps, "view", "session"), 3),
        "redraws_per_s": round(C.median([w["redraws_per_s"] for w in view]), 2),
        "ms_per_redraw": round(C.median([w["ms_per_redraw"] for w in view]), 2),
        "drawing_share_of_wall": round(C.median([w["drawing_share"] for w in view]), 3),
        "us_per_scan": {n: round(1e6 / C.median(sps[n]), 1) for n in names},
    }


def measure_parts() -> dict:
    session = WatchSession(_app(), WatchOptions(run=_options(), watch=WATCH))
    for _ in range(WARMUP):
        session.scan()
    engine = session.engine
    drawer = Drawer()
    screen = WatchScreen(session, rung_view)
    drawer(screen)

    def record(n, h=session.history, e=engine):
        for _ in range(n):
            h.record(e.scans, e.clock.now_ms)

    def sample(n, w=session.watch, t=engine.table):
        for _ in range(n):
            w.sample(t)

    def breaks(n, b=session.breaks):
        for _ in range(n):
            b.after_scan()

    def draw(n, d=drawer, s=screen):
        for _ in range(n):
            d(s)

    samples = C.sample_rounds({"record": record, "sample": sample, "breaks": breaks, "draw": draw},
                              {"record": 2000, "sample": 2000, "breaks": 2000, "draw": 5}, 9)
    session.quit()
    return {
        "history_record_us": round(C.median(samples["record"]) / 1e3, 2),
        "watch_sample_us": round(C.median(samples["sample"]) / 1e3, 2),
        "breakpoints_after_scan_us": round(C.median(samples["breaks"]) / 1e3, 2),
        "draw_ms": round(C.median(samples["draw"]) / 1e6, 2),
        "draw_ansi_chars": drawer.chars,
        "data_files": len(engine.table.files()),
        "data_table_bytes": sum(len(f.data) * f.data.itemsize for f in engine.table.files()),
    }


def profile(seconds: float = 3.0) -> None:
    case = ViewLoopCase()
    prof = cProfile.Profile()
    prof.enable()
    case.window(seconds)
    prof.disable()
    case.session.quit()
    stats = pstats.Stats(prof)
    total = stats.total_tt
    print(f"--- cProfile of the view loop, {seconds:.0f} s (times under the profiler, total {total:.2f} s)")
    by_name = {}
    for (path, line, func), (_cc, _nc, tt, ct, _callers) in stats.stats.items():
        by_name[f"{path.split('softplc_lite/')[-1]}:{func}"] = (tt, ct)
    for key in ("watch/terminal.py:tick", "watch/session.py:run_for", "watch/session.py:scan",
                "ladder/engine.py:scan", "watch/history.py:record", "watch/watchlist.py:sample",
                "watch/breakpoints.py:after_scan", "bench_watch.py:__call__"):
        found = [v for k, v in by_name.items() if k.endswith(key)]
        if found:
            tt, ct = found[0]
            print(f"  {key:36} cumulative {ct:6.2f} s ({100 * ct / total:4.1f}%)")
    stats.sort_stats("tottime").print_stats(12)


def main() -> int:
    if "--profile" in sys.argv[1:]:
        profile()
        return 0
    t_start = time.perf_counter()
    loops = measure_loops()
    parts = measure_parts()
    wall = time.perf_counter() - t_start
    ok = loops["ratio_view_over_run"] >= TARGET_RATIO
    verdict = "PASS" if ok else "MISS"
    s = loops["scans_per_s"]
    print(f"--- programs/modbus_master, T4:0.PRE=0, simulated 1 ms scans; {ROUNDS} rounds of {WINDOW_S} s each")
    for name, label in (("run", "softplc run loop (Runner.run)"), ("session", "WatchSession.scan, nothing drawn"),
                        ("view", f"watch view, full speed, {WIDTH}x{HEIGHT} drawn")):
        lo, hi = loops["scans_per_s_min_max"][name]
        print(f"{label:36} {s[name]:8,} scans/s [{lo:,}..{hi:,}]  {loops['us_per_scan'][name]:6.1f} us/scan")
    print(f"view / run    {loops['ratio_view_over_run']:.3f}  = cost {100 * (1 - loops['ratio_view_over_run']):.1f}% "
          f"[{verdict}: cost <= {100 * (1 - TARGET_RATIO):.0f}%]")
    print(f"session / run {loops['ratio_session_over_run']:.3f}  (the per-scan work alone)")
    print(f"redraws {loops['redraws_per_s']:.2f}/s (at most {REDRAW_HZ}), {loops['ms_per_redraw']:.1f} ms each, "
          f"{100 * loops['drawing_share_of_wall']:.1f}% of the wall time")
    print(f"parts: History.record {parts['history_record_us']:.2f} us, WatchList.sample "
          f"{parts['watch_sample_us']:.2f} us, after_scan {parts['breakpoints_after_scan_us']:.2f} us per scan; "
          f"a draw {parts['draw_ms']:.1f} ms ({parts['draw_ansi_chars']:,} characters); table "
          f"{parts['data_files']} files, {parts['data_table_bytes']:,} bytes")
    path = C.write_results("bench_watch", {
        "app": "programs/modbus_master", "sets": list(SETS), "watch": list(WATCH), "screen": [WIDTH, HEIGHT],
        "method": {"window_s": WINDOW_S, "rounds": ROUNDS, "warmup_scans": WARMUP, "run_chunk": CHUNK,
                   "gc": "enabled", "figures": "medians over the rounds; ratios: median of per-round ratios"},
        **loops,
        "parts": parts,
        "target_ratio_view_over_run": TARGET_RATIO,
        "verdict": verdict,
        "wall_s": round(wall, 1),
    })
    print(f"wrote {path} ({wall:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
