"""The Modbus RTU slave written in ladder (programs/modbus_slave): its
response time on the simulated wire, its transactions per second against
pymodbus's own serial server over a pty, and the scan time it costs.

    python benchmarks/bench_modbus_slave.py             # about 1 minute; needs socat and pymodbus
    python benchmarks/bench_modbus_slave.py --quick     # a smoke run of about 6 s (results not written)
    python benchmarks/bench_modbus_slave.py --json PATH # also write the results to PATH

Every app is a copy of programs/modbus_slave in a temporary directory
(tests/helpers/modbus_slave_app.py ``copy_app``), run fresh with the compiled
executor unless said otherwise; its holding registers N10:0..199 hold
REGISTERS (the same values pymodbus's server gets), so every reply is
checked against what it must be. The three parts, in this order:

1. Response time on the simulated wire (here; ``WireSlave``: the app on
   simulated time, 1 ms scans, port 0 on a sim:// link whose other end this
   script drives as the master). At 9600, 19200 and 38400 baud 8N1 with the
   quiet-line time N9:5 = 4, 2 and 1 ms (3.5 characters rounded up to whole
   ms), Read Holding Registers (function 3) of 1 and of 125 registers, the
   request written at a scan boundary: the gap from the end of the
   request's last byte to the start of the reply's first byte (the
   ``transact_timed`` figure: the reply's first arrival less one character
   time), beside the 3.5-character minimum at that baud and their ratio.
   Simulated time is exact, so one transaction would do; WIRE_REPEATS are run
   and must agree to the nanosecond. Also the scans a transaction takes: up to
   the one that serves it (the served counter C5:0 moves in it; its reply
   leaves at its end), and until the reply's last byte has arrived.

2. Transactions per second over a socat pty (modbus_slave_tps.py): the
   ladder slave as a ``softplc_lite run`` process, free-running and at 1 ms
   scans, against pymodbus's ``ModbusSerialServer``, each served to
   pymodbus's sync client (the baseline: ladder / pymodbus, target >= 0.8)
   and to a raw pyserial master that keeps the 3.5-character gap (the
   slave's own turnaround).

3. Scan time (modbus_slave_scan.py): the slave's idle and serving scans
   against an empty app's on simulated time, the rungs and instructions they
   run, and a profile of the 125-register serving scan.

The frames, the registers and the slave on simulated time are in
modbus_slave_common.py.

Writes benchmarks/results/bench_modbus_slave.json (not with --quick, unless
--json is given); prints figures, baselines, ratios and PASS/MISS (a miss is
reported, not failed); exits 0, or 1 when socat is missing or a check fails.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import _common as C


from modbus_slave_common import MS, Apps, CheckFailed, frames, transact, wire_slave
from modbus_slave_scan import IDLE_SCANS, KINDS, SCAN_ROUNDS, SCAN_TX, bench_scan
from modbus_slave_tps import (
    PTY_ROUNDS,
    PTY_TRANSACTIONS,
    RAW_TRANSACTIONS,
    TARGET_LADDER_OVER_PYMODBUS,
    bench_pty,
)
from helpers.ptypair import SocatMissing, socat_processes

# 1. simulated wire
WIRE_BAUDS = {9600: 4, 19200: 2, 38400: 1}  # baud: N9:5, 3.5 characters rounded up to whole ms
WIRE_SIZES = (1, 125)
WIRE_REPEATS = 3


# -- 1. response time on the simulated wire ---------------------------------------------------------------


def bench_wire(apps: Apps, repeats: int) -> dict:
    rows = []
    for baud, quiet_ms in WIRE_BAUDS.items():
        s = wire_slave(apps, baud, quiet_ms)
        try:
            for count in WIRE_SIZES:
                kind = f"read {count}"
                txs = [transact(s, kind) for _ in range(repeats)]
                gaps = {tx.gap_ns for tx in txs}
                serve = {tx.serve_index for tx in txs}
                if len(gaps) != 1 or len(serve) != 1:
                    raise CheckFailed(f"{baud} baud, {kind}: the simulated runs differ: gaps {gaps}, serving scans {serve}")
                # the tests' helper measures the same gap
                request, reply = frames(kind)
                got, gap_check = s.transact_timed(request)
                s.scans(3)
                if got != reply or gap_check != txs[0].gap_ns:
                    raise CheckFailed(f"{baud} baud, {kind}: transact_timed says {gap_check} ns, this script {txs[0].gap_ns}")
                tx = txs[0]
                t35 = 3.5 * s.char_ns
                end_ms = tx.last_request_byte_end / MS - tx.sent_at / MS  # the request's end, from its write
                # the gap as the rungs make it: wait for the next scan to see the last byte, then the quiet
                # timer's N9:5 ms, counted from the scan after (a TON times from the scan after it goes true)
                model_ms = (math.ceil(end_ms + 1e-9) - end_ms) + quiet_ms + 1
                rows.append({
                    "baud": baud, "quiet_ms": quiet_ms, "registers": count, "request_bytes": len(request),
                    "reply_bytes": len(reply), "char_us": round(s.char_ns / 1000, 2),
                    "gap_ms": round(tx.gap_ns / MS, 4), "t35_ms": round(t35 / MS, 4),
                    "ratio_gap_over_t35": round(tx.gap_ns / t35, 3), "model_gap_ms": round(model_ms, 4),
                    "scans_to_serve": tx.serve_index + 1, "scans_to_reply_end": tx.scans_to_reply_end,
                    "line_ms": round((tx.reply_end - tx.sent_at) / MS, 3),
                })
        finally:
            s.close()
    print(f"--- 1. response time on the simulated wire (1 ms scans, function 3 from address 0, the request written "
          f"at a scan boundary; {repeats} runs each, identical):")
    print("   baud  N9:5  regs  reply B   gap ms  3.5 chars ms  gap / 3.5 chars  scans to serve  to reply end  line ms")
    for r in rows:
        print(f"  {r['baud']:5}  {r['quiet_ms']:4}  {r['registers']:4}  {r['reply_bytes']:7}  {r['gap_ms']:7.3f}  "
              f"{r['t35_ms']:12.3f}  {r['ratio_gap_over_t35']:14.2f}x  {r['scans_to_serve']:14}  "
              f"{r['scans_to_reply_end']:12}  {r['line_ms']:7.2f}")
    print("  gap = (to the next scan after the request's last byte) + N9:5 + 1 scan (the quiet timer counts from the "
          "scan after it starts); the reply leaves at the end of the serving scan", flush=True)
    for r in rows:
        if abs(r["gap_ms"] - r["model_gap_ms"]) > 1e-3:
            print(f"  note: {r['baud']} baud, {r['registers']} registers: gap {r['gap_ms']} ms, the model says "
                  f"{r['model_gap_ms']} ms")
    return {"rows": rows, "repeats": repeats}


# -- main --------------------------------------------------------------------------------------------------


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run; results not written")
    parser.add_argument("--json", metavar="PATH", help="also write the results to PATH")
    args = parser.parse_args()
    quick = args.quick
    t_start = time.perf_counter()
    apps = Apps()
    try:
        wire = bench_wire(apps, 1 if quick else WIRE_REPEATS)
        try:
            pty = bench_pty(apps, 1 if quick else PTY_ROUNDS, 60 if quick else PTY_TRANSACTIONS,
                            60 if quick else RAW_TRANSACTIONS)
        except SocatMissing as e:
            print(f"bench_modbus_slave: {e}", file=sys.stderr)
            return 1
        scan = bench_scan(apps, 3 if quick else SCAN_ROUNDS, 3 if quick else SCAN_TX, 300 if quick else IDLE_SCANS)
    except CheckFailed as e:
        print(f"check failed: {e}", file=sys.stderr)
        return 1
    finally:
        apps.close()
    wall = time.perf_counter() - t_start
    left = socat_processes()
    figures = {"quick": quick, "wire": wire, "pty": pty, "scan": scan, "wall_s": round(wall, 1),
               "socat_left": left}
    t = pty["transactions_per_s"]
    su = scan["scan_us"]
    print(f"\nsummary ({wall:.1f} s):")
    print("  1. simulated wire, gap after the request / the 3.5-character minimum: " + ", ".join(
        f"{r['baud']} {r['gap_ms']:.2f} ms = {r['ratio_gap_over_t35']:.2f}x" for r in wire["rows"]
        if r["registers"] == WIRE_SIZES[0]) + " (the same for 1 and 125 registers)")
    print(f"  2. pty, pymodbus sync client: ladder {t['ladder']}/s, at 1 ms scans {t['ladder 1ms']}/s, pymodbus's "
          f"server {t['pymodbus']}/s: {pty['ratios']['ladder/pymodbus']:.3f}x [{pty['verdict']} >= "
          f"{TARGET_LADDER_OVER_PYMODBUS}], {pty['ratios']['ladder 1ms/pymodbus']:.2f}x [{pty['verdict_1ms']}]; "
          f"turnaround (raw pyserial) {pty['raw']['turnaround_ms']['ladder']:.2f} / "
          f"{pty['raw']['turnaround_ms']['ladder 1ms']:.2f} / {pty['raw']['turnaround_ms']['pymodbus']:.2f} ms")
    print(f"  3. scan: empty app {su['empty']:.1f} us, slave idle {su['idle']:.1f} us, serving "
          + ", ".join(f"{k} {su[k]:,.0f} us ({scan['ratio_over_idle'][k]:.0f}x idle)" for k in KINDS))
    if left:
        print(f"warning: socat processes left: {left}", file=sys.stderr)
    C.save_figures("bench_modbus_slave", figures, quick, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
