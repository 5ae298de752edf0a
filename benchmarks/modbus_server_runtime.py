"""The runtime of bench_modbus_server.py: a softplc app with MODBTCPS,
scanning in real time, every scan timed from inside.

    python benchmarks/modbus_server_runtime.py APP_DIR OUT_JSON [NICE [MODULES]]

MODULES: the server modules whose hooks are timed, comma-separated
(MODBTCPS by default; bench_enips_server.py times ENIPS and MODBTCPS of one
app, each apart).

Builds the Runner ``softplc run APP --realtime --fresh`` builds (real-time
clock, the app's own scan period, no retentive saves), at the priority NICE
(an increment for os.nice; 0 by default), times HOT_SCANS scans back to back
first (the work with warm caches), then wraps, for the benchmark only:

- ``engine.scan``: perf_counter_ns around the whole scan (inputs, ladder,
  outputs: what delays the next scan);
- MODBTCPS's input and output hooks (the entries in ``engine.input_hooks``
  and ``engine.output_hooks``): their time together, the server's whole cost
  to the scan;
- both also in this thread's CPU time (``time.thread_time_ns``): the work
  itself, without the time the process sat preempted by another on a busy
  machine;
- ``runner._lateness``: how late each scan started against its due time.

Per scan it keeps: the start (CLOCK_MONOTONIC, the clock the client
processes stamp their windows with), the whole scan and the hooks in ns of
wall and of CPU time,
the ladder's own time (``engine.last_scan_ms``: what the watchdog S:28
judges) and the lateness of its start in ms. Prints "ready PORT
SERVER_PID PID" once the server listens, scans until standard input
closes, then writes the records and the end state (mode, fault, watchdog
setpoint, late scans, the server's counters) to OUT_JSON.
"""

from __future__ import annotations

import json
import os
import select
import statistics
import sys
import time
from array import array
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(1, str(HERE.parent))

from softplc_lite.app import load_app  # noqa: E402
from softplc_lite.ladder import status as S  # noqa: E402
from softplc_lite.ladder.engine import Mode  # noqa: E402
from softplc_lite.runner import RunOptions, Runner  # noqa: E402
from softplc_lite.tlm.modbtcps import status as C  # noqa: E402


HOT_SCANS = 2000


class ScanRecords:
    """One entry per scan, in arrays (no allocation per scan beyond the floats)."""

    def __init__(self) -> None:
        self.start = array("d")  # time.monotonic() at the scan's start
        self.scan_ns = array("q")  # the whole engine.scan
        self.hooks_ns = array("q")  # MODBTCPS's on_input + on_output
        self.scan_cpu_ns = array("q")  # the same two, in this thread's CPU time (no time spent preempted)
        self.hooks_cpu_ns = array("q")
        self.ladder_ms = array("d")  # engine.last_scan_ms (the ladder alone: the watchdog's measure)
        self.late_ms = array("d")  # how late the scan started (0 for the first)
        self.hooks_this_scan = 0
        self.hooks_cpu_this_scan = 0
        self.late_next = 0.0
        self.by_module: dict[str, array] = {}  # each module's hooks, wall ns, when more than one is timed
        self.module_this_scan: dict[str, int] = {}

    def as_json(self) -> dict:
        out = {name: getattr(self, name).tolist() for name in ("start", "scan_ns", "hooks_ns", "scan_cpu_ns",
                                                                "hooks_cpu_ns", "ladder_ms", "late_ms")}
        out.update({f"hooks_ns_{name}": values.tolist() for name, values in self.by_module.items()})
        return out


def instrument(runner: Runner, modules: list, records: ScanRecords) -> None:
    engine = runner.engine
    perf = time.perf_counter_ns
    cpu = time.thread_time_ns
    if len(modules) > 1:
        records.by_module = {m.name: array("q") for m in modules}

    def timed_input(hook, name):
        def on_input(engine):
            c0, t0 = cpu(), perf()
            hook(engine)
            spent = perf() - t0
            records.hooks_this_scan += spent
            records.hooks_cpu_this_scan += cpu() - c0
            records.module_this_scan[name] = records.module_this_scan.get(name, 0) + spent
        return on_input

    def timed_output(hook, name):
        def on_output(engine, enabled):
            c0, t0 = cpu(), perf()
            hook(engine, enabled)
            spent = perf() - t0
            records.hooks_this_scan += spent
            records.hooks_cpu_this_scan += cpu() - c0
            records.module_this_scan[name] = records.module_this_scan.get(name, 0) + spent
        return on_output

    def owner(hook):
        return next((m for m in modules if getattr(hook, "__self__", None) is m), None)

    engine.input_hooks = [timed_input(h, owner(h).name) if owner(h) is not None else h for h in engine.input_hooks]
    engine.output_hooks = [timed_output(h, owner(h).name) if owner(h) is not None else h
                           for h in engine.output_hooks]
    scan = engine.scan
    monotonic = time.monotonic

    def timed_scan():
        records.hooks_this_scan = records.hooks_cpu_this_scan = 0
        start = monotonic()
        c0, t0 = cpu(), perf()
        scan()
        elapsed = perf() - t0
        elapsed_cpu = cpu() - c0
        records.start.append(start)
        records.scan_ns.append(elapsed)
        records.hooks_ns.append(records.hooks_this_scan)
        records.scan_cpu_ns.append(elapsed_cpu)
        records.hooks_cpu_ns.append(records.hooks_cpu_this_scan)
        records.ladder_ms.append(engine.last_scan_ms)
        records.late_ms.append(records.late_next)
        records.late_next = 0.0
        for name, values in records.by_module.items():
            values.append(records.module_this_scan.get(name, 0))
        records.module_this_scan.clear()

    engine.scan = timed_scan
    lateness = runner._lateness

    def timed_lateness(late_s, period):
        records.late_next = late_s * 1000
        lateness(late_s, period)

    runner._lateness = timed_lateness


