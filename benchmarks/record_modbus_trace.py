"""Record programs/modbus_master/pymodbus-session.trace: the Modbus RTU master
(programs/modbus_master) against pymodbus, a real third-party slave, over a
socat pty pair; then check the recording replays to the same data table.

    python benchmarks/record_modbus_trace.py [--out TRACE]

(default TRACE: programs/modbus_master/pymodbus-session.trace; needs socat
and pymodbus 3.16; about 2 s.) Replay it with

    softplc run programs/modbus_master --fresh --replay programs/modbus_master/pymodbus-session.trace --scans N

where N, in the trace's header comments, is the scans the replay takes to
give the last recorded query its outcome (more scans poll on past the end
of the recording: one more query, reported as an output difference, and a
timeout).

The session is ONE run of the app exactly as shipped: nothing in the data
table changes while it runs (N7:0 = 0, N7:1 = 125, polls paced 50 ms by
T4:0, 1 ms scans on the real-time clock, the port's timeout 250 ms from
COMGENIUS.LST), so a replay needs no --set at all. Port 0 is end A of the
pty pair (``--port 0=A``). What answers on end B changes, in PHASES, from
the slave side only:

1. ``good``: pymodbus (tests/helpers/modbus_peer.py's ModbusPeer: unit 2, 38400,
   200 holding registers, register k = (k * 7 + 3) & 0xFFFF): good replies,
   copied to the safe block N11;
2. ``silent``: nobody (pymodbus stopped): the master's COMSCANs time out
   (C5:3, 250 ms each);
3. ``garbage``: this script holds end B and answers a query with the bytes
   FF FE 00: neither COMSCAN can match, the master clears its receive
   buffer (C5:4);
4. ``exception``: pymodbus with only 100 holding registers (a slave whose
   map shrank): reading 0..124 is past its end, exception 02 illegal data
   address (C5:2, N7:21 = 2); N11 keeps the last good block;
5. ``good``: pymodbus with the 200 registers again: good replies resume.

A phase ends after its number of outcomes of its kind; the next phase
starts in the scan that counted that outcome (which ends the transaction:
the next query leaves with the pacing, about 50 ms later), so
every query of the trace gets exactly one of the four outcomes, and the
script keeps the master's scans stopped while it swaps what is on end B.

Why not change N7:0 mid-run to get the exception: a replay repeats the
program's side only if the program sends the same bytes, so it would need
the same data table change at the same scan. With the slave side changing,
the replay is the plain app and --replay.

Why it replays deterministically: a replay port delivers each recorded RX
event at (the program's write of the query it answers) + (its recorded
delay), and the replay runs on simulated 1 ms scans, so every replay is the
same, scan for scan. The outcomes also equal the recorded run's because
each exchange is one clean outcome: a whole reply, a whole exception, three
garbage bytes (the first one already fails both COMSCANs) or nothing for
250 ms (recorded delays of replies are a few ms). The script checks it:
it replays the new trace on simulated time and compares counters, N11 and
N7:21 with the recorded run's, and that the replayed program wrote exactly
the recorded queries. It then writes the recorded run's figures into the
trace's header comments (tests/test_modbus_master.py checks them against
the bytes of the trace and the replay). Exit status 0 when all is well, 1
otherwise (the trace is then left as recorded, for a look).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
for _p in (REPO, REPO / "tests"):  # the package from a checkout; ptypair, modbus_peer
    if str(_p) not in sys.path:
        sys.path.insert(1, str(_p))

import serial  # noqa: E402

from helpers.modbus_peer import ModbusPeer  # noqa: E402
from helpers.ptypair import PtyPair  # noqa: E402
from softplc_lite.app import load_app  # noqa: E402
from softplc_lite.runner import RunOptions, Runner  # noqa: E402

APP = REPO / "programs" / "modbus_master"
TRACE = APP / "pymodbus-session.trace"
REGISTERS = [(k * 7 + 3) & 0xFFFF for k in range(200)]
SHRUNK = 100  # registers of the slave in the exception phase (< 125: reading 0..124 fails)
GARBAGE = b"\xff\xfe\x00"
QUERY_BYTES = 8  # 02 03 00 00 00 7D 85 D8

# (what is on end B, the outcome that ends the phase, how many of them)
PHASES = (("good", "good", 4), ("silent", "timeouts", 2), ("garbage", "garbage", 1),
          ("exception", "exceptions", 2), ("good", "good", 4))

SIDES = {"good": f"pymodbus, {len(REGISTERS)} registers", "silent": "nobody", "garbage": "FF FE 00 for a reply",
         "exception": f"pymodbus, {SHRUNK} registers"}

COUNTERS = {"polls": "C5:0.ACC", "good": "C5:1.ACC", "exceptions": "C5:2.ACC", "timeouts": "C5:3.ACC",
            "garbage": "C5:4.ACC"}
OUTCOMES = ("good", "exceptions", "timeouts", "garbage")


def master(sets=(), **options) -> Runner:
    """The modbus_master app in a Runner (the app's snapshot untouched)."""
    app = load_app(APP, state_dir=None, use_cache=False)  # writes nothing beside the app
    app.state_dir = None
    return Runner(app, RunOptions(fresh=True, sets=tuple(sets), **options), log=lambda msg: None)


def figures(runner: Runner) -> dict:
    """What a run ends with: the counters, N7:21 and the safe block N11."""
    t = runner.table
    out = {name: t.read(addr) for name, addr in COUNTERS.items()}
    out["last_exception"] = t.read("N7:21")
    out["N11"] = [t.read(f"N11:{k}") for k in range(125)]
    return out


def port0(runner: Runner):
    """The pyserial object behind logical port 0 (a replay port in a replay)."""
    return runner.app.modules[0].ports.ports[0].serial


class SlaveSide:
    """What is on end B of the pair: pymodbus, nobody, or this script sending garbage."""

    def __init__(self, pair: PtyPair) -> None:
        self.pair = pair
        self.peer: ModbusPeer | None = None
        self.port: serial.Serial | None = None
        self.query = bytearray()

    def become(self, kind: str) -> None:
        self.stop()
        if kind == "good":
            self.peer = ModbusPeer(self.pair.b, REGISTERS).start()
        elif kind == "exception":
            self.peer = ModbusPeer(self.pair.b, REGISTERS[:SHRUNK]).start()
        elif kind == "garbage":
            self.port = serial.Serial(self.pair.b, 38400, timeout=0)  # open() flushes stale bytes
            self.query.clear()
        elif kind != "silent":
            raise ValueError(kind)

    def poll(self) -> None:
        """In the garbage phase: answer each whole query with GARBAGE."""
        if self.port is None:
            return
        self.query += self.port.read(256)
        while len(self.query) >= QUERY_BYTES:
            del self.query[:QUERY_BYTES]
            self.port.write(GARBAGE)

    def stop(self) -> None:
        if self.peer is not None:
            self.peer.stop()
            self.peer = None
        if self.port is not None:
            self.port.close()
            self.port = None


def record(path: str | Path, phases=PHASES, sets=(), seconds: float = 20.0, pair_dir=None) -> dict:
    """Run the master against the PHASES, recording port 0 into ``path``;
    the recorded run's figures (see figures()) plus ``scans`` and ``phases``."""
    with PtyPair(pair_dir) as pair:
        side = SlaveSide(pair)
        runner = None
        try:
            side.become(phases[0][0])
            runner = master(sets, realtime=True, ports=(f"0={pair.a}",), record=str(path))
            t = runner.table
            deadline = time.monotonic() + seconds
            scans = 0
            for number, (kind, outcome, wanted) in enumerate(phases):
                if number:
                    side.become(kind)  # between transactions: Busy is off, no query in flight
                base = t.read(COUNTERS[outcome])
                while t.read(COUNTERS[outcome]) - base < wanted:
                    if time.monotonic() > deadline:
                        raise TimeoutError(f"phase {number + 1} ({kind}): {t.read(COUNTERS[outcome]) - base} of "
                                           f"{wanted} {outcome} after {seconds} s; {figures(runner)}")
                    runner.run(1)
                    scans += 1
                    side.poll()
            result = figures(runner)
        finally:
            if runner is not None:
                runner.engine.close()  # also closes the trace
            side.stop()
    result["scans"] = scans
    result["phases"] = [list(p) for p in phases]
    return result


def replay(path: str | Path, polls: int, sets=(), executor: str = "compiled", max_scans: int = 100_000) -> dict:
    """Replay ``path`` on simulated time until ``polls`` transactions have an
    outcome; figures() plus ``scans``, ``now_ms``, ``finished`` and ``mismatches``."""
    runner = master(sets, executor=executor, replay=str(path))
    try:
        t = runner.table
        scans = 0
        while sum(t.read(COUNTERS[o]) for o in OUTCOMES) < polls and scans < max_scans:
            runner.run(1)
            scans += 1
        result = figures(runner)
        port = port0(runner)
        result.update(scans=scans, now_ms=runner.engine.clock.now_ms, finished=port.finished,
                      mismatches=list(port.mismatches))
    finally:
        runner.engine.close()
    return result


def annotate(path: str | Path, recorded: dict, replay_scans: int) -> None:
    """Put the recorded run's figures, and the replay command, into the trace's header comments."""
    lines = Path(path).read_text(encoding="utf-8").splitlines(keepends=True)
    counts = " ".join(f"{name}={recorded[name]}" for name in COUNTERS)
    notes = [
        "# made by benchmarks/record_modbus_trace.py (its docstring tells the session):",
        "# programs/modbus_master as shipped, port 0 on a socat pty, pymodbus 3.16 slave unit 2 on the other end;",
        "# on the far end, in turn: " + "; ".join(f"{SIDES[k]} ({n} {o})" for k, o, n in recorded["phases"]),
        f"# recorded run: {counts} last_exception={recorded['last_exception']}",
        ("# replay: softplc run programs/modbus_master --fresh --replay programs/modbus_master/pymodbus-session.trace"
         f" --scans {replay_scans}"),
        # read by ports/trace.py: a --replay without --scans stops there
        f"# scans: {replay_scans} (the replay's: at the app's 1 ms a scan, the last reply is counted in scan "
        f"{replay_scans})",
    ]
    header = 1 if lines and lines[0].startswith("# softplc_lite port trace") else 0
    lines[header:header] = [n + "\n" for n in notes]
    Path(path).write_text("".join(lines), encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(TRACE), help="the trace to write (default: %(default)s)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    recorded = record(args.out)
    counts = ", ".join(f"{name} {recorded[name]}" for name in COUNTERS)
    print(f"recorded {args.out}: {counts}; last exception {recorded['last_exception']}; "
          f"{recorded['scans']} scans, {time.perf_counter() - t0:.1f} s")
    problems = []
    for outcome in OUTCOMES:
        if recorded[outcome] < 1:
            problems.append(f"the recording has no {outcome}")
    if recorded["N11"] != REGISTERS[:125]:
        problems.append("the safe block N11 is not pymodbus's registers 0..124")
    if recorded["polls"] != sum(recorded[o] for o in OUTCOMES):
        problems.append("a query without an outcome")
    replays = [replay(args.out, recorded["polls"], executor=e) for e in ("compiled", "reference")]
    for r in replays:
        for key in (*COUNTERS, "last_exception", "N11"):
            if r[key] != recorded[key]:
                problems.append(f"replay: {key} {r[key] if key != 'N11' else '...'} != recorded "
                                f"{recorded[key] if key != 'N11' else '...'}")
        if r["mismatches"] or not r["finished"]:
            problems.append(f"replay: finished={r['finished']}, output differences {r['mismatches'][:3]}")
    if (replays[0]["scans"], replays[0]["now_ms"]) != (replays[1]["scans"], replays[1]["now_ms"]):
        problems.append("the two executors' replays took different numbers of scans")
    print(f"replayed on simulated time: {replays[0]['scans']} scans ({replays[0]['now_ms']} ms), counters "
          + ("equal the recorded run's" if not problems else "DIFFER"))
    if problems:
        for p in problems:
            print(f"problem: {p}", file=sys.stderr)
        return 1
    annotate(args.out, recorded, replays[0]["scans"])
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
