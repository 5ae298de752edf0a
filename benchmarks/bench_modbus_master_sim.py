"""Modbus master app on simulated time: scans per second of
programs/modbus_master as shipped, against a baseline commit measured in
the same invocation.

    python benchmarks/bench_modbus_master_sim.py [--baseline COMMIT] [--runs N] [--scans N] [--quick]

The app runs as ``softplc run programs/modbus_master --fresh --scans N``
runs it: its own port 0 (the simulated 38400-baud wire to the simulated
slave), SimulatedClock of 1 ms, compiled executor, the shipped 50 ms poll
(``poll``) and also with ``T4:0.PRE=0`` (``back-to-back``: polls back to
back, the busiest the wire gets). A run is ``Runner.run(SCANS)`` timed with
``perf_counter`` in a fresh process (so each tree imports its own package).

The baseline is the commit given (default: the one before the issue-17
COMGENIUS/port work), checked out in a temporary ``git worktree`` that is
removed at the end. The two trees run interleaved (baseline, current,
baseline, current, ...) RUNS times per case; a figure is the median scans
per wall second, the ratio the median of the per-pair ratios current /
baseline, with its range; the best run of each tree and their ratio are
reported too (on a busy machine, the least disturbed figures). Every run
also reports the app's data table after the scans (the counters C5, the safe block N11, the clock); the two
trees must agree exactly, or the script fails.

Target: current / baseline >= 1.5 on the shipped app (the engine-speed
target, docs/performance.md).

Writes benchmarks/results/bench_modbus_master_sim.json (not with --quick);
exits 0, or 1 when the trees disagree.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import _common as C

BASELINE = "8c16f62"  # main before the issue-17 COMGENIUS, port and wire changes
RUNS = 9
SCANS = 50_000
TARGET = 1.5
CASES = {"poll": (), "back-to-back": ("T4:0.PRE=0",)}

# Run in a fresh interpreter inside one tree: time SCANS scans, print JSON.
CHILD = r"""
import hashlib, json, sys, time
sys.path.insert(0, sys.argv[1])
import softplc_lite
assert softplc_lite.__file__.startswith(sys.argv[1]), softplc_lite.__file__
from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
app = load_app(sys.argv[1] + "/programs/modbus_master", state_dir=None)
app.state_dir = None
r = Runner(app, RunOptions(fresh=True, sets=tuple(json.loads(sys.argv[3]))), log=lambda msg: None)
try:
    t0 = time.perf_counter()
    r.run(int(sys.argv[2]))
    wall = time.perf_counter() - t0
    t = r.table
    state = {"counters": [t.read(f"C5:{k}.ACC") for k in range(5)],
             "n11": [t.read(f"N11:{k}") for k in range(125)],
             "controls": [t.read(f"R6:{k}.LEN") for k in range(3)],
             "now_ms": r.engine.clock.now_ms}
finally:
    r.engine.close()
print(json.dumps({"wall_s": wall, "state": state}))
"""


def run_once(tree: Path, scans: int, sets: tuple[str, ...]) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(tree), str(scans), json.dumps(list(sets))],
                         cwd=tree, capture_output=True, text=True, timeout=600, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", default=BASELINE)
    ap.add_argument("--runs", type=int, default=RUNS)
    ap.add_argument("--scans", type=int, default=SCANS)
    ap.add_argument("--quick", action="store_true", help="3 runs of 5,000 scans; no results file")
    ap.add_argument("--json")
    args = ap.parse_args()
    runs, scans = (3, 5_000) if args.quick else (args.runs, args.scans)
    base_commit = subprocess.run(["git", "-C", str(C.REPO), "rev-parse", "--short", args.baseline],
                                 capture_output=True, text=True, check=True).stdout.strip()
    head = subprocess.run(["git", "-C", str(C.REPO), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True, check=True).stdout.strip()
    tmp = Path(tempfile.mkdtemp(prefix="bench_mm_sim_"))
    base_tree = tmp / "baseline"
    subprocess.run(["git", "-C", str(C.REPO), "worktree", "add", "--detach", "-q", str(base_tree), base_commit],
                   check=True)
    figures: dict = {"baseline": base_commit, "current": f"{head} (work tree)", "scans_per_run": scans,
                     "runs": runs, "target": TARGET, "cases": {}}
    failed = False
    try:
        print(f"programs/modbus_master, {scans:,} scans of 1 ms simulated, {runs} interleaved runs; "
              f"baseline {base_commit} vs the work tree ({head})")
        for case, sets in CASES.items():
            base_rates, new_rates, ratios = [], [], []
            for _ in range(runs):
                b = run_once(base_tree, scans, sets)
                n = run_once(C.REPO, scans, sets)
                if b["state"] != n["state"]:
                    print(f"  {case}: the trees disagree after {scans} scans:\n    baseline {b['state']}\n"
                          f"    current  {n['state']}")
                    failed = True
                base_rates.append(scans / b["wall_s"])
                new_rates.append(scans / n["wall_s"])
                ratios.append(new_rates[-1] / base_rates[-1])
            ratio = statistics.median(ratios)
            out = {
                "baseline_scans_per_s": round(statistics.median(base_rates)),
                "baseline_range": [round(min(base_rates)), round(max(base_rates))],
                "current_scans_per_s": round(statistics.median(new_rates)),
                "current_range": [round(min(new_rates)), round(max(new_rates))],
                "ratio": round(ratio, 2),
                "ratio_range": [round(min(ratios), 2), round(max(ratios), 2)],
                # on a busy machine the best run of each is the least disturbed
                "baseline_best": round(max(base_rates)),
                "current_best": round(max(new_rates)),
                "ratio_of_bests": round(max(new_rates) / max(base_rates), 2),
                "counters": n["state"]["counters"],
            }
            if case == "poll":
                out["verdict"] = "PASS" if ratio >= TARGET else "MISS"
            figures["cases"][case] = out
            print(f"  {case:12s}: baseline {out['baseline_scans_per_s']:,} scans/s "
                  f"({out['baseline_range'][0]:,}-{out['baseline_range'][1]:,}), current "
                  f"{out['current_scans_per_s']:,} ({out['current_range'][0]:,}-{out['current_range'][1]:,}); "
                  f"ratio {ratio:.2f}x ({out['ratio_range'][0]}-{out['ratio_range'][1]}), "
                  f"of the best runs {out['ratio_of_bests']:.2f}x"
                  + (f" [{out['verdict']} >= {TARGET}]" if "verdict" in out else "")
                  + f"; counters {out['counters']}", flush=True)
    finally:
        subprocess.run(["git", "-C", str(C.REPO), "worktree", "remove", "--force", str(base_tree)], check=True)
        Path(tmp).rmdir()
    C.save_figures("bench_modbus_master_sim", figures, args.quick, args.json)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
