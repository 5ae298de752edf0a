"""Part 3 of bench_modbus_slave.py: the scan time the ladder Modbus slave
costs, the work it does (rungs, instructions) and where the serving scan's
time goes.

On simulated time (``WireSlave``, 19200 baud, N9:5 = 2): ``engine.scan()``
timed with ``time.perf_counter_ns`` around each call, the garbage collector
paused; SCAN_ROUNDS rounds, interleaved (order rotating), each with
IDLE_SCANS idle scans of the slave (no traffic), IDLE_SCANS of an otherwise
empty app (one rung ``XIC B3/0 OTE B3/1``, no modules, same scan period) and
SCAN_TX transactions of each kind: read 1 register, read 125 (function 3),
write 123 (function 16). A transaction's scans are split into the serving
scan (the served counter moves in it), the scans while the request arrives
and the quiet time runs (before), and those while the reply leaves (after).
Medians of all samples; ratios medians of the per-round ratios against the
slave's idle scan.

Counted (untimed, one transaction of each kind): rungs executed, per program
file (each compiled rung callable wrapped with a counter), and instructions
visited by the reference executor (``executor="reference"``, its
``Interpreter.instruction`` wrapped: every instruction of every rung run,
true or false, and of them those reached with the rung condition true), in
an idle scan, in the serving scan and in the whole transaction beyond as
many idle scans.

Then a cProfile of the 125-register serving scan splits its time by program
file (each file's rungs plus everything they call, but a JSR's callee file)
and gives the share of ``DataTable.resolve`` (the general address resolver);
and, without the profiler (``_common.sample_rounds``, GC paused), one lookup
of the register loop's source ``N[N13:15]:[N13:11]`` (an indirect file
number) against one of ``N12:[N13:13]`` (a fixed file), both as the compiled
rungs resolve them (``resolvers.resolver``: since the compiler's fast path
takes an indirect file number too, both are fast-path lookups).
"""

from __future__ import annotations

import cProfile
import gc
import pstats
import re
import statistics
import time

import _common as C
from modbus_slave_common import Apps, CheckFailed, frames, transact, wire_slave

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.ladder.interpreter import Interpreter
from softplc_lite.runner import Runner, RunOptions

EMPTY_LADDER = "XIC B3/0 OTE B3/1\n"
SCAN_BAUD, SCAN_QUIET_MS = 19200, 2
SCAN_ROUNDS = 9
SCAN_TX = 15
IDLE_SCANS = 1500
PROFILE_TX = 20
KINDS = ("read 1", "read 125", "write 123")


def empty_runner(apps: Apps) -> Runner:
    path = apps.root / "empty.lad"
    path.write_text(EMPTY_LADDER, encoding="utf-8")
    r = Runner(load_app(path), RunOptions(fresh=True, scan_ms=1), log=lambda msg: None)
    r.engine.set_mode(Mode.RUN)
    r.engine.scan()
    return r


def time_scans(engine, n: int) -> list[int]:
    scan, now = engine.scan, time.perf_counter_ns
    out = []
    for _ in range(n):
        t0 = now()
        scan()
        out.append(now() - t0)
    return out


