"""Modbus RTU master benchmark: the ladder master of
programs/modbus_master against pymodbus's own clients, on the same pymodbus
server over the same socat pty pair; and the ladder on the simulated
38400-baud wire against the wire-time minimum.

    python benchmarks/bench_modbus_master.py

The transaction everywhere is Read Holding Registers, slave 2, start 0,
count 125 (query ``02 03 00 00 00 7D 85 D8``, 255-byte reply), answered by
one pymodbus 3.16 ``ModbusSerialServer`` (tests/helpers/modbus_peer.py: unit 2,
38400 8N1, 200 holding registers), in a process of its own, on end B of one
socat pty pair, for the whole run. On end A, in turn:

1. ``ladder``: the app programs/modbus_master as shipped but for
   ``T4:0.PRE=0`` (polls back to back), port 0 overridden to end A, on the
   real-time clock with free-running scans (``realtime=True, scan_ms=0``),
   compiled executor: a transaction is one good reply counted by C5:1;
2. ``sync``: pymodbus's ``ModbusSerialClient(A, framer=FramerType.RTU,
   baudrate=38400, timeout=1, retries=0)``, calling
   ``read_holding_registers(0, count=125, device_id=2)`` in a loop;
3. ``async``: pymodbus's ``AsyncModbusSerialClient`` (same arguments),
   awaiting the same call in a loop (its own asyncio loop, this thread).

Method: ROUNDS rounds; in each, every case (the order rotates every round)
opens end A, does WARMUP transactions untimed, then TRANSACTIONS timed ones,
checks the registers it got, and closes end A (so only one client is ever on
the port; opening is not timed). A figure is the median transactions per
second over the rounds; a ratio is the median of the per-round ratios.
Targets: ladder / sync >= 1.0 (the shared testing notes measured the sync
client at about 400/s); ladder / async is reported against the notes'
async figure (about 1,500/s), without a target. A pty does not enforce the
baud rate (about 0.2 ms for 256 bytes), so these figures are the cost of
the software on both ends, not of a 38400-baud line.

Why the server runs in another process: in this one, as a background
thread, it shares the GIL with the master, and the ladder's free-running
scans starve it: measured here, 60 to 110 transactions/s with a few 250 ms
timeouts per thousand, against about 1,900/s and none with the server in a
process of its own (as a slave is on a real line).

Then the simulated wire (the app's own port 0, ``sim://modbus?device=modbus
&id=2&registers=200``, SimulatedClock 1 ms, T4:0.PRE=0): SIM_SCANS scans
per run, SIM_RUNS runs. Figures: simulated ms per transaction (between the
first and the last good reply of a run) against the wire-time minimum 70.31
ms (query 2.08 + 3.5-character gap 0.91 + reply 66.41 + gap 0.91; target:
within 10%), and the wall-clock scans per second and transactions per wall
second of that run (how much faster than the real line the simulation goes).

Writes benchmarks/results/bench_modbus_master.json; prints figures,
ratios and verdicts (a miss is reported, not failed); exits 0, or 1 when
socat is missing or a check fails.
"""

from __future__ import annotations

import logging
import statistics
import sys
import time

import _common as C


from pymodbus_clients import async_reads, sync_reads  # noqa: E402

from helpers.modbus_peer import PeerProcess  # noqa: E402
from helpers.ptypair import PtyPair, SocatMissing  # noqa: E402
from softplc_lite.app import load_app  # noqa: E402
from softplc_lite.runner import RunOptions, Runner  # noqa: E402

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

APP = C.REPO / "programs" / "modbus_master"
REGISTERS = [(k * 7 + 3) & 0xFFFF for k in range(200)]
ROUNDS = 15
WARMUP = 20
TRANSACTIONS = 300  # timed, per case and round (about 0.8 s for the sync client)
SIM_SCANS = 20_000  # 20 simulated seconds: about 280 transactions
SIM_RUNS = 5

CHAR_NS = 260_417  # 38400 8N1
GAP_NS = 911_460
WIRE_MIN_MS = (8 * CHAR_NS + GAP_NS + 255 * CHAR_NS + GAP_NS) / 1e6
TARGET_LADDER_OVER_SYNC = 1.0
TARGET_SIM_RATIO = 1.10
NOTES_PER_S = {"sync": 400, "async": 1500}  # /work/shared/testing-notes.md


def master(**options) -> Runner:
    app = load_app(APP, state_dir=None)
    app.state_dir = None
    return Runner(app, RunOptions(fresh=True, sets=("T4:0.PRE=0",), **options), log=lambda msg: None)


def signed(word: int) -> int:
    return word - 0x10000 if word & 0x8000 else word


# -- the three masters: each returns seconds for TRANSACTIONS timed transactions ---------------------------


