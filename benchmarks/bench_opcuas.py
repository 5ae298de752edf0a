"""OPCUAS, the OPC UA server over the data table: reads and data-change
notifications a second served to asyncua's Client with the ladder at a
10 ms real-time scan, beside asyncua's own plain Server holding as many
variables in the same run; the scan time the server adds; memory per
monitored item.

    python benchmarks/bench_opcuas.py           # about 1 minute; needs asyncua
    python benchmarks/bench_opcuas.py --quick   # about 30 s (results not written)
    python benchmarks/bench_opcuas.py --tiny    # a few seconds, for the test (results not written)
    python benchmarks/bench_opcuas.py --json PATH

Processes (the machine's cores are shared by all of them):

- the runtime (modbus_server_runtime.py, timing OPCUAS's hooks): a softplc
  app with OPCUAS, the Modbus bench's 100 rungs over N10 and a file N20 of
  1,000 words, at a 10 ms real-time scan; OPCUAS serves its symbols and
  every data file (some 2,000 variables), no security, limits raised;
- the baseline (opcuas_load.py serve): asyncua's plain Server with as many
  Int16 variables, no security, its first 100 given new values every 10 ms
  as a scan would (the ladder changes N10's 100 words every scan);
- the clients, asyncua's Client in this process (one asyncio loop): K
  clients each reading N10:0..99 (V0..V99 on the baseline) in one Read
  request in a loop; one client subscribed to the same 100 variables,
  publishing every 10 ms, counting the data changes it is sent.

ROUNDS rounds, each a window of every kind against OPCUAS and against the
baseline, their order alternating; the ratio OPCUAS / baseline is the
median of the rounds'. Beside each rate, each server process's CPU time per
read or notification (which does not depend on who set the pace: the
client shares the machine).

The scan time added: the runtime times OPCUAS's input and output hooks and
the whole scan in its thread's CPU time, every scan; the windows under
clients against the quiet window before any client, and the late scans in
each (a start a whole period late). The server is a process of its own
that answers from the image each scan publishes, so by design a client
costs the scan nothing beyond that publication.

Memory per monitored item: the resident memory (VmRSS) of each server
process with one subscription of no item, then of 1,000 monitored items
(N20:0..999; V0..V999), the difference over 1,000.

Writes benchmarks/results/bench_opcuas.json (not with --quick or --tiny,
unless --json is given); exits 0, or 1 when a check fails (a client error,
a refusal the server counted, a refused monitored item, the runtime faulted
or left RUN). Late scans under clients are reported (MISS), not failed.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import sys
from pathlib import Path

import _common as C
import opcuas_load as L
from bench_modbus_server import RUNTIME, CheckFailed, Child, finish, idle_window, ladder, scans_in, span, stop_all

from helpers.modbus_peer import free_tcp_port

SCAN_MS = 10
WORDS = 100
ITEMS = 1000
CLIENT_COUNTS = (1, 4)
NS = "urn:softplc-lite:opcuas"
FULL = {"rounds": 3, "window_s": 3.0, "idle_s": 4.0, "settle_s": 2.0, "items": 1000}
QUICK = {"rounds": 1, "window_s": 2.0, "idle_s": 2.0, "settle_s": 1.5, "items": 1000}
TINY = {"rounds": 1, "window_s": 0.5, "idle_s": 0.5, "settle_s": 0.5, "items": 100}  # the suite's: seconds
BASELINE = str(C.HERE / "opcuas_load.py")
KINDS = ("reads K=1", "reads K=4", "notifications")


def opcuas_xml(port: int) -> str:
    return f"""<?xml version="1.0"?>
<!-- Limits raised out of the way and SecurityPolicy None, as the baseline serves: this measures
     the server, not its limits or its encryption. -->
<OpcUaServer address="127.0.0.1" port="{port}" maxSessions="20" maxSubscriptions="100"
             maxMonitoredItems="5000" status="N40:0" securityNone="yes"/>
