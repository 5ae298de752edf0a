"""Part 2 of bench_modbus_slave.py: the ladder Modbus slave's transactions
per second over a pty, against pymodbus's own serial server.

One socat pty pair (tests/helpers/ptypair.py ``PtyPair``); the slave on end A,
pymodbus's sync client ``ModbusSerialClient(B, framer=RTU, baudrate=19200,
timeout=1, retries=0)`` calling ``read_holding_registers(0, count=125,
device_id=1)`` on end B. Three slaves take turns on end A, one at a time,
each started and stopped in every round (the order rotating):

- ``ladder``: the real CLI in a process of its own,
  ``python -m softplc_lite run APP --fresh --realtime --scan-ms 0
  --set N9:5=1 --port 0=A --load REGISTERS.json --print C5:0.ACC ...``
  (free-running scans); stopped with SIGINT (SIGKILL if it does not go),
  its printed counters checked (every request served; no exception, bad
  frame or other frame);
- ``ladder 1ms``: the same with ``--scan-ms 1`` (the period the app's
  softplc.toml sets);
- ``pymodbus``: pymodbus 3.16's ``ModbusSerialServer`` (tests/helpers/modbus_peer.py
  ``PeerProcess``: unit 1, 200 holding registers, RTU, in a process of its
  own).

For each: PTY_WARMUP untimed reads, then PTY_TRANSACTIONS timed ones; the
last reply's registers checked. Figures are medians over PTY_ROUNDS rounds,
ratios medians of the per-round ratios. Target: ladder / pymodbus >= 0.8. A
pty ignores the baud rate: this is software on both ends.

Beside it, with the same slave still running, a raw pyserial master (write
the 8-byte request, ``read(255)`` blocking, then the 3.5-character silence
an RTU master keeps after a reply, 1.82 ms at 19200, before the next
request) measures the slave's own turnaround: median ms from the request
written to the whole reply read, and transactions per second. pymodbus's
sync client looks at the port only every ``max(4 characters, 1 ms)``
(2.08 ms at 19200 baud) and needs two looks that agree, so its rate steps
with the slave's turnaround. A request without a reply (1 s timeout) or
with an exception reply fails the run.
"""

from __future__ import annotations

import ctypes
import json
import logging
import os
import re
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

import _common as C


import serial
from helpers.modbus_peer import PeerProcess
from helpers.modbus_slave_app import SLAVE_APP, copy_app
from modbus_slave_common import (
    MS,
    REGISTERS,
    Apps,
    CheckFailed,
    read_reply,
    read_request,
    signed,
    verdict,
)
from helpers.ptypair import PtyPair
from pymodbus import FramerType
from pymodbus.client import ModbusSerialClient
from pymodbus.exceptions import ModbusException

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

PTY_ROUNDS = 5
PTY_WARMUP = 20
PTY_TRANSACTIONS = 250
RAW_TRANSACTIONS = 250
PTY_BAUD = 19200
T35_S = 3.5 * 10 / PTY_BAUD  # the RTU frame gap at PTY_BAUD 8N1 (10 bits a character)
TARGET_LADDER_OVER_PYMODBUS = 0.8
NOTES_SYNC_PER_S = 400  # /work/shared/testing-notes.md: the sync client, 125 registers, at 38400 baud
START_S = 20.0  # how long a slave process may take to answer its first request
STOP_S = 5.0


def _die_with_parent() -> None:  # in the child between fork and exec (as tests/helpers/ptypair.py does for socat)
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: SIGINT at the end (or SIGKILL) still ends it
        pass


