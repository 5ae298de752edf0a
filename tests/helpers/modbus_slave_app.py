"""The ladder Modbus slave (programs/modbus_slave) for tests and benchmarks:
a copy of the app in a temporary directory, run by a Runner, with its port
on a sim:// link whose other end the test drives as the master.

    slave = WireSlave(tmp_path)            # RUN, first scan done (CRC table built)
    reply = slave.transact(with_crc(bytes.fromhex("01 03 00 00 00 02")))
    slave.close()
"""

from __future__ import annotations

import itertools
import re
import shutil
from pathlib import Path

import serial

import softplc_lite.ports.urlhandler  # noqa: F401  (sim://)
from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.ports.wire import char_time_ns
from softplc_lite.runner import RunOptions, Runner

SLAVE_APP = Path(__file__).resolve().parents[2] / "programs" / "modbus_slave"
MASTER_APP = Path(__file__).resolve().parents[2] / "programs" / "modbus_master"
_links = itertools.count()


def copy_app(source: Path, target: Path, baud: int | None = None) -> Path:
    """A copy of the app ``source`` at ``target`` (never the repository's own
    directory, so no snapshot lands there), with port 0's baud rate changed."""
    shutil.copytree(source, target, ignore=shutil.ignore_patterns(".softplc"))
    if baud is not None:
        lst = target / "COMGENIUS.LST"
        text = lst.read_text(encoding="latin-1")
        text = re.sub(r"^(0, .*?, ISO-8859-1, )\d+,", rf"\g<1>{baud},", text, flags=re.M)
        lst.write_text(text, encoding="latin-1")
    return target


def slave_runner(target: Path, baud: int | None = None, **options) -> Runner:
    """A copy of the slave app at ``target``, run fresh by a Runner in RUN
    (no scan yet); ``options`` are RunOptions fields (executor, sets, ports)."""
    runner = Runner(load_app(copy_app(SLAVE_APP, target, baud)), RunOptions(fresh=True, **options))
    runner.engine.set_mode(Mode.RUN)
    return runner


def link_name(prefix: str = "mbs") -> str:
    return f"{prefix}{next(_links)}"


class WireSlave:
    """The ladder slave on simulated time, its port 0 on a sim:// link; the
    test's end of the link is ``port`` (same clock, same baud)."""

    def __init__(self, tmp_path: Path, executor: str = "compiled", baud: int = 19200, sets: tuple[str, ...] = (),
                 name: str | None = None) -> None:
        self.link = link_name()
        self.runner = slave_runner(tmp_path / (name or self.link), baud, executor=executor, sets=sets,
                                   ports=(f"0=sim://{self.link}",))
        self.engine = self.runner.engine
        self.table = self.engine.table
        self.port = serial.serial_for_url(f"sim://{self.link}", baudrate=baud)
        self.port.set_clock(lambda: self.engine.clock.now_ms * 1_000_000)
        self.char_ns = char_time_ns(baud)
        self.engine.scan()  # first pass: file 50 builds the CRC table

    def transact(self, frame: bytes, limit_ms: int = 400) -> bytes | None:
        """Send ``frame``; the reply, once 5 scans have passed without a new
        byte after it started, or None when nothing came within ``limit_ms``."""
        reply, _ = self.transact_timed(frame, limit_ms)
        return reply

    def transact_timed(self, frame: bytes, limit_ms: int = 400) -> tuple[bytes | None, int | None]:
        """(reply or None, ns from the request's last byte on the wire to the
        reply's first byte arriving, less one character time: the gap)."""
        sent_at = self.engine.clock.now_ms * 1_000_000
        self.port.write(frame)
        last_byte_at = sent_at + len(frame) * self.char_ns
        got = bytearray()
        first = None
        quiet = 0
        for _ in range(limit_ms):
            self.engine.scan()
            data, times = self.port.read_timed()
            if data:
                if first is None:
                    first = times[0]
                got += data
                quiet = 0
            elif got:
                quiet += 1
                if quiet >= 5:
                    break
        if not got:
            return None, None
        return bytes(got), first - self.char_ns - last_byte_at

    def scans(self, n: int) -> None:
        for _ in range(n):
            self.engine.scan()

    def counters(self) -> dict[str, int]:
        t = self.table
        return {name: t.read(f"C5:{k}.ACC") for k, name in
                enumerate(("served", "exceptions", "bad", "others", "broadcasts"))}

    def close(self) -> None:
        self.port.close()
        self.engine.close()
