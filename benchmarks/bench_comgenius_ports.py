"""COMGENIUS ports benchmark: COMPRINT-to-COMSCAN round trips over
``loop://`` and a socat pty pair, against raw pyserial moving the same bytes
over the same kinds of port; and bytes per second through the simulated
link (``sim://`` at an unlimited rate) against ``loop://``.

    python benchmarks/bench_comgenius_ports.py

Two frames:

- ``text``: the manual's example 1, ``"Rack no: %3o has %2d modules.\\r\\n"``
  with 5 and 2 (30 bytes), printed from and scanned back into two N words;
- ``reply``: a Modbus reply-sized frame, ``"\\x02\\x03\\xfa%.250C%#R"`` with 125
  words (255 bytes: header, 250 data bytes, CRC-16), printed from an N file
  and scanned back into another (the CRC is checked on every match).

Measurements (all in one process, one thread, free-running: no sleeps):

1. ``ladder loop://``: one runtime (Engine + ComGenius, compiled executor,
   SimulatedClock 1 ms) whose port 0 is ``loop://``. Its ladder prints the
   frame, then COMSCANs the echo, then re-arms both rungs itself (a phase
   bit latched by COMPRINT DN and unlatched by COMSCAN DN); a round trip is
   one COMPRINT DN followed by the matching COMSCAN DN, counted by an ADD in
   the ladder. On loop:// that is exactly 2 scans (the bytes leave at the
   output point, the echo is read at the next input point).
2. ``ladder pty``: two runtimes on the two ends of a socat pty pair,
   scanned alternately (A, B, A, B, ...). A prints the frame and COMSCANs
   the reply; B COMSCANs the frame and COMPRINTs it back (a request/response
   exchange, as a Modbus master and slave); a round trip is A's COMPRINT DN
   to A's COMSCAN DN of the echoed frame, through socat both ways.
3. ``ladder sim://``: the same two runtimes as 2, on the two ends of a
   simulated link at an unlimited rate (``sim://NAME?rate=unlimited``, on
   the engines' clock): no kernel, no socat, no per-byte queue, so this is
   the runtime's own cost of a request/response exchange.
4. baselines ``raw loop://``, ``raw pty`` and ``raw sim://``: pyserial alone
   moving the same bytes the same way: on loop:// ``write`` then
   ``read(in_waiting)``; on a (second) pty pair and on a second sim:// link
   A ``write``s, B reads (``timeout=0``, polling) until it has the whole
   frame and writes it back, A reads until it has it all. The ratio
   ladder / raw is the cost of the runtime (scans, formatting, matching,
   buffers, the driver) per round trip.
5. bytes per second: ``sim://NAME?rate=unlimited`` (two ends of one link,
   default real-time clock) and ``loop://`` (one port): write 4 KiB, read
   what is there (``read(in_waiting)``), repeat; the figure is bytes read
   per second. pyserial's loop:// moves every byte through a queue.Queue
   (a put and a get per byte), so it is slow at this; sim:// moves chunks.

Method (as bench_comgenius_format.py): each case is a function that runs
``number`` round trips (or 4 KiB writes); ``number`` is calibrated so a
sample lasts about SAMPLE_S; the cases are then sampled in ROUNDS rounds,
interleaved (the order rotates every round), with the garbage collector
paused. A figure is the median over the rounds; a ratio is the median of
the per-round ratios. Every frame is checked end to end before timing, and
the ladders count COMSCAN errors (there must be none). No targets: the
script prints figures and ratios, writes benchmarks/results/
bench_comgenius_ports.json and exits 0 (1 if a check fails or socat is
missing).

A pty does not enforce the baud rate (shared testing notes): these are
round trips through the kernel and socat, not 38400-baud wire times (the
reply frame alone takes 66.4 ms on a real 38400 8N1 line).
"""

from __future__ import annotations

import sys
import time

import _common as C


import serial  # noqa: E402