class LadderProcess:
    """``python -m softplc_lite run`` on a copy of the slave app, port 0 on ``port``."""

    PRINTS = ("C5:0.ACC", "C5:1.ACC", "C5:2.ACC", "C5:3.ACC")

    def __init__(self, app: Path, port: str, scan_ms: int, load: Path, log: Path) -> None:
        self.cmd = [sys.executable, "-m", "softplc_lite", "run", str(app), "--fresh", "--realtime",
                    "--scan-ms", str(scan_ms), "--set", "N9:5=1", "--port", f"0={port}", "--load", str(load)]
        for addr in self.PRINTS:
            self.cmd += ["--print", addr]
        self.log = log
        env = dict(os.environ)
        env["PYTHONPATH"] = str(C.REPO) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        with open(log, "wb") as fh:
            self.proc = subprocess.Popen(self.cmd, stdin=subprocess.DEVNULL, stdout=fh, stderr=subprocess.STDOUT,
                                         cwd=str(C.REPO), env=env, preexec_fn=_die_with_parent)
        self.output = ""
        self.counters: dict[str, int] = {}

    def stop(self) -> None:
        proc = self.proc
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(STOP_S)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(STOP_S)
        self.output = self.log.read_text(errors="replace")
        for addr in self.PRINTS:
            m = re.search(rf"^{re.escape(addr)} = (-?\d+)$", self.output, re.MULTILINE)
            if m:
                self.counters[addr] = int(m.group(1))
        m = re.search(r": (\d+) scans, ([\d.]+) s real time", self.output)
        if m:
            self.scans, self.run_s = int(m.group(1)), float(m.group(2))


class PymodbusProcess:
    def __init__(self, port: str) -> None:
        self.peer = PeerProcess(port, REGISTERS, device_id=1, baudrate=PTY_BAUD)
        self.proc = self.peer.proc

    def stop(self) -> None:
        self.peer.stop()


def wait_ready(port: str, proc: subprocess.Popen) -> float:
    """Seconds until the slave on the far end answers a read of 125 registers."""
    request, reply = read_request(125), read_reply(125)
    t0 = time.perf_counter()
    with serial.serial_for_url(port, baudrate=PTY_BAUD, timeout=0.2) as ser:
        while True:
            ser.reset_input_buffer()
            ser.write(request)
            if ser.read(len(reply)) == reply:
                break
            if proc.poll() is not None:
                raise CheckFailed(f"the slave process exited with status {proc.returncode} before answering")
            if time.perf_counter() - t0 > START_S:
                raise CheckFailed(f"no reply from the slave in {START_S} s")
        time.sleep(0.01)
        ser.reset_input_buffer()
    return time.perf_counter() - t0


def pymodbus_reads(port: str, warmup: int, transactions: int) -> tuple[float, float]:
    """(transactions/s, the client's poll interval in ms) of pymodbus's sync client. Every reply must come
    (a ModbusIOException after the 1 s timeout fails the run) and be no exception reply; the last one's
    registers must be REGISTERS[:125]."""
    client = ModbusSerialClient(port, framer=FramerType.RTU, baudrate=PTY_BAUD, timeout=1, retries=0)
    if not client.connect():
        raise CheckFailed(f"pymodbus: cannot open {port}")
    done = 0
    good = None

    def read():
        nonlocal done, good
        reply = client.read_holding_registers(0, count=125, device_id=1)
        if reply.isError():
            raise CheckFailed(f"pymodbus client, request {done + 1}: {reply}")
        done += 1
        good = reply

    try:
        for _ in range(warmup):
            read()
        now = time.perf_counter
        t0 = now()
        for _ in range(transactions):
            read()
        elapsed = now() - t0
        if good is None or good.registers != REGISTERS[:125]:
            raise CheckFailed(f"pymodbus client: {good}")
        return transactions / elapsed, client._recv_interval * 1000
    except ModbusException as e:
        raise CheckFailed(f"pymodbus client, request {done + 1}: {type(e).__name__}: {e}") from e
    finally:
        client.close()


