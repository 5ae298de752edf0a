"""MODBTCPS, the Modbus TCP server over the data table:
requests per second beside pymodbus's own server, the scan time a request
adds, and 50 busy clients against the scan.

    python benchmarks/bench_modbus_server.py           # about 2.7 minutes; needs pymodbus
    python benchmarks/bench_modbus_server.py --quick   # about 35 s (results not written)
    python benchmarks/bench_modbus_server.py --json PATH
    python benchmarks/bench_modbus_server.py --runtime-nice -10   # the runtime at a higher priority

Processes (the machine's cores are shared by all of them; the CPU each used
in each window is printed, to say which one set the pace):

- the runtime (modbus_server_runtime.py): a softplc app in a temporary
  directory, 100 rungs of ladder (a counter, moves, adds, compares, timers
  over N10) at a 10 ms real-time scan (softplc.toml), MODBTCPS serving
  N10:0..99 as holding registers 0..99 of unit 1 (read-only) and N12:0..99
  as 1000..1099 (writable); the rate and connection limits raised out of
  the way (maxRequestsPerSecond 100000, maxConnections 64). It starts
  MODBTCPS's server process, as every run does. Every scan is timed from
  inside (wall and CPU time): the whole scan, MODBTCPS's input and output
  hooks, the ladder alone (engine.last_scan_ms, what the watchdog S:28
  judges), and how late the scan started;
- the baseline (modbus_server_load.py serve): pymodbus 3.16's
  ModbusTcpServer with a plain datastore (SimDevice, 100 registers), in its
  own process, started once and left running;
- the clients (modbus_server_load.py clients): K pymodbus
  AsyncModbusTcpClient connections in one process (one asyncio loop), each
  in a loop of one request at a time, or K connections of a hand-made
  client (RawClient, far lighter); every reply is checked, any error fails
  the run.

The parts, in this order (ROUNDS rounds of every window of PLAN, each against
MODBTCPS and against pymodbus's server, their order rotating; WINDOW_S each):

1. Requests per second: reads of 100 holding registers (function 3) by
   K = 1, 4, 16 pymodbus clients; K = 16 split over 2 client processes (if
   one client process set the pace, two would serve more); K = 16 raw
   clients; and WRITE_CLIENTS clients writing 100 registers (function 16).
   Medians over the rounds [min..max]; the ratio MODBTCPS / pymodbus is the
   median of the per-round ratios. Beside them, each server process's CPU
   time per request, which does not depend on who set the pace.
2. The scan time added per request, from the runtime's own timings. While
   pymodbus's server is loaded the runtime has no client at all: its scans in
   that window are the idle reference, paired with the loaded window of the
   same round and K (same machine load, minutes apart at most). Added scan
   time per request = (mean MODBTCPS hook time per scan loaded - idle) /
   requests per scan, in wall and CPU time, and the whole scan's CPU time
   the same way. Reads are answered by the server process from the image
   the scan publishes, so by design a read costs the scan nothing; a write
   is applied by the scan at its input point.
3. BUSY_CLIENTS pymodbus clients reading in loops for BUSY_S against the
   runtime, then BUSY_S with no client; and a quiet IDLE_S at the start (no
   client anywhere): the scan time, the ladder's time, the start lateness
   and the late scans (a start a whole period late, as Runner.late_scans
   counts), and whether the watchdog would trip (the ladder's longest scan,
   and the whole scan's, against S:28; the runtime must end in RUN). Also
   HOT_SCANS scans timed back to back before the run, caches warm.

Writes benchmarks/results/bench_modbus_server.json (not with --quick, unless
--json is given); exits 0, or 1 when a check fails (a client error, a
refusal the server counted, the runtime faulted). A miss (late scans under
the busy clients) is reported, not failed.
"""

from __future__ import annotations

import argparse
import json
import select
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _common as C

from helpers.modbus_peer import free_tcp_port

