"""Fuzz inputs: hostile Modbus TCP requests to a live MODBTCPS server.

A ``modbus_tcp`` case starts a real runtime of an app with MODBTCPS
(``tests/helpers/modbtcps_apps.py``: the scan in a thread of this process, the server
its own process, on a port found free) and sends it a few hundred requests
drawn from a seed: every function code (served or not), addresses at and
outside the map's edges, quantities and byte counts at and past the
functions' limits and disagreeing with each other, odd coil values, string
LEN words over 82, bodies a byte short or long, unit ids no ``<Unit>`` names,
and now and then a frame that is not Modbus TCP (a protocol id other than 0,
an MBAP length outside 2..254).

The oracle (docs/modbtcps.md "A refused request changes nothing", "Status
words"): every request with a well-formed MBAP header is answered; a request
answered with an exception leaves the whole data table as it was (read
directly, after a following legitimate write has reached the scan, so a
write queued by the refused request would have landed); no answer is
exception 04 (an internal error); a malformed frame closes its connection
and changes nothing; and the status words count every refusal: word 14 rises
by one per exception answer and per connection closed as malformed, each
exception code in its own word.
"""

from __future__ import annotations

import json
import random
import socket
import struct
import tempfile
import time
from pathlib import Path

SERVED = [1, 2, 3, 4, 5, 6, 15, 16, 22, 23]
# tests/helpers/modbtcps_apps.UNIT_1's edges: coils 0..39, 100..107; holding 0..19, 50..54, 100..103, 110..111,
# 200..365 (ST9:0..1, LEN at 200 and 283), 400..483 (packed ST9:2..3, LEN at 400 and 442); input 0..9, 20..21
EDGES = [0, 1, 7, 8, 18, 19, 20, 39, 40, 49, 50, 54, 55, 99, 100, 103, 104, 107, 108, 110, 111, 112, 199, 200,
         201, 282, 283, 284, 365, 366, 399, 400, 401, 441, 442, 443, 483, 484, 1000, 9999, 65534, 65535]
VALUES = [0, 1, 82, 83, 0x7FFF, 0x8000, 0xFF00, 0x00FF, 0xFFFF, 0x1234]
COUNTS = [0, 1, 2, 8, 9, 40, 82, 83, 121, 122, 123, 124, 125, 126, 1968, 1969, 2000, 2001, 65535]
UNIT_2 = """
  <Unit id="2">
    <Coils            start="0"   count="16" address="B3/0"/>
    <HoldingRegisters start="0"   count="10" address="N7:0"/>
  </Unit>
"""
LADDER = "ADD N60:0 1 N60:0\n"  # the scan changes no word a client can reach
SKIPPED_FILES = {"S2", "N40", "N60"}  # the status file, the server's status words, the ladder's counter
REQUESTS = (150, 400)
EXCEPTION_WORDS = {1: "W_EXCEPTION_01", 2: "W_EXCEPTION_02", 3: "W_EXCEPTION_03", 6: "W_REFUSED_RATE",
                   0x0B: "W_EXCEPTION_0B"}
SENTINEL = 19  # holding register 19 (N7:19): written with the value it holds, to wait for the scan


def case_modbus_tcp(draw, rnd, profile):
    from helpers.fuzz_inputs import Case

    n = rnd.randint(*REQUESTS)
    return Case("modbus_tcp", {}, [], note=f"{n} requests", driver="modbus_tcp",
                params={"seed": rnd.randrange(2 ** 32), "requests": n})


def _value(rnd) -> int:
    return rnd.choice(VALUES) if rnd.random() < 0.7 else rnd.randrange(65536)


def _address(rnd) -> int:
    return rnd.choice(EDGES) if rnd.random() < 0.85 else rnd.randrange(65536)


def _count(rnd, usual: list[int]) -> int:
    return rnd.choice(usual) if rnd.random() < 0.6 else rnd.choice(COUNTS) if rnd.random() < 0.8 else rnd.randrange(65536)


