"""The shared port layer (softplc_lite.ports): which module a ``--port``
belongs to, one owner per device, the run's recorder, and what the simulated
wire adds for drivers (timed reads, RTS and CTS)."""

from __future__ import annotations

import io

import pytest

from softplc_lite.ports import (OverrideError, PortClaim, Recorder, assign_port_overrides, claim_conflicts,
                                claim_key, parse_port_overrides)
from softplc_lite.ports.port import LineSettings, SerialPort
from softplc_lite.ports.trace import parse_trace

from helpers.clocks import Clock
from helpers.cli import softplc_here

CHAR = 260_417  # one character at 38400 8N1, ns


# -- --port [MODULE:]N=DEVICE ---------------------------------------------------------------

def test_overrides_parse_with_and_without_a_module():
    assert parse_port_overrides(["0=/dev/ttyUSB0", "modbmast:1 = sim://bus?device=modbus"]) == {
        (None, 0): "/dev/ttyUSB0", ("MODBMAST", 1): "sim://bus?device=modbus"}


@pytest.mark.parametrize("item", ["zero=loop://", "1=", "=loop://", "MODBMAST:=x", "1:2=x"])
def test_bad_override_items_say_what_is_expected(item):
    with pytest.raises(OverrideError, match="expected N=DEVICE or MODULE:N=DEVICE"):
        parse_port_overrides([item])


def test_an_override_given_twice_is_refused():
    with pytest.raises(OverrideError, match="port 1 is given twice"):
        parse_port_overrides(["1=loop://", "1=socket://h:1"])


PORTS = {"COMGENIUS": [0, 1], "MODBMAST": [1, 2]}


def test_a_plain_number_goes_to_the_only_module_with_that_port():
    split = assign_port_overrides({(None, 0): "a", (None, 2): "b", ("MODBMAST", 1): "c"}, PORTS)
    assert split == {"COMGENIUS": {0: "a"}, "MODBMAST": {2: "b", 1: "c"}}


def test_a_number_two_modules_have_must_name_the_module():
    with pytest.raises(OverrideError) as info:
        assign_port_overrides({(None, 1): "x"}, PORTS)
    assert str(info.value) == ("--port 1=x: COMGENIUS and MODBMAST both have a port 1; say which: "
                               "--port COMGENIUS:1=... or --port MODBMAST:1=...")


def test_overrides_for_ports_nobody_has_list_the_ports():
    with pytest.raises(OverrideError, match=r"no module has a port 7 \(ports: COMGENIUS: 0, 1; MODBMAST: 1, 2\)"):
        assign_port_overrides({(None, 7): "x"}, PORTS)
    with pytest.raises(OverrideError, match=r"MODBMAST has no port 0 \(its ports: 1, 2\)"):
        assign_port_overrides({("MODBMAST", 0): "x"}, PORTS)
    with pytest.raises(OverrideError, match="no module DEMO drives ports"):
        assign_port_overrides({("DEMO", 0): "x"}, PORTS)


# -- one owner per device ----------------------------------------------------------------------

def test_claim_keys(tmp_path):
    target = tmp_path / "tty0"
    target.write_text("")
    link = tmp_path / "ttyA"
    link.symlink_to(target)
    assert claim_key(str(link)) == claim_key(str(target)) == str(target)
    assert claim_key(f"spy://{link}?file=x.log") == str(target)
    assert claim_key("socket://LocalHost:5020") == claim_key("socket://localhost:5020?logging=debug")
    for shareable in ("loop://", "sim://bus", "sim://bus?device=modbus", "replay://t.trace?port=1"):
        assert claim_key(shareable) is None


def test_two_ports_on_one_device_are_reported_with_both_places(tmp_path):
    claims = [PortClaim("COMGENIUS", 0, "/dev/ttyUSB0", "COMGENIUS.LST:9"),
              PortClaim("MODBMAST", 1, "sim://bus", "MODBMAST.XML:3"),
              PortClaim("MODBMAST", 2, "sim://bus", "MODBMAST.XML:9"),
              PortClaim("MODBMAST", 3, "/dev/ttyUSB0", "MODBMAST.XML:12")]
    assert claim_conflicts(claims) == [
        "MODBMAST.XML:12: MODBMAST port 3 would open /dev/ttyUSB0, which COMGENIUS port 0 opens "
        "(COMGENIUS.LST:9); a serial device has one owner"]


# -- the recorder -------------------------------------------------------------------------------

class _Port:
    def __init__(self, label: str) -> None:
        self.label = label
        self.record = None  # set by Recorder.add_port: record(label, direction, data, at_ns=None)


def test_the_recorder_writes_every_port_in_time_order(tmp_path):
    """Ports record as they go; frames recorded out of time order within a
    scan (a driver catching up on simulated time) come out sorted."""
    clock = Clock(5_000_000)
    path = tmp_path / "run.trace"
    rec = Recorder(str(path))
    a, b = _Port("0"), _Port("MODBMAST:1")
    rec.add_port(a, "COM1 -> loop://", clock)
    rec.add_port(b, "COM2 -> sim://bus", clock)
    rec.open()  # the engine opens it once every module has attached
    clock.now = 7_000_000
    a.record("0", "TX", b"\x01")
    clock.now = 6_000_000  # recorded later, happened earlier
    b.record("MODBMAST:1", "RX", b"\x02")
    rec.flush()
    clock.now = 8_000_000
    b.record("MODBMAST:1", "TX", b"\x03")
    b.record("MODBMAST:1", "RX", b"\x04", 7_500_000)  # a timed read: recorded at the bytes' arrival
    rec.close()
    text = path.read_text()
    assert "# port 0: COM1 -> loop://" in text and "# port MODBMAST:1: COM2 -> sim://bus" in text
    assert [(e.t_ms, e.port, e.data) for e in parse_trace(text)] == [
        (1.0, "MODBMAST:1", b"\x02"), (2.0, 0, b"\x01"), (2.5, "MODBMAST:1", b"\x04"), (3.0, "MODBMAST:1", b"\x03")]