SCAN_MS = 10
RUNGS = 100
REGISTERS = 100
CLIENT_COUNTS = (1, 4, 16)
SPLIT_CLIENTS, SPLIT_PROCESSES = 16, 2
WRITE_CLIENTS = 4
BUSY_CLIENTS = 50
WRITE_ADDRESS = 1000  # the runtime's writable region (N12:0..99)
RAW_CLIENTS = 16
# The per-scan means compared loaded against idle (scans_in's keys): MODBTCPS's hooks in wall and CPU
# time, and the whole scan in CPU time (its wall time is mostly the ladder, preempted or not).
MEASURES = ("hooks_us_mean", "hooks_cpu_us_mean", "scan_cpu_us_mean")
# Each round: (kind, clients, client processes), each against both servers. "read": pymodbus's async
# client, function 3; "raw": the hand-made client of modbus_server_load.py (reads); "write": function 16.
PLAN = ([("read", k, 1) for k in CLIENT_COUNTS] + [("read", SPLIT_CLIENTS, SPLIT_PROCESSES),
                                                  ("raw", RAW_CLIENTS, 1), ("write", WRITE_CLIENTS, 1)])
FULL = {"rounds": 3, "window_s": 2.5, "busy_s": 10.0, "idle_s": 5.0}
QUICK = {"rounds": 1, "window_s": 1.0, "busy_s": 2.0, "idle_s": 1.0}
LOAD = str(C.HERE / "modbus_server_load.py")
RUNTIME = str(C.HERE / "modbus_server_runtime.py")
START_LIMIT_S = 30.0  # a process's "ready" line (imports pymodbus; a loaded machine is slow)


class CheckFailed(RuntimeError):
    """A request failed, the server refused one, or the runtime faulted."""


# -- the app -------------------------------------------------------------------------------------------------


def ladder(rungs: int = RUNGS) -> str:
    """100 rungs over N10: a counter wrapping below 30000 and rungs that move,
    add, compare and time with it. N10 words stay in 0..30099 (what the
    clients check)."""
    lines = ["DATA N10 100", "DATA N12 100", "DATA T4 30", "DATA B3 8",
             "ADD N10:0 1 N10:0", "GEQ N10:0 30000 CLR N10:0"]
    for k in range(2, rungs):
        lines.append((f"XIO B3/{k} ADD N10:0 {k} N10:{k}", f"MOV N10:0 N10:{k}",
                      f"EQU N10:{k} 0 OTE B3/{k}", f"XIO B3/0 TON T4:{k // 4} 0.01 50 0")[k % 4])
    return "\n".join(lines) + "\n"


def server_xml(port: int) -> str:
    return f"""<?xml version="1.0"?>
<!-- Limits raised out of the way: this measures the server, not its rate limit (the default is 100/s a client). -->
<ModbusTcpServer address="127.0.0.1" port="{port}" maxConnections="64" maxRequestsPerSecond="100000"
                 idleTimeout="600000" status="N40:0">
  <Unit id="1">
    <HoldingRegisters start="0"    count="{REGISTERS}" address="N10:0"/>
    <HoldingRegisters start="{WRITE_ADDRESS}" count="{REGISTERS}" address="N12:0" writable="yes"/>
  </Unit>
</ModbusTcpServer>
"""


def write_app(directory: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "MODULES.LST").write_text("MODBTCPS\n")
    (directory / "MODBTCPS.XML").write_text(server_xml(free_tcp_port()))
    (directory / "main.lad").write_text(ladder())
    (directory / "softplc.toml").write_text(f"[scan]\nscan_ms = {SCAN_MS}\n")
    return directory


# -- the processes -------------------------------------------------------------------------------------------


