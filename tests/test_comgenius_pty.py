"""COMPRINT, COMSCAN and COMRCVSTS between two runtimes over a real pty pair
(socat), 38400 8N1.

Two engines run in this one process, each with its own ComGenius and its
own COMGENIUS.LST: runtime A's port 0 is one end of the pair, runtime B's
port 0 the other. A pty delivers in real time (about 0.2 ms for 256 bytes,
whatever the baud rate), so the tests step both engines and poll with a
wall-clock deadline (``run_until``). The engines run on SimulatedClock, so
a COMSCAN timeout counts scans x scan_ms, not wall time: ports that must
not time out while the test waits have a timeout of thousands of scans,
and the timeout test waits until every character is in B's receive buffer
before it starts its COMSCAN, so its count of scans is exact.

Covers: the manual's examples 1 and 2 across the pair; every row of the
COMSCAN status table; COMRCVSTS overflow; COMPRINT waiting while the
transmit buffer lacks room (B not reading); UTF-8, UTF-16BE, UTF-16LE both
ways and ISO-8859-1 dropping upper bytes; ports missing at start (STOP and
RETRY), a pty vanishing while running and coming back, and the CLI's
report of a missing device. Every test ends its engines and socat.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from helpers.cli import softplc_here
from helpers.ptypair import PtyPair, require_socat, socat_processes
from helpers.apps import make_app
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.engine import SimulatedClock
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.tlm.comgenius.ports import RX_BUFFER_CHARS
from softplc_lite.tlm.errors import ModuleError
from softplc_lite.tlm.registry import instruction_set


STRINGS = r"""[STRINGS]
1 "Rack no: %3o has %2d modules.\r\n"
2 "\x02\x03%.2C%.2C%#R"
3 "%s"
4 "%.2000c"
5 "%*.100c"
6 "AK HM %.14s %.3d"
7 "%s\n"
8 "%s %s %s%\n"
9 "%s%\n"
"""

LONG_MS = 60_000  # a COMSCAN timeout no test reaches (60,000 scans of 1 ms)


def lst(device: str, encoding: str = "ISO-8859-1", timeout_ms: int = LONG_MS, driver: str = "") -> str:
    """COMGENIUS.LST text: port 0 on ``device`` at 38400 8N1 (see ports_line())."""
    return (f"[DRIVER]\nDEBUG=0\n{driver}\n[PORTS]\n0, {device}, {encoding}, 38400, 8, N, 1, {timeout_ms}\n"
            f"{STRINGS}")


def ports_line(text: str) -> int:
    """The line number of port 0's [PORTS] line."""
    return next(n for n, line in enumerate(text.splitlines(), 1) if line.startswith("0, "))


class Runtime:
    """One engine with its own ComGenius, in RUN, not yet scanned."""

    def __init__(self, program: str, config_text: str, scan_ms: int = 1, executor: str = "compiled") -> None:
        self.module = ComGenius(parse_config(config_text))
        self.engine = Engine(load_text(program, instructions=instruction_set([self.module])), DataTable(),
                             clock=SimulatedClock(scan_ms), executor=executor, modules=[self.module])
        self.engine.set_mode(Mode.RUN)

    @property
    def port(self):
        return self.module.ports.ports[0]

    def scan(self, n: int = 1) -> None:
        for _ in range(n):
            self.engine.scan()

    def write(self, addr: str, value) -> None:
        self.engine.table.write(addr, value)

    def read(self, addr: str):
        return self.engine.table.read(addr)

    def bits(self, addr: str = "R6:0") -> str:
        r = self.engine.table.read(addr)
        return " ".join(k for k in ("EN", "DN", "ER", "EM") if r[k])

    def ctl(self, addr: str = "R6:0") -> dict:
        r = self.engine.table.read(addr)
        return {k: r[k] for k in ("EN", "DN", "ER", "EM", "LEN", "POS")}

    def rx_history(self) -> bytes:
        return b"".join(data for _, d, data in self.port.history if d == "RX")

    def tx_history(self) -> bytes:
        return b"".join(data for _, d, data in self.port.history if d == "TX")

    def close(self) -> None:
        self.engine.close()


def run_until(cond, *runtimes: Runtime, seconds: float = 3.0, pause: float = 0.0005) -> bool:
    """Scan every runtime, then test ``cond``, until it holds or the wall-clock deadline passes."""
    deadline = time.monotonic() + seconds
    while True:
        for r in runtimes:
            r.scan()
        if cond():
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(pause)


