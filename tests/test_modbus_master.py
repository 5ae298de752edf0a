"""The Modbus RTU master ladder program (programs/modbus_master) end to end.

A. Against the simulated slave of its COMGENIUS.LST (``sim://modbus?
   device=modbus&id=2&registers=200``, simulated time, 1 ms scans, both
   executors): good replies fill the safe block N11; the simulated time of
   a transaction is close to the 38400-baud wire minimum; exception 02;
   garbage ahead of a reply; a silent slave (timeouts) and its return.
B. Against pymodbus 3.16 as a real third-party slave (tests/helpers/modbus_peer.py,
   unit 2, 38400), real time: over a socat pty pair (1 ms scans, the
   server in this process; free-running scans, the server in a process of
   its own: see PeerProcess) and over TCP with RTU framing (``socket://``);
   its exception 02; garbage put in front of one reply by a TCP relay;
   pymodbus stopped (timeouts) and started again.
C. Replay: a session recorded against pymodbus (with
   benchmarks/record_modbus_trace.py's ``record()``) replays on simulated
   time to the recorded run's data table, deterministically; and the shipped
   recording programs/modbus_master/pymodbus-session.trace replays to what
   its bytes say (each query's outcome read from the trace independently).

Counters: C5:0 polls, C5:1 good replies, C5:2 exceptions (N7:21 the last
code), C5:3 timeouts, C5:4 garbage clears. Every test closes its engines,
stops its pymodbus servers and relays, and ends its socat.
"""

from __future__ import annotations

import importlib.util
import re
import selectors
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.ports import modbus_slave
from softplc_lite.ports.modbus_slave import initial_value, with_crc
from softplc_lite.ports.trace import read_trace

from helpers.cli import softplc_here
from helpers.ptypair import PtyPair, require_socat, socat_processes

pytest.importorskip("pymodbus", minversion="3.16.1")
from helpers.modbus_peer import ModbusPeer, PeerProcess, free_tcp_port  # noqa: E402
from helpers.words import signed  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TESTS = Path(__file__).resolve().parent
APP = ROOT / "programs" / "modbus_master"
SHIPPED_TRACE = APP / "pymodbus-session.trace"
RECORDER = ROOT / "benchmarks" / "record_modbus_trace.py"

QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")  # slave 2, function 3, start 0, count 125
CHAR_NS = 260_417  # one character at 38400 8N1
GAP_NS = 911_460  # 3.5 characters of silence
WIRE_MIN_MS = (8 * CHAR_NS + GAP_NS + 255 * CHAR_NS + GAP_NS) / 1e6  # 70.31 ms: query, gap, reply, gap
REGISTERS = [(k * 7 + 3) & 0xFFFF for k in range(200)]  # pymodbus's holding registers
GARBAGE = b"\xff\xfe\x00"
EXECUTORS = ["compiled", "reference"]
DEADLINE_S = 5.0  # wall-clock bound of each real-time wait

COUNTERS = {"polls": "C5:0.ACC", "good": "C5:1.ACC", "exceptions": "C5:2.ACC", "timeouts": "C5:3.ACC",
            "garbage": "C5:4.ACC"}
OUTCOMES = ("good", "exceptions", "timeouts", "garbage")


SIM_REGISTERS = [signed(initial_value(k)) for k in range(125)]  # the simulated slave's registers 0..124


# -- helpers ------------------------------------------------------------------------------------------


def master(executor: str = "compiled", sets=(), **options) -> Runner:
    """The modbus_master app, polls back to back (T4:0.PRE=0) unless ``sets`` says otherwise."""
    app = load_app(APP, use_cache=False)
    app.state_dir = None  # tests never touch the app's snapshot
    return Runner(app, RunOptions(fresh=True, executor=executor, sets=("T4:0.PRE=0", *sets), **options),
                  log=lambda msg: None)


def counts(r: Runner) -> dict[str, int]:
    return {name: r.table.read(addr) for name, addr in COUNTERS.items()}


