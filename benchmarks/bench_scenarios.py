"""Scenario throughput: what the test runner (``softplc test``) costs on top
of the engine it drives.

    python benchmarks/bench_scenarios.py             # about 20 s
    python benchmarks/bench_scenarios.py --quick     # a few rounds, no results file
    python benchmarks/bench_scenarios.py --profile   # where the runner's time goes (cProfile)

Two shipped apps, each loaded once per loop with ``PLC.load`` (fresh,
simulated 10 ms scans, as a scenario gets it): programs/motor, the smallest
scan (so the runner's share is largest), and programs/tank (a PID, CPT
arithmetic). Four loops per app, each on a PLC of its own:

1. ``engine``: ``engine.scan()`` in a loop: the engine alone, the baseline
   (with the motor running, as it is in the scenarios but for one scan in 10
   or 100 of ``dense`` and ``expects``);
2. ``long``: a scenario of long steps (``scan 500``, ``run 5 s``) through
   ``runner.run_steps``: the runner's cost per scan;
3. ``expects``: a scenario with the steps an engineer writes, sets, edges
   and expectations every 50 scans or so (``EXPECTS``: about 160 steps per
   1,000 scans, twice programs/motor's own scenario files);
4. ``dense``: the same steps every 5 scans (``DENSE``), denser than any
   shipped file: the cost of a step itself (us a step, printed).

Each body runs ``REPEAT`` times its 1,000 scans (the scenarios' steps go on
from the state the last call left; each call must pass). Method:
``_common.sample_rounds``: ROUNDS rounds, the loops interleaved and their
order rotating, the garbage collector paused; figures are medians of ns per
scan, ratios medians of the per-round ratios. Target: the runner's own cost
at most 10% of the scan throughput (runner / engine >= 0.90) for ``long``
and ``expects``. A miss is reported, not failed; the script exits 0.

Apart: the fixed cost of one scenario (``PLC.load`` of the app, the names
checked, ``close``), which a scenario pays once whatever its length.
"""

from __future__ import annotations

import sys
import time

import _common as C

from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import check_names, run_steps
from softplc_lite.testing.scenario import parse_scenarios

NAME = "bench_scenarios"
TARGET_RATIO = 0.90
SCANS = 1000  # a body's scans per repeat
REPEAT = 5
ROUNDS = 21

LONG = {"motor": "setup:\n    set StopOk = 1\n    set Start = 1\n",
        "tank": ""}
LONG_STEPS = 'scenario "long":\n    scan 500\n    run 5 s\n'

# A block of steps of each app, its waits filled in per kind below.
_BLOCKS = {
    "motor": ("setup:\n    set StopOk = 1\n", """\
    set Start = 1
    scan 1
    expect rising Motor
    expect Motor == 1
    set Start = 0
    {wait}
    expect Motor == 1
    expect Tripped == 0
    {wait}
    expect Motor == 1
    expect FaultLamp == 0
    set StopOk = 0
    scan 1
    expect falling Motor
    expect Motor == 0
    set StopOk = 1
"""),
    "tank": ("", """\
    {half}
    expect Level between 0 and 4095
    expect Valve between 0 and 4095
    expect Percent within 60 of 50
    set Loop[2] = 2000
    {half}
    expect N7:1 == 2041
    expect Loop/9 == 0
"""),
}


def _blocks(wait: str, half: str, scans: int) -> dict:
    return {app: (setup, steps.format(wait=wait, half=half), scans) for app, (setup, steps) in _BLOCKS.items()}


# Blocks of 100 scans (10 blocks: 1,000 scans) with the steps of a scenario
# an engineer writes: about twice the steps a scan of programs/motor's own
# scenario files (86 steps per 1,000 scans; the shipped apps' files have 2 to 130).
EXPECTS = _blocks("run 490 ms", "scan 50", 100)
# The same kinds of step, 10 scans a block (100 blocks): far denser than any
# shipped file, to give the cost of a step itself.
DENSE = _blocks("scan 4", "scan 5", 10)
KINDS = ("long", "expects", "dense")
TARGETED = ("long", "expects")  # the target is for scenarios as written; dense gives the step's cost
APPS = tuple(EXPECTS)