class CheckFailed(RuntimeError):
    pass


def ladder_case(port: str) -> tuple[float, dict]:
    r = master(realtime=True, scan_ms=0, ports=(f"0={port}",))
    try:
        t = r.table
        scan = r.engine.scan  # what Runner.run does free-running, without its per-scan bookkeeping
        r.run(1)  # into RUN

        def good_replies() -> int:
            return t.read("C5:1.ACC")

        deadline = time.monotonic() + 30
        while good_replies() < WARMUP:
            scan()
            if time.monotonic() > deadline:
                raise CheckFailed(f"ladder: no replies ({[t.read(f'C5:{k}.ACC') for k in range(5)]})")
        start = good_replies()
        scans = 0
        t0 = time.perf_counter()
        while good_replies() < start + TRANSACTIONS:
            scan()
            scans += 1
        elapsed = time.perf_counter() - t0
        bad = [t.read(f"C5:{k}.ACC") for k in (2, 3, 4)]
        if bad != [0, 0, 0]:
            raise CheckFailed(f"ladder: exceptions, timeouts, garbage = {bad}")
        if [t.read(f"N11:{k}") for k in range(125)] != [signed(w) for w in REGISTERS[:125]]:
            raise CheckFailed("ladder: the safe block N11 is not pymodbus's registers")
        return elapsed, {"scans_per_transaction": scans / TRANSACTIONS}
    finally:
        r.engine.close()


def sync_case(port: str) -> tuple[float, dict]:
    return _checked("sync", sync_reads(port, WARMUP, transactions=TRANSACTIONS))


def async_case(port: str) -> tuple[float, dict]:
    return _checked("async", async_reads(port, WARMUP, transactions=TRANSACTIONS))


def _checked(name: str, result) -> tuple[float, dict]:
    _, elapsed, reply = result
    if reply.isError() or reply.registers != REGISTERS[:125]:
        raise CheckFailed(f"{name}: {reply}")
    return elapsed, {}


CASES = {"ladder": ladder_case, "sync": sync_case, "async": async_case}


def bench_pty(pair: PtyPair) -> dict:
    peer = PeerProcess(pair.b, REGISTERS)
    try:
        names = list(CASES)
        per_s: dict[str, list[float]] = {n: [] for n in names}
        extra: dict[str, list[dict]] = {n: [] for n in names}
        for rnd in range(ROUNDS):
            for name in names[rnd % len(names):] + names[:rnd % len(names)]:
                elapsed, info = CASES[name](pair.a)
                per_s[name].append(TRANSACTIONS / elapsed)
                extra[name].append(info)
    finally:
        peer.stop()
    ratios = {f"ladder/{o}": statistics.median(a / b for a, b in zip(per_s["ladder"], per_s[o]))
              for o in ("sync", "async")}
    out = {
        "transactions_per_s": {n: round(statistics.median(v)) for n, v in per_s.items()},
        "transactions_per_s_range": {n: [round(min(v)), round(max(v))] for n, v in per_s.items()},
        "ratios": {k: round(v, 2) for k, v in ratios.items()},
        "ladder_scans_per_transaction": round(statistics.median(i["scans_per_transaction"]
                                                                for i in extra["ladder"]), 1),
        "notes_per_s": NOTES_PER_S,
        "target_ladder_over_sync": TARGET_LADDER_OVER_SYNC,
        "verdict_ladder_over_sync": "PASS" if ratios["ladder/sync"] >= TARGET_LADDER_OVER_SYNC else "MISS",
    }
    tps = out["transactions_per_s"]
    print(f"--- pty pair, one pymodbus server, {ROUNDS} rounds x {TRANSACTIONS} transactions "
          f"(125 registers), medians [min..max]:")
    for n in names:
        lo, hi = out["transactions_per_s_range"][n]
        print(f"  {n:7} {tps[n]:6,}/s  [{lo:,}..{hi:,}]")
    print(f"  ladder / sync  {out['ratios']['ladder/sync']:.2f}x  [{out['verdict_ladder_over_sync']} >= "
          f"{TARGET_LADDER_OVER_SYNC}]  (notes: sync about {NOTES_PER_S['sync']}/s)")
    print(f"  ladder / async {out['ratios']['ladder/async']:.2f}x  (notes: async about {NOTES_PER_S['async']:,}/s); "
          f"ladder scans per transaction {out['ladder_scans_per_transaction']}", flush=True)
    return out