def bench_scan(apps: Apps, rounds: int, tx_per_round: int, idle_scans: int) -> dict:
    s = wire_slave(apps, SCAN_BAUD, SCAN_QUIET_MS)
    empty = empty_runner(apps)
    try:
        s.scans(200)
        time_scans(empty.engine, 200)
        for kind in KINDS:  # warm-up
            transact(s, kind)
        names = ["idle", "empty", *KINDS]
        per_round: dict[str, list[float]] = {n: [] for n in names}
        samples: dict[str, list[int]] = {n: [] for n in names}
        phases: dict[str, dict[str, list[int]]] = {k: {"before": [], "after": []} for k in KINDS}
        scans_per_tx: dict[str, int] = {}
        gc.collect()
        gc.disable()
        try:
            for rnd in range(rounds):
                for name in names[rnd % len(names):] + names[:rnd % len(names)]:
                    if name == "idle":
                        xs = time_scans(s.engine, idle_scans)
                    elif name == "empty":
                        xs = time_scans(empty.engine, idle_scans)
                    else:
                        xs = []
                        for _ in range(tx_per_round):
                            tx = transact(s, name)
                            xs.append(tx.serve_ns)
                            phases[name]["before"] += tx.before_ns
                            phases[name]["after"] += tx.after_ns
                            scans_per_tx[name] = len(tx.scan_ns)
                    samples[name] += xs
                    per_round[name].append(statistics.median(xs))
        finally:
            gc.enable()
    finally:
        s.close()
        empty.engine.close()
    us = {n: statistics.median(v) / 1000 for n, v in samples.items()}
    over_idle = {n: statistics.median(a / b for a, b in zip(per_round[n], per_round["idle"])) for n in names}
    phase_us = {k: {p: statistics.median(v) / 1000 for p, v in ph.items()} for k, ph in phases.items()}
    counts = count_work(apps)
    prof = profile_serve(apps, PROFILE_TX)
    resolve = bench_resolve(rounds)
    out = {
        "baud": SCAN_BAUD, "quiet_ms": SCAN_QUIET_MS, "rounds": rounds, "transactions_per_round": tx_per_round,
        "idle_scans_per_round": idle_scans,
        "scan_us": {n: round(v, 2) for n, v in us.items()},
        "scan_us_round_range": {n: [round(min(v) / 1000, 2), round(max(v) / 1000, 2)] for n, v in per_round.items()},
        "ratio_over_idle": {n: round(v, 2) for n, v in over_idle.items()},
        "phase_us": {k: {p: round(v, 2) for p, v in ph.items()} for k, ph in phase_us.items()},
        "scans_per_transaction": scans_per_tx,
        "serve_added_us": {k: round(us[k] - us["idle"], 1) for k in KINDS},
        "counts": counts, "profile_read_125": prof, "resolve": resolve,
    }
    print(f"--- 3. scan time on simulated time ({SCAN_BAUD} baud, N9:5 = {SCAN_QUIET_MS}, 1 ms scans; "
          f"perf_counter_ns around engine.scan(), GC paused), {rounds} rounds interleaved, medians of all samples:")
    print("  scan                                           us  / slave idle   [round medians]")
    rows = [("empty", "empty app (one rung, no modules)"), ("idle", "slave idle (no traffic)")]
    rows += [(k, f"slave, the scan serving a {k}" + (" (fn 16)" if k.startswith("write") else " (fn 3)"))
             for k in KINDS]
    for n, label in rows:
        lo, hi = out["scan_us_round_range"][n]
        print(f"  {label:44} {us[n]:8.1f}  {over_idle[n]:10.2f}x   [{lo:.1f}..{hi:.1f}]")
    print(f"  the slave's idle scan is {us['idle'] - us['empty']:.1f} us more than the empty app's "
          f"({over_idle['idle'] / over_idle['empty']:.1f}x); the serving scan adds "
          + ", ".join(f"{out['serve_added_us'][k]:,.0f} us ({k})" for k in KINDS))
    print("  the other scans of a transaction (request arriving + quiet time / reply leaving), us: "
          + "; ".join(f"{k} {phase_us[k]['before']:.1f} / {phase_us[k]['after']:.1f} "
                      f"({scans_per_tx[k]} scans)" for k in KINDS))
    print_counts(counts)
    print_profile(prof, resolve, us["read 125"])
    return out


class RungCounter:
    """Wraps every rung callable of an engine's files: rungs run, per file."""

    def __init__(self, engine) -> None:
        self.counts: dict[int, int] = {n: 0 for n in engine.files}
        for number, (compiled, _zone) in engine.files.items():
            compiled.rungs[:] = [self._wrap(number, f) for f in compiled.rungs]

    def _wrap(self, number: int, f):
        counts = self.counts

        def rung(c):
            counts[number] += 1
            return f(c)
        return rung

    def take(self) -> dict[int, int]:
        out = {n: v for n, v in self.counts.items() if v}
        for n in self.counts:
            self.counts[n] = 0
        return out


class InstructionCounter:
    """While installed, counts the reference interpreter's instructions: every
    call of ``Interpreter.instruction`` (each instruction of each rung run, true
    or false), and those entered with the rung condition true, per file."""

    def __init__(self) -> None:
        self.visited: dict[int, int] = {}
        self.enabled: dict[int, int] = {}
        self._orig = Interpreter.instruction

    def __enter__(self) -> "InstructionCounter":
        orig, visited, enabled = self._orig, self.visited, self.enabled

        def instruction(interp, ins, c, rung, pfile):
            visited[pfile.number] = visited.get(pfile.number, 0) + 1
            if c:
                enabled[pfile.number] = enabled.get(pfile.number, 0) + 1
            return orig(interp, ins, c, rung, pfile)

        Interpreter.instruction = instruction
        return self

    def __exit__(self, *exc) -> None:
        Interpreter.instruction = self._orig

    def take(self) -> tuple[dict[int, int], dict[int, int]]:
        out = (dict(self.visited), dict(self.enabled))
        self.visited.clear()
        self.enabled.clear()
        return out