def scenario_text(app: str, kind: str) -> str:
    if kind == "long":
        return LONG[app] + LONG_STEPS
    setup, block, scans = (EXPECTS if kind == "expects" else DENSE)[app]
    return setup + f'scenario "{kind}":\n' + block * (SCANS // scans)


class Loop:
    """One app on a PLC of its own; ``body(n)`` runs ``n`` scans (a multiple
    of SCANS) the way its kind says."""

    def __init__(self, app: str, kind: str) -> None:
        self.app, self.kind = app, kind
        self.plc = PLC.load(C.REPO / "programs" / app)
        if kind == "engine":  # the state the long scenario runs in (the motor running)
            setup = parse_scenarios(LONG[app] + 'scenario "setup":\n    scan 1\n')
            assert run_steps(self.plc, setup, setup.scenarios[0]) is None
        else:
            self.file = parse_scenarios(scenario_text(app, kind), f"<{app} {kind}>")
            check_names(self.file, self.plc)
            self.scenario = self.file.scenarios[0]
            self.steps = len(self.file.setup) + len(self.scenario.steps)

    def body(self, n: int) -> None:
        if self.kind == "engine":
            scan = self.plc.engine.scan
            for _ in range(n):
                scan()
            return
        plc, file, scenario = self.plc, self.file, self.scenario
        for _ in range(n // SCANS):
            s0 = plc.scan_number
            failure = run_steps(plc, file, scenario)
            assert failure is None, failure.report()
            assert plc.scan_number - s0 == SCANS, (self.app, self.kind, plc.scan_number - s0)


def fixed_cost_ms(app: str, times: int = 7) -> float:
    """Median ms of a scenario's fixed work: load, check the names, close."""
    file = parse_scenarios(scenario_text(app, "expects"), "<fixed>")
    samples = []
    for _ in range(times):
        t0 = time.perf_counter_ns()
        with PLC.load(C.REPO / "programs" / app) as plc:
            check_names(file, plc)
        samples.append((time.perf_counter_ns() - t0) / 1e6)
    return C.median(samples)


def measure(rounds: int) -> dict:
    loops = {f"{app} {kind}": Loop(app, kind) for app in APPS for kind in ("engine",) + KINDS}
    samples = C.sample_rounds({k: loop.body for k, loop in loops.items()},
                              {k: SCANS * REPEAT for k in loops}, rounds)
    figures: dict = {"apps": {}}
    for app in APPS:
        engine_ns = C.median(samples[f"{app} engine"])
        row = {"engine_scans_per_s": round(1e9 / engine_ns), "engine_us_per_scan": round(engine_ns / 1e3, 2)}
        for kind in KINDS:
            key = f"{app} {kind}"
            ns = C.median(samples[key])
            row[kind] = {"scans_per_s": round(1e9 / ns), "us_per_scan": round(ns / 1e3, 2),
                         "steps_per_1000_scans": loops[key].steps,
                         "us_per_step": round((ns - engine_ns) * SCANS / loops[key].steps / 1e3, 2),
                         # runner / engine in scans per second: the engine's ns over the runner's
                         "ratio": round(C.ratio(samples, f"{app} engine", key), 3)}
        row["fixed_ms_per_scenario"] = round(fixed_cost_ms(app), 1)
        figures["apps"][app] = row
    for loop in loops.values():
        loop.plc.close()
    worst = min(r[k]["ratio"] for r in figures["apps"].values() for k in TARGETED)
    figures["worst_ratio"] = worst
    figures["verdict"] = "PASS" if worst >= TARGET_RATIO else "MISS"
    return figures


def profile(app: str = "motor", kind: str = "expects", repeats: int = 20) -> None:
    loop = Loop(app, kind)
    try:
        C.print_profile(lambda: loop.body(SCANS * repeats), f"{app} {kind}, {SCANS * repeats} scans", 14)
    finally:
        loop.plc.close()


def main() -> int:
    args = sys.argv[1:]
    if "--profile" in args:
        for app in APPS:
            for kind in KINDS:
                profile(app, kind)
        return 0
    quick = "--quick" in args
    t_start = time.perf_counter()
    figures = measure(3 if quick else ROUNDS)
    wall = time.perf_counter() - t_start
    print(f"--- {NAME}: simulated 10 ms scans; {3 if quick else ROUNDS} rounds of {REPEAT} x {SCANS} scans a loop")
    for app, row in figures["apps"].items():
        print(f"programs/{app}: engine alone {row['engine_scans_per_s']:>9,} scans/s "
              f"({row['engine_us_per_scan']:.2f} us/scan); a scenario's load, check and close "
              f"{row['fixed_ms_per_scenario']:.1f} ms")
        for kind in KINDS:
            r = row[kind]
            print(f"  {kind:8} {r['steps_per_1000_scans']:>4} steps/1000 scans {r['scans_per_s']:>9,} scans/s "
                  f"({r['us_per_scan']:.2f} us/scan)  runner / engine {r['ratio']:.3f} = cost "
                  f"{100 * (1 - r['ratio']):.1f}%" + (f", {r['us_per_step']:.2f} us a step" if kind != "long" else ""))
    print(f"worst runner / engine of {' and '.join(TARGETED)} {figures['worst_ratio']:.3f} "
          f"[{figures['verdict']}: cost <= {100 * (1 - TARGET_RATIO):.0f}%]")
    C.save_figures(NAME, {"method": {"rounds": ROUNDS, "scans_per_call": SCANS * REPEAT, "gc": "paused",
                                     "figures": "medians over the rounds; ratios: median of per-round ratios"},
                          **figures, "target_ratio": TARGET_RATIO, "wall_s": round(wall, 1)},
                   quick, None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