def pulse(r: Runtime, bit: str) -> None:
    """Re-arm an instruction: its rung false for one scan."""
    r.write(bit, 0)
    r.scan()
    r.write(bit, 1)


# -- fixtures --------------------------------------------------------------------------------------


@pytest.fixture(scope="module", autouse=True)
def no_socat_left_behind():
    before = set(socat_processes())  # another module's fixture may hold one; not ours to judge
    yield
    assert set(socat_processes()) - before == set(), "a test of this module left socat running"


@pytest.fixture
def pty(tmp_path):
    """A started PtyPair under tmp_path (skips the test when socat is not installed)."""
    require_socat()
    (tmp_path / "ptys").mkdir()
    pair = PtyPair(tmp_path / "ptys")
    try:
        yield pair
    finally:
        pair.close()
        assert pair.leftovers() == []


@pytest.fixture
def runtimes():
    made: list[Runtime] = []

    def make(*args, **kwargs) -> Runtime:
        r = Runtime(*args, **kwargs)
        made.append(r)
        return r

    yield make
    for r in made:
        r.close()


# -- the helper itself -----------------------------------------------------------------------------


def test_ptypair_kill_restart_and_cleanup(tmp_path):
    require_socat()
    with PtyPair(tmp_path) as pair:
        assert os.path.exists(pair.a) and os.path.exists(pair.b) and pair.running
        first = pair.socat_pid
        pair.kill()
        assert not os.path.exists(pair.a) and not os.path.exists(pair.b)  # both ptys vanished
        assert not pair.running and pair.leftovers() == []
        pair.restart()
        assert os.path.exists(pair.a) and os.path.exists(pair.b) and pair.socat_pid != first
        assert pair.socat_pid in socat_processes()
    assert pair.leftovers() == [] and pair.socat_pid not in socat_processes()
    assert pair.starts == 2 and len(pair.started) >= 2


# -- examples 1 and 2 across the pair -----------------------------------------------------------------

PRINTER = """
DATA N7 10
DATA ST9 2
XIC B3/0 COMPRINT R6:0 0 N7:9 N7:0 N7:1
XIC B3/1 COMPRINT R6:1 0 3 ST9:0
"""

SCANNER = """
DATA N7 10
DATA ST9 2
XIC B3/0 COMSCAN R6:0 0 N7:9 N7:0 N7:1
COMRCVSTS 0 C5:0
"""


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_example_1_printed_on_a_is_scanned_back_into_integers_on_b(pty, runtimes, executor):
    a = runtimes(PRINTER, lst(pty.a), executor=executor)
    b = runtimes(SCANNER, lst(pty.b), executor=executor)
    a.write("N7:9", 1)
    a.write("N7:0", 0o17)  # "%3o": octal
    a.write("N7:1", 12)
    b.write("N7:9", 1)
    a.write("B3/0", 1)
    b.write("B3/0", 1)
    assert run_until(lambda: b.bits() == "EN DN", a, b)
    assert a.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 30, "POS": 0}
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 30, "POS": 2}
    assert (b.read("N7:0"), b.read("N7:1")) == (0o17, 12)
    assert a.tx_history() == b.rx_history() == b"Rack no:  17 has 12 modules.\r\n"
    assert b.port.rx == "" and b.read("C5:0.ACC") == 0


def test_example_2_modbus_query_arrives_byte_exact(pty, runtimes):
    a = runtimes(PRINTER, lst(pty.a))
    b = runtimes(SCANNER, lst(pty.b))
    a.write("N7:9", 2)
    a.write("N7:0", 0)  # start
    a.write("N7:1", 125)  # count
    a.write("B3/0", 1)
    query = bytes.fromhex("02 03 00 00 00 7D 85 D8")
    assert run_until(lambda: b.port.rx_bytes == len(query), a, b)
    assert a.ctl()["LEN"] == 8 and a.bits() == "EN DN"
    assert a.tx_history() == query == b.rx_history()
    assert b.port.rx == query.decode("latin-1")
    b.write("N7:9", 2)  # COMSCAN the same format: header literal, two words, CRC checked
    b.write("B3/0", 1)
    b.scan()
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 8, "POS": 3}
    assert (b.read("N7:0"), b.read("N7:1")) == (0, 125)
    assert b.port.rx == ""


# -- the COMSCAN status table -----------------------------------------------------------------------