def hot_scans(engine, modules: list, scans: int) -> dict:
    """Medians of ``scans`` scans back to back (no sleep between them, so the
    caches stay warm), timed the same way: what the work costs hot, beside
    what it costs in a real-time scan that follows a sleep."""
    if engine.mode is not Mode.RUN:
        engine.set_mode(Mode.RUN)  # as Runner.run does first
    perf = time.perf_counter_ns
    whole, hooks = [], []
    for _ in range(scans):
        t0 = perf()
        for module in modules:
            module.on_input(engine)
        t1 = perf()
        for module in modules:
            module.on_output(engine, True)
        t2 = perf()
        engine.scan()
        t3 = perf()
        hooks.append((t1 - t0) + (t2 - t1))
        whole.append(t3 - t2)
    return {"scans": scans, "scan_us_median": statistics.median(whole) / 1000,
            "hooks_us_median": statistics.median(hooks) / 1000}


def _server_counts(module) -> dict:
    """A server module's requests, writes and refusals by kind (its own names)."""
    counters = module.image.counters()
    return {"requests": counters[C.REQUESTS], "writes": counters[C.WRITES], "failed": module.failed,
            "refusals": {name: counters[c] for name, c in module.server.words.refusal_names}}


def main() -> int:
    app_dir, out = sys.argv[1], sys.argv[2]
    nice = int(sys.argv[3]) if len(sys.argv) > 3 else 0
    names = sys.argv[4].split(",") if len(sys.argv) > 4 else ["MODBTCPS"]
    if nice:
        os.nice(nice)  # a negative increment needs the privilege to raise priority
    app = load_app(app_dir)
    runner = Runner(app, RunOptions(realtime=True, fresh=True, save_state=False))
    engine = runner.engine
    modules = [next(m for m in engine.modules if m.name == name) for name in names]
    module = modules[0]
    engine.scan()  # the first scan starts the server (docs/modbtcps.md): measured with it listening
    for m in modules:
        if m.wait_until_listening() is None:
            print(f"{m.name}: {m.failed}", file=sys.stderr)
            return 1
    hot = hot_scans(engine, modules, HOT_SCANS)
    records = ScanRecords()
    instrument(runner, modules, records)

    def stdin_closed(runner: Runner) -> None:  # between scans: outside the timed scan
        if select.select([0], [], [], 0)[0] and not os.read(0, 4096):
            runner.request_stop()

    runner.between_scans.append(stdin_closed)
    others = "".join(f" {m.port} {m.process.pid}" for m in modules[1:])
    print(f"ready {module.port} {module.process.pid} {os.getpid()}{others}", flush=True)
    try:
        runner.run(None)
        counters = module.image.counters()
        servers = {m.name: _server_counts(m) for m in modules}
    finally:
        runner.close()
    state = {
        "nice": os.getpriority(os.PRIO_PROCESS, 0),
        "hot": hot,
        "scan_ms": engine.settings.scan_ms,
        "watchdog_ms": engine.s[S.WATCHDOG_MS] or engine.settings.watchdog_ms,
        "mode": engine.mode.name,
        "fault": str(engine.fault) if engine.fault is not None else None,
        "scans": engine.scans,
        "max_ladder_ms": engine.max_scan_ms,
        "late_scans": runner.late_scans,
        "max_lateness_ms": runner.max_lateness_ms,
        "requests": counters[C.REQUESTS],
        "writes": counters[C.WRITES],
        "refusals": {name: counters[c] for name, c in (
            ("rate", C.REFUSED_RATE), ("limit", C.REFUSED_LIMIT), ("network", C.REFUSED_NETWORK),
            ("exception_01", C.EXCEPTION_01), ("exception_02", C.EXCEPTION_02), ("exception_03", C.EXCEPTION_03),
            ("exception_0B", C.EXCEPTION_0B), ("malformed", C.MALFORMED), ("idle", C.IDLE))},
        "failed": module.failed,
        "servers": servers,
    }
    Path(out).write_text(json.dumps({"state": state, "scans": records.as_json()}), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
