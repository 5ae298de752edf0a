"""COMPRINT, COMSCAN, COMRCVCLEAR, COMXMITCLEAR and COMRCVSTS on real
pyserial ports (``loop://`` and ``socket://``), on both executors: every row
of the manual's COMSCAN status table, COMPRINT's all-or-nothing buffer,
overflow, encodings, faults (a port that cannot be opened, one that goes
away and comes back), DEBUG output and recording."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.engine import SimulatedClock
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.ports import OverrideError
from softplc_lite.runner import module_engine
from softplc_lite.tlm.comgenius.ports import RX_BUFFER_CHARS, TX_BUFFER_BYTES, port_url
from softplc_lite.tlm.errors import ModuleError
from softplc_lite.tlm.registry import instruction_set

STRINGS = r"""
[STRINGS]
1 "Rack no: %3o has %2d modules.\r\n"
2 "Rack no: %o has %d modules.%\r%\n"
3 "%s"
4 "%.2000c"
5 "%*.100c"
6 "%k"
7 "AK HM %.14s %.3d"
8 "%.4s"
9 "%d;"
10 "%d;%.6s"
"""


def config_text(ports: str = "0, loop://, ISO-8859-1, 38400, 8, N, 1, 50", driver: str = "DEBUG=0") -> str:
    return f"[DRIVER]\n{driver}\n[PORTS]\n{ports}\n{STRINGS}"


@pytest.fixture
def engines():
    made: list[Engine] = []
    yield made
    for e in made:
        e.close()


@pytest.fixture(params=["compiled", "reference"])
def plc(request, engines):
    """plc(program, ports=..., driver=..., values=..., options=...) -> an engine in RUN, not yet scanned."""

    def make(program: str, ports: str | None = None, driver: str = "DEBUG=0", values: dict | None = None,
             options: dict | None = None, scan_ms: int = 10) -> Engine:
        module = ComGenius(parse_config(config_text(ports, driver) if ports else config_text(driver=driver)))
        program_ = load_text(program, instructions=instruction_set([module]))
        table = DataTable()
        e = module_engine(program_, table, clock=SimulatedClock(scan_ms), executor=request.param, modules=[module],
                          module_options=options)
        engines.append(e)
        for addr, value in (values or {}).items():
            e.table.write(addr, value)
        e.set_mode(Mode.RUN)
        return e
    return make


def ctl(e: Engine, addr: str = "R6:0") -> dict:
    r = e.table.read(addr)
    return {k: r[k] for k in ("EN", "DN", "ER", "EM", "LEN", "POS")}


def bits(e: Engine, addr: str = "R6:0") -> str:
    r = e.table.read(addr)
    return " ".join(k for k in ("EN", "DN", "ER", "EM") if r[k])


# -- COMPRINT then COMSCAN over loop:// ---------------------------------------------------

ECHO = """
DATA N7 10
XIC B3/0 COMPRINT R6:0 0 1 N7:0 N7:1
XIC B3/1 COMSCAN R6:1 0 2 N7:5 N7:6
"""


def test_comprint_queues_and_comscan_matches_the_echo(plc):
    e = plc(ECHO, values={"N7:0": 5, "N7:1": 2, "B3/0": 1, "B3/1": 1})
    e.scan()  # COMPRINT queues, the output point writes; COMSCAN saw nothing yet
    assert ctl(e) == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 30, "POS": 0}
    assert bits(e, "R6:1") == "EN"
    e.scan()  # the echo arrived at this scan's input point
    assert ctl(e, "R6:1") == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 30, "POS": 2}
    assert (e.table.read("N7:5"), e.table.read("N7:6")) == (5, 2)
    module = e.modules[0]
    assert module.ports.ports[0].rx == ""  # a successful COMSCAN takes what it matched


def test_comprint_fires_once_per_transition(plc):
    e = plc(ECHO, values={"N7:0": 1, "N7:1": 1, "B3/0": 1})
    port = None
    for _ in range(3):
        e.scan()
        port = e.modules[0].ports.ports[0]
    assert port.tx_bytes == 30  # three true scans, one output
    e.table.write("B3/0", 0)
    e.scan()
    assert bits(e) == ""  # a false rung clears EN DN ER
    e.table.write("B3/0", 1)
    e.scan()
    assert port.tx_bytes == 60 and bits(e) == "EN DN"


# -- the COMSCAN status table ---------------------------------------------------------------

SCAN = """
DATA N7 10
DATA ST9 2
XIC B3/0 COMSCAN R6:0 0 N7:9 ST9:0 N7:0
XIC B3/1 COMPRINT R6:1 0 3 ST9:1
"""


def feed(e: Engine, text: str) -> None:
    """Send ``text`` out of the port (loop:// brings it back next scan)."""
    e.table.write("ST9:1", text)
    e.table.write("B3/1", 1)
    e.scan()
    e.table.write("B3/1", 0)


def test_comscan_success_sets_dn_len_pos(plc):
    e = plc(SCAN, values={"N7:9": 7})
    feed(e, "AK HM 12345678901234 567\r\n")
    e.table.write("B3/0", 1)
    e.scan()
    assert ctl(e) == {"EN": 1, "DN": 1, "ER": 0, "EM": 0, "LEN": 24, "POS": 2}
    assert (e.table.read("ST9:0"), e.table.read("N7:0")) == ("12345678901234", 567)
    assert e.modules[0].ports.ports[0].rx == "\r\n"  # what the format did not use stays


def test_comscan_mismatch_sets_dn_er_and_puts_everything_back(plc):
    e = plc(SCAN, values={"N7:9": 7})
    feed(e, "AK HX 1")
    e.table.write("B3/0", 1)
    e.scan()
    assert ctl(e) == {"EN": 1, "DN": 1, "ER": 1, "EM": 0, "LEN": 4, "POS": 0}  # LEN: the mismatch offset
    assert e.modules[0].ports.ports[0].rx == "AK HX 1"  # nothing taken: another COMSCAN may match it
    e.table.write("B3/0", 0)
    e.table.write("N7:9", 3)  # "%s" matches the same characters
    e.scan()
    e.table.write("B3/0", 1)
    e.scan()
    assert ctl(e)["DN"] == 1 and ctl(e)["ER"] == 0 and e.table.read("ST9:0") == "AK"


def test_comscan_waits_without_dn_then_times_out_with_em(plc):
    e = plc(SCAN, values={"N7:9": 7})  # port timeout 50 ms, 10 ms scans
    feed(e, "AK HM 1234")
    e.table.write("B3/0", 1)
    e.scan()  # t = 20 ms: the transition
    waiting = ctl(e)
    assert (waiting["DN"], waiting["ER"], waiting["EM"]) == (0, 0, 0)
    assert waiting["LEN"] == 10 and waiting["POS"] == 0  # read all 10, no spec complete yet
    for _ in range(4):  # 30..60 ms: still inside the 50 ms
        e.scan()
        assert bits(e) == "EN"
    e.scan()  # 70 ms
    assert ctl(e) == {"EN": 1, "DN": 1, "ER": 1, "EM": 1, "LEN": 10, "POS": 0}  # 50 ms after the transition
    assert e.modules[0].ports.ports[0].rx == "AK HM 1234"  # read characters go back


def test_comscan_completes_when_the_rest_arrives_within_the_timeout(plc):
    e = plc(SCAN, values={"N7:9": 7})
    feed(e, "AK HM 123")
    e.table.write("B3/0", 1)
    e.scan()
    assert bits(e) == "EN"
    feed(e, "45678901234 56789")  # the rest; %.3d takes 567
    assert bits(e) == "EN"  # sent this scan, back at the next input point
    e.scan()
    assert ctl(e)["DN"] == 1 and ctl(e)["ER"] == 0
    assert (e.table.read("ST9:0"), e.table.read("N7:0")) == ("12345678901234", 567)


def test_comscan_rung_false_before_completion_gives_no_completion(plc):
    e = plc(SCAN, values={"N7:9": 7})
    e.table.write("B3/0", 1)
    e.scan()
    assert bits(e) == "EN"
    e.table.write("B3/0", 0)
    e.scan()
    assert bits(e) == ""
    feed(e, "AK HM 12345678901234 567")
    e.scan()
    assert bits(e) == ""  # the data arrived, but nothing is scanning for it
    assert e.modules[0].ports.ports[0].rx == "AK HM 12345678901234 567"


def test_comscan_params_are_staging_areas_written_before_dn(plc):
    e = plc(SCAN, values={"N7:9": 7})
    feed(e, "AK HM 12345678901234 5")
    e.table.write("B3/0", 1)
    e.scan()
    assert bits(e) == "EN"
    assert e.table.read("ST9:0") == "12345678901234"  # written though the match is not complete
    assert ctl(e)["POS"] == 1


@pytest.mark.parametrize("program,problem", [
    ("XIC B3/0 COMSCAN R6:0 3 3 ST9:0", "port 3 is not configured"),
    ("XIC B3/0 COMSCAN R6:0 N7:0 3 ST9:0", "port -1 is out of range"),
    ("XIC B3/0 COMSCAN R6:0 0 44 ST9:0", "format 44: no such string"),
    ("XIC B3/0 COMSCAN R6:0 0 6 ST9:0", "format 6: "),
    ("XIC B3/0 COMSCAN R6:0 0 3 N7:1", "format 3: "),  # %s given an integer
    ("XIC B3/0 COMSCAN R6:0 0 3", "format 3: too few Params"),
    ("XIC B3/0 COMPRINT R6:0 3 1 N7:0 N7:0", "port 3 is not configured"),
    ("XIC B3/0 COMPRINT R6:0 0 44", "format 44: no such string"),
    ("XIC B3/0 COMPRINT R6:0 0 6 N7:0", "format 6: "),
    ("XIC B3/0 COMPRINT R6:0 0 1 N7:0", "format 1: too few Params"),
])
def test_errors_set_dn_er_never_an_exception(plc, capsys, program, problem):
    e = plc("DATA ST9 1\nDATA N7 2\n" + program, driver="DEBUG=1", values={"N7:0": -1, "B3/0": 1, "N7:1": 4})
    feed_free = e.modules[0].ports.ports[0]
    feed_free.rx = "text"
    e.scan()
    assert e.mode is Mode.RUN
    assert bits(e) == "EN DN ER"
    assert problem in capsys.readouterr().err


# -- COMPRINT's transmit buffer ------------------------------------------------------------

BIG = """
DATA N10 1000
XIC B3/0 COMPRINT R6:0 0 4 N10:0
XIC B3/1 COMPRINT R6:1 0 4 N10:0
XIC B3/2 COMPRINT R6:2 0 4 N10:0
XIC B3/3 COMXMITCLEAR 0
"""


def test_comprint_waits_for_room_all_or_nothing(plc):
    e = plc(BIG, values={"B3/0": 1, "B3/1": 1, "B3/2": 1})
    port = e.modules[0].ports.ports[0]
    assert port.tx_size == TX_BUFFER_BYTES == 4096
    e.scan()
    # 2000 + 2000 fit the 4096-byte buffer; the third waits, nothing of it queued
    assert (bits(e, "R6:0"), bits(e, "R6:1"), bits(e, "R6:2")) == ("EN DN", "EN DN", "EN")
    assert port.tx_bytes == 4000
    e.scan()  # the buffer went out at the output point: now it fits
    assert bits(e, "R6:2") == "EN DN" and ctl(e, "R6:2")["LEN"] == 2000


def test_comprint_dropped_when_rung_goes_false_while_waiting(plc):
    e = plc(BIG, values={"B3/0": 1, "B3/1": 1, "B3/2": 1})
    port = e.modules[0].ports.ports[0]
    e.scan()
    e.table.write("B3/2", 0)
    e.scan()
    e.scan()
    assert port.tx_bytes == 4000 and bits(e, "R6:2") == ""


def test_comxmitclear_throws_away_what_is_not_sent(plc):
    e = plc(BIG, values={"B3/0": 1, "B3/3": 1})
    port = e.modules[0].ports.ports[0]
    e.scan()  # queued, then cleared on the next rung, before the output point
    assert bits(e) == "EN DN" and port.tx_bytes == 0 and not port.tx


# -- COMRCVSTS, COMRCVCLEAR and overflow -------------------------------------------------

STATUS = """
DATA N10 1000
DATA N7 1
XIC B3/0 COMPRINT R6:0 0 4 N10:0
XIC B3/1 COMSCAN R6:1 0 5 N7:0
COMRCVSTS 0 C5:0
XIC B3/2 COMRCVCLEAR 0
"""


def test_comrcvsts_counts_and_overflow_clears_after_a_comscan_makes_room(plc):
    e = plc(STATUS)
    c = lambda: (e.table.read("C5:0.PRE"), e.table.read("C5:0.ACC"), e.table.read("C5:0/OV"))  # noqa: E731
    e.scan()
    assert c() == (RX_BUFFER_CHARS, 0, 0)
    for expected in (0, 2000, 4000):  # each COMPRINT's echo arrives at the next scan's input
        assert c()[1] == expected
        e.table.write("B3/0", 1)
        e.scan()
        e.table.write("B3/0", 0)
        e.scan()
    assert c() == (4096, 4096, 1)  # 6000 sent, 4096 kept, OV
    port = e.modules[0].ports.ports[0]
    assert port.dropped == 6000 - 4096
    e.table.write("B3/1", 1)  # COMSCAN "%*.100c" removes 100 characters
    e.scan()
    e.scan()
    assert bits(e, "R6:1") == "EN DN"
    assert c() == (4096, 3996, 0)


def test_comrcvclear_empties_the_receive_buffer(plc):
    e = plc(STATUS)
    e.table.write("B3/0", 1)
    e.scan()
    e.scan()
    assert e.table.read("C5:0.ACC") == 2000
    e.table.write("B3/2", 1)
    e.scan()
    assert e.modules[0].ports.ports[0].rx == ""
    e.table.write("B3/2", 0)
    e.scan()
    assert e.table.read("C5:0.ACC") == 0


def test_no_control_instructions_on_a_bad_port_raise_a_minor_fault(plc):
    e = plc("COMRCVSTS N7:0 C5:0\nCOMRCVCLEAR 9\n", values={"N7:0": 40})
    e.scan()
    assert e.mode is Mode.RUN
    assert e.table.read(f"S:{S.MINOR_FAULT_BITS}/{S.MINOR_MODULE_BIT}") == 1
    assert e.table.read(f"S:{S.MINOR_FAULT_CODE}") == S.MINOR_CODE_PORT
    assert e.table.read("C5:0.PRE") == 0  # untouched


# -- encodings ------------------------------------------------------------------------------

ENC = """
DATA ST9 2
XIC B3/0 COMPRINT R6:0 0 9 N7:0
XIC B3/0 COMPRINT R6:2 0 3 ST9:0
XIC B3/0 COMPRINT R6:3 1 3 ST9:0
XIC B3/1 COMSCAN R6:1 0 10 N7:1 ST9:1
"""


@pytest.mark.parametrize("enc,codec", [("UTF-8", "utf-8"), ("UTF-16BE", "utf-16-be"), ("UTF-16LE", "utf-16-le")])
def test_non_latin_text_round_trips_through_each_unicode_encoding(plc, enc, codec):
    text = "Жёлтый 世界"
    e = plc(ENC, ports=f"0, loop://, {enc}, 38400, 8, N, 1, 50\n1, loop://, {enc}, 38400, 8, N, 1, 50",
            values={"ST9:0": text, "N7:0": 42, "B3/0": 1})
    e.scan()
    port = e.modules[0].ports.ports[0]
    wire = ("42;" + text).encode(codec)
    assert port.history[-1][2] == wire and port.tx_bytes == len(wire) == ctl(e)["LEN"] + ctl(e, "R6:2")["LEN"]
    e.table.write("B3/1", 1)
    e.scan()  # the echo decodes back into 16-bit characters
    assert bits(e, "R6:1") == "EN DN"
    assert (e.table.read("N7:1"), e.table.read("ST9:1")) == (42, "Жёлтый")


def test_iso_8859_1_drops_the_upper_byte_and_us_ascii_sends_question_marks(plc):
    e = plc(ENC, ports="0, loop://, ISO-8859-1, 38400, 8, N, 1, 50\n1, loop://, US-ASCII, 9600, 8, N, 1, 50",
            values={"ST9:0": "Ł\u0142é", "B3/0": 1})
    e.scan()
    ports = e.modules[0].ports.ports
    assert ports[0].history[-1][2] == b"0;AB\xe9"  # U+0141 -> 0x41, U+0142 -> 0x42
    assert ports[1].history[-1][2] == b"???"
    e.scan()
    assert ports[1].rx == "???" and ports[0].rx == "0;AB\xe9"


def test_utf8_sequence_split_across_reads_waits_for_the_rest(plc):
    e = plc("DATA N7 1", ports="0, loop://, UTF-8, 38400, 8, N, 1, 50")
    port = e.modules[0].ports.ports[0]
    data = "дом".encode()  # six bytes, two per character
    for chunk, expected in ((data[:1], ""), (data[1:2], "д"), (data[2:3], "д"), (data[3:], "дом")):
        port.serial.write(chunk)  # loop:// brings each chunk back at the next input point
        e.scan()
        assert port.rx == expected


# -- ports: names, overrides, faults -----------------------------------------------------

def test_physical_port_names():
    assert port_url("COM1", {}, "linux") == "/dev/ttyS0"
    assert port_url("com2", {}, "win32") == "COM2"
    assert port_url("0", {}, "linux") == "/dev/ttyS0"  # the manual's sample: port 0 is COM1
    assert port_url("COM3", {3: "/dev/ttyUSB0"}, "linux") == "/dev/ttyUSB0"
    assert port_url("socket://h:1", {}, "linux") == "socket://h:1"
    assert port_url("/dev/ttyACM0", {}, "linux") == "/dev/ttyACM0"


def test_a_port_that_cannot_be_opened_stops_the_start_naming_its_line(plc):
    with pytest.raises(ModuleError) as info:
        plc("DATA N7 1", ports="0, loop://, ISO-8859-1, 38400, 8, N, 1, 50\n"
                               "5, /dev/softplc-no-such-device, ISO-8859-1, 9600, 8, N, 1, 50")
    text = info.value.report()
    assert text.startswith("COMGENIUS.LST:5: [PORTS]: port 5: cannot open /dev/softplc-no-such-device")
    assert "PORT_ERRORS=RETRY" in text


def test_port_override_replaces_the_physical_field(plc):
    e = plc("DATA N7 1", ports="0, /dev/softplc-no-such-device, ISO-8859-1, 38400, 8, N, 1, 50",
            options={"ports": {0: "loop://"}})
    assert e.modules[0].ports.ports[0].up


def test_override_of_an_unconfigured_port_is_an_error(plc):
    with pytest.raises(OverrideError, match=r"--port 4=loop://: no module has a port 4 \(ports: COMGENIUS: 0\)"):
        plc("DATA N7 1", options={"ports": {4: "loop://"}})


class Peer:
    """A TCP peer for socket:// that can go away and come back."""

    def __init__(self) -> None:
        probe = socket.socket()
        probe.bind(("127.0.0.1", 0))
        self.port = probe.getsockname()[1]
        probe.close()
        self.server: socket.socket | None = None
        self.conns: list[socket.socket] = []
        self.received = bytearray()

    def start(self) -> None:
        self.server = socket.socket()
        self.server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.server.bind(("127.0.0.1", self.port))
        self.server.listen()
        threading.Thread(target=self._serve, args=(self.server,), daemon=True).start()

    def _serve(self, server: socket.socket) -> None:
        try:
            while True:
                conn, _ = server.accept()
                self.conns.append(conn)
                threading.Thread(target=self._echo, args=(conn,), daemon=True).start()
        except OSError:
            return

    def _echo(self, conn: socket.socket) -> None:
        try:
            while data := conn.recv(4096):
                self.received += data
                conn.sendall(data)
        except OSError:
            return

    def stop(self) -> None:
        if self.server is not None:
            try:
                self.server.shutdown(socket.SHUT_RDWR)  # wakes the accept() thread, frees the address
            except OSError:
                pass
            self.server.close()
            self.server = None
        for c in self.conns:
            try:
                c.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            c.close()
        self.conns.clear()


def wait_until(cond, e: Engine, seconds: float = 5.0) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        e.scan()
        if cond():
            return True
        time.sleep(0.005)
    return False


PING = """
DATA ST9 2 = "ping" ""
XIC B3/0 COMPRINT R6:0 0 3 ST9:0
XIC B3/1 COMSCAN R6:1 0 8 ST9:1
"""


def test_port_down_at_start_with_retry_then_vanishes_and_comes_back(plc):
    peer = Peer()
    try:
        e = plc(PING, ports=f"0, socket://127.0.0.1:{peer.port}, ISO-8859-1, 38400, 8, N, 1, 500",
                driver="DEBUG=0\nPORT_ERRORS=RETRY\nRETRY_MS=20")
        assert e.module_warnings and "cannot open socket://" in e.module_warnings[0]
        port = e.modules[0].ports.ports[0]
        e.table.write("B3/0", 1)
        e.scan()
        assert bits(e) == "EN DN ER"  # the port is down: ER, and the engine scans on
        assert e.mode is Mode.RUN
        peer.start()
        assert wait_until(lambda: port.up, e)  # retried every 20 ms
        e.table.write("B3/0", 0)
        e.scan()
        e.table.write("B3/0", 1)
        e.table.write("B3/1", 1)
        assert wait_until(lambda: bits(e, "R6:1") == "EN DN", e)
        assert e.table.read("ST9:1") == "ping" and bytes(peer.received) == b"ping"
        peer.stop()  # the device goes away while running
        assert wait_until(lambda: not port.up, e)
        e.table.write("B3/0", 0)
        e.scan()
        e.table.write("B3/0", 1)
        e.scan()
        assert bits(e) == "EN DN ER"
        peer.start()  # and comes back
        assert wait_until(lambda: port.up, e)
        e.table.write("B3/0", 0)
        e.table.write("B3/1", 0)
        e.scan()
        e.table.write("B3/0", 1)
        e.table.write("B3/1", 1)
        assert wait_until(lambda: bits(e, "R6:1") == "EN DN", e)
        assert bits(e) == "EN DN"
    finally:
        peer.stop()


# -- DEBUG and recording ------------------------------------------------------------------

def test_debug_2_logs_frames_in_hex_with_timestamps_and_debug_0_is_silent(plc, capsys):
    e = plc(ECHO, driver="DEBUG=2", values={"N7:0": 5, "N7:1": 2, "B3/0": 1})
    e.scan()
    e.scan()
    err = capsys.readouterr().err
    assert "port 0 TX   30 bytes: 52 61 63 6B 20 6E 6F 3A" in err  # "Rack no:"
    assert "port 0 RX   30 bytes: 52 61 63 6B" in err
    assert "t=10ms" in err and "t=20ms" in err
    e2 = plc(ECHO, driver="DEBUG=0", values={"N7:0": 5, "N7:1": 2, "B3/0": 1})
    e2.scan()
    e2.scan()
    assert capsys.readouterr().err == ""


def test_record_writes_every_frame_with_time_port_and_direction(plc, tmp_path):
    trace = tmp_path / "trace.txt"
    e = plc(ECHO, values={"N7:0": 5, "N7:1": 2, "B3/0": 1}, options={"record": str(trace)})
    e.scan()
    e.scan()
    e.close()
    from softplc_lite.ports.trace import read_trace

    events = read_trace(trace)
    assert [(ev.t_ms, ev.port, ev.direction) for ev in events] == [(10.0, 0, "TX"), (20.0, 0, "RX")]
    assert events[0].data == b"Rack no:   5 has  2 modules.\r\n" == events[1].data
    assert "# port 0: loop:// -> loop:// 38400 8N1 ISO-8859-1" in trace.read_text()


def test_check_warns_about_ports_and_formats_it_can_see():
    from softplc_lite.ladder.ast import walk

    module = ComGenius(parse_config(config_text()))
    program = load_text("COMPRINT R6:0 4 1 N7:0 N7:1\nCOMSCAN R6:1 0 3 N7:0\nCOMRCVSTS 9 C5:0\n"
                        "COMSCAN R6:2 N7:5 99\nCOMPRINT R6:3 0 1 N7:0 N7:1\n",
                        instructions=instruction_set([module]))
    found = [w.report() for rung in program.files[2].rungs for ins in walk(rung.elements)
             for w in module.check(ins)]
    assert found == [
        "<program>:1:15: COMPRINT: port 4 is not configured in [PORTS] of COMGENIUS.LST (configured: 0); "
        "it will set ER",
        "<program>:2:18: COMSCAN: Param 1 is N7:0 (an integer); %s in format 3 needs a STRING",
        "<program>:3:11: COMRCVSTS: port 9 is not configured in [PORTS] of COMGENIUS.LST (configured: 0); "
        "it will set a minor fault",
        "<program>:4:19: COMSCAN: format 99 is not in the string table (strings 1..10); it will set ER",
    ]


def test_an_operation_lost_to_a_restore_starts_again(plc):
    # A snapshot taken while COMSCAN waited holds EN without DN; the new run's
    # instruction has nothing in progress: it starts again instead of hanging.
    e = plc(SCAN, values={"N7:9": 7, "B3/0": 1, "R6:0/EN": 1})
    e.scan()
    assert bits(e) == "EN"  # matching again, timeout counted from now
    for _ in range(5):
        e.scan()
    assert bits(e) == "EN DN ER EM"