SCAN_B = """
DATA N7 10
DATA ST9 2
XIC B3/0 COMSCAN R6:0 0 6 ST9:0 N7:0
"""


def send(a: Runtime, b: Runtime, text: str) -> None:
    """A sends ``text`` (COMPRINT "%s"); scan both until B's receive buffer holds all of it."""
    before = b.port.rx_bytes
    a.write("ST9:0", text)
    pulse(a, "B3/1")
    assert run_until(lambda: b.port.rx_bytes == before + len(text), a, b), (b.port.rx_bytes, before, text)
    assert a.bits("R6:1") == "EN DN"


def test_comscan_success_dn_len_pos(pty, runtimes):
    a, b = runtimes(PRINTER, lst(pty.a)), runtimes(SCAN_B, lst(pty.b))
    send(a, b, "AK HM 12345678901234 567\r\n")
    b.write("B3/0", 1)
    b.scan()
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 24, "POS": 2}
    assert (b.read("ST9:0"), b.read("N7:0")) == ("12345678901234", 567)
    assert b.port.rx == "\r\n"  # only what the format used is taken


def test_comscan_mismatch_dn_er_offset_nothing_consumed(pty, runtimes):
    a, b = runtimes(PRINTER, lst(pty.a)), runtimes(SCAN_B, lst(pty.b))
    send(a, b, "AK HX 1")
    b.write("B3/0", 1)
    b.scan()
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 1, "EM": 0, "LEN": 4, "POS": 0}
    assert b.port.rx == "AK HX 1"


def test_comscan_timeout_dn_er_em_on_the_engine_clock(pty, runtimes):
    a = runtimes(PRINTER, lst(pty.a))
    b = runtimes(SCAN_B, lst(pty.b, timeout_ms=50), scan_ms=10)  # 50 ms = 5 scans of 10 ms
    send(a, b, "AK HM 1234")
    b.write("B3/0", 1)
    b.scan()  # the transition
    assert b.ctl() == {"EN": 1, "DN": 0, "ER": 0, "EM": 0, "LEN": 10, "POS": 0}
    for _ in range(4):
        b.scan()
        assert b.bits() == "EN"
    b.scan()  # 50 ms after the transition
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 1, "EM": 1, "LEN": 10, "POS": 0}
    assert b.port.rx == "AK HM 1234"  # read characters go back


def test_comscan_waits_without_dn_then_completes_when_the_rest_arrives(pty, runtimes):
    a, b = runtimes(PRINTER, lst(pty.a)), runtimes(SCAN_B, lst(pty.b))
    send(a, b, "AK HM 123")
    b.write("B3/0", 1)
    for _ in range(20):  # 20 scans and about 10 ms of wall time: waiting, no DN
        b.scan()
        time.sleep(0.0005)
        assert b.bits() == "EN"
    assert (b.ctl()["LEN"], b.ctl()["POS"]) == (9, 0)
    a.write("ST9:0", "45678901234 5678")
    pulse(a, "B3/1")
    assert run_until(lambda: b.read("R6:0/DN") == 1, a, b)
    assert b.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 24, "POS": 2}
    assert (b.read("ST9:0"), b.read("N7:0")) == ("12345678901234", 567)
    assert b.port.rx == "8"


def test_comscan_rung_false_before_completion_no_completion(pty, runtimes):
    a, b = runtimes(PRINTER, lst(pty.a)), runtimes(SCAN_B, lst(pty.b))
    b.write("B3/0", 1)
    b.scan()
    assert b.bits() == "EN"
    b.write("B3/0", 0)
    b.scan()
    assert b.bits() == ""
    send(a, b, "AK HM 12345678901234 567")
    b.scan(5)
    assert b.bits() == "" and b.ctl()["LEN"] == 0
    assert b.port.rx == "AK HM 12345678901234 567"  # arrived, but nothing is scanning for it


# -- COMRCVSTS overflow, COMPRINT waiting for room ----------------------------------------------------

BIG_A = """
DATA N10 1000
XIC B3/0 COMPRINT R6:0 0 4 N10:0
"""

STATUS_B = """
DATA N7 1
XIC B3/1 COMSCAN R6:1 0 5 N7:0
COMRCVSTS 0 C5:0
"""


