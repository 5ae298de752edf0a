"""Mutation testing time (``softplc test --mutate``) for programs/motor and
programs/modbus_slave: mutants a second, and the cores used, with one
worker process and with one a CPU in the same run (the one-job run is the
baseline the speed-up is measured against).

    python benchmarks/bench_mutation.py [--sample K] [--quick] [--json PATH]

Each app is mutation-tested with its own scenario files (APP/tests), the
same mutants in both runs: all of motor's, every K-th of modbus_slave's
(``--sample``, 4 by default: each of its ~760 mutants runs the app's
scenarios of simulated Modbus traffic). The budget is large enough that no mutant is cut
short, so both runs judge the same mutants, and the outcomes are checked to
agree. Figures: wall seconds, mutants judged a second (killed, survived,
invalid or timed out; not-covered ones are not run), and the cores used:
CPU time of this process and its worker processes over the wall time.
The machine is shared, so the speed-up of N jobs over one is only as good
as the cores free during the run. The script always exits 0.
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import _common as C

from softplc_lite.testing.mutation import NOT_COVERED, OUT_OF_TIME, run_mutation

APPS = ("motor", "modbus_slave")
BUDGET_S = 3600.0


def _cpu_s() -> float:
    me = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, once reaped
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def measure(app: str, jobs: int, sample: int) -> tuple[dict, list]:
    cpu, wall = _cpu_s(), time.perf_counter()
    report = run_mutation(C.REPO / "programs" / app, jobs=jobs, budget=BUDGET_S,
                          select=lambda m: m.index % sample == 0)
    wall, cpu = time.perf_counter() - wall, _cpu_s() - cpu
    judged = sum(1 for o in report.outcomes if o.status not in (NOT_COVERED, OUT_OF_TIME))
    figures = {
        "jobs": report.jobs,
        "mutants": len(report.mutants),
        "judged": judged,
        "counts": {s: report.count(s) for s in sorted({o.status for o in report.outcomes})},
        "score_percent": None if report.score is None else round(report.score, 1),
        "mutation_wall_s": round(report.seconds, 3),
        "total_wall_s": round(wall, 3),  # with the baseline run and the loads
        "mutants_per_s": round(judged / report.seconds, 2) if report.seconds else None,
        "cores_used": round(cpu / wall, 2) if wall else None,
    }
    return figures, [o.status for o in report.outcomes]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sample", type=int, default=4, help="modbus_slave: every K-th mutant (default 4)")
    ap.add_argument("--quick", action="store_true", help="modbus_slave every 20th mutant; no results file")
    ap.add_argument("--json", default=None, help="also write the figures here")
    args = ap.parse_args()
    n = os.cpu_count() or 1
    results: dict = {"cpu_count": n}
    for app in APPS:
        sample = 1 if app == "motor" else (20 if args.quick else args.sample)
        many, outcomes_n = measure(app, n, sample)
        one, outcomes_1 = measure(app, 1, sample)
        speedup = one["mutation_wall_s"] / many["mutation_wall_s"] if many["mutation_wall_s"] else None
        results[app] = {"sample_every": sample, "jobs_1": one, f"jobs_{n}": many,
                        "speedup": None if speedup is None else round(speedup, 2),
                        "outcomes_agree": outcomes_1 == outcomes_n}
        for label, f in ((f"{n} jobs", many), ("1 job", one)):
            print(f"{app:13s} {label:7s}: {f['judged']:4d} mutants judged in {f['mutation_wall_s']:7.2f} s = "
                  f"{f['mutants_per_s']:6.2f} mutants/s, {f['cores_used']:.2f} cores used, "
                  f"score {f['score_percent']}% {f['counts']}")
        print(f"{app:13s} speed-up {n} jobs over 1: {results[app]['speedup']}x; "
              f"outcomes agree: {results[app]['outcomes_agree']}")
    C.save_figures("bench_mutation", results, args.quick, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
