"""What the parts of bench_modbus_slave.py share: the registers the slave
holds, the request and reply frames, the app directories, and the slave on
simulated time (``WireSlave``) with a transaction timed scan by scan.

The scripts are run as ``python benchmarks/NAME.py``; importing _common puts
tests/ on ``sys.path`` for the tests' helpers (ptypair, modbus_peer,
modbus_slave_app).
"""

from __future__ import annotations

import shutil
import struct
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (tests/ on sys.path)
from helpers.modbus_slave_app import WireSlave

from softplc_lite.ports.modbus_slave import with_crc

MS = 1_000_000
REGISTERS = [(k * 7 + 3) & 0xFFFF for k in range(200)]
WRITE_VALUES = [(k * 13 + 5) & 0xFFFF for k in range(123)]


class CheckFailed(RuntimeError):
    pass


def verdict(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def signed(word: int) -> int:
    return word - 0x10000 if word & 0x8000 else word


# -- frames ------------------------------------------------------------------------------------------------


def read_request(count: int, unit: int = 1) -> bytes:
    return with_crc(struct.pack(">BBHH", unit, 3, 0, count))


def read_reply(count: int, unit: int = 1) -> bytes:
    return with_crc(struct.pack(f">BBB{count}H", unit, 3, 2 * count, *REGISTERS[:count]))


def write_request(count: int, unit: int = 1) -> bytes:
    return with_crc(struct.pack(f">BBHHB{count}H", unit, 16, 0, count, 2 * count, *WRITE_VALUES[:count]))


def write_reply(count: int, unit: int = 1) -> bytes:
    return with_crc(struct.pack(">BBHH", unit, 16, 0, count))


def frames(kind: str) -> tuple[bytes, bytes]:
    """(request, expected reply) of a transaction kind."""
    return {"read 1": (read_request(1), read_reply(1)),
            "read 125": (read_request(125), read_reply(125)),
            "write 123": (write_request(123), write_reply(123))}[kind]


# -- the slave on simulated time ---------------------------------------------------------------------------


class Apps:
    """App directories in one temporary directory, removed by close()."""

    def __init__(self) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="bench_modbus_slave-"))
        self.count = 0

    def name(self, stem: str) -> str:
        self.count += 1
        return f"{stem}{self.count}"

    def close(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


def wire_slave(apps: Apps, baud: int, quiet_ms: int, executor: str = "compiled") -> WireSlave:
    s = WireSlave(apps.root, executor=executor, baud=baud, sets=(f"N9:5={quiet_ms}",), name=apps.name("wire"))
    load_registers(s)
    return s


def load_registers(s: WireSlave) -> None:
    for k, w in enumerate(REGISTERS):
        s.table.write(f"N10:{k}", signed(w))


class Transaction:
    """One request to the slave on simulated time, scan by scan (what
    ``WireSlave.transact_timed`` does, plus a timer around each scan and the
    index of the scan that served it)."""

    def __init__(self, s: WireSlave, request: bytes, reply_len: int, per_scan=None, after: int = 3,
                 limit: int = 2000) -> None:
        engine, port, clock = s.engine, s.port, s.engine.clock
        scan, now = engine.scan, time.perf_counter_ns
        read_served = (lambda: s.table.read("C5:0.ACC"))
        self.sent_at = clock.now_ms * MS
        port.write(request)
        last_request_byte_end = self.sent_at + len(request) * s.char_ns
        served0 = read_served()
        self.scan_ns: list[int] = []
        self.counts: list = []
        self.serve_index: int | None = None
        got = bytearray()
        first = last = None
        for k in range(limit):
            t0 = now()
            scan()
            self.scan_ns.append(now() - t0)
            if per_scan is not None:
                self.counts.append(per_scan())
            if self.serve_index is None and read_served() != served0:
                self.serve_index = k
            data, times = port.read_timed()
            if data:
                if first is None:
                    first = times[0]
                last = times[-1]
                got += data
                if len(got) >= reply_len:
                    break
        else:
            raise CheckFailed(f"no complete reply to {request[:8].hex(' ')}... in {limit} scans (got {len(got)} bytes)")
        self.reply = bytes(got)
        self.scans_to_reply_end = len(self.scan_ns)
        for _ in range(after):  # the line rests a little before the next request
            t0 = now()
            scan()
            self.scan_ns.append(now() - t0)
            if per_scan is not None:
                self.counts.append(per_scan())
        if self.serve_index is None:
            raise CheckFailed("the served counter C5:0 did not move")
        self.gap_ns = first - s.char_ns - last_request_byte_end
        self.last_request_byte_end = last_request_byte_end
        self.reply_end = last

    @property
    def serve_ns(self) -> int:
        return self.scan_ns[self.serve_index]

    @property
    def before_ns(self) -> list[int]:
        return self.scan_ns[:self.serve_index]

    @property
    def after_ns(self) -> list[int]:
        return self.scan_ns[self.serve_index + 1:]


def transact(s: WireSlave, kind: str, per_scan=None) -> Transaction:
    request, reply = frames(kind)
    tx = Transaction(s, request, len(reply), per_scan=per_scan)
    if tx.reply != reply:
        raise CheckFailed(f"{kind}: reply {tx.reply[:12].hex(' ')}... is not {reply[:12].hex(' ')}...")
    if kind == "write 123" and [s.table.read(f"N10:{k}") for k in (0, 122)] != [signed(WRITE_VALUES[k]) for k in (0, 122)]:
        raise CheckFailed("write 123: N10 does not hold the written values")
    if kind == "write 123":
        load_registers(s)  # the next read expects REGISTERS again
    return tx