def test_the_recorder_never_writes_a_time_before_one_already_written(tmp_path):
    clock = Clock(0)
    rec = Recorder(str(tmp_path / "t.trace"))
    port = _Port("0")
    rec.add_port(port, "x", clock)
    rec.open()
    clock.now = 2_000_000
    port.record("0", "TX", b"\x01")
    rec.flush()
    clock.now = 1_000_000  # e.g. a real-time port beside simulated ones
    port.record("0", "RX", b"\x02")
    rec.close()
    assert [e.t_ms for e in parse_trace((tmp_path / "t.trace").read_text())] == [2.0, 2.0]


# -- what the simulated wire gives a driver ---------------------------------------------------

def test_timed_reads_give_each_byte_its_arrival_time(opened, clock):
    a = opened("sim://timed", clock, baudrate=38400)
    b = opened("sim://timed", clock, baudrate=38400)
    a.write(b"\x01\x02\x03")
    clock.now = 2 * CHAR
    assert b.read_timed() == (b"\x01\x02", [CHAR, 2 * CHAR])
    clock.now = 10 * CHAR
    assert b.read_timed() == (b"\x03", [3 * CHAR])
    assert b.read_timed() == (b"", [])


def test_rts_of_one_end_is_cts_of_the_other(opened, clock):
    """A null-modem cable: pyserial raises RTS when a port opens; each
    change is seen by the other end's CTS with the time it happened."""
    a = opened("sim://modem", clock, baudrate=9600)
    b = opened("sim://modem", clock, baudrate=9600)
    assert b.cts_state()[0] is True  # raised at open (on the default clock: the fixture sets ours after)
    clock.now = 1_000
    a.rts = False
    clock.now = 5_000
    assert b.cts_state() == (False, 1_000) and b.cts is False
    a.rts = True
    assert b.cts_state() == (True, 5_000)
    assert a.cts is True  # b's RTS, raised when b opened


def test_a_device_decides_cts_and_by_default_follows_rts(opened, clock):
    port = opened("sim://dev-cts?device=echo", clock, baudrate=9600)
    assert port.cts_state()[0] is True
    clock.now = 7
    port.rts = False
    assert port.cts_state() == (False, 7)


def test_a_serial_port_reads_with_times_only_on_a_clocked_port(clock):
    sim = SerialPort("0", "sim://sp-timed?device=echo", LineSettings(38400), lambda level, msg: None, clock)
    loop = SerialPort("1", "loop://", LineSettings(38400), lambda level, msg: None, clock)
    sim.open()
    loop.open()
    try:
        assert sim.clocked and not loop.clocked
        sim.write(b"\x05")
        loop.write(b"\x05")
        clock.now = 100_000_000
        data, times = sim.read_timed()
        assert data == b"\x05" and times == [CHAR + (7 * CHAR + 1) // 2 + CHAR]  # echo after 3.5 characters
        assert loop.read_timed() == (b"\x05", None)
        assert [(d, bytes(x)) for _, d, x in sim.history] == [("TX", b"\x05"), ("RX", b"\x05")]
    finally:
        sim.close()
        loop.close()


def test_a_port_that_cannot_be_opened_is_down_with_the_reason(clock):
    log = io.StringIO()
    port = SerialPort("3", "/dev/softplc-no-such-tty", LineSettings(9600), lambda level, msg: log.write(msg), clock,
                      retry_ms=10)
    with pytest.raises(Exception, match="no such device"):
        port.open()
    assert not port.up and port.error == "no such device"  # in words, not pyserial's "[Errno 2] ..." text
    assert port.read() == b"" and port.write(b"x") == 0 and port.read_timed() == (b"", None)
    port.url = "loop://"
    port.next_try = 0
    assert port.retry() and port.up and "back up" in log.getvalue()
    port.close()
    assert not port.retry()  # a closed port stays closed


def test_an_unwritable_trace_stops_the_start_and_nothing_is_written(tmp_path):
    """--record to a place that cannot be written: refused before the first
    scan (exit 1, the path named), not a fault in the middle of the run."""
    run = softplc_here("run", "programs/loopback", "--fresh", "--state", str(tmp_path / "s"), "--scans", "20",
                       "--record", str(tmp_path / "no-dir" / "x.trace"))
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert run.stderr.strip() == (f"error: --record: cannot write {tmp_path / 'no-dir' / 'x.trace'}: "
                                  "no such file or directory")


def test_a_recorder_that_never_opened_closes_quietly(tmp_path):
    rec = Recorder(str(tmp_path / "never.trace"))
    rec.add_port(_Port("0"), "x", Clock(0))
    rec.close()
    assert not (tmp_path / "never.trace").exists()