def test_comrcvsts_overflow_then_a_comscan_that_takes_characters_clears_ov(pty, runtimes):
    a, b = runtimes(BIG_A, lst(pty.a)), runtimes(STATUS_B, lst(pty.b))
    status = lambda: (b.read("C5:0.PRE"), b.read("C5:0.ACC"), b.read("C5:0/OV"))  # noqa: E731
    for _ in range(3):  # 3 x 2000 bytes while B does not scan
        a.write("B3/0", 1)
        a.scan()
        assert a.bits() == "EN DN" and a.ctl()["LEN"] == 2000
        a.write("B3/0", 0)
        a.scan()
    assert a.port.tx_bytes == 6000 and not a.port.tx
    assert run_until(lambda: b.port.rx_bytes == 6000, b)  # B reads (4,096 bytes a scan at most)
    assert status() == (RX_BUFFER_CHARS, 4096, 1)
    assert b.port.dropped == 6000 - 4096 and b.port.overflow
    b.write("B3/1", 1)  # "%*.100c": takes 100 characters
    b.scan()
    assert b.bits("R6:1") == "EN DN"
    assert status() == (4096, 3996, 0)


def fill_until_a_comprint_waits(a: Runtime) -> int:
    """COMPRINT 2000-byte frames from A (B not reading) until one waits for room; how many went."""
    a.write("B3/0", 1)
    done = 0
    for _ in range(100):  # the pty chain (about 31 KB here), then A's 4,096-byte buffer fill up
        a.scan()
        if a.bits() == "EN":
            # Not queued at once. socat may still be moving bytes along (then it completes soon):
            # it counts as waiting once it has stayed EN, no DN, for 0.2 s of wall time.
            deadline = time.monotonic() + 0.2
            while a.bits() == "EN" and time.monotonic() < deadline:
                time.sleep(0.0005)
                a.scan()
            if a.bits() == "EN":
                return done
        assert a.bits() == "EN DN", a.ctl()  # never ER
        done += 1
        pulse(a, "B3/0")
    raise AssertionError(f"{done} COMPRINTs of 2000 bytes all went through without waiting")


def test_comprint_waits_while_the_transmit_buffer_lacks_room_then_completes(pty, runtimes):
    a, b = runtimes(BIG_A, lst(pty.a)), runtimes(STATUS_B, lst(pty.b))
    done = fill_until_a_comprint_waits(a)
    assert a.port.tx and len(a.port.tx) + 2000 > 4096  # the output does not fit: nothing of it queued
    assert a.ctl()["LEN"] == 0
    # B reads (dropping what overflows its receive buffer): room comes back, the COMPRINT completes.
    assert run_until(lambda: a.read("R6:0/DN") == 1, a, b)
    assert a.ctl() == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 2000, "POS": 0}
    sent = (done + 1) * 2000
    assert run_until(lambda: b.port.rx_bytes == sent, a, b)  # every byte of every COMPRINT arrives
    assert a.port.tx_bytes == sent and not a.port.tx


def test_a_comprint_waiting_for_room_ends_with_er_when_the_pty_vanishes(pty, runtimes):
    driver = "PORT_ERRORS=RETRY\nRETRY_MS=20"
    a, b = runtimes(BIG_A, lst(pty.a, driver=driver)), runtimes(STATUS_B, lst(pty.b, driver=driver))
    fill_until_a_comprint_waits(a)
    kept = len(a.port.tx)
    pty.kill()
    assert run_until(lambda: a.read("R6:0/DN") == 1, a)
    assert a.bits() == "EN DN ER" and not a.port.up and a.engine.mode is Mode.RUN
    assert len(a.port.tx) == kept  # what the buffer held stays there (docs/serial.md, Faults)
    stale = b.port.serial
    pty.restart()
    # B first: pyserial's open() flushes what reached a pty before it was opened.
    assert run_until(lambda: b.port.up and b.port.serial is not stale, b)
    assert run_until(lambda: not a.port.tx and b.port.rx_bytes == kept, a, b)  # sent once A is back
    assert a.port.up and a.port.tx_bytes == a.port.tx_bytes // 2000 * 2000


# -- encodings -------------------------------------------------------------------------------------

TALK = """
DATA ST9 4
XIC B3/0 COMPRINT R6:0 0 7 ST9:0
XIC B3/1 COMSCAN R6:1 0 8 ST9:1 ST9:2 ST9:3
"""

TEXT = "Жёлтый 世界 ✓"