from helpers.ptypair import PtyPair, SocatMissing  # noqa: E402
from softplc_lite.datatable import DataTable  # noqa: E402
from softplc_lite.ladder import Engine, Mode, load_text  # noqa: E402
from softplc_lite.ladder.engine import SimulatedClock  # noqa: E402
from softplc_lite.ports import urlhandler  # noqa: E402
from softplc_lite.tlm.comgenius import ComGenius  # noqa: E402
from softplc_lite.tlm.comgenius.config import parse_config  # noqa: E402
from softplc_lite.tlm.comgenius.params import ValueParam  # noqa: E402
from softplc_lite.tlm.comgenius.printf import format_text  # noqa: E402
from softplc_lite.tlm.registry import instruction_set  # noqa: E402

SAMPLE_S = 0.04
ROUNDS = 15
MAX_TRIPS = 30_000  # per sample: the ladder's 16-bit counter must not overflow
CHUNK = 4096

TEXT_FORMAT = "Rack no: %3o has %2d modules.\r\n"
REPLY_FORMAT = "\x02\x03\xfa%.250C%#R"
REPLY_WORDS = [((k * 40503 + 12345) & 0xFFFF) for k in range(125)]  # the whole 16-bit range
REPLY_SIGNED = [w - 0x10000 if w & 0x8000 else w for w in REPLY_WORDS]

LST = r"""[DRIVER]
DEBUG=0
[PORTS]
0, {device}, ISO-8859-1, 38400, 8, N, 1, 3600000
[STRINGS]
1 "Rack no: %3o has %2d modules.\r\n"
2 "\x02\x03\xfa%.250C%#R"
"""

# Operands per frame: (format, what is printed, where the echo is scanned into)
FRAMES = {
    "text": ("1", "N7:0 N7:1", "N7:5 N7:6"),
    "reply": ("2", "N10:0", "N11:0"),
}

MASTER = """
DATA N7 30
DATA N10 125
DATA N11 125
// phase B3/0 = 0: print the frame; 1: scan the echo. COMPRINT DN latches, COMSCAN DN unlatches.
XIO B3/0 COMPRINT R6:0 0 {fmt} {out}
XIC B3/0 COMSCAN R6:1 0 {fmt} {into}
XIC R6:0/DN OTL B3/0
XIC R6:1/DN OTU B3/0
XIC R6:1/DN XIO R6:1/ER ADD N7:20 1 N7:20
XIC R6:1/ER ADD N7:21 1 N7:21
"""

ECHO = """
DATA N7 30
DATA N10 125
// phase B3/0 = 0: scan a frame; 1: print it back.
XIO B3/0 COMSCAN R6:1 0 {fmt} {out}
XIC B3/0 COMPRINT R6:0 0 {fmt} {out}
XIC R6:1/DN OTL B3/0
XIC R6:0/DN OTU B3/0
XIC R6:1/ER ADD N7:21 1 N7:21
"""


def frame_bytes(kind: str) -> bytes:
    if kind == "text":
        return format_text(TEXT_FORMAT, [ValueParam(5), ValueParam(2)]).encode("latin-1")
    return format_text(REPLY_FORMAT, [ValueParam(REPLY_WORDS)]).encode("latin-1")


class Runtime:
    def __init__(self, program: str, device: str) -> None:
        self.module = ComGenius(parse_config(LST.format(device=device)))
        self.engine = Engine(load_text(program, instructions=instruction_set([self.module])), DataTable(),
                             clock=SimulatedClock(1), executor="compiled", modules=[self.module])
        self.engine.set_mode(Mode.RUN)
        self.scan = self.engine.scan
        self.count = self.engine.table.word_ref("N7:20")
        self.errors = self.engine.table.word_ref("N7:21")

    def load(self, kind: str) -> None:
        t = self.engine.table
        if kind == "text":
            t.write("N7:0", 5)
            t.write("N7:1", 2)
        else:
            for k, w in enumerate(REPLY_SIGNED):
                t.write(f"N10:{k}", w)

    def close(self) -> None:
        self.engine.close()


# -- the cases: each runs n round trips -------------------------------------------------------