def raw_reads(port: str, warmup: int, transactions: int) -> tuple[float, float]:
    """(transactions/s, median ms from the request written to the whole reply read) with plain pyserial:
    write the request, read the reply (blocking, 1 s timeout), keep the 3.5-character silence an RTU master
    must keep after a reply (T35_S: 1.82 ms at 19200 baud), write the next request."""
    request, reply = read_request(125), read_reply(125)
    now = time.perf_counter_ns
    silence_ns = round(T35_S * 1e9)
    with serial.serial_for_url(port, baudrate=PTY_BAUD, timeout=1) as ser:
        turnaround = []
        t_start = 0
        quiet_until = now()
        for k in range(warmup + transactions):
            if k == warmup:
                t_start = now()
            wait = quiet_until - now()
            if wait > 0:
                time.sleep(wait / 1e9)
            t0 = now()
            ser.write(request)
            got = ser.read(len(reply))
            t1 = now()
            quiet_until = t1 + silence_ns
            if got != reply:
                raise CheckFailed(f"raw pyserial, request {k + 1}: reply {got[:12].hex(' ')}... ({len(got)} bytes"
                                  + (", 1 s timeout" if len(got) < len(reply) else "") + ")")
            if k >= warmup:
                turnaround.append(t1 - t0)
        elapsed = (now() - t_start) / 1e9
    return transactions / elapsed, statistics.median(turnaround) / MS