@pytest.mark.parametrize("enc,codec", [("UTF-8", "utf-8"), ("UTF-16BE", "utf-16-be"), ("UTF-16LE", "utf-16-le")])
def test_non_latin_text_both_directions(pty, runtimes, enc, codec):
    a, b = runtimes(TALK, lst(pty.a, enc)), runtimes(TALK, lst(pty.b, enc))
    a.write("ST9:0", TEXT)
    b.write("ST9:0", TEXT[::-1])
    for r in (a, b):
        r.write("B3/0", 1)
        r.write("B3/1", 1)
    assert run_until(lambda: a.bits("R6:1") == b.bits("R6:1") == "EN DN", a, b)
    wire_ab = (TEXT + "\n").encode(codec)
    wire_ba = (TEXT[::-1] + "\n").encode(codec)
    assert a.tx_history() == wire_ab == b.rx_history()
    assert b.tx_history() == wire_ba == a.rx_history()
    assert a.ctl()["LEN"] == len(wire_ab) and b.ctl()["LEN"] == len(wire_ba)
    assert [b.read(f"ST9:{k}") for k in (1, 2, 3)] == TEXT.split(" ")
    assert [a.read(f"ST9:{k}") for k in (1, 2, 3)] == TEXT[::-1].split(" ")
    assert a.port.rx == b.port.rx == ""


def test_iso_8859_1_drops_the_upper_8_bits(pty, runtimes):
    a, b = runtimes(TALK, lst(pty.a)), runtimes(TALK, lst(pty.b))
    a.write("ST9:0", "Ł\u0142é Жx")  # U+0141 -> 0x41, U+0142 -> 0x42, U+0416 -> 0x16
    a.write("B3/0", 1)
    assert run_until(lambda: b.port.rx_bytes == 7, a, b)
    assert a.tx_history() == b.rx_history() == b"AB\xe9 \x16x\n"
    assert b.port.rx == "AB\xe9 \x16x\n"


# -- faults ----------------------------------------------------------------------------------------

EXCHANGE_A = """
DATA N7 10
DATA ST9 2
XIC B3/0 COMPRINT R6:0 0 7 ST9:0
"""

EXCHANGE_B = """
DATA ST9 2
XIC B3/0 COMSCAN R6:0 0 9 ST9:0
XIC B3/5 COMRCVSTS 0 C5:0
"""


def exchange(a: Runtime, b: Runtime, text: str) -> None:
    """A fresh COMPRINT on A and COMSCAN on B: ``text`` goes across."""
    a.write("ST9:0", text)
    for r in (a, b):
        r.write("B3/0", 0)
        r.scan()
        r.write("B3/0", 1)
    assert run_until(lambda: b.bits() == "EN DN", a, b), (a.ctl(), b.ctl(), a.port, b.port)
    assert a.bits() == "EN DN" and b.read("ST9:0") == text


def test_port_missing_at_start_stops_the_engine_construction_naming_the_line(tmp_path, runtimes):
    missing = str(tmp_path / "ttyA")
    with pytest.raises(ModuleError) as info:
        runtimes(EXCHANGE_A, lst(missing))
    text = info.value.report()
    assert ports_line(lst(missing)) == 5
    assert text.startswith(f"COMGENIUS.LST:5: [PORTS]: port 0: cannot open {missing}")
    assert "PORT_ERRORS=RETRY" in text


def test_port_missing_at_start_with_retry_comes_up_when_socat_starts(tmp_path, runtimes):
    require_socat()
    pair = PtyPair(tmp_path, start=False)
    try:
        a = runtimes(EXCHANGE_A, lst(pair.a, driver="PORT_ERRORS=RETRY\nRETRY_MS=50"))
        assert a.engine.module_warnings and f"cannot open {pair.a}" in a.engine.module_warnings[0]
        assert not a.port.up
        a.write("ST9:0", "hello")
        a.write("B3/0", 1)
        a.scan()
        assert a.bits() == "EN DN ER" and a.engine.mode is Mode.RUN
        a.scan(10)
        assert a.engine.mode is Mode.RUN and not a.port.up
        pair.start()  # creates the link paths
        assert run_until(lambda: a.port.up, a, seconds=3)  # retried every 50 ms of wall time
        b = runtimes(EXCHANGE_B, lst(pair.b))
        exchange(a, b, "hello")
    finally:
        pair.close()
        assert pair.leftovers() == []