def random_pdu(rnd: random.Random) -> bytes:
    """A request PDU: a served function most of the time, its fields near the edges."""
    f = rnd.choice(SERVED) if rnd.random() < 0.85 else rnd.randrange(256)
    a = _address(rnd)
    if f in (1, 2):
        body = struct.pack(">HH", a, _count(rnd, [1, 8, 16, 40, 2000, 2001, 0]))
    elif f in (3, 4):
        body = struct.pack(">HH", a, _count(rnd, [1, 2, 10, 83, 125, 126, 0]))
    elif f == 5:
        body = struct.pack(">HH", a, rnd.choice([0xFF00, 0x0000, 0x0001, 0xFFFF, 0x00FF, 0x1234, 0xFF01]))
    elif f == 6:
        if rnd.random() < 0.3:  # a string's LEN word
            a = rnd.choice([200, 283, 400, 442])
        body = struct.pack(">HH", a, _value(rnd))
    elif f == 22:
        if rnd.random() < 0.4:
            a = rnd.choice([200, 283, 400, 442])
        body = struct.pack(">HHH", a, _value(rnd), _value(rnd))
    elif f == 15:
        count = _count(rnd, [1, 8, 9, 16, 40, 1968, 1969, 0])
        nbytes = (count + 7) // 8 if rnd.random() < 0.7 else rnd.randrange(256)
        body = struct.pack(">HHB", a, count, nbytes & 0xFF) + bytes(rnd.randrange(256) for _ in range(min(nbytes, 246)))
    elif f in (16, 23):
        if rnd.random() < 0.2:
            a = rnd.choice([200, 283, 400, 442])
        count = _count(rnd, [1, 2, 4, 83, 121, 122, 123, 124, 0])
        nbytes = 2 * count if rnd.random() < 0.7 else rnd.randrange(256)
        data = b"".join(struct.pack(">H", _value(rnd)) for _ in range(min(nbytes, 240) // 2))
        if f == 16:
            body = struct.pack(">HHB", a, count, nbytes & 0xFF) + data
        else:
            body = struct.pack(">HHHHB", _address(rnd), _count(rnd, [1, 2, 20, 125, 126, 0]), a, count,
                               nbytes & 0xFF) + data
    else:  # a function not served, with a body of any shape
        body = bytes(rnd.randrange(256) for _ in range(rnd.choice([0, 1, 4, 5, 8, 20])))
    r = rnd.random()
    if r < 0.06:
        body = body[:-1]
    elif r < 0.12:
        body += bytes([rnd.randrange(256)])
    return bytes([f]) + body[:252]


def random_frame(rnd: random.Random, tid: int) -> tuple[bytes, bool]:
    """An MBAP frame and whether it is malformed (not Modbus TCP: the server closes the connection)."""
    unit = 1 if rnd.random() < 0.8 else rnd.choice([2, 2, 0, 3, 247, 255])
    pdu = random_pdu(rnd)
    if rnd.random() < 0.04:
        if rnd.randrange(2):
            return struct.pack(">HHHB", tid, rnd.choice([1, 0xFFFF]), len(pdu) + 1, unit) + pdu, True
        return struct.pack(">HHHB", tid, 0, rnd.choice([0, 1, 255, 300, 65535]), unit) + pdu, True
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu, False


class Conn:
    def __init__(self, port: int) -> None:
        self.port = port
        self.sock: socket.socket | None = None

    def open(self) -> socket.socket:
        if self.sock is None:
            self.sock = socket.create_connection(("127.0.0.1", self.port), timeout=5.0)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return self.sock

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None

    def ask(self, frame: bytes) -> bytes | None:
        """The reply frame, or None if the server closed the connection; TimeoutError if it said nothing."""
        s = self.open()
        try:
            s.sendall(frame)
            reply = b""
            while len(reply) < 6 or len(reply) < 6 + struct.unpack(">H", reply[4:6])[0]:
                chunk = s.recv(512)
                if not chunk:
                    self.close()
                    return None
                reply += chunk
            return reply
        except (ConnectionResetError, BrokenPipeError):
            self.close()
            return None


def _table(engine) -> dict:
    from softplc_lite.datatable.jsonio import export_table

    for _ in range(5):  # read while the scan runs: a file made meanwhile is read again
        try:
            return {k: v for k, v in export_table(engine.table).items() if k not in SKIPPED_FILES}
        except RuntimeError:
            time.sleep(0.01)
    return {k: v for k, v in export_table(engine.table).items() if k not in SKIPPED_FILES}


def _fname(function: int) -> str:
    """A function for a signature: each served one by its number, the others as one."""
    return f"f{function}" if function in SERVED else "f-other"


def _same(a, b) -> bool:
    """Equal, a NaN equal to a NaN (a float word holding one is unchanged)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def _diff(before: dict, after: dict) -> list[str]:
    out = []
    for k in sorted(set(before) | set(after)):
        a, b = before.get(k), after.get(k)
        if not _same(a, b):
            if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
                out += [f"{k}:{i} {x!r} -> {y!r}" for i, (x, y) in enumerate(zip(a, b)) if not _same(x, y)]
            else:
                out.append(f"{k}: {str(a)[:40]} -> {str(b)[:40]}")
    return out


def run_modbus_case(case, root: Path, timeout: float, runner):
    from helpers.fuzz_oracle import Finding, Result
    from helpers.modbtcps_apps import Running, UNIT_1, server_xml, write_app

    from softplc_lite.tlm.modbtcps import status as S

    p = case.params
    rnd = random.Random(p["seed"])
    findings: list = []
    start = time.monotonic()
    log = Result(["<modbus_tcp>", f"seed={p['seed']}", f"requests={p['requests']}"], 0, how="modbus")

    def add(cls: str, sig: str, detail: str) -> None:
        findings.append(Finding(cls, f"{cls}:modbus:{sig}", log.argv, detail, case.kind, log))

    app = write_app(Path(root) / "app", server_xml(UNIT_1 + UNIT_2, maxRequestsPerSecond=100000), LADDER)
    plc = Running(app, scan_ms=1)
    conn = Conn(plc.port)
    expected = {"refusals": 0, **{w: 0 for w in EXCEPTION_WORDS.values()}, "W_MALFORMED": 0}
    lines = []
    try:
        for k in range(p["requests"]):
            if time.monotonic() - start > timeout:
                add("hang", "slow", f"{k} of {p['requests']} requests in {timeout:.0f} s")
                break
            frame, malformed = random_frame(rnd, k & 0xFFFF)
            before = _table(plc.engine)
            try:
                reply = conn.ask(frame)
            except (TimeoutError, socket.timeout):
                conn.close()
                if malformed:
                    continue  # a length past the bytes sent: the server waits for the rest; not counted yet
                add("no-answer", f"{_fname(frame[7])}", f"no answer in 5 s to {frame.hex()}")
                continue
            lines.append(f"{frame.hex()} -> {reply.hex() if reply else 'closed'}")
            if reply is None:
                if malformed:
                    expected["refusals"] += 1
                    expected["W_MALFORMED"] += 1
                else:
                    add("no-answer", f"closed:{_fname(frame[7])}", f"the connection closed on a well-formed {frame.hex()}")
                    continue
            elif malformed:
                add("malformed-answered", f"{_fname(frame[7])}", f"{frame.hex()} answered {reply.hex()}")
                continue
            elif reply[:2] != frame[:2] or reply[6] != frame[6] or reply[7] not in (frame[7], frame[7] | 0x80):
                add("wrong-reply", f"{_fname(frame[7])}", f"{frame.hex()} answered {reply.hex()}")
                continue
            elif reply[7] == frame[7] and frame[7] < 0x80:
                continue  # answered normally: what it wrote is the client's right
            else:
                code = reply[8] if len(reply) > 8 else -1
                if code not in EXCEPTION_WORDS:
                    add("exception-code", f"{_fname(frame[7])}:{code}", f"{frame.hex()} answered exception {code}")
                    continue
                expected["refusals"] += 1
                expected[EXCEPTION_WORDS[code]] += 1
            # a legitimate write after the refusal: once it is answered, the scan has taken whatever came before
            sentinel = plc.engine.table.read(f"N7:{SENTINEL}") & 0xFFFF
            ok = conn.ask(struct.pack(">HHHBBHH", 0xFFFF, 0, 6, 1, 6, SENTINEL, sentinel))
            if ok is None or ok[7] != 6:
                add("no-answer", "sentinel", f"the write after {frame.hex()} answered {ok.hex() if ok else 'closed'}")
                conn.close()
            changed = _diff(before, _table(plc.engine))
            if changed:
                add("changed-by-refusal", f"{_fname(frame[7])}:{'malformed' if malformed else reply[8]}",
                    f"{frame.hex()} answered {reply.hex() if reply else 'closed'} and changed {changed[:6]}")
        conn.close()
        words = {"refusals": S.W_REFUSALS, **{w: getattr(S, w) for w in list(EXCEPTION_WORDS.values()) + ["W_MALFORMED"]}}
        deadline = time.monotonic() + 5.0
        while True:
            got = {name: plc.status(w) & 0xFFFF for name, w in words.items()}
            want = {name: n & 0xFFFF for name, n in expected.items()}
            if got == want or time.monotonic() > deadline:
                break
            time.sleep(0.02)
        if got != want:
            add("refusal-uncounted", ",".join(n for n in want if got[n] != want[n]),
                f"status words {got}, expected {want}")
    finally:
        conn.close()
        try:
            plc.stop()
        except BaseException as e:  # noqa: BLE001 - the runtime's own failure is a finding
            add("exception", f"{type(e).__name__}", f"the runtime ended with {type(e).__name__}: {str(e)[:200]}")
    log.seconds = time.monotonic() - start
    log.out = "\n".join(lines[-200:])
    return findings, [log]