def bench_pty(apps: Apps, rounds: int, transactions: int, raw_transactions: int) -> dict:
    pair = PtyPair(names=("slaveA", "masterB"), lifetime_s=max(120, rounds * 40 + 60))
    started: list[subprocess.Popen] = []
    try:
        app = copy_app(SLAVE_APP, apps.root / "pty-app", baud=PTY_BAUD)
        load = apps.root / "registers.json"
        load.write_text(json.dumps({"N10": [signed(w) for w in REGISTERS]}), encoding="utf-8")
        cases = {
            "ladder": lambda: LadderProcess(app, pair.a, 0, load, apps.root / "ladder0.log"),
            "ladder 1ms": lambda: LadderProcess(app, pair.a, 1, load, apps.root / "ladder1.log"),
            "pymodbus": lambda: PymodbusProcess(pair.a),
        }
        names = list(cases)
        tps = {n: [] for n in names}
        raw_tps = {n: [] for n in names}
        raw_ms = {n: [] for n in names}
        ready_s = {n: [] for n in names}
        scans_per_s: list[float] = []
        poll_ms = None
        for rnd in range(rounds):
            for name in names[rnd % len(names):] + names[:rnd % len(names)]:
                slave = cases[name]()
                started.append(slave.proc)
                step = "starting"
                try:
                    ready_s[name].append(wait_ready(pair.b, slave.proc))
                    step = "pymodbus client"
                    per_s, poll_ms = pymodbus_reads(pair.b, PTY_WARMUP, transactions)
                    tps[name].append(per_s)
                    step = "raw pyserial"
                    per_s, ms = raw_reads(pair.b, PTY_WARMUP, raw_transactions)
                    raw_tps[name].append(per_s)
                    raw_ms[name].append(ms)
                except Exception as e:
                    slave.stop()
                    said = getattr(slave, "output", "") or ""
                    raise CheckFailed(f"{name}, round {rnd + 1}, {step}: {type(e).__name__}: {e}"
                                      + (f"\n{name} said:\n{said}" if said else "")) from e
                finally:
                    slave.stop()
                if isinstance(slave, LadderProcess):
                    c = slave.counters
                    asked = 1 + 2 * PTY_WARMUP + transactions + raw_transactions  # +1: the request that found it ready
                    if slave.proc.returncode != 0 or len(c) != len(LadderProcess.PRINTS):
                        raise CheckFailed(f"{name}: exit status {slave.proc.returncode}, output:\n{slave.output}")
                    if c["C5:0.ACC"] < asked or c["C5:1.ACC"] or c["C5:2.ACC"] or c["C5:3.ACC"]:
                        raise CheckFailed(f"{name}: counters {c} after at least {asked} requests")
                    if name == "ladder" and getattr(slave, "scans", None):
                        scans_per_s.append(slave.scans / slave.run_s)
    finally:
        for p in started:
            if p.poll() is None:
                p.kill()
                p.wait(STOP_S)
        pair.close()
    left = pair.leftovers() + [p.pid for p in started if p.poll() is None]
    if left:
        print(f"warning: processes left: {left}", file=sys.stderr)

    def med(d: dict) -> dict:
        return {n: statistics.median(v) for n, v in d.items()}

    ratios = {f"{n}/pymodbus": statistics.median(a / b for a, b in zip(tps[n], tps["pymodbus"]))
              for n in ("ladder", "ladder 1ms")}
    raw_ratios = {f"{n}/pymodbus": statistics.median(a / b for a, b in zip(raw_tps[n], raw_tps["pymodbus"]))
                  for n in ("ladder", "ladder 1ms")}
    out = {
        "rounds": rounds, "transactions": transactions, "raw_transactions": raw_transactions, "warmup": PTY_WARMUP,
        "client_baudrate": PTY_BAUD, "client_poll_ms": round(poll_ms, 3),
        "transactions_per_s": {n: round(v) for n, v in med(tps).items()},
        "transactions_per_s_range": {n: [round(min(v)), round(max(v))] for n, v in tps.items()},
        "ratios": {k: round(v, 3) for k, v in ratios.items()},
        "raw": {"transactions_per_s": {n: round(v) for n, v in med(raw_tps).items()},
                "turnaround_ms": {n: round(v, 3) for n, v in med(raw_ms).items()},
                "turnaround_ms_range": {n: [round(min(v), 3), round(max(v), 3)] for n, v in raw_ms.items()},
                "ratios": {k: round(v, 3) for k, v in raw_ratios.items()}},
        "ready_s": {n: round(statistics.median(v), 2) for n, v in ready_s.items()},
        "ladder_scans_per_s": round(statistics.median(scans_per_s)) if scans_per_s else None,
        "notes_sync_per_s_at_38400": NOTES_SYNC_PER_S,
        "target_ladder_over_pymodbus": TARGET_LADDER_OVER_PYMODBUS,
        "verdict": verdict(ratios["ladder/pymodbus"] >= TARGET_LADDER_OVER_PYMODBUS),
        "verdict_1ms": verdict(ratios["ladder 1ms/pymodbus"] >= TARGET_LADDER_OVER_PYMODBUS),
    }
    t, rng = out["transactions_per_s"], out["transactions_per_s_range"]
    rt, rms = out["raw"]["transactions_per_s"], out["raw"]["turnaround_ms"]
    print(f"--- 2. over a socat pty: pymodbus's sync client (RTU, baudrate {PTY_BAUD}) reading 125 holding registers "
          f"of unit 1, {rounds} rounds x {transactions} transactions after {PTY_WARMUP} untimed, medians [min..max]; "
          f"beside it a raw pyserial master ({raw_transactions} reads a round):")
    print("  slave on the other end                          pymodbus client /s          ratio   raw /s  turnaround ms")
    labels = {"ladder": "ladder, softplc run --realtime --scan-ms 0",
              "ladder 1ms": "ladder, softplc run --realtime --scan-ms 1",
              "pymodbus": "pymodbus ModbusSerialServer (baseline)"}
    for n in names:
        ratio = f"{ratios[n + '/pymodbus']:5.2f}x" if n != "pymodbus" else "     1"
        print(f"  {labels[n]:46}  {t[n]:6,} [{rng[n][0]:,}..{rng[n][1]:,}]  {ratio:>12}  {rt[n]:7,}  {rms[n]:13.2f}")
    print(f"  ladder / pymodbus {ratios['ladder/pymodbus']:.3f}x [{out['verdict']}: >= {TARGET_LADDER_OVER_PYMODBUS}]; "
          f"at 1 ms scans {ratios['ladder 1ms/pymodbus']:.2f}x [{out['verdict_1ms']}]; raw pyserial: "
          f"{raw_ratios['ladder/pymodbus']:.2f}x and {raw_ratios['ladder 1ms/pymodbus']:.2f}x")
    print(f"  the pymodbus client looks at the port every {poll_ms:.2f} ms and wants two looks that agree: "
          f"a transaction takes a whole number of looks (2 = {1000 / (2 * poll_ms):.0f}/s, 3 = "
          f"{1000 / (3 * poll_ms):.0f}/s, 4 = {1000 / (4 * poll_ms):.0f}/s, less its own work); "
          f"the ladder process scanned {out['ladder_scans_per_s'] or 0:,} times a second free-running "
          f"(whole run, idle included); the notes' sync baseline is {NOTES_SYNC_PER_S}/s at 38400 baud "
          f"(looks every 1.04 ms)", flush=True)
    return out

