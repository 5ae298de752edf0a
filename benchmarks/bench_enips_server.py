"""ENIPS, the EtherNet/IP server over the data table: reads a second of 100
words through a CIP tag and through PCCC, beside MODBTCPS in the same
runtime; the scan time a request adds; late scans under 50 busy clients.

    python benchmarks/bench_enips_server.py           # about 1.5 minutes; needs pycomm3 and pymodbus
    python benchmarks/bench_enips_server.py --quick   # about 30 s (results not written)
    python benchmarks/bench_enips_server.py --json PATH

The runtime (modbus_server_runtime.py, timing both servers' hooks apart) is
one softplc app with MODBTCPS and ENIPS, 100 rungs of ladder over N10 (the
Modbus bench's) at a 10 ms real-time scan; both servers serve N10:0..99,
ENIPS also N12:0..99 writable; limits raised out of the way. The baseline is
MODBTCPS in the same runtime at the same moment of the run: reads of 100
holding registers by pymodbus's client, against reads of the tag
``N10[0]{100}`` by pycomm3's LogixDriver and of ``N10:0{100}`` by its
SLCDriver (PCCC). Clients (enips_server_load.py) are one process each, so
none shares an interpreter; K = 1 and 4; ROUNDS rounds, the three kinds'
order rotating; the ratio ENIPS / MODBTCPS is the median of each round's.

The scan time added per request: ENIPS's hooks (its input and output points,
timed inside the runtime) in the windows its clients load it, against the
quiet window before any client, divided by the requests a scan. Reads are
answered by the server process from the image the scan publishes, so by
design a read costs the scan nothing beyond the publication every scan makes.

Then BUSY_CLIENTS raw EtherNet/IP clients (one process, asyncio) read 100
words and write their own word in turn for BUSY_S against the runtime, and
the late scans and start lateness are compared with the quiet window.

Writes benchmarks/results/bench_enips_server.json (not with --quick, unless
--json is given); exits 0, or 1 when a check fails (a client error, a
refusal a server counted, the runtime faulted or left RUN). Late scans under
the busy clients are reported (MISS), not failed: the machine is shared.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import _common as C
from bench_modbus_server import (RUNTIME, START_LIMIT_S, CheckFailed, Child, client_results, finish, idle_window,
                                 ladder, scans_in, server_xml, span)

from helpers.modbus_peer import free_tcp_port

SCAN_MS = 10
WORDS = 100
KINDS = ("cip", "pccc", "modbus")
CLIENT_COUNTS = (1, 4)
BUSY_CLIENTS = 50
FULL = {"rounds": 3, "window_s": 3.0, "busy_s": 8.0, "idle_s": 4.0}
QUICK = {"rounds": 1, "window_s": 1.5, "busy_s": 2.0, "idle_s": 1.5}
LOAD = str(C.HERE / "enips_server_load.py")
LABEL = {"cip": "CIP tag (pycomm3 LogixDriver)", "pccc": "PCCC (pycomm3 SLCDriver)",
         "modbus": "MODBTCPS (pymodbus), baseline"}


def enips_xml(port: int) -> str:
    return f"""<?xml version="1.0"?>
<!-- Limits raised out of the way: this measures the server, not its limits. -->
<EtherNetIpServer address="127.0.0.1" port="{port}" maxConnections="80" maxRequestsPerSecond="100000"
                  idleTimeout="600000" status="N41:0">
  <Writable address="N12:0" count="{WORDS}"/>