def ladder_case(master: Runtime, echo: Runtime | None):
    data, i = master.count
    scan = master.scan
    if echo is None:
        def run(n):
            data[i] = 0
            while data[i] < n:
                scan()
    else:
        scan_b = echo.scan

        def run(n):
            data[i] = 0
            while data[i] < n:
                scan()
                scan_b()
    return run


def raw_loop_case(port, frame: bytes):
    size = len(frame)

    def run(n, write=port.write, read=port.read):
        for _ in range(n):
            write(frame)
            got = read(port.in_waiting)
            while len(got) < size:
                got += read(port.in_waiting)
    return run


def raw_pty_case(a, b, frame: bytes):
    size = len(frame)

    def run(n, wa=a.write, ra=a.read, wb=b.write, rb=b.read):
        for _ in range(n):
            wa(frame)
            got = rb(CHUNK)
            while len(got) < size:
                got += rb(CHUNK)
            wb(got)
            back = ra(CHUNK)
            while len(back) < size:
                back += ra(CHUNK)
    return run


def bytes_case(writer, reader):
    chunk = bytes(range(256)) * (CHUNK // 256)

    def run(n, write=writer.write, read=reader.read):
        got = 0
        for _ in range(n):
            write(chunk)
            got += len(read(reader.in_waiting))
        while got < n * CHUNK:  # nothing may stay behind
            got += len(read(reader.in_waiting))
    return run


# -- timing ---------------------------------------------------------------------------------


def calibrate(body, cap: int) -> int:
    number = 1
    while True:
        t0 = time.perf_counter_ns()
        body(number)
        elapsed = time.perf_counter_ns() - t0
        if elapsed >= SAMPLE_S * 1e9 / 4 or number >= cap:
            return max(1, min(cap, int(number * SAMPLE_S * 1e9 / max(elapsed, 1))))
        number *= 4


def interleaved(cases: dict[str, tuple[object, int]], rounds: int = ROUNDS) -> dict[str, list[float]]:
    """ns per unit of each case, one sample per round, cases interleaved."""
    numbers = {name: calibrate(body, cap) for name, (body, cap) in cases.items()}
    return C.sample_rounds({name: body for name, (body, _) in cases.items()}, numbers, rounds)


median, ratio = C.median, C.ratio


def per_s(ns: float) -> float:
    return 1e9 / ns


# -- checks before timing ----------------------------------------------------------------------------


def check_ladder(kind: str, master: Runtime, echo: Runtime | None) -> dict:
    """Run some round trips and verify what came back; the scans each round trip took."""
    master.load(kind)
    scans = 0
    data, i = master.count
    data[i] = 0
    deadline = time.monotonic() + 5
    while data[i] < 50:
        master.scan()
        if echo is not None:
            echo.scan()
        scans += 1
        if time.monotonic() > deadline:
            raise SystemExit(f"check failed: {kind}: no round trips ({master.engine.table.read('R6:1')})")
    t = master.engine.table
    if kind == "text":
        back = [t.read("N7:5"), t.read("N7:6")]
        assert back == [5, 2], back
    else:
        back = [t.read(f"N11:{k}") for k in range(125)]
        assert back == REPLY_SIGNED, back[:5]
    assert master.errors[0][master.errors[1]] == 0, "the master's COMSCAN failed"
    if echo is not None:
        assert echo.errors[0][echo.errors[1]] == 0, "the echo's COMSCAN failed"
    port = master.module.ports.ports[0]
    tx = [d for _, direction, d in port.history if direction == "TX"]
    assert tx[-1] == frame_bytes(kind), tx[-1][:16]
    return {"scans_per_round_trip": round(scans / 50, 2)}


def open_raw_pty(pair: PtyPair):
    a = serial.Serial(pair.a, 38400, timeout=0)
    b = serial.Serial(pair.b, 38400, timeout=0)
    return a, b


# -- main -------------------------------------------------------------------------------------


def bench_round_trips(pairs: list[PtyPair]) -> dict:
    out: dict = {}
    urlhandler.register()
    ra, rb = open_raw_pty(pairs[0])
    loop = serial.serial_for_url("loop://", timeout=0)
    sa = serial.serial_for_url("sim://bench-raw?rate=unlimited", baudrate=38400, timeout=0)
    sb = serial.serial_for_url("sim://bench-raw?rate=unlimited", baudrate=38400, timeout=0)
    opened: list[Runtime] = []
    try:
        for kind, pair in zip(FRAMES, pairs[1:]):
            fmt, printed, into = FRAMES[kind]
            frame = frame_bytes(kind)
            master_text = MASTER.format(fmt=fmt, out=printed, into=into)
            echo_text = ECHO.format(fmt=fmt, out="N10:0" if kind == "reply" else "N7:0 N7:1")
            sim_url = f"sim://bench-{kind}?rate=unlimited"
            loop_rt = Runtime(master_text, "loop://")
            a, b = Runtime(master_text, pair.a), Runtime(echo_text, pair.b)
            sim_a, sim_b = Runtime(master_text, sim_url), Runtime(echo_text, sim_url)
            opened = [loop_rt, a, b, sim_a, sim_b]
            scans = {"loop://": check_ladder(kind, loop_rt, None), "pty": check_ladder(kind, a, b),
                     "sim://": check_ladder(kind, sim_a, sim_b)}
            for case in (raw_loop_case(loop, frame), raw_pty_case(ra, rb, frame), raw_pty_case(sa, sb, frame)):
                case(1)  # each raw case returns only once the whole frame came back
            assert loop.in_waiting == 0 and ra.in_waiting == 0 and sa.in_waiting == 0
            cases = {
                "ladder loop://": (ladder_case(loop_rt, None), MAX_TRIPS),
                "raw loop://": (raw_loop_case(loop, frame), 1 << 22),
                "ladder pty": (ladder_case(a, b), MAX_TRIPS),
                "raw pty": (raw_pty_case(ra, rb, frame), 1 << 22),
                "ladder sim://": (ladder_case(sim_a, sim_b), MAX_TRIPS),
                "raw sim://": (raw_pty_case(sa, sb, frame), 1 << 22),
            }
            s = interleaved(cases)
            for rt in opened:
                assert rt.errors[0][rt.errors[1]] == 0, f"{kind}: a COMSCAN failed while timing"
            out[kind] = {
                "frame_bytes": len(frame),
                "round_trips_per_s": {name: round(per_s(median(v))) for name, v in s.items()},
                "us_per_round_trip": {name: {"median": round(median(v) / 1e3, 2), "best": round(min(v) / 1e3, 2)}
                                      for name, v in s.items()},
                "ratio_ladder_over_raw": {t: round(ratio(s, f"ladder {t}", f"raw {t}"), 2)
                                          for t in ("loop://", "pty", "sim://")},
                "ratio_ladder_over_ladder_sim": {t: round(ratio(s, f"ladder {t}", "ladder sim://"), 2)
                                                 for t in ("loop://", "pty")},
                "scans_per_round_trip": {t: v["scans_per_round_trip"] for t, v in scans.items()},
            }
            r = out[kind]
            print(f"--- round trips, {kind} frame ({len(frame)} bytes): per second (us each)")
            for name in cases:
                u = r["us_per_round_trip"][name]
                print(f"  {name:15} {r['round_trips_per_s'][name]:>9,}/s  ({u['median']:8.2f} us, best {u['best']:.2f})")
            lr = r["ratio_ladder_over_raw"]
            print(f"  ladder / raw: loop:// {lr['loop://']:.1f}x, pty {lr['pty']:.1f}x, sim:// {lr['sim://']:.1f}x; "
                  f"scans per round trip (A's): " + ", ".join(f"{t} {v}" for t, v in r["scans_per_round_trip"].items()),
                  flush=True)
            for rt in opened:
                rt.close()
            opened = []
    finally:
        for rt in opened:
            rt.close()
        for p in (ra, rb, loop, sa, sb):
            p.close()
    return out


def bench_bytes() -> dict:
    urlhandler.register()
    sa = serial.serial_for_url("sim://bench-ports?rate=unlimited", baudrate=38400, timeout=0)
    sb = serial.serial_for_url("sim://bench-ports?rate=unlimited", baudrate=38400, timeout=0)
    loop = serial.serial_for_url("loop://", timeout=0)
    try:
        chunk = bytes(range(256)) * (CHUNK // 256)
        sa.write(chunk)
        assert sb.read(sb.in_waiting) == chunk and sb.in_waiting == 0
        sb.write(chunk[:10])
        assert sa.read(sa.in_waiting) == chunk[:10]
        cases = {"sim:// unlimited": (bytes_case(sa, sb), 1 << 20), "loop://": (bytes_case(loop, loop), 1 << 20)}
        s = interleaved(cases)
    finally:
        for p in (sa, sb, loop):
            p.close()
    out = {
        "write_bytes": CHUNK,
        "bytes_per_s": {name: round(CHUNK * per_s(median(v))) for name, v in s.items()},
        "us_per_4KiB": {name: round(median(v) / 1e3, 3) for name, v in s.items()},
        "ratio_loop_over_sim_time": round(ratio(s, "loop://", "sim:// unlimited"), 1),
    }
    print("--- bytes per second, 4 KiB writes, reads of what is there")
    for name in cases:
        print(f"  {name:17} {out['bytes_per_s'][name] / 1e6:9.1f} MB/s  ({out['us_per_4KiB'][name]:.2f} us per 4 KiB)")
    print(f"  loop:// takes {out['ratio_loop_over_sim_time']:,.0f}x sim://'s time per 4 KiB", flush=True)
    return out


def main() -> int:
    t_start = time.perf_counter()
    try:
        pairs = [PtyPair(names=(f"raw{k}A", f"raw{k}B")) for k in range(1)]  # raw pyserial's pair
        pairs += [PtyPair(names=(f"{kind}A", f"{kind}B")) for kind in FRAMES]
    except SocatMissing as e:
        print(f"bench_comgenius_ports: {e}", file=sys.stderr)
        return 1
    try:
        trips = bench_round_trips(pairs)
    finally:
        for p in pairs:
            p.close()
        left = [pid for p in pairs for pid in p.leftovers()]
        if left:
            print(f"warning: socat processes left: {left}", file=sys.stderr)
    throughput = bench_bytes()
    wall = time.perf_counter() - t_start
    path = C.write_results("bench_comgenius_ports", {
        "method": {"sample_s": SAMPLE_S, "rounds": ROUNDS, "gc": "disabled while sampling",
                   "figures": "median over the rounds; ratios: median of per-round ratios",
                   "engine": "compiled executor, SimulatedClock(1 ms), free-running scans, one thread",
                   "pty": "socat -d -d pty,raw,echo=0 pty,raw,echo=0 (does not enforce the baud rate)"},
        "round_trips": trips,
        "throughput": throughput,
        "wall_s": round(wall, 1),
    })
    print(f"\nsummary ({wall:.1f} s):")
    for kind, r in trips.items():
        rt = r["round_trips_per_s"]
        print(f"  {kind:5} ({r['frame_bytes']:3} B): ladder loop:// {rt['ladder loop://']:,}/s "
              f"({r['ratio_ladder_over_raw']['loop://']:.1f}x raw {rt['raw loop://']:,}/s), "
              f"ladder pty {rt['ladder pty']:,}/s ({r['ratio_ladder_over_raw']['pty']:.1f}x raw {rt['raw pty']:,}/s), "
              f"ladder sim:// {rt['ladder sim://']:,}/s")
    b = throughput["bytes_per_s"]
    print(f"  bytes: sim:// unlimited {b['sim:// unlimited'] / 1e6:.0f} MB/s, loop:// {b['loop://'] / 1e6:.2f} MB/s "
          f"(loop:// takes {throughput['ratio_loop_over_sim_time']:,.0f}x as long)")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