def outcomes(r: Runner) -> int:
    """Transactions that ended, one way or another."""
    return sum(r.table.read(COUNTERS[o]) for o in OUTCOMES)


def safe_block(r: Runner) -> list[int]:
    return [r.table.read(f"N11:{k}") for k in range(125)]


def run_until(r: Runner, cond, scans: int | None = None, seconds: float | None = None, on_scan=None) -> bool:
    """Scan until ``cond()`` holds (True), or ``scans`` scans / ``seconds`` of wall time have passed (False)."""
    deadline = None if seconds is None else time.monotonic() + seconds
    done = 0
    while not cond():
        if (scans is not None and done >= scans) or (deadline is not None and time.monotonic() > deadline):
            return False
        r.run(1, on_scan=on_scan)
        done += 1
    return True


def port0(r: Runner):
    """The pyserial object behind the master's logical port 0."""
    return r.app.modules[0].ports.ports[0].serial


def assert_in_step(c: dict[str, int]) -> None:
    """Every poll sent has one outcome, but for the one that may be in flight."""
    assert c["polls"] - sum(c[o] for o in OUTCOMES) in (0, 1), c


@pytest.fixture
def masters():
    """Make masters with master(); every engine is closed at the end of the test."""
    made: list[Runner] = []

    def make(*args, **kwargs) -> Runner:
        r = master(*args, **kwargs)
        made.append(r)
        return r

    yield make
    for r in made:
        r.engine.close()


@pytest.fixture
def peers():
    """Start pymodbus slaves with peers(port, registers); all stopped at the end of the test."""
    started: list[ModbusPeer] = []

    def start(port: str, registers=REGISTERS) -> ModbusPeer:
        peer = ModbusPeer(port, registers).start()
        started.append(peer)
        return peer

    yield start
    for peer in started:
        peer.stop()


@pytest.fixture
def pair(tmp_path):
    """A socat pty pair under tmp_path (skips the test when socat is not installed)."""
    require_socat()
    (tmp_path / "ptys").mkdir()
    with PtyPair(tmp_path / "ptys") as p:
        yield p
    assert p.leftovers() == []


@pytest.fixture(scope="module", autouse=True)
def nothing_left_behind():
    before_socat = set(socat_processes())
    before_threads = {t for t in threading.enumerate()}
    yield
    assert set(socat_processes()) - before_socat == set(), "a test of this module left socat running"
    left = [t.name for t in threading.enumerate() if t not in before_threads and t.is_alive()]
    assert left == [], f"threads left running: {left}"


# -- A. the simulated slave -----------------------------------------------------------------------------