def count_work(apps: Apps) -> dict:
    """Rungs (compiled executor) and instructions (reference executor) in an idle scan, the serving scan
    and a whole transaction of each kind."""
    out: dict = {}
    # compiled: rungs per file
    s = wire_slave(apps, SCAN_BAUD, SCAN_QUIET_MS)
    try:
        s.scans(20)
        rc = RungCounter(s.engine)
        s.scans(1)
        idle = rc.take()
        out["compiled_rungs"] = {"idle": sum(idle.values()), "idle_by_file": idle}
        for kind in KINDS:
            tx = transact(s, kind, per_scan=rc.take)
            serve = tx.counts[tx.serve_index]
            whole = sum(sum(c.values()) for c in tx.counts)
            out["compiled_rungs"][kind] = {"serve": sum(serve.values()), "serve_by_file": serve,
                                           "transaction_scans": len(tx.counts),
                                           "transaction_beyond_idle": whole - len(tx.counts) * sum(idle.values())}
    finally:
        s.close()
    # reference: instructions, and rungs again (the two executors must agree on the rungs)
    with InstructionCounter() as ic:
        s = wire_slave(apps, SCAN_BAUD, SCAN_QUIET_MS, executor="reference")
        try:
            s.scans(20)
            rc = RungCounter(s.engine)
            rc.take()
            ic.take()
            s.scans(1)
            idle_rungs = rc.take()
            visited, enabled = ic.take()
            ref = {"idle": {"visited": sum(visited.values()), "enabled": sum(enabled.values()),
                            "rungs": sum(idle_rungs.values())}}
            if idle_rungs != out["compiled_rungs"]["idle_by_file"]:
                raise CheckFailed(f"idle rungs: reference {idle_rungs}, compiled {out['compiled_rungs']['idle_by_file']}")

            def both():
                r = rc.take()
                v, e = ic.take()
                return r, v, e

            for kind in KINDS:
                tx = transact(s, kind, per_scan=both)
                r, v, e = tx.counts[tx.serve_index]
                if r != out["compiled_rungs"][kind]["serve_by_file"]:
                    raise CheckFailed(f"{kind}: serving scan rungs: reference {r}, compiled "
                                      f"{out['compiled_rungs'][kind]['serve_by_file']}")
                whole_v = sum(sum(c[1].values()) for c in tx.counts)
                ref[kind] = {"visited": sum(v.values()), "enabled": sum(e.values()), "rungs": sum(r.values()),
                             "visited_by_file": v,
                             "transaction_visited_beyond_idle": whole_v - len(tx.counts) * ref["idle"]["visited"]}
        finally:
            s.close()
    out["reference_instructions"] = ref
    return out


def print_counts(counts: dict) -> None:
    cr, ri = counts["compiled_rungs"], counts["reference_instructions"]
    print("  work done (counted; the two executors run the same rungs): rungs run and instructions visited "
          "(every instruction of every rung run, true or false; in brackets those with the rung condition true)")
    print(f"    idle scan: {cr['idle']} rungs, {ri['idle']['visited']} instructions [{ri['idle']['enabled']}]")
    for kind in KINDS:
        c, r = cr[kind], ri[kind]
        files = ", ".join(f"file {n} {v:,}" for n, v in sorted(r["visited_by_file"].items(), key=lambda kv: -kv[1]))
        print(f"    serving a {kind}: {c['serve']:,} rungs, {r['visited']:,} instructions [{r['enabled']:,}] "
              f"(instructions by file: {files}); the whole transaction ({c['transaction_scans']} scans) beyond as "
              f"many idle scans: {c['transaction_beyond_idle']:,} rungs, "
              f"{r['transaction_visited_beyond_idle']:,} instructions")


