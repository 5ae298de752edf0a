"""The shortcuts COMSCAN and the simulated wire take, each with a
test that fails if the work it skips was needed:

- COMSCAN does not repeat a match on the same receive buffer when the last
  attempt needed more input and took no Param, nor on one that only grew
  while a fixed-size field still lacks characters; a changed buffer, a
  re-armed instruction or a Param-taking partial match is matched again,
  and the timeout still fires;
- a device link (sim://...?device=) skips its pump while nothing can
  arrive and the device's poll is not due; a port reading it sees exactly
  what it saw with the pump run at every read.
"""

from __future__ import annotations

import itertools
import random
from pathlib import Path

import pytest
import serial

from softplc_lite.app import load_app
from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder.engine import SimulatedClock
from softplc_lite.ports import simlink
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.tlm.comgenius.scanf import ScanFormat
from softplc_lite.tlm.registry import instruction_set

from helpers.clocks import Clock
from helpers.reference_checks import crc16_modbus_ref

REPO_APP = Path(__file__).resolve().parent.parent / "programs" / "modbus_master"
_names = itertools.count()

STRINGS = r"""
[STRINGS]
1 "\x02\x03\xfa%.250C%#R"
2 "%d,%d"
"""

PROGRAM = """
DATA N11 125
XIC B3/0 COMSCAN R6:1 0 1 N11:0
XIC B3/1 COMSCAN R6:2 0 2 N11:0 N11:1
"""


@pytest.fixture(params=["compiled", "reference"])
def scanner(request):
    made = []

    def make() -> tuple[Engine, object]:
        config = parse_config(f"[DRIVER]\nDEBUG=0\n[PORTS]\n0, loop://, ISO-8859-1, 38400, 8, N, 1, 500\n{STRINGS}")
        module = ComGenius(config)
        e = Engine(load_text(PROGRAM, instructions=instruction_set([module])), DataTable(),
                   clock=SimulatedClock(10), executor=request.param, modules=[module])
        e.set_mode(Mode.RUN)
        made.append(e)
        return e, module.ports.ports[0]
    yield make
    for e in made:
        e.close()


@pytest.fixture
def matches(monkeypatch):
    """Counts the matches COMSCAN actually runs."""
    calls = []
    real = ScanFormat.match_counted

    def counting(self, data, params=(), final=False):
        calls.append(data)
        return real(self, data, params, final)
    monkeypatch.setattr(ScanFormat, "match_counted", counting)
    return calls


def bits(e: Engine, control: str) -> tuple[int, int, int, int]:
    t = e.table
    return tuple(t.read(f"{control}/{b}") for b in ("EN", "DN", "ER", "EM"))


def test_an_unchanged_buffer_is_matched_once_while_waiting(scanner, matches):
    e, port = scanner()
    port.rx = "\x02\x03\xfa" + "A" * 10
    e.table.write("B3/0", 1)
    for _ in range(5):
        e.scan()
    assert matches == [port.rx]  # the later scans reuse that attempt
    assert bits(e, "R6:1") == (1, 0, 0, 0)
    assert e.table.read("R6:1.LEN") == 13  # still set every scan from the kept result


def test_a_buffer_that_changed_after_a_failed_attempt_is_matched_again(scanner, matches):
    e, port = scanner()
    port.rx = "\x02"
    e.table.write("B3/0", 1)
    e.scan()
    e.scan()
    port.rx = "\x05"  # same length, other content: a mismatch now
    e.scan()
    assert len(matches) == 2
    assert bits(e, "R6:1") == (1, 1, 1, 0)


def test_a_buffer_growing_inside_a_fixed_field_is_not_matched_again(scanner, matches):
    e, port = scanner()
    port.rx = "\x02\x03\xfa" + "A" * 10  # %.250C stops: it needs 253 characters in all
    e.table.write("B3/0", 1)
    e.scan()
    for n in (20, 100, 252):
        port.rx += "A" * (n - len(port.rx))
        e.scan()
        assert e.table.read("R6:1.LEN") == n  # NEED_MORE at the buffer's end, as a match gives
    assert len(matches) == 1
    assert bits(e, "R6:1") == (1, 0, 0, 0)
    port.rx += "A"  # 253: the field is there, now the CRC is needed: matched again
    e.scan()
    assert len(matches) == 2


def test_a_grown_buffer_whose_start_changed_is_matched_again(scanner, matches):
    e, port = scanner()
    port.rx = "\x02\x03\xfa" + "A" * 10
    e.table.write("B3/0", 1)
    e.scan()
    port.rx = "\x02\x05\xfa" + "A" * 20  # longer, but not the old buffer plus more
    e.scan()
    assert len(matches) == 2
    assert bits(e, "R6:1") == (1, 1, 1, 0)


def test_a_buffer_that_grew_to_a_whole_reply_matches(scanner):
    e, port = scanner()
    words = [(k * 7 + 3) & 0xFF for k in range(250)]
    frame = bytes([0x02, 0x03, 0xFA, *words])
    frame += crc16_modbus_ref(frame, 0xFFFF).to_bytes(2, "little")
    port.rx = frame[:3].decode("latin-1")
    e.table.write("B3/0", 1)
    e.scan()
    e.scan()
    port.rx += frame[3:].decode("latin-1")
    e.scan()
    assert bits(e, "R6:1") == (1, 1, 0, 0)
    assert e.table.read("R6:1.LEN") == 255
    assert port.rx == ""