</EtherNetIpServer>
"""


def write_app(directory: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "MODULES.LST").write_text("ENIPS\nMODBTCPS\n")
    (directory / "MODBTCPS.XML").write_text(server_xml(free_tcp_port()))
    (directory / "ENIPS.XML").write_text(enips_xml(free_tcp_port()))
    (directory / "main.lad").write_text(ladder() + "MOV N41:15 N41:14\n")  # N41: ENIPS's status block
    (directory / "softplc.toml").write_text(f"[scan]\nscan_ms = {SCAN_MS}\n")
    return directory


def load(kind: str, port: int, clients: int, window_s: float, watch: list[int]) -> dict:
    """``clients`` clients of ``kind`` (a process each; "raw": all in one) for
    one window, started together; their figures summed."""
    processes = 1 if kind == "raw" else clients
    lead_s = 1.5 + 0.3 * processes
    start_at = time.monotonic() + lead_s
    procs = []
    for k in range(processes):
        spec = {"kind": kind, "port": port, "clients": clients if kind == "raw" else 1, "count": WORDS, "warmup": 3,
                "start_at": start_at, "window_s": window_s, "watch": watch if k == 0 else []}
        procs.append(subprocess.Popen([sys.executable, LOAD, json.dumps(spec)], stdout=subprocess.PIPE, text=True))
    results = client_results(procs, window_s + lead_s + START_LIMIT_S)
    errors = sum(r["errors"] for r in results)
    if errors:
        why = next(r["first_error"] for r in results if r["errors"])
        raise CheckFailed(f"{errors} failed requests of {clients} {kind} clients: {why}")
    late = max(r["ready_late_s"] for r in results)
    return {"kind": kind, "clients": clients, "done": sum(r["done"] for r in results), "window_s": window_s,
            "start": start_at, "end": start_at + window_s, "ready_late_s": late, "cpu_s": results[0]["cpu_s"]}


def run(cfg: dict, work: Path) -> dict:
    app = write_app(work / "app")
    records_path = work / "scans.json"
    runtime = Child([RUNTIME, str(app), str(records_path), "0", "ENIPS,MODBTCPS"], "the runtime (ENIPS, MODBTCPS)")
    enips_port, enips_pid, runtime_pid, modbus_port, modbus_pid = runtime.fields
    ports = {"cip": enips_port, "pccc": enips_port, "raw": enips_port, "modbus": modbus_port}
    server_pid = {"cip": enips_pid, "pccc": enips_pid, "raw": enips_pid, "modbus": modbus_pid}
    watch = [enips_pid, modbus_pid, runtime_pid]
    windows = []

    def window(kind: str, clients: int, rnd: int, seconds: float) -> None:
        w = load(kind, ports[kind], clients, seconds, watch)
        w["round"] = rnd
        used = w["cpu_s"].get(str(server_pid[kind]))
        w["server_cpu_us_per_request"] = 1e6 * used / w["done"] if used and w["done"] else None
        windows.append(w)
        print(f"  round {rnd} {kind:<6} K={clients:<3} {w['done'] / seconds:8.0f} req/s   server CPU "
              f"{100 * (used or 0) / seconds:.0f} %", flush=True)

    try:
        quiet = idle_window(cfg["idle_s"], settle_s=1.0)
        for rnd in range(cfg["rounds"]):
            for k in CLIENT_COUNTS:
                for j in range(len(KINDS)):
                    window(KINDS[(rnd + j) % len(KINDS)], k, rnd, cfg["window_s"])
        window("raw", BUSY_CLIENTS, 0, cfg["busy_s"])
        after_busy = idle_window(cfg["idle_s"])
    finally:
        runtime.stop()
    if not records_path.exists():
        raise CheckFailed("the runtime wrote no records (it did not stop cleanly)")
    result = json.loads(records_path.read_text(encoding="utf-8"))
    return {"windows": windows, "quiet": quiet, "after_busy": after_busy, "state": result["state"],
            "records": result["scans"]}


def enips_hooks_us(records: dict, start: float, end: float) -> tuple[float, int]:
    """ENIPS's hooks per scan (mean, wall us) and the scans, in [start, end)."""
    idx = [i for i, t in enumerate(records["start"]) if start <= t < end]
    hooks = [records["hooks_ns_ENIPS"][i] / 1000 for i in idx]
    return (statistics.fmean(hooks) if hooks else 0.0), len(idx)