def profile_serve(apps: Apps, transactions: int) -> dict:
    """cProfile of the scans that serve a 125-register read (compiled): time by program file (its rungs' own
    time plus everything the rungs call, but a JSR's callee file), and how much of it is ``DataTable.resolve``."""
    s = wire_slave(apps, SCAN_BAUD, SCAN_QUIET_MS)
    try:
        tx = transact(s, "read 125")
        k_serve = tx.serve_index
        request, reply = frames("read 125")
        prof = cProfile.Profile()
        for _ in range(transactions):  # the same scan serves every time: simulated time, same phase
            served0 = s.table.read("C5:0.ACC")
            s.port.write(request)
            for _k in range(k_serve):
                s.engine.scan()
            prof.enable()
            s.engine.scan()
            prof.disable()
            if s.table.read("C5:0.ACC") != served0 + 1:
                raise CheckFailed("profile: the scan profiled was not the serving scan")
            got = bytearray()
            for _k in range(2000):
                s.engine.scan()
                data, _t = s.port.read_timed()
                got += data
                if len(got) >= len(reply):
                    break
            if bytes(got) != reply:
                raise CheckFailed("profile: wrong reply")
            s.scans(3)
    finally:
        s.close()
    stats = pstats.Stats(prof)
    total = stats.total_tt

    def ladder_file(path: str) -> str | None:
        m = re.match(r"<ladder file (\d+)>", path)
        return f"file {m.group(1)}" if m else None

    groups: dict[str, float] = {}
    resolve_s, resolve_calls = 0.0, 0
    for (path, _line, func), (_cc, _nc, tt, _ct, callers) in stats.stats.items():
        own = ladder_file(path)
        if own is not None:
            groups[own] = groups.get(own, 0.0) + tt
        elif path.endswith("softplc_lite/ladder/engine.py"):
            groups["engine (run_file, JSR, scan)"] = groups.get("engine (run_file, JSR, scan)", 0.0) + tt
        elif func != "_jsr":
            for (cpath, _cl, _cf), edge in callers.items():  # a helper called from a rung: its whole time
                g = ladder_file(cpath)
                if g is not None:
                    groups[g] = groups.get(g, 0.0) + edge[3]
        if path.endswith("softplc_lite/datatable/table.py") and func == "resolve":
            for (cpath, _cl, _cf), edge in callers.items():
                if not cpath.endswith("softplc_lite/datatable/table.py"):
                    resolve_s += edge[3]
                    resolve_calls += edge[1]
    groups["other (the COMGENIUS hooks, the clock)"] = max(total - sum(groups.values()), 0.0)
    shares = dict(sorted(((k, v / total) for k, v in groups.items()), key=lambda kv: -kv[1]))
    return {"transactions": transactions, "ms_per_scan_under_profiler": round(total / transactions * 1000, 2),
            "shares": {k: round(v, 3) for k, v in shares.items()},
            "resolve_share": round(resolve_s / total, 3), "resolve_calls_per_scan": resolve_calls / transactions}


def bench_resolve(rounds: int) -> dict:
    """ns per call of the compiled code's address lookup for the register loop's source N[N13:15]:[N13:11]
    (the file number is indirect too) against its destination N12:[N13:13] (a fixed file), on the slave's own
    table (``resolvers.resolver``, what the rungs call; both now take the compiler's fast path)."""
    from softplc_lite.datatable import parse_address
    from softplc_lite.ladder.resolvers import resolver as _resolver

    apps = Apps()
    s = wire_slave(apps, SCAN_BAUD, SCAN_QUIET_MS)
    try:
        t = s.table
        for addr, v in (("N13:15", 10), ("N13:11", 5), ("N13:13", 7)):
            t.write(addr, v)
        source = _resolver(t, parse_address("N[N13:15]:[N13:11]"))
        dest = _resolver(t, parse_address("N12:[N13:13]"))
        if source()[1] != 5 or dest()[1] != 7:
            raise CheckFailed("resolve: the wrong element")

        def body(f):
            def run(n: int) -> None:
                for _ in range(n):
                    f()
            return run

        samples = C.sample_rounds({"source": body(source), "dest": body(dest)}, {"source": 20_000, "dest": 20_000},
                                  rounds)
    finally:
        s.close()
        apps.close()
    return {"ns": {k: round(C.median(v), 1) for k, v in samples.items()},
            "ratio_source_over_dest": round(C.ratio(samples, "source", "dest"), 1), "rounds": rounds}


def print_profile(prof: dict, resolve: dict, serve_us: float) -> None:
    names = {"file 63": "CRC", "file 53": "read registers", "file 51": "process", "file 2": "main",
             "file 120": "receive", "file 57": "write registers"}
    parts = [f"{k}{' (' + names[k] + ')' if k in names else ''} {100 * v:.0f}%"
             for k, v in prof["shares"].items() if v >= 0.01]
    calls = prof["resolve_calls_per_scan"]
    print(f"  cProfile of the scan serving a read of 125 ({prof['transactions']} of them, "
          f"{prof['ms_per_scan_under_profiler']:.1f} ms each under the profiler), by program file (its rungs and "
          f"all they call): " + ", ".join(parts))
    print(f"    DataTable.resolve (the general resolver) {100 * prof['resolve_share']:.0f}% of it, {calls:.0f} calls "
          f"a scan; the register loop's N[N13:15]:[N13:11] (an indirect file number) takes the compiler's fast "
          f"path: one lookup {resolve['ns']['source']:,.0f} ns against {resolve['ns']['dest']:,.0f} ns for "
          f"N12:[N13:13] (a fixed file; {resolve['ratio_source_over_dest']:.1f}x; GC paused); the serving scan is "
          f"{serve_us:,.0f} us", flush=True)