class Child:
    """A process that prints "ready ..." and runs until its standard input
    closes. ``wait=False``: started only; ``ready()`` waits for its line (so
    that two children start side by side)."""

    def __init__(self, args: list[str], what: str, wait: bool = True) -> None:
        self.what = what
        self.fields: list[int] = []
        self.proc = subprocess.Popen([sys.executable, *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True)
        if wait:
            self.ready()

    def ready(self) -> None:
        line = self._ready_line()
        if not line.startswith("ready "):
            self.stop()
            raise CheckFailed(f"{self.what} did not start (exit status {self.proc.returncode})")
        self.fields = [int(x) for x in line.split()[1:]]

    def _ready_line(self) -> str:
        ready, _, _ = select.select([self.proc.stdout], [], [], START_LIMIT_S)
        return self.proc.stdout.readline().strip() if ready else ""

    def close_input(self) -> None:
        """Tell the child to stop (``stop`` waits for it)."""
        if self.proc.poll() is None:
            try:
                self.proc.stdin.close()
            except OSError:
                pass

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.close_input()
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self.proc.stdout.close()


def idle_window(seconds: float, settle_s: float = 0.0) -> dict:
    """A window of ``seconds`` with no client, after ``settle_s`` (the
    runtime's first scans and the baseline's start behind us): its start
    and end, to find the scans in it (scans_in)."""
    time.sleep(settle_s)
    start = time.monotonic()
    time.sleep(seconds)
    return {"start": start, "end": time.monotonic()}


def stop_all(children: list[Child]) -> None:
    """Stop children side by side: each is told first, then each awaited."""
    for child in children:
        child.close_input()
    for child in children:
        child.stop()


def client_results(procs: list[subprocess.Popen], timeout_s: float) -> list[dict]:
    """Each client process's line of JSON, once all have finished their
    window; none is left behind when one fails."""
    results = []
    try:
        for p in procs:
            try:
                out, _ = p.communicate(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                raise CheckFailed(f"a client process did not finish within {timeout_s:.0f} s") from None
            if p.returncode != 0 or not out.strip():
                raise CheckFailed(f"a client process failed (exit status {p.returncode})")
            results.append(json.loads(out))
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.communicate()
    return results


def load(port: int, clients: int, function: int, window_s: float, watch: list[int], processes: int = 1,
         address: int = 0, raw: bool = False) -> dict:
    """``clients`` clients over ``processes`` processes for one window; the
    processes' figures summed. Every process is given the same start on
    CLOCK_MONOTONIC, far enough ahead for it to import pymodbus, connect and
    warm up (a start missed is reported in ready_late_s)."""
    per = [clients // processes + (1 if k < clients % processes else 0) for k in range(processes)]
    lead_s = 1.0 + 0.02 * clients + 0.2 * (processes - 1)
    start_at = time.monotonic() + lead_s
    procs = []
    for k, n in enumerate(per):
        spec = {"port": port, "clients": n, "function": function, "count": REGISTERS, "address": address,
                "warmup": 3, "start_at": start_at, "window_s": window_s, "timeout_s": 5.0,
                "watch": watch if k == 0 else [], "raw": raw}
        procs.append(subprocess.Popen([sys.executable, LOAD, "clients", json.dumps(spec)], stdout=subprocess.PIPE,
                                      text=True))
    results = client_results(procs, window_s + lead_s + START_LIMIT_S)
    first = results[0]
    cpu = dict(first["cpu_s"])
    cpu["clients"] = sum(r["cpu_s"]["clients"] for r in results)
    errors = sum(r["errors"] for r in results)
    if errors:
        why = next(r["first_error"] for r in results if r["errors"])
        raise CheckFailed(f"{errors} failed requests with {clients} clients (function {function}): {why}")
    return {"clients": clients, "processes": processes, "function": function, "raw": raw,
            "done": sum(r["done"] for r in results), "window_s": window_s,
            "start": min(r["start"] for r in results), "end": max(r["end"] for r in results),
            "ready_late_s": max(r["ready_late_s"] for r in results), "cpu_s": cpu}


# -- the runtime's scans in a window -------------------------------------------------------------------------


def scans_in(records: dict, start: float, end: float) -> dict:
    """The runtime's scans that started in [start, end): counts, means and tails."""
    idx = [i for i, t in enumerate(records["start"]) if start <= t < end]
    if not idx:
        return {"scans": 0}
    hooks = [records["hooks_ns"][i] / 1000 for i in idx]
    whole = [records["scan_ns"][i] / 1000 for i in idx]
    ladder_ms = [records["ladder_ms"][i] for i in idx]
    late = [records["late_ms"][i] for i in idx]
    hooks_cpu = [records["hooks_cpu_ns"][i] / 1000 for i in idx]
    whole_cpu = [records["scan_cpu_ns"][i] / 1000 for i in idx]

    def p99(xs):
        return sorted(xs)[min(len(xs) - 1, int(0.99 * len(xs)))]

    return {"scans": len(idx), "hooks_us_mean": statistics.fmean(hooks), "hooks_us_median": statistics.median(hooks),
            "hooks_us_p99": p99(hooks), "hooks_us_max": max(hooks),
            "scan_us_mean": statistics.fmean(whole), "scan_us_median": statistics.median(whole),
            "scan_us_p99": p99(whole), "scan_us_max": max(whole),
            "hooks_cpu_us_mean": statistics.fmean(hooks_cpu), "scan_cpu_us_mean": statistics.fmean(whole_cpu),
            "scan_cpu_us_median": statistics.median(whole_cpu), "scan_cpu_us_max": max(whole_cpu),
            "ladder_ms_max": max(ladder_ms), "late_ms_max": max(late), "late_ms_p99": p99(late),
            "late_scans": sum(1 for x in late if x >= SCAN_MS)}


def cpu_percent(window: dict, pids: dict[str, int]) -> dict[str, float | None]:
    out = {"clients": 100 * window["cpu_s"]["clients"] / window["window_s"]}
    for name, pid in pids.items():
        used = window["cpu_s"].get(str(pid))
        out[name] = None if used is None else 100 * used / window["window_s"]
    return out


# -- the run -------------------------------------------------------------------------------------------------


def run(cfg: dict, work: Path) -> dict:
    app = write_app(work / "app")
    records_path = work / "scans.json"
    runtime = Child([RUNTIME, str(app), str(records_path), str(cfg["runtime_nice"])], "the runtime (MODBTCPS)")
    ours_port, server_pid, runtime_pid = runtime.fields
    try:
        baseline = Child([LOAD, "serve"], "pymodbus's server")
    except BaseException:
        runtime.stop()
        raise
    base_port, base_pid = baseline.fields
    pids = {"modbtcps_server": server_pid, "runtime": runtime_pid, "pymodbus_server": base_pid}
    watch = list(pids.values())
    servers = {"modbtcps": ours_port, "pymodbus": base_port}
    windows: list[dict] = []

    def window(kind: str, server: str, clients: int, processes: int = 1, rnd: int = 0,
               seconds: float | None = None) -> None:
        function = 16 if kind == "write" else 3
        address = WRITE_ADDRESS if function == 16 and server == "modbtcps" else 0
        w = load(servers[server], clients, function, seconds or cfg["window_s"], watch, processes, address,
                 raw=kind == "raw")
        w.update(kind=kind, server=server, round=rnd, cpu_percent=cpu_percent(w, pids))
        server_cpu = w["cpu_s"].get(str(pids[server + "_server"]))
        w["server_cpu_us_per_request"] = 1e6 * server_cpu / w["done"] if server_cpu and w["done"] else None
        windows.append(w)
        rate = w["done"] / w["window_s"]
        print(f"  round {rnd} {kind:<6} {server:<9} K={clients:<3} x{processes} proc  {rate:8.0f} req/s   "
              f"CPU %: server {w['cpu_percent'][server + '_server']:.0f}, clients {w['cpu_percent']['clients']:.0f}, "
              f"runtime {w['cpu_percent']['runtime']:.0f}", flush=True)

    try:
        quiet = idle_window(cfg["idle_s"], settle_s=1.0)
        for rnd in range(cfg["rounds"]):
            for j, (kind, k, procs) in enumerate(PLAN):
                order = ["modbtcps", "pymodbus"] if (rnd + j) % 2 == 0 else ["pymodbus", "modbtcps"]
                for server in order:
                    window(kind, server, k, procs, rnd)
        window("busy", "modbtcps", BUSY_CLIENTS, 1, 0, cfg["busy_s"])
        t1 = time.monotonic()
        time.sleep(cfg["busy_s"])
        after_busy = {"start": t1, "end": time.monotonic()}
    finally:
        baseline.stop()
        runtime.stop()
    if not records_path.exists():
        raise CheckFailed("the runtime wrote no records (it did not stop cleanly)")
    result = json.loads(records_path.read_text(encoding="utf-8"))
    return {"windows": windows, "quiet": quiet, "after_busy": after_busy, "pids": pids,
            "state": result["state"], "records": result["scans"]}


# -- figures -------------------------------------------------------------------------------------------------


def span(xs: list[float], fmt: str = "{:.0f}") -> str:
    return f"{fmt.format(statistics.median(xs))} [{fmt.format(min(xs))}..{fmt.format(max(xs))}]"


def figures_of(raw: dict, cfg: dict) -> dict:
    records = raw["records"]
    windows = raw["windows"]
    state = raw["state"]
    for w in windows:
        w["rate"] = w["done"] / w["window_s"]
        w["runtime_scans"] = scans_in(records, w["start"], w["end"])
    quiet = scans_in(records, raw["quiet"]["start"], raw["quiet"]["end"])
    after_busy = scans_in(records, raw["after_busy"]["start"], raw["after_busy"]["end"])

    def find(kind, server, clients, processes, rnd):
        return next(w for w in windows if (w["kind"], w["server"], w["clients"], w["processes"], w["round"])
                    == (kind, server, clients, processes, rnd))

    rows = []
    for kind, k, procs in PLAN:
        ours = [find(kind, "modbtcps", k, procs, r) for r in range(cfg["rounds"])]
        base = [find(kind, "pymodbus", k, procs, r) for r in range(cfg["rounds"])]
        per_scan: list[float] = []
        added: dict[str, list[float]] = {m: [] for m in MEASURES}
        for o, b in zip(ours, base):
            so, sb = o["runtime_scans"], b["runtime_scans"]
            if so["scans"] and sb["scans"]:
                requests_per_scan = o["done"] / so["scans"]
                per_scan.append(requests_per_scan)
                for m in MEASURES:
                    added[m].append((so[m] - sb[m]) / requests_per_scan)
        rows.append({
            "kind": kind, "clients": k, "processes": procs,
            "modbtcps_rates": [w["rate"] for w in ours], "pymodbus_rates": [w["rate"] for w in base],
            "ratio": statistics.median(o["rate"] / b["rate"] for o, b in zip(ours, base)),
            "server_cpu_us_per_request": {name: [w["server_cpu_us_per_request"] or 0 for w in ws]
                                          for name, ws in (("modbtcps", ours), ("pymodbus", base))},
            "cpu_percent_modbtcps": {n: statistics.median(w["cpu_percent"][n] or 0 for w in ours)
                                     for n in ("modbtcps_server", "clients", "runtime")},
            "cpu_percent_pymodbus": {n: statistics.median(w["cpu_percent"][n] or 0 for w in base)
                                     for n in ("pymodbus_server", "clients", "runtime")},
            "requests_per_scan": per_scan,
            "loaded": {m: [w["runtime_scans"].get(m) for w in ours] for m in MEASURES},
            "idle": {m: [w["runtime_scans"].get(m) for w in base] for m in MEASURES},
            "added_per_request": added,
            "ready_late_s_max": max(w["ready_late_s"] for w in ours + base),
            "late_ms_max_loaded": max(w["runtime_scans"].get("late_ms_max", 0) for w in ours),
            "late_scans_loaded": sum(w["runtime_scans"].get("late_scans", 0) for w in ours),
            "ladder_ms_max_loaded": max(w["runtime_scans"].get("ladder_ms_max", 0) for w in ours),
        })
    busy = next(w for w in windows if w["kind"] == "busy")
    late_where = []  # every late scan of the run, and the window it fell in
    labelled = [(w["start"], w["end"], f"{w['kind']} {w['server']} K={w['clients']} round {w['round']}")
                for w in windows] + [(raw["quiet"]["start"], raw["quiet"]["end"], "quiet start"),
                                     (raw["after_busy"]["start"], raw["after_busy"]["end"], "after the busy clients")]
    for t, late in zip(records["start"], records["late_ms"]):
        if late >= SCAN_MS:
            where = next((label for a, b, label in labelled if a <= t < b), "between windows (client processes "
                                                                               "starting or ending)")
            late_where.append({"late_ms": late, "where": where})
    return {"config": cfg, "scan_ms": SCAN_MS, "rungs": RUNGS, "registers": REGISTERS, "rows": rows,
            "quiet": quiet, "busy": {"rate": busy["rate"], "cpu_percent": busy["cpu_percent"],
                                     "scans": busy["runtime_scans"], "ready_late_s": busy["ready_late_s"]},
            "after_busy": after_busy, "late_scans": late_where, "state": state}


KIND_NAMES = {"read": "read (3)", "raw": "read (3), raw client", "write": "write (16)"}


def row_name(r: dict) -> str:
    procs = f" in {r['processes']} procs" if r["processes"] > 1 else ""
    return f"{KIND_NAMES[r['kind']]}, K={r['clients']}{procs}"


def report(f: dict) -> list[str]:
    """Print the figures; return what failed (empty: all checks passed)."""
    rows, state = f["rows"], f["state"]
    rounds = f["config"]["rounds"]
    print(f"\n1. Requests per second, {f['registers']} registers a request, unit 1; median [min..max] of "
          f"{rounds} round(s). MODBTCPS: the ladder ({f['rungs']} rungs) scanning every {f['scan_ms']} ms.")
    print(f"{'':28} {'MODBTCPS':>22} {'pymodbus server':>22} {'ratio':>7} {'server CPU us/request':>22}"
          "   CPU %: MODBTCPS server/clients/runtime; pymodbus server/clients")
    for r in rows:
        co, cb = r["cpu_percent_modbtcps"], r["cpu_percent_pymodbus"]
        per = r["server_cpu_us_per_request"]
        cpu_per = f"{statistics.median(per['modbtcps']):.0f} / {statistics.median(per['pymodbus']):.0f}"
        print(f"{row_name(r):28} {span(r['modbtcps_rates']):>22} {span(r['pymodbus_rates']):>22} {r['ratio']:>6.2f}x "
              f"{cpu_per:>22}   {co['modbtcps_server']:.0f}/{co['clients']:.0f}/{co['runtime']:.0f}; "
              f"{cb['pymodbus_server']:.0f}/{cb['clients']:.0f}")
    print("   (a write to MODBTCPS is answered once the scan has applied it: at most one a scan per client)")

    print("\n2. Scan time added per request: (the mean per scan loaded - idle) / requests per scan, us; idle = the "
          "runtime's scans\n   while only pymodbus's server was loaded, same round. Wall time, and CPU time (the "
          "scan thread's: without preemption). Median [min..max] over rounds.")
    print(f"{'':28} {'requests/scan':>16} {'hooks wall idle':>16} {'loaded':>16} {'added/request':>19}"
          f" {'hooks CPU added/request':>24} {'whole scan CPU added':>21}   loaded: latest start ms, late scans")
    for r in rows:
        if r["processes"] > 1:
            continue
        if not r["requests_per_scan"]:
            print(f"{row_name(r):28} (no scans in a window)")
            continue
        added = r["added_per_request"]
        print(f"{row_name(r):28} {span(r['requests_per_scan'], '{:.2f}'):>16} "
              f"{span(r['idle']['hooks_us_mean'], '{:.1f}'):>16} {span(r['loaded']['hooks_us_mean'], '{:.1f}'):>16} "
              f"{span(added['hooks_us_mean'], '{:.2f}'):>19} {span(added['hooks_cpu_us_mean'], '{:.2f}'):>24} "
              f"{span(added['scan_cpu_us_mean'], '{:.2f}'):>21}   "
              f"{r['late_ms_max_loaded']:.1f}, {r['late_scans_loaded']}")

    q, b, a = f["quiet"], f["busy"]["scans"], f["after_busy"]
    cpu = f["busy"]["cpu_percent"]
    print(f"\n3. {BUSY_CLIENTS} busy clients (reads in loops) against the runtime: {f['busy']['rate']:.0f} req/s "
          f"served; CPU %: MODBTCPS's server {cpu['modbtcps_server']:.0f}, clients {cpu['clients']:.0f}, "
          f"runtime {cpu['runtime']:.0f}")
    print(f"{'':34} {'quiet start':>14} {str(BUSY_CLIENTS) + ' busy clients':>18} {'no clients, after':>18}")
    for label, key, fmt in (("scans", "scans", "{}"), ("whole scan, us median", "scan_us_median", "{:.0f}"),
                            ("whole scan, us p99", "scan_us_p99", "{:.0f}"),
                            ("whole scan, us max", "scan_us_max", "{:.0f}"),
                            ("whole scan CPU, us median", "scan_cpu_us_median", "{:.0f}"),
                            ("whole scan CPU, us max", "scan_cpu_us_max", "{:.0f}"),
                            ("MODBTCPS hooks, us mean", "hooks_us_mean", "{:.1f}"),
                            ("MODBTCPS hooks CPU, us mean", "hooks_cpu_us_mean", "{:.1f}"),
                            ("MODBTCPS hooks, us max", "hooks_us_max", "{:.0f}"),
                            ("ladder (S:8 measure), ms max", "ladder_ms_max", "{:.2f}"),
                            ("start lateness, ms p99", "late_ms_p99", "{:.2f}"),
                            ("start lateness, ms max", "late_ms_max", "{:.2f}"),
                            ("late scans (>= one period)", "late_scans", "{}")):
        cells = [fmt.format(s[key]) if s.get("scans") else "-" for s in (q, b, a)]
        print(f"{label:34} {cells[0]:>14} {cells[1]:>18} {cells[2]:>18}")
    hot = state["hot"]
    print(f"   the same work hot ({hot['scans']} scans back to back, caches warm): whole scan "
          f"{hot['scan_us_median']:.1f} us, MODBTCPS hooks {hot['hooks_us_median']:.1f} us (medians)")
    print(f"   runtime at the end: mode {state['mode']}, {state['scans']} scans, the ladder's longest "
          f"{state['max_ladder_ms']:.2f} ms against the watchdog S:28 = {state['watchdog_ms']} ms; "
          f"{state['late_scans']} late scan{'' if state['late_scans'] == 1 else 's'} in the whole run "
          f"(latest start {state['max_lateness_ms']:.1f} ms after due)")
    for item in f["late_scans"]:
        print(f"   a late scan: {item['late_ms']:.1f} ms, {item['where']}")
    watchdog_ok = (state["mode"] == "RUN" and b.get("scans", 0) > 0 and state["max_ladder_ms"] < state["watchdog_ms"]
                   and b["scan_us_max"] / 1000 < state["watchdog_ms"])
    late = b.get("late_scans", "-")
    print(f"   under {BUSY_CLIENTS} busy clients: the watchdog {'would not trip: PASS' if watchdog_ok else 'MISS'}; "
          f"late scans (a start a whole period late): {late} ({'PASS' if late == 0 else 'MISS'})")

    failed = []
    if state["mode"] != "RUN":
        failed.append(f"the runtime ended in mode {state['mode']}: {state['fault']}")
    if state["failed"]:
        failed.append(f"MODBTCPS failed: {state['failed']}")
    refused = {k: v for k, v in state["refusals"].items() if v}
    if refused:
        failed.append(f"the server refused requests: {refused}")
    late_start = max([r["ready_late_s_max"] for r in rows] + [f["busy"]["ready_late_s"]])
    if late_start > 0:
        print(f"   note: a client was ready {late_start:.2f} s after its window began "
              "(that window is short by as much)")
    return failed


def finish(name: str, cfg: dict, quick: bool, json_path, run, figures_of, report) -> int:
    """The end every server benchmark shares (this one, bench_enips_server,
    bench_opcuas): ``run(cfg, directory)`` in a temporary directory, its
    figures (``figures_of(raw)``), their report (``report(figures)``: the
    failed checks), the wall time, the figures saved; 1 when a check failed."""
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix=f"{name}-") as tmp:
        try:
            raw = run(cfg, Path(tmp))
        except CheckFailed as e:
            print(f"FAILED: {e}")
            return 1
    figures = figures_of(raw)
    failed = report(figures)
    figures["wall_s"] = time.monotonic() - started
    print(f"\nwall time {figures['wall_s']:.0f} s")
    C.save_figures(name, {**figures, "config": cfg, "failures": failed}, quick, str(json_path) if json_path else None)
    for problem in failed:
        print(f"FAILED: {problem}")
    return 1 if failed else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run of about 35 s (results not written)")
    parser.add_argument("--json", metavar="PATH", help="also write the figures to PATH")
    parser.add_argument("--runtime-nice", type=int, default=0, metavar="N",
                        help="run the runtime at nice N (e.g. -10: before the clients; needs the privilege)")
    args = parser.parse_args()
    cfg = dict(QUICK if args.quick else FULL, runtime_nice=args.runtime_nice)
    print(f"MODBTCPS against pymodbus's ModbusTcpServer: {cfg['rounds']} round(s) of {cfg['window_s']} s windows, "
          f"{BUSY_CLIENTS} busy clients for {cfg['busy_s']} s; the runtime at nice {cfg['runtime_nice']}")
    return finish("bench_modbus_server", cfg, args.quick, args.json, run, lambda raw: figures_of(raw, cfg), report)


if __name__ == "__main__":
    sys.exit(main())
