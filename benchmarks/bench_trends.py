"""Trend recording's cost to the scan: scans a second with 20 addresses
recorded every scan (CSV and VCD, ``softplc run --trend-file``'s
BackgroundRecorder) against the same app with no recording, in the same
run, rounds interleaved.

    python benchmarks/bench_trends.py           # about 40 s
    python benchmarks/bench_trends.py --quick   # about 10 s (results not written)

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
median of the rounds' ratios; the wall-clock ratio is printed beside it. Writes benchmarks/results/bench_trends.json (not with
--quick); exits 1 when the target is missed.
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
from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.trends.background import BackgroundRecorder
from softplc_lite.trends.series import resolve_series

ADDRESSES = [f"N10:{k}" for k in range(0, 85, 5)] + ["B3/2", "T4:1.ACC", "F8:0"]
TARGET = 0.95
FULL = {"rounds": 7, "scans": 40_000}
QUICK = {"rounds": 3, "scans": 10_000}


def scan_rate(app: Path, scans: int, record: str | None, work: Path) -> tuple[float, float]:
    """(scans a second on the wall clock, scans a second of the scan
    thread's own CPU time)."""
    runner = Runner(load_app(app), RunOptions(fresh=True, save_state=False))
    recorder = None
    if record is not None:
        series = resolve_series(ADDRESSES, runner.table, runner.app.program.symbols)
        recorder = BackgroundRecorder(runner.table, series, work / f"trend.{record}", "bench", "simulated",
                                      follow=False)  # as softplc run records on simulated time
        runner.after_scan.append(recorder.after_scan)
    runner.run(2_000)  # warm: the compiled rungs, the caches
    t0, c0 = time.perf_counter(), time.thread_time()
    runner.run(scans)
    elapsed, cpu = time.perf_counter() - t0, time.thread_time() - c0
    if recorder is not None:
        recorder.close()  # outside the timing: the run's end waits for the writer
        assert recorder.rows == scans + 2_000, recorder.rows
    runner.close()
    return scans / elapsed, scans / cpu


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json")
    args = ap.parse_args()
    cfg = QUICK if args.quick else FULL
    with tempfile.TemporaryDirectory(prefix="bench_trends_") as tmp:
        work = Path(tmp)
        app = make_app(work / "app", ladder() + "MOV N10:1 F8:0\n")
        rates: dict[str, list[float]] = {"off": [], "csv": [], "vcd": []}
        cpu_rates: dict[str, list[float]] = {"off": [], "csv": [], "vcd": []}
        for rnd in range(cfg["rounds"]):
            order = ["off", "csv", "vcd"] if rnd % 2 == 0 else ["vcd", "csv", "off"]
            for kind in order:
                wall, cpu = scan_rate(app, cfg["scans"], None if kind == "off" else kind, work)
                rates[kind].append(wall)
                cpu_rates[kind].append(cpu)
    ratios = {kind: [r / off for r, off in zip(rates[kind], rates["off"])] for kind in ("csv", "vcd")}
    cpu_ratios = {kind: [r / off for r, off in zip(cpu_rates[kind], cpu_rates["off"])] for kind in ("csv", "vcd")}
    print(f"scans a second, {len(ADDRESSES)} addresses recorded every scan vs none "
          f"({cfg['rounds']} rounds of {cfg['scans']:,} scans; median [min..max])")
    for title, table, rat in (("wall clock (the writer process shares the machine's two cores)", rates, ratios),
                              ("the scan thread's own CPU time (the scan's work alone)", cpu_rates, cpu_ratios)):
        print(f" {title}:")
        for kind in ("off", "csv", "vcd"):
            xs = table[kind]
            line = f"  {kind:<4} {statistics.median(xs):10,.0f} [{min(xs):,.0f}..{max(xs):,.0f}]"
            if kind != "off":
                r = rat[kind]
                line += f"   recording / none {statistics.median(r):.3f} [{min(r):.3f}..{max(r):.3f}]"
            print(line)
    off_us = 1e6 / statistics.median(cpu_rates["off"])
    added = {k: 1e6 / statistics.median(cpu_rates[k]) - off_us for k in ("csv", "vcd")}
    print(f" recording adds {added['csv']:.2f} us (csv) and {added['vcd']:.2f} us (vcd) to a {off_us:.1f} us scan; "
          f"5% of a scan is reached from a {max(added.values()) / 0.05:.0f} us scan up (a 10 ms real-time scan: "
          f"{100 * max(added.values()) / 10_000:.3f}%)")
    verdict = {kind: statistics.median(r) >= TARGET for kind, r in cpu_ratios.items()}
    print(f"target: recording at most 5% slower in the scan's own time (ratio >= {TARGET}): "
          + ", ".join(f"{k} {'PASS' if ok else 'MISS'}" for k, ok in verdict.items())
          + "; on the wall clock: " + ", ".join(f"{k} {statistics.median(r):.3f}" for k, r in ratios.items()))
    figures = {"rates": rates, "ratios": ratios, "cpu_rates": cpu_rates, "cpu_ratios": cpu_ratios, "added_us": added,
               "target": TARGET, "verdict": verdict, "config": cfg}
    C.save_figures("bench_trends", figures, args.quick, args.json)
    return 0 if all(verdict.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
