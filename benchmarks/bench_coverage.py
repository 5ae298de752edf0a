"""Coverage overhead: scan time with ``softplc test --coverage`` measuring
against without it, in the same run.

    python benchmarks/bench_coverage.py             # about 30 s
    python benchmarks/bench_coverage.py --quick     # a few rounds, no results file
    python benchmarks/bench_coverage.py --profile   # where a recorded scan's time goes (cProfile)

Three shipped apps, each loaded as a scenario gets it (fresh, simulated
time, no state saved): programs/motor (a seal-in with a branch, counters,
a timer; the motor held running), programs/tank (a PID and CPT
arithmetic) and programs/subroutines (JSR every scan, nested JSRs, a JMP).
Three loops per app, each on a PLC of its own:

1. ``off``: coverage off, ``PLC.load(app)``: the compiled code, the fast
   path every run without coverage takes (and the plain engine: the same
   code ``softplc run`` scans);
2. ``reference``: the reference interpreter without recording
   (``executor="reference"``): what coverage's choice of executor costs by
   itself;
3. ``on``: ``PLC.load(app, coverage=Coverage())``: the reference
   interpreter through the recording subclass (testing/coverage.py).

Each body runs SCANS scans. Method: ``_common.sample_rounds``: ROUNDS
rounds, the loops interleaved and their order rotating, the garbage
collector paused; figures are medians of us per scan, ratios medians of
the per-round ratios (scan time over scan time: how many times slower).
There is no target: coverage runs only when asked for; the figures say
what asking costs, and the ``on / reference`` ratio is the recording's
own share. With coverage off no code of the recorder runs at all
(tests/test_coverage.py checks that no recorder exists), so ``off`` is the
plain compiled engine.
"""

from __future__ import annotations

import sys
import tempfile
import time

import _common as C

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.testing.coverage import Coverage
from softplc_lite.testing.plc import PLC

NAME = "bench_coverage"
SCANS = 2000
ROUNDS = 15
APPS = {"motor": {"StopOk": 1, "Start": 1}, "tank": {}, "subroutines": {}}
KINDS = ("off", "reference", "on")


def _plc(app: str, kind: str) -> PLC:
    path = C.REPO / "programs" / app
    if kind == "off":
        return PLC.load(path)
    if kind == "on":
        return PLC.load(path, coverage=Coverage())
    state_dir = tempfile.mkdtemp(prefix="bench-coverage-")
    runner = Runner(load_app(path, state_dir=state_dir),
                    RunOptions(fresh=True, save_state=False, executor="reference"), log=lambda msg: None)
    return PLC(runner, state_dir)


class Loop:
    def __init__(self, app: str, kind: str) -> None:
        self.plc = _plc(app, kind)
        for name, value in APPS[app].items():
            self.plc.set(name, value)
        self.plc.scan(1)

    def body(self, n: int) -> None:
        scan = self.plc.engine.scan
        for _ in range(n):
            scan()

    def close(self) -> None:
        self.plc.close()


def measure(rounds: int) -> dict:
    loops = {f"{app} {kind}": Loop(app, kind) for app in APPS for kind in KINDS}
    try:
        samples = C.sample_rounds({k: loop.body for k, loop in loops.items()}, {k: SCANS for k in loops}, rounds)
        for loop in loops.values():
            assert loop.plc.engine.fault is None, loop.plc.engine.fault
    finally:
        for loop in loops.values():
            loop.close()
    figures: dict = {"apps": {}}
    for app in APPS:
        row = {kind: {"us_per_scan": round(C.median(samples[f"{app} {kind}"]) / 1e3, 2)} for kind in KINDS}
        row["on_over_off"] = round(C.ratio(samples, f"{app} on", f"{app} off"), 2)
        row["reference_over_off"] = round(C.ratio(samples, f"{app} reference", f"{app} off"), 2)
        row["on_over_reference"] = round(C.ratio(samples, f"{app} on", f"{app} reference"), 2)
        figures["apps"][app] = row
    return figures


def profile(app: str = "motor", scans: int = 20000) -> None:
    loop = Loop(app, "on")
    try:
        C.print_profile(lambda: loop.body(scans), f"programs/{app} with coverage, {scans} scans")
    finally:
        loop.close()


def main() -> int:
    args = sys.argv[1:]
    if "--profile" in args:
        for app in APPS:
            profile(app)
        return 0
    quick = "--quick" in args
    rounds = 3 if quick else ROUNDS
    t_start = time.perf_counter()
    figures = measure(rounds)
    wall = time.perf_counter() - t_start
    print(f"--- {NAME}: simulated scans; {rounds} rounds of {SCANS} scans a loop, interleaved")
    for app, row in figures["apps"].items():
        print(f"programs/{app}: off (compiled) {row['off']['us_per_scan']:.2f} us/scan, reference "
              f"{row['reference']['us_per_scan']:.2f}, coverage on {row['on']['us_per_scan']:.2f}")
        print(f"  on / off {row['on_over_off']:.2f}x   reference / off {row['reference_over_off']:.2f}x   "
              f"on / reference {row['on_over_reference']:.2f}x (the recording's own cost)")
    C.save_figures(NAME, {"method": {"rounds": rounds, "scans_per_call": SCANS, "gc": "paused",
                                     "figures": "medians over the rounds; ratios: median of per-round ratios"},
                          **figures, "wall_s": round(wall, 1)},
                   quick, None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