@pytest.mark.parametrize("executor", EXECUTORS)
def test_sim_good_replies_fill_the_safe_block(executor, masters):
    r = masters(executor)
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 10, scans=2000)
    c = counts(r)
    assert c["exceptions"] == c["timeouts"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == SIM_REGISTERS
    slave = modbus_slave.find_slave("modbus")
    assert slave.requests == c["polls"] and slave.ignored == 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_sim_transaction_time_is_near_the_wire_minimum(executor, masters):
    """Back to back (T4:0.PRE=0), a transaction takes 70.31 ms on the wire
    (query 2.08 + gap 0.91 + reply 66.41 + gap 0.91); with 1 ms scans and a
    scan or two to re-arm the rungs, the ladder is within 10% of it."""
    r = masters(executor)
    at_good: list[int] = []

    def note(engine) -> None:
        if engine.table.read("C5:1.ACC") > len(at_good):
            at_good.append(engine.clock.now_ms)

    assert run_until(r, lambda: len(at_good) >= 21, scans=3000, on_scan=note)
    per_transaction = (at_good[20] - at_good[0]) / 20
    assert WIRE_MIN_MS <= per_transaction <= 1.10 * WIRE_MIN_MS, per_transaction
    assert counts(r)["timeouts"] == 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_sim_exception_02_counts_and_leaves_the_safe_block_alone(executor, masters):
    r = masters(executor, sets=["N7:0=150"])  # 150 + 125 > 200 registers: illegal data address
    assert run_until(r, lambda: r.table.read("C5:2.ACC") >= 3, scans=1000)
    c = counts(r)
    assert r.table.read("N7:21") == 2
    assert c["good"] == c["timeouts"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == [0] * 125


@pytest.mark.parametrize("executor", EXECUTORS)
def test_sim_garbage_before_a_reply_is_cleared_then_polling_recovers(executor, masters):
    """Three garbage bytes arrive 1 ms after the third query was written,
    before the slave's reply starts (at 2.99 ms): both COMSCANs fail, the
    master clears its receive buffer and polls again; good replies go on."""
    r = masters(executor)
    injected: list[int] = []

    def inject(engine) -> None:
        if not injected and engine.table.read("C5:0.ACC") == 3:  # the third query left in this scan
            written_ns = engine.clock.now_ms * 1_000_000
            modbus_slave.find_slave("modbus").end.send(GARBAGE, written_ns + 1_000_000)
            injected.append(engine.table.read("C5:1.ACC"))

    assert run_until(r, lambda: r.table.read("C5:4.ACC") >= 1, scans=500, on_scan=inject)
    assert injected == [2]
    good_at_clear = r.table.read("C5:1.ACC")
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= good_at_clear + 5, scans=1000)
    c = counts(r)
    assert c["garbage"] == 1 and c["exceptions"] == c["timeouts"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == SIM_REGISTERS


@pytest.mark.parametrize("executor", EXECUTORS)
def test_sim_silent_slave_times_out_then_replies_resume(executor, masters):
    r = masters(executor)
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 2, scans=1000)  # ends a transaction: Busy off
    slave = modbus_slave.find_slave("modbus")
    slave.unit(2).online = False  # slave 2 switched off: silence
    start_ms = r.engine.clock.now_ms
    assert run_until(r, lambda: r.table.read("C5:3.ACC") >= 2, scans=1000)
    assert r.engine.clock.now_ms - start_ms >= 2 * 250  # the port's timeout, on simulated time
    assert slave.ignored == 2
    slave.unit(2).online = True
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 5, scans=1000)
    c = counts(r)
    assert c["timeouts"] == 2 and c["exceptions"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == SIM_REGISTERS


def test_sim_polls_again_after_a_restart_from_a_snapshot_taken_mid_transaction(tmp_path):
    """What `softplc run programs/modbus_master --scans 3000` twice does (the
    second run restores the retentive snapshot of the first): the first run
    ends with a poll in flight, the second must poll again."""
    for run in (1, 2):
        app = load_app(APP, state_dir=tmp_path)
        r = Runner(app, RunOptions(fresh=run == 1), log=lambda msg: None)
        try:
            polls = r.table.read("C5:0.ACC")
            r.run(3000)
            if run == 1:
                assert polls == 0 and r.table.read("B3/0") == 1 and r.table.read("R6:1/EN") == 1
                assert r.table.read("R6:1/DN") == 0  # a transaction under way when the run stopped
            else:
                assert polls == 25
                assert r.table.read("C5:0.ACC") > polls  # fails: 25, the master is stuck
        finally:
            r.save()  # the snapshot the second run restores; it also ends the saver thread a slow run starts
            r.engine.close()


# -- B. pymodbus, a real slave ----------------------------------------------------------------------------


@pytest.mark.parametrize("executor", EXECUTORS)
def test_pymodbus_over_a_pty_pair(executor, masters, peers, pair):
    peers(pair.b)
    r = masters(executor, realtime=True, scan_ms=1, ports=(f"0={pair.a}",))
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 20, seconds=DEADLINE_S), counts(r)
    c = counts(r)
    assert c["exceptions"] == c["timeouts"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == REGISTERS[:125]


def test_pymodbus_in_another_process_free_running(masters, pair):
    """Free-running scans (scan_ms=0), pymodbus in a process of its own (see PeerProcess)."""
    peer = PeerProcess(pair.b, REGISTERS)
    try:
        r = masters(realtime=True, scan_ms=0, ports=(f"0={pair.a}",))
        assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 100, seconds=DEADLINE_S), counts(r)
        c = counts(r)
        assert c["exceptions"] == c["timeouts"] == c["garbage"] == 0, c
        assert_in_step(c)
        assert safe_block(r) == REGISTERS[:125]
    finally:
        peer.stop()