def test_a_rearmed_comscan_matches_the_same_buffer_again(scanner, matches):
    e, port = scanner()
    port.rx = "\x02\x03"
    e.table.write("B3/0", 1)
    e.scan()
    e.table.write("B3/0", 0)
    e.scan()
    e.table.write("B3/0", 1)
    e.scan()
    assert len(matches) == 2


def test_a_partial_match_that_wrote_a_param_is_repeated(scanner, matches):
    e, port = scanner()
    port.rx = "12,"  # %d stored 12, then the second %d needs more input
    e.table.write("B3/1", 1)
    e.scan()
    assert e.table.read("N11:0") == 12
    e.table.write("N11:0", 0)  # the ladder overwrites it: the next attempt stores it again
    e.scan()
    assert e.table.read("N11:0") == 12
    assert len(matches) == 2


def test_the_timeout_fires_while_the_match_is_skipped(scanner):
    e, port = scanner()
    port.rx = "\x02\x03"
    e.table.write("B3/0", 1)
    for _ in range(49):  # 490 ms of 10 ms scans: the port's timeout is 500 ms
        e.scan()
    assert bits(e, "R6:1") == (1, 0, 0, 0)
    e.scan()
    e.scan()
    assert bits(e, "R6:1") == (1, 1, 1, 1)


# -- the wire ------------------------------------------------------------------------------------------

QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")


def _open(url: str, clock: Clock):
    import softplc_lite.ports.urlhandler  # noqa: F401  (registers the schemes)
    port = serial.serial_for_url(url, baudrate=38400, timeout=0)
    port.set_clock(clock)
    return port


@pytest.mark.parametrize("seed", range(6))
def test_a_quiet_device_link_reads_what_an_always_pumped_one_reads(seed):
    """Two device links driven alike at irregular times, one with the quiet
    shortcut disabled: every read returns the same bytes at the same time."""
    rng = random.Random(seed)
    clock = Clock()
    fault = ["", "&silent=1", "&cut=100", "&pause_after=20&pause_ms=3"][seed % 4]
    urls = [f"sim://t_speed{next(_names)}?device=modbus&id=2&registers=200{fault}" for _ in range(2)]
    ports = [_open(url, clock) for url in urls]
    try:
        always = simlink.device_links(urls[1].split("?")[0][6:])[-1]
        always.quiet_from = lambda now: 0  # the pump runs at every read, as before the shortcut
        got = [[], []]
        skipped = 0
        for _ in range(400):
            clock.now += rng.choice([10_000, 100_000, 260_417, 500_000, 1_000_000, 3_000_000])
            if rng.random() < 0.03:
                query = QUERY if rng.random() < 0.8 else QUERY[:5]  # a whole query, or a broken one
                for p in ports:
                    p.write(query)
            for k, p in enumerate(ports):
                quiet = k == 0 and clock.now < p._end.link.quiet_until
                data = p.read_now()
                skipped += quiet
                got[k].append((clock.now, data))
        assert got[0] == got[1]
        assert skipped > 50  # the shortcut was taken
        assert any(d for _, d in got[0]) or "silent" in urls[0]
    finally:
        for p in ports:
            p.close()


def test_a_write_ends_the_quiet_and_the_frame_end_is_due():
    """Read every 0.1 ms: the query's last byte is taken before the slave's
    3.5-character silence has passed, so the link must wake for the
    device's poll (next_due) with nothing on either wire."""
    clock = Clock()
    port = _open(f"sim://t_speed{next(_names)}?device=modbus&id=2&registers=200", clock)
    try:
        assert port.read_now() == b""
        assert port._end.link.quiet_until > clock.now  # nothing on the line: quiet for good
        port.write(QUERY)
        assert port._end.link.quiet_until == 0
        first = None
        reply = b""
        for _ in range(1000):
            clock.now += 100_000
            data = port.read_now()
            if data and first is None:
                first = clock.now
            reply += data
        assert reply[:3] == bytes([0x02, 0x03, 0xFA]) and len(reply) == 255
        # the query's 8 characters, 3.5 characters of silence, then the reply's first character
        end = 8 * 260_417 + 911_458
        assert end + 260_417 <= first < end + 260_417 + 100_000 + 1
    finally:
        port.close()


def test_the_app_on_a_silent_slave_still_times_out():
    """Nothing ever arrives (the slave is id 3): the wire is quiet from the
    query's end on, and the COMSCANs' 250 ms timeout still fires."""
    app = load_app(REPO_APP, use_cache=False)
    app.state_dir = None
    r = Runner(app, RunOptions(fresh=True, ports=("0=sim://modbus?device=modbus&id=3&registers=200",)),
               log=lambda msg: None)
    try:
        r.run(1000)
        assert r.table.read("C5:3.ACC") == 3  # 1 s: a poll every 50 ms + 250 ms timeout
        assert r.table.read("C5:1.ACC") == 0
    finally:
        r.engine.close()
