"""The Modbus RTU slave written in ladder (programs/modbus_slave) with a
third-party master: pymodbus 3.16's synchronous RTU client.

- Over a socat pty pair, against the real command line: ``python -m
  softplc_lite run APP --fresh --realtime --scan-ms 0 --port 0=PTY_A``, run
  until SIGINT, as on hardware. pymodbus opens the other pty. Every function
  at its limits, writes read back through the protocol, exceptions 01/02/03,
  silence on bad frames, recovery after garbage; the slave's own counters
  (the summary ``softplc run`` prints when it ends) must agree with what the
  master saw.
- Over ``socket://``: both pyserial's socket:// and the slave's port are TCP
  clients, so a relay in the test (a serial device server such as a Moxa
  NPort, in a thread) joins them; the slave runs in-process on real time,
  scanned free-running by a background thread, and the data table is checked
  after the writes.

Facts about ptys and pymodbus this relies on: /work/shared/testing-notes.md
(ptys ignore the baud rate and take only 8N1; pymodbus takes ``count=`` and
``device_id=`` keywords).
"""

from __future__ import annotations

import json
import logging
import os
import re
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from pymodbus.client import ModbusSerialClient
from pymodbus.framer import FramerType

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.runner import RunOptions, Runner

from helpers.modbus_slave_app import SLAVE_APP, copy_app
from helpers.ptypair import PtyPair, require_socat
from helpers.reference_checks import rtu_frame as frame
from helpers.words import signed

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

BAUD = 19200  # the slave's port 0 in COMGENIUS.LST (a pty ignores it; 8N1 is what matters)
START_S = 10.0  # the CLI and its first answer
SILENCE_S = 0.1  # "no reply": nothing within this long (the slave answers in a few ms)
REPLY_S = 0.5  # a raw reply must be complete within this long
ROOT = Path(__file__).resolve().parent.parent


# -- the protocol, independently of softplc_lite ---------------------------------------------------