def test_pymodbus_over_tcp_with_rtu_framing(masters, peers):
    url = f"socket://127.0.0.1:{free_tcp_port()}"
    peers(url)
    r = masters(realtime=True, scan_ms=1, ports=(f"0={url}",))
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 20, seconds=DEADLINE_S), counts(r)
    c = counts(r)
    assert c["exceptions"] == c["timeouts"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == REGISTERS[:125]


def test_pymodbus_exception_02_past_its_map(masters, peers):
    url = f"socket://127.0.0.1:{free_tcp_port()}"
    peers(url)
    r = masters(realtime=True, scan_ms=1, ports=(f"0={url}",), sets=["N7:0=150"])  # 150 + 125 > 200
    assert run_until(r, lambda: r.table.read("C5:2.ACC") >= 3, seconds=DEADLINE_S), counts(r)
    c = counts(r)
    assert r.table.read("N7:21") == 2
    assert c["good"] == c["timeouts"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == [0] * 125


class GarbageRelay:
    """A TCP relay between the master (``url``) and pymodbus on ``upstream``
    that puts GARBAGE in front of the reply to query number ``inject_at``
    (1-based), in the same send as the reply's first bytes."""

    def __init__(self, upstream: int, inject_at: int) -> None:
        self.upstream = upstream
        self.inject_at = inject_at
        self.query_bytes = 0
        self.injected = threading.Event()
        self.failure: BaseException | None = None
        self._stop = threading.Event()
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self.listener.getsockname()[1]}"
        self.thread = threading.Thread(target=self._run, name="garbage-relay", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            self.listener.settimeout(0.05)
            while not self._stop.is_set():
                try:
                    client, _ = self.listener.accept()
                    break
                except TimeoutError:
                    continue
            else:
                return
            with client, socket.create_connection(("127.0.0.1", self.upstream)) as server:
                with selectors.DefaultSelector() as sel:
                    sel.register(client, selectors.EVENT_READ)
                    sel.register(server, selectors.EVENT_READ)
                    while not self._stop.is_set():
                        for key, _ in sel.select(0.05):
                            data = key.fileobj.recv(4096)
                            if not data:
                                return
                            if key.fileobj is client:
                                self.query_bytes += len(data)
                                server.sendall(data)
                            else:
                                if self.query_bytes // len(QUERY) == self.inject_at and not self.injected.is_set():
                                    data = GARBAGE + data
                                    self.injected.set()
                                client.sendall(data)
        except BaseException as e:  # reported by close()
            self.failure = e

    def close(self) -> None:
        self._stop.set()
        self.thread.join(5)
        self.listener.close()
        assert not self.thread.is_alive(), "the relay thread did not stop"
        if self.failure is not None:
            raise self.failure


def test_pymodbus_garbage_before_a_reply_is_cleared_then_polling_recovers(masters, peers):
    port = free_tcp_port()
    peers(f"socket://127.0.0.1:{port}")
    relay = GarbageRelay(port, inject_at=5)
    try:
        r = masters(realtime=True, scan_ms=1, ports=(f"0={relay.url}",))
        assert run_until(r, lambda: r.table.read("C5:4.ACC") >= 1, seconds=DEADLINE_S), counts(r)
        assert relay.injected.is_set()
        good_at_clear = r.table.read("C5:1.ACC")
        assert good_at_clear >= 4  # the four replies before the garbage
        assert run_until(r, lambda: r.table.read("C5:1.ACC") >= good_at_clear + 5, seconds=DEADLINE_S), counts(r)
        c = counts(r)
        assert c["garbage"] >= 1 and c["exceptions"] == 0, c  # how many clears it takes may vary
        assert_in_step(c)
        assert safe_block(r) == REGISTERS[:125]
    finally:
        relay.close()


def test_pymodbus_stopped_times_out_then_a_new_server_answers(masters, peers, pair):
    peer = peers(pair.b)
    r = masters(realtime=True, scan_ms=1, ports=(f"0={pair.a}",))
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= 3, seconds=DEADLINE_S), counts(r)
    peer.stop()
    timeouts_at_stop = r.table.read("C5:3.ACC")
    polls_at_stop = r.table.read("C5:0.ACC")
    t0 = time.monotonic()
    assert run_until(r, lambda: r.table.read("C5:3.ACC") >= timeouts_at_stop + 2, seconds=DEADLINE_S), counts(r)
    assert time.monotonic() - t0 >= 0.25  # the port's 250 ms, on the real-time engine clock
    assert r.table.read("C5:0.ACC") >= polls_at_stop + 2  # polling went on
    peers(pair.b)  # a new pymodbus on the same pty
    good_at_restart = r.table.read("C5:1.ACC")
    assert run_until(r, lambda: r.table.read("C5:1.ACC") >= good_at_restart + 5, seconds=DEADLINE_S), counts(r)
    c = counts(r)
    assert c["timeouts"] >= 2 and c["exceptions"] == c["garbage"] == 0, c
    assert_in_step(c)
    assert safe_block(r) == REGISTERS[:125]


# -- C. record and replay ---------------------------------------------------------------------------------


def load_recorder():
    spec = importlib.util.spec_from_file_location("record_modbus_trace", RECORDER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def replay(path: Path, polls: int, executor: str = "compiled", sets=()) -> dict:
    """Replay ``path`` on simulated time (1 ms scans) until ``polls``
    transactions have an outcome: the counters, N7:21, N11, the scans and
    simulated ms it took, and the replay port's verdict."""
    app = load_app(APP, use_cache=False)
    app.state_dir = None
    r = Runner(app, RunOptions(fresh=True, executor=executor, sets=tuple(sets), replay=str(path)), log=lambda m: None)
    try:
        scans = 0
        while outcomes(r) < polls and scans < 20_000:
            r.run(1)
            scans += 1
        port = port0(r)
        return {**counts(r), "last_exception": r.table.read("N7:21"), "N11": safe_block(r), "scans": scans,
                "now_ms": r.engine.clock.now_ms, "finished": port.finished, "mismatches": list(port.mismatches)}
    finally:
        r.engine.close()


def trace_outcomes(path: Path) -> dict:
    """What the bytes of a trace say, independently of the ladder: port 0's
    TX bytes must be whole queries; the RX bytes after each query (up to
    the next) are its outcome: a whole reply with a good CRC (good, its
    registers kept), an exception reply (its code kept), nothing (a
    timeout) or anything else (garbage)."""
    events = [e for e in read_trace(path) if e.port == 0]
    tx = b"".join(e.data for e in events if e.direction == "TX")
    assert tx == QUERY * (len(tx) // len(QUERY)) and tx, "port 0 sent something other than whole queries"
    answers: list[bytearray] = []
    sent = 0
    for e in events:
        if e.direction == "TX":
            for k in range(len(e.data)):
                if (sent + k) % len(QUERY) == 0:
                    answers.append(bytearray())
            sent += len(e.data)
        else:
            assert answers, "RX before the first query"
            answers[-1] += e.data
    out = {"polls": len(answers), "good": 0, "exceptions": 0, "timeouts": 0, "garbage": 0,
           "last_exception": 0, "N11": [0] * 125, "sequence": []}
    for rx in map(bytes, answers):
        if len(rx) == 255 and rx[:3] == b"\x02\x03\xfa" and with_crc(rx[:-2]) == rx:
            kind = "good"
            out["N11"] = [signed(w) for w in struct.unpack(">125H", rx[3:253])]
        elif len(rx) == 5 and rx[:2] == b"\x02\x83" and with_crc(rx[:3]) == rx:
            kind = "exceptions"
            out["last_exception"] = rx[2]
        elif not rx:
            kind = "timeouts"
        else:
            kind = "garbage"
        out[kind] += 1
        out["sequence"].append(kind)
    return out


def header_figures(path: Path) -> dict:
    """The recorded run's figures the recording script wrote into the trace's header."""
    text = path.read_text(encoding="utf-8")
    m = re.search(r"^# recorded run: (.*)$", text, re.M)
    assert m, f"{path} has no '# recorded run:' comment"
    return {k: int(v) for k, v in (item.split("=") for item in m.group(1).split())}


def test_a_recorded_session_replays_to_the_same_data_table(tmp_path):
    """Record the recording script's session (good replies, pymodbus stopped,
    garbage, a shrunk map's exceptions, good again) with polls back to back,
    then replay it on simulated time with both executors."""
    require_socat()
    recorder = load_recorder()
    path = tmp_path / "session.trace"
    (tmp_path / "ptys").mkdir()
    sets = ("T4:0.PRE=0",)
    recorded = recorder.record(path, sets=sets, pair_dir=tmp_path / "ptys")
    assert recorded["polls"] == sum(recorded[o] for o in OUTCOMES)
    assert all(recorded[o] >= 1 for o in OUTCOMES), recorded
    assert recorded["N11"] == REGISTERS[:125] and recorded["last_exception"] == 2
    from_bytes = trace_outcomes(path)
    assert {k: from_bytes[k] for k in COUNTERS} == {k: recorded[k] for k in COUNTERS}
    replays = [replay(path, recorded["polls"], executor, sets) for executor in EXECUTORS]
    for got in replays:
        assert {k: got[k] for k in (*COUNTERS, "last_exception", "N11")} == \
            {k: recorded[k] for k in (*COUNTERS, "last_exception", "N11")}
        assert got["finished"] and got["mismatches"] == []
    assert replays[0] == replays[1]  # scan for scan, simulated ms for simulated ms
    assert replay(path, recorded["polls"], "compiled", sets) == replays[0]  # and again


def test_the_shipped_trace_replays_to_what_it_recorded():
    """programs/modbus_master/pymodbus-session.trace (made by
    benchmarks/record_modbus_trace.py): the app as shipped, no --set."""
    expected = trace_outcomes(SHIPPED_TRACE)
    assert all(expected[o] >= 1 for o in OUTCOMES), expected  # every outcome is in it
    assert expected["N11"] == REGISTERS[:125] and expected["last_exception"] == 2
    assert header_figures(SHIPPED_TRACE) == {**{k: expected[k] for k in COUNTERS},
                                            "last_exception": expected["last_exception"]}
    replays = [replay(SHIPPED_TRACE, expected["polls"], executor) for executor in EXECUTORS]
    for got in replays:
        assert {k: got[k] for k in (*COUNTERS, "last_exception", "N11")} == \
            {k: expected[k] for k in (*COUNTERS, "last_exception", "N11")}
        assert got["finished"] and got["mismatches"] == []
    assert replays[0] == replays[1]


def test_the_shipped_trace_replays_with_the_command_in_its_header(tmp_path):
    text = SHIPPED_TRACE.read_text(encoding="utf-8")
    m = re.search(r"^# replay: softplc run (.*)$", text, re.M)
    assert m, "no '# replay:' comment"
    args = m.group(1).split() + ["--state", str(tmp_path)]
    p = softplc_here("run", *args)
    assert p.returncode == 0, p.stderr
    expected = trace_outcomes(SHIPPED_TRACE)
    for name, addr in COUNTERS.items():
        assert f"{name} ({addr}) = {expected[name]}\n" in p.stdout, p.stdout
    assert "last exception code (N7:21) = 2\n" in p.stdout
    assert "output matched" in p.stderr, p.stderr