"""


def write_app(directory: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "MODULES.LST").write_text("OPCUAS\n")
    (directory / "OPCUAS.XML").write_text(opcuas_xml(free_tcp_port()))
    (directory / "main.lad").write_text(f"DATA N20 {ITEMS}\n" + ladder())
    (directory / "softplc.toml").write_text(f"[scan]\nscan_ms = {SCAN_MS}\n")
    return directory


def register_entry_point(work: Path) -> None:
    """OPCUAS's entry point where the installed distribution's metadata
    predates it (an editable install made before pyproject.toml listed it):
    a dist-info on PYTHONPATH for the runtime, as tests/helpers/opcua_apps.py does."""
    from softplc_lite.tlm.registry import installed

    if "OPCUAS" in installed():
        return
    info = work / "site" / "softplc_opcuas_entry-1.0.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: softplc-opcuas-entry\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[softplc_lite.tlms]\nOPCUAS = softplc_lite.tlm.opcuas:OpcUaServer\n")
    sys.path.insert(0, str(work / "site"))
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(work / "site"), os.environ.get("PYTHONPATH")) if p)


def space_of(app: Path) -> tuple[int, list[int]]:
    """How many variables OPCUAS's address space holds for the app (the
    baseline holds as many), and the words of N10 the ladder changes every
    scan (the ones subscribed to: the baseline changes as many every 10 ms).
    The space is laid out as the module lays it out, on an engine without
    the module: no server process is started for a count."""
    from softplc_lite.app import load_app
    from softplc_lite.datatable import DataTable
    from softplc_lite.ladder.engine import Mode
    from softplc_lite.runner import module_engine
    from softplc_lite.tlm.opcuas.space import build_space, rung_comments

    loaded = load_app(app, use_cache=False)
    module = next(m for m in loaded.modules if m.name == "OPCUAS")
    table = DataTable()
    engine = module_engine(loaded.program, table, loaded.settings)
    try:
        module.reference_config(table)  # as attach does: the status words are variables too
        space = build_space(table, module.app_name, module.config, loaded.program.symbols, None,
                            rung_comments(loaded.program))
        engine.set_mode(Mode.RUN)
        seen = []
        for _ in range(4):
            engine.scan()
            seen.append([table.read(f"N10:{k}") for k in range(WORDS)])
        changing = [k for k in range(WORDS) if all(a[k] != b[k] for a, b in zip(seen, seen[1:]))]
        if not changing:
            raise CheckFailed("the ladder changes no word of N10 every scan: nothing to subscribe to")
        return len(space.variables), changing
    finally:
        engine.close()


def run(cfg: dict, work: Path) -> dict:
    register_entry_point(work)
    app = write_app(work / "app")
    variables, changing = space_of(app)
    records_path = work / "scans.json"
    runtime = Child([RUNTIME, str(app), str(records_path), "0", "OPCUAS"], "the runtime (OPCUAS)", wait=False)
    baseline = Child([BASELINE, "serve", str(variables), str(len(changing)), str(SCAN_MS)],
                     "asyncua's plain Server", wait=False)
    try:
        runtime.ready()
        baseline.ready()
    except CheckFailed:
        stop_all([baseline, runtime])
        raise
    opc_port, opc_pid, runtime_pid = runtime.fields
    base_port, base_pid = baseline.fields
    server = {"opcuas": (opc_port, opc_pid), "asyncua": (base_port, base_pid)}
    ids = {"opcuas": [f"ns=2;s=N10:{k}" for k in range(WORDS)], "asyncua": [f"ns=2;s=V{k}" for k in range(WORDS)]}
    n = cfg["items"]
    items = {"opcuas": [f"ns=2;s=N20:{k}" for k in range(n)], "asyncua": [f"ns=2;s=V{k}" for k in range(n)]}
    subscribed = {"opcuas": [f"ns=2;s=N10:{k}" for k in changing],
                  "asyncua": [f"ns=2;s=V{k}" for k in range(len(changing))]}
    windows, memory = [], {}

    def window(kind: str, name: str, rnd: int) -> None:
        port, pid = server[name]
        if kind == "notifications":
            w = asyncio.run(L.notifications(port, pid, subscribed[name], cfg["window_s"], SCAN_MS))
        else:
            w = asyncio.run(L.reads(port, pid, ids[name], int(kind[-1]), cfg["window_s"]))
        used = w["server_cpu_s"]
        if w["errors"]:
            raise CheckFailed(f"{w['errors']} bad reads from {name}: {w['first_error']}")
        w.update(kind=kind, server=name, round=rnd, rate=w["done"] / (w["end"] - w["start"]),
                 server_cpu_us_per=1e6 * used / w["done"] if w["done"] else None)
        windows.append(w)
        print(f"  round {rnd} {kind:<14} {name:<8} {w['rate']:8.0f}/s   server CPU "
              f"{w['server_cpu_us_per'] or 0:.0f} us each", flush=True)

    try:
        L.quiet_asyncua()
        quiet = idle_window(cfg["idle_s"], settle_s=1.0)
        for rnd in range(cfg["rounds"]):
            for kind in KINDS:
                order = ("opcuas", "asyncua") if rnd % 2 == 0 else ("asyncua", "opcuas")
                for name in order:
                    window(kind, name, rnd)
        for name in ("opcuas", "asyncua"):
            port, pid = server[name]
            memory[name] = asyncio.run(L.item_memory(port, pid, items[name], cfg["settle_s"]))
            print(f"  memory {name:<8} {memory[name]['bytes_per_item']:8.0f} bytes an item", flush=True)
    finally:
        stop_all([baseline, runtime])
    if not records_path.exists():
        raise CheckFailed("the runtime wrote no records (it did not stop cleanly)")
    result = json.loads(records_path.read_text(encoding="utf-8"))
    return {"windows": windows, "quiet": quiet, "memory": memory, "variables": variables,
            "subscribed": len(changing), "state": result["state"],
            "records": result["scans"]}


def figures_of(raw: dict) -> dict:
    records, windows = raw["records"], raw["windows"]
    quiet = scans_in(records, raw["quiet"]["start"], raw["quiet"]["end"])
    table = {}
    for kind in KINDS:
        ours = [w for w in windows if w["kind"] == kind and w["server"] == "opcuas"]
        base = [w for w in windows if w["kind"] == kind and w["server"] == "asyncua"]
        loaded = [scans_in(records, w["start"], w["end"]) for w in ours]
        table[kind] = {
            "opcuas": [w["rate"] for w in ours], "asyncua": [w["rate"] for w in base],
            "ratio": [o["rate"] / b["rate"] for o, b in zip(ours, base) if b["rate"]],
            "opcuas_cpu_us": [w["server_cpu_us_per"] for w in ours if w["server_cpu_us_per"]],
            "asyncua_cpu_us": [w["server_cpu_us_per"] for w in base if w["server_cpu_us_per"]],
            "hooks_cpu_us": [s.get("hooks_cpu_us_mean", 0.0) for s in loaded],
            "scan_cpu_us": [s.get("scan_cpu_us_mean", 0.0) for s in loaded],
            "late_scans": [s.get("late_scans", 0) for s in loaded], "scans": [s.get("scans", 0) for s in loaded]}
    return {"variables": raw["variables"], "subscribed": raw["subscribed"], "table": table, "quiet": quiet, "memory": raw["memory"],
            "state": raw["state"]}


def report(fig: dict) -> list[str]:
    failures = []
    q = fig["quiet"]
    print(f"\nladder at a 10 ms real-time scan; both servers hold {fig['variables']} variables; "
          "median [min..max] over the rounds")
    print(f"{'':34} {'OPCUAS /s':>20} {'asyncua Server /s':>20} {'ratio':>18} {'CPU us each':>16}")
    for kind, row in fig["table"].items():
        what = ("reads of 100 variables, " + kind.split()[1] + " clients" if kind.startswith("reads")
                else f"data changes of {fig['subscribed']}, 1 client")
        cpu = f"{span(row['opcuas_cpu_us'])} / {span(row['asyncua_cpu_us'])}" if row["opcuas_cpu_us"] else "-"
        print(f"{what:34} {span(row['opcuas']):>20} {span(row['asyncua']):>20} {span(row['ratio'], '{:.2f}'):>18}"
              f" {cpu:>16}")
    print("\nthe scan (the runtime's thread CPU time, us a scan, mean) with no client and under each kind:")
    print(f"{'':34} {'OPCUAS hooks':>14} {'whole scan':>12} {'late scans':>12}")
    print(f"{'no client':34} {q.get('hooks_cpu_us_mean', 0):>14.1f} {q.get('scan_cpu_us_mean', 0):>12.1f} "
          f"{q.get('late_scans', 0):>12}")
    for kind, row in fig["table"].items():
        print(f"{kind:34} {statistics.median(row['hooks_cpu_us']):>14.1f} "
              f"{statistics.median(row['scan_cpu_us']):>12.1f} {sum(row['late_scans']):>12}")
    print("\nmemory a monitored item (server process RSS, 0 then "
          f"{max(m['items'] for m in fig['memory'].values())} items):")
    for name, m in fig["memory"].items():
        print(f"{name:34} {m['bytes_per_item']:>10.0f} bytes  ({m['rss_kib_0']} -> {m['rss_kib_items']} KiB)")
        if m["refused"]:
            failures.append(f"{name} refused {m['refused']} of {m['items']} monitored items")
    state = fig["state"]
    if state["mode"] != "RUN" or state["fault"]:
        failures.append(f"the runtime ended in {state['mode']} ({state['fault']})")
    for name, server in state.get("servers", {}).items():
        refused = {k: v for k, v in server["refusals"].items() if v}
        if refused or server["failed"]:
            failures.append(f"{name} refused or failed: {refused or server['failed']}")
    late = sum(sum(row["late_scans"]) for row in fig["table"].values())
    print(f"late scans under clients: {late} ({'PASS' if late == 0 else 'MISS'})")
    return failures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--tiny", action="store_true")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    cfg = TINY if args.tiny else QUICK if args.quick else FULL
    return finish("bench_opcuas", cfg, args.quick or args.tiny, args.json, run, figures_of, report)


if __name__ == "__main__":
    sys.exit(main())
