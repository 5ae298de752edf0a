"""Retentive memory while running: what saving the data table
every 100 ms costs the Modbus master app.

    python benchmarks/bench_retentive.py
    python benchmarks/bench_retentive.py --quick      # a smoke run of a few seconds (results not written)
    python benchmarks/bench_retentive.py --json PATH  # also write the results to PATH

The app is programs/modbus_master as ``softplc run programs/modbus_master
--fresh`` runs it: compiled, simulated time (1 ms scans), its simulated
slave on the simulated wire; scans are free-running, so the saves' wall-clock
100 ms come around as often as they can.

1. Save cost for that app's table (after 3000 scans), in a temporary
   directory, each the median of SAVE_REPEATS: ``snapshot.encode`` (what the
   scan thread does between two scans), ``snapshot.write`` not durable (temp
   file + rename: a periodic save, done by the writer thread), durable (+
   fsync, the ``.prev`` link, the directory fsync: one periodic save in 5 s
   and the final one); baseline: ``snapshot.save`` (what every save did
   before, every 5 s). And ``Retentive.tick``, the whole cost to the scan
   thread of one save (encode + hand-over to the writer thread).
2. Scans per second of the app with ``save_ms = 100`` against ``save_ms = 0``
   (no periodic saves), two runners in one process, ROUNDS interleaved rounds
   of SCANS scans (as ``benchmarks/_common.sample_rounds``: the order rotates,
   the garbage collector paused); the ratio is the median of the per-round
   ratios. Target: >= 0.95. Beside it the same ratio of the process's CPU
   time per scan (every thread), which other jobs on the machine move far
   less than the wall clock. A third runner, also ``save_ms = 0``, gives the
   same-run noise floor (the A/A ratio of two identical runners: how far
   from 1.0 this shared machine puts a ratio that should be 1.0). Also the
   saves made, and how long each took
   from encoding to the rename on disk (the writer's lag: it decides how
   much older than 100 ms the last snapshot on disk can be; see
   docs/engine.md).

Writes benchmarks/results/bench_retentive.json (not with --quick); a miss
is reported, never turned into a non-zero exit status.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import _common as C

from softplc_lite.app import load_app
from softplc_lite.datatable import snapshot
from softplc_lite.runner import RunOptions, Runner

NAME = "bench_retentive"
APP = C.REPO / "programs" / "modbus_master"
SAVE_REPEATS = 200
ROUNDS = 20
SCANS = 20000  # per round: about 0.25-0.3 s here, two or three saves
TARGET_RATIO = 0.95


def runner(state: Path, save_ms: int) -> Runner:
    app = load_app(APP, state)
    app.settings.save_ms = save_ms
    return Runner(app, RunOptions(fresh=True), log=lambda msg: print(f"  log: {msg}"))


def median_us(fn, repeats: int) -> float:
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter_ns()
        fn()
        samples.append(time.perf_counter_ns() - t0)
    return statistics.median(samples) / 1000


def bench_save_cost(tmp: Path, repeats: int) -> dict:
    r = runner(tmp / "cost", 0)
    r.run(3000)
    table = r.table
    data = snapshot.encode(table)
    path = tmp / "cost" / "datatable.snap"
    snapshot.write(data, path, True)  # a NAME and a .prev exist from here on: the steady state
    us = {
        "encode": median_us(lambda: snapshot.encode(table), repeats * 10),
        "write": median_us(lambda: snapshot.write(data, path, False), repeats),
        "write_durable": median_us(lambda: snapshot.write(data, path, True), repeats // 4),
        "baseline_save": median_us(lambda: snapshot.save(table, path), repeats // 4),
    }
    # The scan thread's share: Retentive.tick (encode + hand the bytes to the writer thread).
    ticker = runner(tmp / "tick", 100)
    ticker.run(3000)
    ret = ticker.retentive
    tick = []
    for _ in range(repeats):
        t0 = time.perf_counter_ns()
        ret.tick(ticker.table, time.monotonic())
        tick.append(time.perf_counter_ns() - t0)
        time.sleep(0.002)  # let the writer write it, as between two real saves
    us["tick"] = statistics.median(tick) / 1000
    ticker.finish()
    r.finish()
    print(f"1. save cost, the modbus_master table ({len(data)} bytes), median us:")
    print(f"   encode (scan thread, between two scans)       {us['encode']:9.1f}")
    print(f"   Retentive.tick: the scan thread's whole share {us['tick']:9.1f}")
    print(f"   write, not durable (writer thread)            {us['write']:9.1f}")
    print(f"   write, durable: fsync, .prev, dir fsync       {us['write_durable']:9.1f}")
    print(f"   baseline: snapshot.save (each save before)    {us['baseline_save']:9.1f}")
    per_100ms = (us["encode"] + us["write"]) / 100_000
    print(f"   encode + write per 100 ms: {100 * per_100ms:.2f}% of one CPU; the scan thread's share "
          f"{100 * us['tick'] / 100_000:.3f}%")
    return {"snapshot_bytes": len(data), "us_median": {k: round(v, 1) for k, v in us.items()}}


def sample_wall_and_cpu(bodies: dict, scans: int, rounds: int) -> tuple[dict, dict]:
    """``_common.sample_rounds`` measuring two things per call: wall-clock
    ns per scan, and the process's CPU ns per scan (``time.process_time``:
    every thread, so the writer thread's work counts too, wherever it ran).
    The CPU figure does not move when other jobs take this machine's CPUs
    away, which the wall-clock one does."""
    import gc

    for body in bodies.values():
        body(scans)  # warm-up
    names = list(bodies)
    wall: dict[str, list[float]] = {n: [] for n in names}
    cpu: dict[str, list[float]] = {n: [] for n in names}
    gc.collect()
    gc.disable()
    try:
        for r in range(rounds):
            for name in names[r % len(names):] + names[:r % len(names)]:
                t0, c0 = time.perf_counter_ns(), time.process_time_ns()
                bodies[name](scans)
                wall[name].append((time.perf_counter_ns() - t0) / scans)
                cpu[name].append((time.process_time_ns() - c0) / scans)
    finally:
        gc.enable()
    return wall, cpu


def bench_throughput(tmp: Path, rounds: int, scans: int) -> dict:
    saving, plain, twin = runner(tmp / "save100", 100), runner(tmp / "save0", 0), runner(tmp / "twin", 0)
    ret = saving.retentive
    paused_at: list[float] = []

    def save100(n: int) -> None:
        # As if it had run on without the other runners' rounds in between: the
        # wall-clock time it spent paused does not count towards its next save
        # (otherwise a save would fall due at the start of every round).
        if paused_at:
            paused = time.monotonic() - paused_at.pop()
            ret.due += paused
            ret._last_durable += paused
        saving.run(n)
        paused_at.append(time.monotonic())

    try:
        bodies = {"save_ms=100": save100, "save_ms=0": plain.run, "save_ms=0 (A/A twin)": twin.run}
        samples, cpu = sample_wall_and_cpu(bodies, scans, rounds)
        ret._collect()
        lags = [w * 1000 for w in ret._latencies]
    finally:
        problems = saving.finish() + plain.finish() + twin.finish()
    if problems:
        raise SystemExit(f"{NAME}: a save failed: {problems}")
    per_s = {k: 1e9 / C.median(v) for k, v in samples.items()}
    # ns per scan, plain / saving = scans per second, saving / plain
    ratio = C.ratio(samples, "save_ms=0", "save_ms=100")
    noise = C.ratio(samples, "save_ms=0", "save_ms=0 (A/A twin)")
    cpu_ratio = C.ratio(cpu, "save_ms=0", "save_ms=100")
    cpu_noise = C.ratio(cpu, "save_ms=0", "save_ms=0 (A/A twin)")
    cpu_us = {k: C.median(v) / 1000 for k, v in cpu.items()}
    wall = sum(samples["save_ms=100"]) * scans / 1e9
    verdict = "PASS" if ratio >= TARGET_RATIO else "MISS"
    noisy = abs(noise - 1) > 1 - TARGET_RATIO  # the twins differ by more than the margin
    print(f"2. modbus_master, {rounds} rounds x {scans} scans, median:   scans/s   CPU us/scan (all threads)")
    print(f"   save_ms=100                            {per_s['save_ms=100']:10,.0f}   {cpu_us['save_ms=100']:8.2f}")
    print(f"   save_ms=0 (baseline: no periodic saves) {per_s['save_ms=0']:9,.0f}   {cpu_us['save_ms=0']:8.2f}")
    print(f"   save_ms=0 (its twin)                   {per_s['save_ms=0 (A/A twin)']:10,.0f}   "
          f"{cpu_us['save_ms=0 (A/A twin)']:8.2f}")
    print(f"   ratio {ratio:.3f} (scans/s, median of per-round ratios)  {verdict} >= {TARGET_RATIO}; "
          f"A/A ratio of the twins {noise:.3f} (the noise floor)")
    print(f"   CPU ratio {cpu_ratio:.3f} (baseline CPU per scan / saving CPU per scan); A/A {cpu_noise:.3f}")
    if noisy:
        print(f"   NOISY: the twins differ by more than the {1 - TARGET_RATIO:.0%} margin; the machine is too busy "
              f"for this ratio to mean much: run again when it is quiet")
    print(f"   saves written {ret.saves} in {wall:.1f} s of save_ms=100 rounds ({ret.saves / wall:.1f}/s); "
          f"writer lag (encode to rename), "
          f"last {len(lags)}: median {statistics.median(lags):.2f} ms, max {max(lags):.2f} ms")
    return {"scans_per_s": {k: round(v) for k, v in per_s.items()}, "ratio": round(ratio, 4),
            "ratio_a_a": round(noise, 4), "cpu_us_per_scan": {k: round(v, 3) for k, v in cpu_us.items()},
            "cpu_ratio": round(cpu_ratio, 4), "cpu_ratio_a_a": round(cpu_noise, 4),
            "target": TARGET_RATIO, "verdict": verdict, "noisy": noisy, "rounds": rounds, "scans_per_round": scans,
            "saves": ret.saves, "lag_ms": {"median": round(statistics.median(lags), 2), "max": round(max(lags), 2)}}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run; results not written")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH")
    args = parser.parse_args()
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="softplc-bench-retentive-") as tmp:
        cost = bench_save_cost(Path(tmp), 40 if args.quick else SAVE_REPEATS)
        throughput = bench_throughput(Path(tmp), 6 if args.quick else ROUNDS, SCANS)
    figures = {"app": "programs/modbus_master", "save_cost": cost, "throughput": throughput,
               "wall_s": round(time.perf_counter() - t_start, 1)}
    C.save_figures(NAME, figures, args.quick, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