def pack_bits(bits) -> bytes:
    out = bytearray((len(bits) + 7) // 8)
    for k, bit in enumerate(bits):
        if bit:
            out[k // 8] |= 1 << (k % 8)
    return bytes(out)


# Known data for the limit tests: every word of O, I (128 words = 2,048 bits each), N10 (1000)
# and N11 (grown to 125) holds a pattern, so no read can pass by returning zeros.
def o_word(w: int) -> int:
    return (w * 0x1357 + 0x0A5C) & 0xFFFF


def i_word(w: int) -> int:
    return (w * 0x2468 + 1) & 0xFFFF


def holding(k: int) -> int:
    return (k * 31 + 7) & 0xFFFF


def input_register(k: int) -> int:
    return (0xFFFF - 3 * k) & 0xFFFF


def bits_of(word) -> list[bool]:
    """The 2,048 bits of a 128-word file whose word w is ``word(w)``."""
    return [bool(word(k // 16) >> (k % 16) & 1) for k in range(128 * 16)]


def is_exception(response, function: int, code: int) -> bool:
    return response.isError() and response.function_code == function | 0x80 and response.exception_code == code


# -- the command line on a pty pair ---------------------------------------------------------------

class CliSlave:
    """``softplc run`` of a copy of the slave app on pty A, real time,
    free-running, until stop(); pymodbus's client (``client``) on pty B.
    ``served``/``exceptions`` count the normal and exception replies the
    master received, to compare with the slave's own counters at the end."""

    def __init__(self, tmp_path: Path, args: list[str]) -> None:
        require_socat()
        self.pair = PtyPair(tmp_path)
        self.app = copy_app(SLAVE_APP, tmp_path / "app")
        self.out_path, self.err_path = tmp_path / "stdout.txt", tmp_path / "stderr.txt"
        cmd = [sys.executable, "-m", "softplc_lite", "run", str(self.app), "--fresh", "--realtime",
               "--scan-ms", "0", "--port", f"0={self.pair.a}", *args]
        self.proc: subprocess.Popen | None = None
        self.client: ModbusSerialClient | None = None
        self.served = self.exceptions = 0
        try:
            with open(self.out_path, "w") as out, open(self.err_path, "w") as err:
                self.proc = subprocess.Popen(cmd, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=out, stderr=err)
            self.client = ModbusSerialClient(self.pair.b, framer=FramerType.RTU, baudrate=BAUD, timeout=0.5,
                                             retries=0)
            assert self.client.connect(), f"pymodbus cannot open {self.pair.b}"
            self.raw = self.client.socket  # pymodbus's own pyserial port, for frames it cannot send
            self._wait_until_serving()
        except BaseException:
            self.close()
            raise

    def _wait_until_serving(self) -> None:
        """Requests written before the slave opened its pty (or before its
        first scan cleared the receive buffer) are lost: repeat a small read
        until it is answered."""
        deadline = time.monotonic() + START_S
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise AssertionError(f"softplc run ended with status {self.proc.returncode}:\n{self.output()}")
            reply = self.transact(frame("01 03 00 00 00 01"), expect=7)
            if reply:
                assert reply[:3] == bytes.fromhex("01 03 02"), reply.hex(" ")
                self.served += 1
                return
        raise AssertionError(f"the slave did not answer within {START_S} s:\n{self.output()}")

    # raw frames, on pymodbus's port (between its transactions) ---------------------------------
    def transact(self, request: bytes, expect: int | None = None, quiet: float = SILENCE_S) -> bytes:
        """Write ``request``; return the reply: ``expect`` bytes (waiting up
        to REPLY_S for them), or, when ``expect`` is None, whatever comes
        within ``quiet`` seconds (b"" for silence)."""
        self.raw.reset_input_buffer()
        self.raw.write(request)
        self.raw.flush()
        got = bytearray()
        deadline = time.monotonic() + (REPLY_S if expect else quiet)
        while time.monotonic() < deadline and (expect is None or len(got) < expect):
            self.raw.timeout = max(0.0, deadline - time.monotonic())
            chunk = self.raw.read(expect - len(got) if expect else 512)
            got += chunk
        if expect and len(got) == expect:  # anything more than expected is a fault too
            self.raw.timeout = 0.02
            got += self.raw.read(512)
        return bytes(got)

    def silent(self, request: bytes) -> bool:
        return self.transact(request, expect=None) == b""

    def raw_exception(self, request: bytes, code: int) -> bytes:
        """Send ``request``, which must get exception ``code``; returns the reply."""
        reply = self.transact(request, expect=5)
        assert reply == frame(f"{request[0]:02x} {request[1] | 0x80:02x} {code:02x}"), (request.hex(" "), reply.hex(" "))
        self.exceptions += 1
        return reply

    # pymodbus, counted ---------------------------------------------------------------------------
    def ok(self, response):
        assert not response.isError(), response
        self.served += 1
        return response

    def exception(self, response, function: int, code: int) -> None:
        assert is_exception(response, function, code), response
        self.exceptions += 1

    # the end -------------------------------------------------------------------------------------
    def output(self) -> str:
        text = []
        for path in (self.out_path, self.err_path):
            try:
                text.append(path.read_text(errors="replace"))
            except OSError:
                pass
        return "\n".join(text)

    def stop(self) -> dict[str, int]:
        """SIGINT, as Ctrl-C: the run must end cleanly (status 0) and print
        its summary; the counters of that summary."""
        assert self.proc.poll() is None, f"softplc run ended early:\n{self.output()}"
        self.proc.send_signal(signal.SIGINT)
        try:
            status = self.proc.wait(10)
        except subprocess.TimeoutExpired:
            raise AssertionError("softplc run did not end within 10 s of SIGINT") from None
        assert status == 0, f"softplc run exited {status}:\n{self.output()}"
        out = self.out_path.read_text()
        counters = {name: int(value) for name, value in
                    re.findall(r"^(served|exceptions|bad|others|broadcasts) \(C5:\d\.ACC\) = (-?\d+)$", out, re.MULTILINE)}
        assert set(counters) == {"served", "exceptions", "bad", "others", "broadcasts"}, out
        return counters

    def close(self) -> None:
        if self.client is not None:
            self.client.close()
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self.pair.close()
        assert self.pair.leftovers() == []


@pytest.fixture
def cli(tmp_path):
    """Start ``softplc run`` with extra arguments; killed after the test
    whatever happened."""
    started: list[CliSlave] = []

    def start(*args: str) -> CliSlave:
        slave = CliSlave(tmp_path, list(args))
        started.append(slave)
        return slave

    yield start
    for slave in started:
        slave.close()


def limits_data(tmp_path: Path) -> Path:
    path = tmp_path / "limits.json"
    path.write_text(json.dumps({
        "O": [signed(o_word(w)) for w in range(128)],
        "I": [signed(i_word(w)) for w in range(128)],
        "N10": [signed(holding(k)) for k in range(1000)],
        "N11": [signed(input_register(k)) for k in range(125)],  # grown from 16 to 125
    }))
    return path


def test_every_function_at_its_limits_over_a_pty(tmp_path, cli):
    """2,048 I/O bits, 1,000 holding and 125 input registers (the limits as
    data, on the command line), every function at the Modbus quantity limits
    and at the last address that fits; one more is exception 02."""
    s = cli("--load", str(limits_data(tmp_path)), "--set", "N9:0=2048", "--set", "N9:2=125")
    c = s.client
    coils, inputs = bits_of(o_word), bits_of(i_word)

    # 01 / 02: 2,000 bits from an odd start, and from the last start that fits (48 + 2000 = 2048)
    for start in (37, 48):
        assert s.ok(c.read_coils(start, count=2000, device_id=1)).bits[:2000] == coils[start:start + 2000]
        assert s.ok(c.read_discrete_inputs(start, count=2000, device_id=1)).bits[:2000] == inputs[start:start + 2000]
    s.exception(c.read_coils(49, count=2000, device_id=1), 1, 2)
    s.exception(c.read_discrete_inputs(49, count=2000, device_id=1), 2, 2)
    # a quantity not a multiple of 8: the unused high bits of the last byte are zero
    reply = s.transact(frame("01 01 00 05 00 0b"), expect=7)  # 11 coils from 5
    assert reply == frame("01 01 02 " + pack_bits(coils[5:16]).hex()) and reply[4] < 8, reply.hex(" ")
    s.served += 1

    # 03: 125 registers, the last of the table; 04: 125 input registers (register 0 is the scan counter)
    assert s.ok(c.read_holding_registers(875, count=125, device_id=1)).registers == [holding(k) for k in range(875, 1000)]
    s.exception(c.read_holding_registers(876, count=125, device_id=1), 3, 2)
    assert s.ok(c.read_input_registers(0, count=125, device_id=1)).registers[1:] == [
        input_register(k) for k in range(1, 125)]
    assert s.ok(c.read_input_registers(1, count=124, device_id=1)).registers == [input_register(k) for k in range(1, 125)]
    s.exception(c.read_input_registers(1, count=125, device_id=1), 4, 2)

    # 16: 123 registers up to the last one, read back through the protocol
    values = [(k * 977 + 0x8000) & 0xFFFF for k in range(123)]
    response = s.ok(c.write_registers(877, values, device_id=1))
    assert (response.address, response.count) == (877, 123)
    assert s.ok(c.read_holding_registers(875, count=125, device_id=1)).registers == [holding(875), holding(876), *values]
    s.exception(c.write_registers(878, values, device_id=1), 16, 2)  # 878 + 123 > 1000: nothing written
    assert s.ok(c.read_holding_registers(998, count=2, device_id=1)).registers == values[-2:]

    # 15: 1,968 coils from bit 45 (not a byte boundary), an odd pattern; the bits either side keep
    new = [(k * 7) % 5 < 2 for k in range(1968)]
    response = s.ok(c.write_coils(45, new, device_id=1))
    assert (response.address, response.count) == (45, 1968)
    expected = coils[:45] + new + coils[45 + 1968:]
    assert s.ok(c.read_coils(0, count=2000, device_id=1)).bits[:2000] == expected[:2000]
    assert s.ok(c.read_coils(48, count=2000, device_id=1)).bits[:2000] == expected[48:]
    s.exception(c.write_coils(81, new, device_id=1), 15, 2)  # 81 + 1968 > 2048

    # 05: the last coil on, off; one past the end
    s.ok(c.write_coil(2047, True, device_id=1))
    assert s.ok(c.read_coils(2040, count=8, device_id=1)).bits[:8] == expected[2040:2047] + [True]
    s.ok(c.write_coil(2047, False, device_id=1))
    s.ok(c.write_coil(0, not expected[0], device_id=1))
    assert s.ok(c.read_coils(0, count=1, device_id=1)).bits[0] == (not expected[0])
    assert s.ok(c.read_coils(2047, count=1, device_id=1)).bits[0] is False
    s.exception(c.write_coil(2048, True, device_id=1), 5, 2)

    # 06: the last register, a value with bit 15 set; one past the end
    s.ok(c.write_register(999, 0x8001, device_id=1))
    s.ok(c.write_register(0, 0x7FFF, device_id=1))
    assert s.ok(c.read_holding_registers(999, count=1, device_id=1)).registers == [0x8001]
    assert s.ok(c.read_holding_registers(0, count=2, device_id=1)).registers == [0x7FFF, holding(1)]
    s.exception(c.write_register(1000, 1, device_id=1), 6, 2)

    counters = s.stop()
    assert counters == {"served": s.served, "exceptions": s.exceptions, "bad": 0, "others": 0, "broadcasts": 0}


def test_exceptions_01_02_03_over_a_pty(cli):
    """The default limits (64 I/O bits, 1,000 holding registers, 16 input
    registers): 02 one past each; 03 for quantities and values the
    specification forbids (pymodbus refuses to send those, so raw frames);
    01 for functions the slave does not serve, from pymodbus (22, 23) and
    raw. Nothing a refused write carried lands."""
    s = cli("--set", "N10:998=11", "--set", "N10:999=12", "--set", "O:3=-32768")
    c = s.client
    # 02: one past the end of each table (and the last element that fits works)
    assert s.ok(c.read_coils(59, count=5, device_id=1)).bits[:5] == [False] * 4 + [True]  # O:3/17 is coil 63
    s.exception(c.read_coils(60, count=5, device_id=1), 1, 2)
    s.exception(c.read_discrete_inputs(0, count=65, device_id=1), 2, 2)
    assert s.ok(c.read_holding_registers(998, count=2, device_id=1)).registers == [11, 12]
    s.exception(c.read_holding_registers(999, count=2, device_id=1), 3, 2)
    s.ok(c.read_input_registers(10, count=6, device_id=1))
    s.exception(c.read_input_registers(10, count=7, device_id=1), 4, 2)
    s.exception(c.write_coil(64, True, device_id=1), 5, 2)
    s.exception(c.write_register(1000, 5, device_id=1), 6, 2)
    s.exception(c.write_coils(60, [True, False, True, False, True], device_id=1), 15, 2)
    s.exception(c.write_registers(998, [1, 2, 3], device_id=1), 16, 2)
    s.exception(c.read_coils(0xFFFF, count=1, device_id=1), 1, 2)  # above 32767: no negative start
    assert s.ok(c.read_holding_registers(998, count=2, device_id=1)).registers == [11, 12]  # nothing written
    assert s.ok(c.read_coils(59, count=5, device_id=1)).bits[:5] == [False] * 4 + [True]

    # 03: quantities outside the specification, a coil value neither FF00 nor 0000, byte counts that lie
    for request in ("01 01 00 00 00 00", "01 01 00 00 07 d1", "01 02 00 00 00 00", "01 02 00 00 07 d1",
                    "01 03 00 00 00 00", "01 03 00 00 00 7e", "01 04 00 01 00 00", "01 04 00 01 00 7e",
                    "01 05 00 01 12 34", "01 05 00 01 00 ff",
                    "01 0f 00 00 00 00 00", "01 0f 00 00 00 09 01 ff",  # 9 coils in 1 byte
                    "01 10 00 00 00 00 00", "01 10 00 00 00 02 02 00 01",  # 2 registers in 2 bytes
                    "01 10 00 00 00 7c 02 00 01",  # 124 registers (a consistent frame, one data word)
                    "01 0f 00 00 07 b1 01 ff"):  # 1,969 coils (likewise)
        s.raw_exception(frame(request), 3)
    # function 15 for 1,969 coils, with its 247 data bytes: a 256-byte frame, exception 03
    request = frame("01 0f 00 00 07 b1 f7" + "a5" * 247)
    assert len(request) == 256
    s.raw_exception(request, 3)
    assert s.ok(c.read_coils(0, count=8, device_id=1)).bits[:8] == [False] * 8  # none of it landed

    # 01: functions the slave does not serve, from pymodbus and raw
    s.exception(c.mask_write_register(address=0, and_mask=0xFF00, or_mask=0x0012, device_id=1), 22, 1)
    s.exception(c.readwrite_registers(read_address=0, read_count=2, write_address=0, values=[1, 2], device_id=1),
                23, 1)
    for request in ("01 07", "01 08 00 00 12 34", "01 11", "01 2b 0e 01 00", "01 41 00 00 00 01"):
        s.raw_exception(frame(request), 1)
    assert s.ok(c.read_holding_registers(0, count=2, device_id=1)).registers == [0, 0]  # 22 and 23 wrote nothing

    counters = s.stop()
    assert counters == {"served": s.served, "exceptions": s.exceptions, "bad": 0, "others": 0, "broadcasts": 0}


def test_silence_on_bad_frames_and_recovery_after_garbage_over_a_pty(cli):
    """No reply to a bad CRC, another unit id, a truncated frame, a frame
    too long to be Modbus, or a broadcast (which is executed); after garbage
    and a quiet line the next pymodbus request is answered."""
    s = cli("--set", "N10:5=1234")
    c = s.client
    good = frame("01 03 00 05 00 01")
    silent = {
        "bad CRC": good[:-1] + bytes([good[-1] ^ 0x01]),
        "another unit id": frame("02 03 00 05 00 01"),
        "unit 247": frame("f7 06 00 05 00 63"),
        "truncated": good[:5],
        "read with a stray byte": frame("01 03 00 05 00 01 00"),
        "function 16 short of its data": frame("01 10 00 05 00 02 04 00 01"),
        "300 bytes": bytes((k * 37 + 11) & 0xFF for k in range(300)),
    }
    bad_or_others = 0
    for name, request in silent.items():
        assert s.silent(request), name
        bad_or_others += 1
        assert s.ok(c.read_holding_registers(5, count=1, device_id=1)).registers == [1234], name
    # a broadcast write: executed, never answered
    assert s.silent(frame("00 06 00 05 00 2a"))
    assert s.ok(c.read_holding_registers(5, count=1, device_id=1)).registers == [42]
    assert s.silent(frame("00 0f 00 00 00 03 01 05"))  # coils 0..2 = 1, 0, 1
    assert s.ok(c.read_coils(0, count=3, device_id=1)).bits[:3] == [True, False, True]

    # garbage on the line, then a quiet line (20 ms, ten times the slave's quiet time), then pymodbus
    for garbage in (b"\xff", b"\x00" * 17, b"hello, slave\r\n", bytes(range(256)), frame("01 03 00 05 00 01")[:7],
                    b"\x01\x03\x02"):
        s.raw.write(garbage)
        s.raw.flush()
        time.sleep(0.02)
        bad_or_others += 1
        assert s.ok(c.read_holding_registers(5, count=1, device_id=1)).registers == [42], garbage.hex(" ")
    s.ok(c.write_register(5, 7, device_id=1))
    assert s.ok(c.read_holding_registers(5, count=1, device_id=1)).registers == [7]

    counters = s.stop()
    assert counters["served"] == s.served and counters["exceptions"] == 0 and counters["broadcasts"] == 2
    assert counters["bad"] + counters["others"] == bad_or_others, counters
    assert counters["others"] >= 2  # unit 2 and unit 247 at least


def test_back_to_back_requests_of_one_length_with_a_10_ms_scan_over_a_pty(cli):
    """A slave scanning every 10 ms (softplc's default period) and a master
    that sends its next request the moment a reply is in: on a pty the whole
    request is there before the slave's next scan, with the same byte count
    as the one before. Every request must still be answered, in order, and
    each write done once (a write repeated later would undo the test's own
    changes in between)."""
    s = cli("--scan-ms", "10")
    c = s.client
    for k in range(15):  # all 8-byte requests: 06, 03, 05, 01 in turn (about 35 ms each: 3-4 scans)
        s.ok(c.write_register(k % 10, 1000 + k, device_id=1))
        assert s.ok(c.read_holding_registers(k % 10, count=1, device_id=1)).registers == [1000 + k], k
        s.ok(c.write_coil(k % 64, k % 2 == 0, device_id=1))
        assert s.ok(c.read_coils(k % 64, count=1, device_id=1)).bits[0] == (k % 2 == 0), k
    assert s.ok(c.read_holding_registers(0, count=10, device_id=1)).registers == [
        1010 + k if k < 5 else 1000 + k for k in range(10)]
    counters = s.stop()
    assert counters == {"served": s.served, "exceptions": 0, "bad": 0, "others": 0, "broadcasts": 0}


# -- socket:// through a relay -----------------------------------------------------------------------

class Relay:
    """A serial device server in a thread: listens on two TCP ports, accepts
    one connection on each, and copies bytes both ways until closed."""

    def __init__(self) -> None:
        self.listeners = []
        for _ in range(2):
            sock = socket.socket()
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(("127.0.0.1", 0))
            sock.listen(1)
            self.listeners.append(sock)
        self.ports = [sock.getsockname()[1] for sock in self.listeners]
        self.conns: list[socket.socket] = []
        self.copied = [0, 0]
        self._stop_r, self._stop_w = os.pipe()
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="relay", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            for sock in self.listeners:  # both ends, in order (each connect completes in the backlog)
                ready, _, _ = select.select([sock, self._stop_r], [], [], 10)
                if sock not in ready:
                    return
                conn, _ = sock.accept()
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                self.conns.append(conn)
            a, b = self.conns
            while True:
                ready, _, _ = select.select([a, b, self._stop_r], [], [], 10)
                if self._stop_r in ready:
                    return
                for src in ready:
                    data = src.recv(65536)
                    if not data:
                        return
                    dst = b if src is a else a
                    dst.sendall(data)
                    self.copied[0 if src is a else 1] += len(data)
        except Exception as e:  # reported by close()
            self.error = e

    def close(self) -> None:
        os.write(self._stop_w, b"x")
        self.thread.join(5)
        for sock in self.conns + self.listeners:
            sock.close()
        os.close(self._stop_r)
        os.close(self._stop_w)
        assert not self.thread.is_alive()


class Scanner:
    """Scans an engine free-running in a background thread until stopped."""

    def __init__(self, engine) -> None:
        self.engine = engine
        self.stop_event = threading.Event()
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="scanner", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            while not self.stop_event.is_set():
                self.engine.scan()
                time.sleep(0)  # offer the interpreter to the relay and the client between scans
        except Exception as e:  # reported by the test
            self.error = e

    def stop(self) -> None:
        self.stop_event.set()
        self.thread.join(5)
        assert not self.thread.is_alive()


def test_pymodbus_over_socket_through_a_serial_server(tmp_path):
    """socket:// at both ends and a relay between: 3, 6, 16, 1, 15 and an
    exception, with the data table checked after the writes."""
    relay = Relay()
    runner = scanner = client = None
    try:
        app = load_app(copy_app(SLAVE_APP, tmp_path / "app"))
        runner = Runner(app, RunOptions(fresh=True, realtime=True, scan_ms=0, sets=("N10:3=-2", "N10:4=300"),
                                        ports=(f"0=socket://127.0.0.1:{relay.ports[0]}",)))
        table = runner.engine.table
        runner.engine.set_mode(Mode.RUN)
        runner.engine.scan()  # the first scan clears the receive buffer: done before any request can come
        scanner = Scanner(runner.engine)
        # pymodbus's sync serial client sizes its reads by in_waiting, which on pyserial's socket:// is
        # only ever 0 or 1 (testing notes): it takes one byte every 4 character times (2.08 ms at
        # 19200), so a 251-byte reply takes it about 0.55 s however fast the slave is (measured: the
        # slave's whole reply is in the socket 5 ms after the request). Hence 2 s, not 0.5 s.
        client = ModbusSerialClient(f"socket://127.0.0.1:{relay.ports[1]}", framer=FramerType.RTU, baudrate=BAUD,
                                    timeout=2.0, retries=0)
        assert client.connect()
        assert client.read_holding_registers(3, count=2, device_id=1).registers == [0xFFFE, 300]

        assert not client.write_register(5, 0xBEEF, device_id=1).isError()
        assert client.read_holding_registers(5, count=1, device_id=1).registers == [0xBEEF]
        assert table.read("N10:5") == signed(0xBEEF)

        values = [(k * 4099) & 0xFFFF for k in range(123)]
        response = client.write_registers(100, values, device_id=1)
        assert not response.isError() and (response.address, response.count) == (100, 123)
        assert client.read_holding_registers(100, count=123, device_id=1).registers == values
        assert [table.read(f"N10:{k}") for k in range(100, 223)] == [signed(v) for v in values]

        bits = [k % 3 == 0 or k == 63 for k in range(3, 64)]
        assert not client.write_coils(3, bits, device_id=1).isError()
        assert client.read_coils(0, count=64, device_id=1).bits[:64] == [False] * 3 + bits
        assert table.read_word("O:0") & 0xFFFF == sum(1 << k for k in range(16) if k >= 3 and k % 3 == 0)
        assert table.read("O:3/17") == 1 and table.read("O:3/16") == 0  # coil 63, coil 62

        assert is_exception(client.read_coils(1, count=64, device_id=1), 1, 2)  # 1 + 64 past the 64 I/O bits
        assert is_exception(client.write_registers(990, values[:11], device_id=1), 16, 2)
        assert table.read("N10:999") == 0
        scanner.stop()
        assert scanner.error is None, scanner.error
        assert [table.read(f"C5:{k}.ACC") for k in range(5)] == [7, 2, 0, 0, 0]
        assert runner.engine.mode is Mode.RUN and runner.engine.fault is None
        assert relay.copied[0] > 0 and relay.copied[1] > 0 and relay.error is None
    finally:
        if scanner is not None:
            scanner.stop()
        if client is not None:
            client.close()
        if runner is not None:
            runner.engine.close()
        relay.close()