def test_pty_vanishes_while_running_then_comes_back(pty, runtimes):
    driver = "PORT_ERRORS=RETRY\nRETRY_MS=20"
    a, b = runtimes(EXCHANGE_A, lst(pty.a, driver=driver)), runtimes(EXCHANGE_B, lst(pty.b, driver=driver))
    exchange(a, b, "before")
    # B starts a COMSCAN that waits for a frame that will not come.
    b.write("B3/0", 0)
    b.scan()
    b.write("B3/0", 1)
    b.scan()
    assert b.bits() == "EN"
    pty.kill()  # socat dies: both ptys vanish
    assert run_until(lambda: not a.port.up and not b.port.up, a, b)
    assert b.bits() == "EN DN ER"  # the waiting COMSCAN fails with ER (not a timeout: no EM)
    assert a.engine.mode is Mode.RUN and b.engine.mode is Mode.RUN
    # Instructions started after the loss: DN ER, and the engines scan on.
    a.write("ST9:0", "lost")
    for r in (a, b):
        pulse(r, "B3/0")
        r.scan()
        assert r.bits() == "EN DN ER"
    b.write("B3/5", 1)  # COMRCVSTS has no CONTROL: a down port is a minor fault, code 7
    b.scan()
    assert b.read(f"S:{S.MINOR_FAULT_BITS}/{S.MINOR_MODULE_BIT}") == 1
    assert b.read(f"S:{S.MINOR_FAULT_CODE}") == S.MINOR_CODE_PORT
    a.scan(20)
    b.scan(20)
    assert a.engine.mode is Mode.RUN and b.engine.mode is Mode.RUN and b.engine.fault is None
    pty.restart()  # a new socat, the same link paths
    assert run_until(lambda: a.port.up and b.port.up, a, b)
    exchange(a, b, "after")
    exchange(a, b, "again")


def serial_app(tmp_path: Path, device: str, driver: str = "") -> Path:
    """An app directory as programs/strings/ is laid out: MODULES.LST, main.lad, COMGENIUS.LST."""
    return make_app(tmp_path / "serialapp", 'DATA ST9 1 = "ping"\nXIC B3/0 COMPRINT R6:0 0 7 ST9:0\n',
                    MODULES_LST="; the modules this app uses\nCOMGENIUS\n",
                    COMGENIUS_LST=lst(device, driver=driver).encode("latin-1"))


def test_cli_reports_a_missing_device_without_a_traceback(tmp_path):
    missing = tmp_path / "no-such-tty"
    app = serial_app(tmp_path, str(missing))
    p = softplc_here("run", str(app), "--scans", "5", "--fresh")
    assert p.returncode == 1, (p.stdout, p.stderr)
    line = ports_line((app / "COMGENIUS.LST").read_text())
    assert f"{app / 'COMGENIUS.LST'}:{line}: [PORTS]: port 0: cannot open {missing}" in p.stderr
    assert "PORT_ERRORS=RETRY" in p.stderr
    assert "Traceback" not in p.stderr and "Traceback" not in p.stdout


def test_cli_with_retry_runs_on_without_the_device(tmp_path):
    missing = tmp_path / "no-such-tty"
    app = serial_app(tmp_path, str(missing), driver="PORT_ERRORS=RETRY\nRETRY_MS=50")
    p = softplc_here("run", str(app), "--scans", "5", "--fresh", "--set", "B3/0=1", "--print", "R6:0")
    assert p.returncode == 0, (p.stdout, p.stderr)
    line = ports_line((app / "COMGENIUS.LST").read_text())
    assert line == 6
    assert f"warning: {app / 'COMGENIUS.LST'}:{line}: [PORTS]: port 0: cannot open {missing}" in p.stderr
    assert "DN=1" in p.stdout and "ER=1" in p.stdout  # COMPRINT on the down port: DN ER
    assert "Traceback" not in p.stderr


def test_cli_port_override_sends_over_the_pty(tmp_path, pty):
    import serial

    app = serial_app(tmp_path, str(tmp_path / "no-such-tty"))
    reader = serial.Serial(pty.b, 38400, timeout=0)
    try:
        p = softplc_here("run", str(app), "--scans", "3", "--fresh", "--set", "B3/0=1", "--port", f"0={pty.a}",
                         "--print", "R6:0")
        assert p.returncode == 0, (p.stdout, p.stderr)
        assert "DN=1" in p.stdout and "ER=0" in p.stdout and "LEN=5" in p.stdout
        got = b""
        deadline = time.monotonic() + 3
        while len(got) < 5 and time.monotonic() < deadline:
            got += reader.read(100)
            time.sleep(0.001)
        assert got == b"ping\n"
    finally:
        reader.close()