def bench_sim() -> dict:
    runs = []
    for _ in range(SIM_RUNS):
        r = master()
        try:
            t = r.table
            at_good: list[int] = []

            def note(engine, at_good=at_good, t=t) -> None:
                if t.read("C5:1.ACC") > len(at_good):
                    at_good.append(engine.clock.now_ms)

            t0 = time.perf_counter()
            r.run(SIM_SCANS, on_scan=note)
            wall = time.perf_counter() - t0
            bad = [t.read(f"C5:{k}.ACC") for k in (2, 3, 4)]
            if bad != [0, 0, 0] or len(at_good) < 2:
                raise CheckFailed(f"sim: good {len(at_good)}, exceptions, timeouts, garbage = {bad}")
            runs.append({
                "ms_per_transaction": (at_good[-1] - at_good[0]) / (len(at_good) - 1),
                "transactions": len(at_good),
                "wall_s": wall,
                "scans_per_wall_s": SIM_SCANS / wall,
                "transactions_per_wall_s": len(at_good) / wall,
                "simulated_over_wall": r.engine.clock.now_ms / 1000 / wall,
            })
        finally:
            r.engine.close()
    med = {k: statistics.median(run[k] for run in runs) for k in runs[0]}
    ratio = med["ms_per_transaction"] / WIRE_MIN_MS
    out = {
        "scans_per_run": SIM_SCANS, "runs": SIM_RUNS, "scan_ms": 1,
        "wire_min_ms": round(WIRE_MIN_MS, 3),
        "ms_per_transaction": round(med["ms_per_transaction"], 3),
        "ratio_over_wire_min": round(ratio, 4),
        "target_ratio": TARGET_SIM_RATIO,
        "verdict": "PASS" if ratio <= TARGET_SIM_RATIO else "MISS",
        "transactions_per_run": med["transactions"],
        "scans_per_wall_s": round(med["scans_per_wall_s"]),
        "transactions_per_wall_s": round(med["transactions_per_wall_s"]),
        "simulated_over_wall": round(med["simulated_over_wall"], 1),
        "wire_limit_per_s": round(1000 / WIRE_MIN_MS, 2),
    }
    print(f"--- simulated 38400-baud wire, {SIM_RUNS} runs x {SIM_SCANS:,} scans of 1 ms, medians:")
    print(f"  {out['ms_per_transaction']:.3f} simulated ms per transaction vs wire minimum {WIRE_MIN_MS:.2f} ms: "
          f"{ratio:.3f}x [{out['verdict']} <= {TARGET_SIM_RATIO}]")
    print(f"  wall clock: {out['scans_per_wall_s']:,} scans/s, {out['transactions_per_wall_s']:,} transactions "
          f"per wall second ({out['simulated_over_wall']}x real time; the line itself allows "
          f"{out['wire_limit_per_s']}/s)", flush=True)
    return out


def main() -> int:
    t_start = time.perf_counter()
    try:
        pair = PtyPair(names=("masterA", "slaveB"))
    except SocatMissing as e:
        print(f"bench_modbus_master: {e}", file=sys.stderr)
        return 1
    try:
        pty = bench_pty(pair)
    except CheckFailed as e:
        print(f"check failed: {e}", file=sys.stderr)
        return 1
    finally:
        pair.close()
        if pair.leftovers():
            print(f"warning: socat processes left: {pair.leftovers()}", file=sys.stderr)
    try:
        sim = bench_sim()
    except CheckFailed as e:
        print(f"check failed: {e}", file=sys.stderr)
        return 1
    wall = time.perf_counter() - t_start
    path = C.write_results("bench_modbus_master", {
        "method": {"rounds": ROUNDS, "warmup": WARMUP, "transactions_per_sample": TRANSACTIONS,
                   "figures": "median over the rounds; ratios: median of per-round ratios",
                   "transaction": "read holding registers, slave 2, start 0, count 125 (8-byte query, 255-byte reply)",
                   "server": "pymodbus 3.16 ModbusSerialServer (tests/helpers/modbus_peer.py) on a socat pty, "
                             "background thread of this process",
                   "ladder": "programs/modbus_master, T4:0.PRE=0, realtime, scan_ms=0 (free-running), compiled"},
        "pty": pty,
        "sim": sim,
        "wall_s": round(wall, 1),
    })
    tps = pty["transactions_per_s"]
    print(f"\nsummary ({wall:.1f} s):")
    print(f"  pty: ladder {tps['ladder']:,}/s, pymodbus sync {tps['sync']:,}/s, async {tps['async']:,}/s; "
          f"ladder/sync {pty['ratios']['ladder/sync']:.2f}x [{pty['verdict_ladder_over_sync']}], "
          f"ladder/async {pty['ratios']['ladder/async']:.2f}x")
    print(f"  sim: {sim['ms_per_transaction']:.2f} ms per transaction, {sim['ratio_over_wire_min']:.3f}x the wire "
          f"minimum [{sim['verdict']}]; {sim['scans_per_wall_s']:,} scans/s, "
          f"{sim['transactions_per_wall_s']:,} transactions per wall second")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