def figures_of(raw: dict) -> dict:
    records, windows, state = raw["records"], raw["windows"], raw["state"]
    quiet_hooks, _ = enips_hooks_us(records, raw["quiet"]["start"], raw["quiet"]["end"])
    rates: dict = {}
    for w in windows:
        w["rate"] = w["done"] / w["window_s"]
        hooks, scans = enips_hooks_us(records, w["start"], w["end"])
        w["enips_hooks_us"] = hooks
        per_scan = w["done"] / scans if scans else 0
        w["added_us_per_request"] = (hooks - quiet_hooks) / per_scan if per_scan and w["kind"] != "modbus" else None
        rates.setdefault((w["kind"], w["clients"]), []).append(w)
    table = {}
    for k in CLIENT_COUNTS:
        base = rates[("modbus", k)]
        for kind in KINDS:
            ws = rates[(kind, k)]
            ratios = [w["rate"] / b["rate"] for w, b in zip(ws, base) if b["rate"]]
            added = [w["added_us_per_request"] for w in ws if w["added_us_per_request"] is not None]
            cpu = [w["server_cpu_us_per_request"] for w in ws if w["server_cpu_us_per_request"]]
            table[f"{kind} K={k}"] = {"rates": [w["rate"] for w in ws], "ratio_to_modbtcps": ratios,
                                      "added_scan_us_per_request": added, "server_cpu_us_per_request": cpu}
    busy = next(w for w in windows if w["kind"] == "raw")
    return {"table": table, "quiet_enips_hooks_us": quiet_hooks,
            "quiet": scans_in(records, raw["quiet"]["start"], raw["quiet"]["end"]),
            "busy": scans_in(records, busy["start"], busy["end"]), "busy_rate": busy["rate"],
            "after_busy": scans_in(records, raw["after_busy"]["start"], raw["after_busy"]["end"]), "state": state}


def report(fig: dict) -> list[str]:
    failures = []
    print("\nreads of 100 words a second, ladder at a 10 ms real-time scan (median [min..max] over the rounds)")
    print(f"{'':34} {'req/s':>22} {'/ MODBTCPS':>20} {'scan us added/req':>18} {'server CPU us/req':>18}")
    for name, row in fig["table"].items():
        kind, k = name.split()
        ratio = span(row["ratio_to_modbtcps"], "{:.2f}") if kind != "modbus" else "1 (baseline)"
        added = span(row["added_scan_us_per_request"], "{:.2f}") if row["added_scan_us_per_request"] else "-"
        cpu = span(row["server_cpu_us_per_request"]) if row["server_cpu_us_per_request"] else "-"
        print(f"{LABEL[kind] + ' ' + k:34} {span(row['rates']):>22} {ratio:>20} {added:>18} {cpu:>18}")
    q, b, a = fig["quiet"], fig["busy"], fig["after_busy"]
    print(f"\n{BUSY_CLIENTS} busy clients ({fig['busy_rate']:.0f} requests/s, reads and writes) against the quiet "
          "windows before and after them:")
    print(f"{'':34} {'quiet':>10} {'busy':>10} {'after':>10}")
    for label, key in (("scans", "scans"), ("late scans (>= one period)", "late_scans"),
                       ("start lateness, ms max", "late_ms_max"), ("start lateness, ms p99", "late_ms_p99"),
                       ("ladder, ms max", "ladder_ms_max")):
        print(f"{label:34} {q.get(key, 0):>10.4g} {b.get(key, 0):>10.4g} {a.get(key, 0):>10.4g}")
    state = fig["state"]
    print(f"ENIPS hooks per scan with no client: {fig['quiet_enips_hooks_us']:.1f} us (the whole table's "
          f"publication); both servers' hooks hot (2000 scans back to back): {state['hot']['hooks_us_median']:.1f} us, "
          f"the whole scan {state['hot']['scan_us_median']:.1f} us (medians)")
    if state["mode"] != "RUN" or state["fault"]:
        failures.append(f"the runtime ended in {state['mode']} ({state['fault']})")
    for name, server in state.get("servers", {}).items():
        refused = {k: v for k, v in server["refusals"].items() if v}
        if refused or server["failed"]:
            failures.append(f"{name} refused or failed: {refused or server['failed']}")
    late = b.get("late_scans", 0)
    print(f"under {BUSY_CLIENTS} busy clients: late scans {late} ({'PASS' if late == 0 else 'MISS'})")
    return failures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    cfg = QUICK if args.quick else FULL
    return finish("bench_enips_server", cfg, args.quick, args.json, run, figures_of, report)


if __name__ == "__main__":
    sys.exit(main())
