"""The shortcuts on the Modbus master's scan, each
with a test that fails if the work it skips was needed:

- a clocked COMGENIUS port does not read a quiet simulated link at all, and
  the link skips a pump its device's ``next_due`` says would do nothing: the
  app runs exactly as with every port read and every pump done at every scan;
- ControlledInstruction keeps a direct CONTROL's word; an indirect one is
  still resolved at every call;
- the simulated Modbus slave reuses the reply to the same read on unchanged
  registers, and %R the CRC of equal bytes.
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
from softplc_lite.ports.modbus_slave import ModbusSlave, respond, with_crc
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.tlm.comgenius import ComGenius, checksum
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.tlm.registry import instruction_set

from helpers.clocks import Clock
from helpers.reference_checks import crc16_modbus_ref

REPO_APP = Path(__file__).resolve().parent.parent / "programs" / "modbus_master"
_names = itertools.count()
QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")


def _app_run(scans: int, sets: tuple[str, ...], device: str, every_scan: bool) -> dict:
    """The shipped app for ``scans`` scans; with ``every_scan`` its port
    reads the link at every scan and the link pumps its device at every read
    (no quiet time, a device that cannot tell), as before the shortcuts."""
    app = load_app(REPO_APP, use_cache=False)
    app.state_dir = None
    r = Runner(app, RunOptions(fresh=True, sets=sets, ports=(f"0={device}",)), log=lambda msg: None)
    try:
        port = r.engine.modules[0].serial_ports()[0]
        if every_scan:
            port.quiet = None
            link = port.serial.sim_link
            link.device.next_due = lambda now: now
        r.run(scans)
        t = r.table
        return {
            "counters": [t.read(f"C5:{k}.ACC") for k in range(5)],
            "n11": [t.read(f"N11:{k}") for k in range(125)],
            "controls": [[t.read(f"R6:{k}.{m}") for m in ("LEN", "POS")] + [t.read(f"R6:{k}/EN")]
                         for k in range(3)],
            "history": list(port.history),
            "rx_bytes": port.rx_bytes,
            "tx_bytes": port.tx_bytes,
            "rx": port.rx,
        }
    finally:
        r.engine.close()


@pytest.mark.parametrize("sets, fault", [
    ((), ""),
    (("T4:0.PRE=0",), ""),
    (("T4:0.PRE=0",), "&cut=100"),  # every reply cut short: the COMSCANs time out
    ((), "&pause_after=20&pause_ms=3&turnaround_ms=2"),
    ((), "&garbage=0102"),
])
def test_the_app_reads_what_it_read_with_every_port_read_and_pump_done(sets, fault):
    device = f"sim://t_io{next(_names)}?device=modbus&id=2&registers=200{fault}"
    fast = _app_run(2500, sets, device, every_scan=False)
    slow = _app_run(2500, sets, device, every_scan=True)
    assert fast == slow
    assert fast["counters"][0] > 5  # it polled


def _open(url: str, clock: Clock):
    import softplc_lite.ports.urlhandler  # noqa: F401  (registers the schemes)
    port = serial.serial_for_url(url, baudrate=38400, timeout=0)
    port.set_clock(clock)
    return port


@pytest.mark.parametrize("seed", range(4))
def test_a_read_that_skips_needless_pumps_reads_what_an_always_pumped_one_reads(seed):
    """Two device links driven alike at irregular times; one device says it
    is always due (so its link pumps at every read): the same bytes at the
    same times, and the other link pumped less."""
    rng = random.Random(seed)
    clock = Clock()
    fault = ["", "&cut=100", "&pause_after=20&pause_ms=3", "&turnaround_ms=1"][seed]
    urls = [f"sim://t_io{next(_names)}?device=modbus&id=2&registers=200{fault}" for _ in range(2)]
    ports = [_open(url, clock) for url in urls]
    pumps = [0, 0]
    try:
        for k, p in enumerate(ports):
            link = p.sim_link
            real = link.pump

            def counted(now, real=real, k=k):
                pumps[k] += 1
                real(now)
            link.pump = counted
        ports[1].sim_link.device.next_due = lambda now: now
        got = [[], []]
        for _ in range(600):
            clock.now += rng.choice([10_000, 100_000, 260_417, 500_000, 1_000_000])
            if rng.random() < 0.03:
                query = QUERY if rng.random() < 0.8 else QUERY[:5]  # a whole query, or a broken one
                for p in ports:
                    p.write(query)
            for k, p in enumerate(ports):
                got[k].append((clock.now, p.read_now()))
        assert got[0] == got[1]
        assert any(d for _, d in got[0])
        assert pumps[0] < pumps[1]
    finally:
        for p in ports:
            p.close()


def test_a_device_send_from_outside_ends_the_quiet():
    """A test (or a device driven by another thread) sending toward the
    port: a port that found the link quiet reads it at once."""
    clock = Clock()
    port = _open(f"sim://t_io{next(_names)}?device=modbus&id=2&registers=200", clock)
    try:
        assert port.read_now() == b""
        assert port.sim_link.quiet_until > clock.now
        end = port.sim_link.device.end
        end.send(b"\x01\x02", clock.now)
        clock.now += 2 * 260_417
        assert port.read_now() == b"\x01\x02"
    finally:
        port.close()


# -- ControlledInstruction ---------------------------------------------------------------------------

def test_an_indirect_control_is_resolved_at_every_call():
    config = parse_config("[DRIVER]\nDEBUG=0\n[PORTS]\n0, loop://, ISO-8859-1, 38400, 8, N, 1, 500\n"
                          '[STRINGS]\n1 "AB"\n')
    module = ComGenius(config)
    program = "DATA R6 4\nXIC B3/0 COMSCAN R6:[N7:5] 0 1\n"
    e = Engine(load_text(program, instructions=instruction_set([module])), DataTable(),
               clock=SimulatedClock(10), executor="compiled", modules=[module])
    try:
        e.set_mode(Mode.RUN)
        port = module.ports.ports[0]
        e.table.write("N7:5", 1)
        e.table.write("B3/0", 1)
        e.scan()
        assert e.table.read("R6:1/EN") == 1 and e.table.read("R6:1/DN") == 0
        e.table.write("N7:5", 2)  # the same instruction now has R6:2: a new transition there
        port.rx = "AB"
        e.scan()
        assert (e.table.read("R6:2/EN"), e.table.read("R6:2/DN"), e.table.read("R6:2.LEN")) == (1, 1, 2)
        assert e.table.read("R6:1/DN") == 0
    finally:
        e.close()


# -- the simulated slave's reply and the CRC -----------------------------------------------------------

def test_the_slave_answers_changed_registers_with_a_new_reply():
    slave = ModbusSlave(slave_id=[1, 2], registers=20)
    read = with_crc(bytes.fromhex("02 03 00 00 00 03"))
    first = respond(read, slave)
    assert respond(read, slave) == first
    slave.unit(2).holding_registers[1] = 0xBEEF
    second = respond(read, slave)
    assert second[5:7] == b"\xbe\xef" and second != first
    other = respond(with_crc(bytes.fromhex("01 03 00 00 00 03")), slave)  # the other id, same PDU
    assert other[0] == 1 and other[3:9] != second[3:9]
    inputs = respond(with_crc(bytes.fromhex("02 04 00 00 00 03")), slave)
    assert inputs[1] == 4 and inputs[3:9] != second[3:9]
    assert slave.requests == 5


def test_crc_of_equal_long_bytes_is_kept_and_of_other_bytes_computed():
    rng = random.Random(7)
    long_a = bytes(rng.randrange(256) for _ in range(253))
    long_b = long_a[:-1] + bytes([long_a[-1] ^ 1])
    for data, preload in [(long_a, 0xFFFF), (b"\x02\x03\x00\x00", 0xFFFF), (long_a, 0xFFFF), (long_a, 0),
                          (long_b, 0xFFFF), (bytearray(long_b), 0xFFFF), (list(long_a), 0xFFFF), (long_a, 0xFFFF)]:
        assert checksum.crc16_bytes(data, preload) == crc16_modbus_ref(bytes(data), preload)
