"""Trend recording's cost to the scan: scans a second with 20 addresses
recorded every scan (CSV and VCD, ``softplc run --trend-file``'s
BackgroundRecorder) against the same app with no recording, in the same
run, rounds interleaved.

    python benchmarks/bench_trends.py           # about 40 s
    python benchmarks/bench_trends.py --quick   # about 5 s (results not written)

The app is the Modbus server bench's 100 rungs over N10 (moves, adds,
compares, timers: a 20-30 us scan here), on simulated time so the scans run
back to back; the 20 addresses are 17 words of N10, a bit, a timer's ACC
and a float. The writer process formats beside the scan; the scan thread
only copies the raw values into a buffer and appends it to the spool every
512 rows. Two measures: scans a second on the wall clock, and in the scan
thread's own CPU time (what recording adds to the scan's work; on the wall
clock the writer process, busy formatting on the other core, also takes the
shared cores and caches from the scan on this 2-core machine). The target:
at most 5% slower (a ratio of at least 0.95) in the scan's own time, the
median of the rounds' ratios. The shipped apps are measured the same way
beside it (20 words of each app's data table; fewer rounds), for what a
real app's scan gives. Writes benchmarks/results/bench_trends.json (not
with --quick); exits 1 when the target is missed on the bench ladder.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import _common as C
from bench_modbus_server import ladder

from helpers.apps import make_app
from helpers.shipped_apps import copy_app
from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.trends.background import BackgroundRecorder
from softplc_lite.trends.series import resolve_series

ADDRESSES = [f"N10:{k}" for k in range(0, 85, 5)] + ["B3/2", "T4:1.ACC", "F8:0"]
TARGET = 0.95
FULL = {"rounds": 16, "scans": 20_000, "app_rounds": 10, "app_scans": 10_000}
QUICK = {"rounds": 4, "scans": 5_000, "app_rounds": 2, "app_scans": 2_000}
SHIPPED = ("modbus_slave", "tank", "modbus_master")
WORDS = 20


def words_of(table) -> list[str]:
    """WORDS addresses of an app's table: the first words of its N files,
    the largest first (the app's working data)."""
    found: list[str] = []
    for f in sorted((f for f in table.files() if f.ftype.letter == "N"), key=lambda f: -len(f.data)):
        found += [f"{f.name}:{k}" for k in range(min(len(f.data), WORDS - len(found)))]
    return found


def paired_rates(app: Path, kind: str, rounds: int, scans: int, work: Path,
                 addresses: list[str] | None = None) -> tuple[list, list]:
    """One runner, blocks of ``scans`` scans with and without the recording
    hook in turn (the same heap, the same caches, seconds apart: the noise of
    a shared machine falls on both): (scans a second of the scan thread's CPU
    time without, with), a pair a round."""
    runner = Runner(load_app(app), RunOptions(fresh=True, save_state=False))
    series = resolve_series(addresses or words_of(runner.table), runner.table, runner.app.program.symbols)
    recorder = BackgroundRecorder(runner.table, series, work / f"trend.{kind}", "bench", "simulated",
                                  follow=False)  # as softplc run records on simulated time
    hook = recorder.hook()
    runner.run(2_000)  # warm: the compiled rungs, the caches
    off, on = [], []
    for rnd in range(rounds):
        for recording in ((False, True) if rnd % 2 == 0 else (True, False)):
            if recording:
                runner.after_scan.append(hook)
            c0 = time.thread_time()
            runner.run(scans)
            rate = scans / (time.thread_time() - c0)
            (on if recording else off).append(rate)
            runner.after_scan.clear()
    recorder.close()  # the writer formats the spool: outside the timing
    runner.close()
    return off, on


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json")
    args = ap.parse_args()
    cfg = QUICK if args.quick else FULL
    with tempfile.TemporaryDirectory(prefix="bench_trends_") as tmp:
        work = Path(tmp)
        app = make_app(work / "app", ladder() + "MOV N10:1 F8:0\n")
        # the scan thread does the same for either format (the writer formats after a simulated run):
        # both measured, and judged together
        pairs = {kind: paired_rates(app, kind, cfg["rounds"], cfg["scans"], work, ADDRESSES)
                 for kind in ("csv", "vcd")}
        apps = {name: paired_rates(copy_app(name, work), "csv", cfg["app_rounds"], cfg["app_scans"], work)
                for name in SHIPPED}
    print(f"scans a second of the scan thread's CPU time, {len(ADDRESSES)} addresses recorded every scan against "
          f"none, in the same runner ({cfg['rounds']} rounds of {cfg['scans']:,} scans each way; median [min..max])")
    ratios, added, verdict = {}, {}, {}
    for kind, (off, on) in pairs.items():
        r = [b / a for a, b in zip(off, on)]
        ratios[kind] = r
        added[kind] = 1e6 / statistics.median(on) - 1e6 / statistics.median(off)
        verdict[kind] = statistics.median(r) >= TARGET
        print(f"  {kind}: none {statistics.median(off):,.0f}, recording {statistics.median(on):,.0f}: "
              f"recording / none {statistics.median(r):.3f} [{min(r):.3f}..{max(r):.3f}], "
              f"+{added[kind]:.2f} us to a {1e6 / statistics.median(off):.1f} us scan")
    every = [x for r in ratios.values() for x in r]
    verdict["both"] = statistics.median(every) >= TARGET
    print(f"  every round of both: recording / none {statistics.median(every):.3f}")
    print(f"the shipped apps, {WORDS} words each ({cfg['app_rounds']} rounds of {cfg['app_scans']:,} scans, CSV):")
    app_ratios = {}
    for name, (off, on) in apps.items():
        r = app_ratios[name] = [b / a for a, b in zip(off, on)]
        print(f"  {name}: recording / none {statistics.median(r):.3f} [{min(r):.3f}..{max(r):.3f}], "
              f"+{1e6 / statistics.median(on) - 1e6 / statistics.median(off):.2f} us to a "
              f"{1e6 / statistics.median(off):.1f} us scan")
    worst = max(added.values())
    print(f"  5% of a scan is reached from a {worst / 0.05:.0f} us scan up; of a 10 ms real-time scan it is "
          f"{100 * worst / 10_000:.3f}%")
    print(f"target: recording at most 5% slower (ratio >= {TARGET}): "
          + ", ".join(f"{k} {'PASS' if ok else 'MISS'}" for k, ok in verdict.items()))
    figures = {"pairs": pairs, "ratios": ratios, "apps": apps, "app_ratios": app_ratios, "added_us": added, "target": TARGET, "verdict": verdict,
               "config": cfg}
    C.save_figures("bench_trends", figures, args.quick, args.json)
    return 0 if verdict["both"] else 1


if __name__ == "__main__":
    sys.exit(main())
