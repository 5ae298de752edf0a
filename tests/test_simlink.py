"""sim:// ports: links between two ends, exact wire timing, the echo device."""

from __future__ import annotations

import doctest
import itertools
import re
import time

import pytest
import serial

import softplc_lite.ports.urlhandler as urlhandler
from softplc_lite.ports import simdevices, simlink, wire
from softplc_lite.ports.simdevices import EchoDevice

from helpers.clocks import Clock


CHAR_38400 = 260417  # 10 bits at 38400 baud, ns
QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")
REPLY = bytes([0x02, 0x03, 0xFA]) + bytes(range(250)) + b"\x12\x34"  # 255 bytes

_names = itertools.count()




@pytest.fixture(autouse=True)
def no_links_left():
    """Every link a test opened is gone once its ports are closed."""
    yield
    assert not any(name.startswith("t_") for name in simlink.link_names())


def fresh() -> str:
    return f"t_{next(_names)}"


def pair(opened, clock, suffix: str = "", **settings):
    name = fresh()
    return opened(f"sim://{name}{suffix}", clock, **settings), opened(f"sim://{name}{suffix}", clock, **settings)


def test_register_is_idempotent():
    urlhandler.register()
    urlhandler.register()
    assert serial.protocol_handler_packages.count(urlhandler.PACKAGE) == 1


def test_two_ends_exchange_bytes(opened, clock):
    a, b = pair(opened, clock, baudrate=38400)
    assert a.write(b"ping") == 4
    assert b.write(b"pong!") == 5
    clock.now = 10_000_000
    assert b.in_waiting == 4 and a.in_waiting == 5
    assert b.read(10) == b"ping"
    assert a.read(2) == b"po" and a.read(10) == b"ng!"
    assert a.read(1) == b"" and b.in_waiting == 0


def test_query_arrives_exactly_after_eight_characters(opened, clock):
    a, b = pair(opened, clock, baudrate=38400)
    a.write(QUERY)
    for j in range(8):
        clock.now = (j + 1) * CHAR_38400 - 1
        assert b.in_waiting == j
        clock.now += 1
        assert b.in_waiting == j + 1
    clock.now = 2_083_335
    assert b.read(8) == QUERY[:7]
    clock.now = 2_083_336
    assert b.read(8) == QUERY[7:]


def test_long_reply_arrives_over_several_scans(opened, clock):
    a, b = pair(opened, clock, baudrate=38400)
    b.write(REPLY)
    seen = []
    for scan in range(1, 8):
        clock.now = scan * 10_000_000
        seen.append(a.in_waiting)
    assert seen == [38, 76, 115, 153, 191, 230, 255]
    assert a.read(300) == REPLY
    # completes at 255 characters, 66.41 ms, and not one ns before
    c, d = pair(opened, clock, baudrate=38400)
    start = clock.now
    d.write(REPLY)
    got = bytearray()
    for scan in range(1, 7):
        clock.now = start + scan * 10_000_000
        got += c.read(c.in_waiting)
    clock.now = start + 66_406_334
    got += c.read(300)
    assert len(got) == 254
    clock.now += 1
    got += c.read(300)
    assert bytes(got) == REPLY


def test_writes_queue_behind_a_busy_wire(opened, clock):
    a, b = pair(opened, clock, baudrate=38400)
    a.write(QUERY)
    clock.now = 1_000_000  # 3 characters have arrived, the 4th is on the wire
    assert a.out_waiting == 5
    a.write(b"\x01\x02")
    assert a.out_waiting == 7
    second = 8 * CHAR_38400 + CHAR_38400  # waits for the wire, then one character
    clock.now = second - 1
    assert b.read(20) == QUERY and a.out_waiting == 2
    clock.now = second
    assert b.read(20) == b"\x01" and a.out_waiting == 1
    clock.now = second + CHAR_38400
    assert b.read(20) == b"\x02" and a.out_waiting == 0
    # a write to an idle wire starts at once
    clock.now = 50_000_000
    a.write(b"x")
    clock.now += CHAR_38400
    assert b.read(1) == b"x"


@pytest.mark.parametrize("settings,char_ns", [
    (dict(bytesize=7, parity="E", stopbits=1), 260417),   # 10 bits
    (dict(bytesize=8, parity="N", stopbits=2), 286458),   # 11 bits
    (dict(bytesize=8, parity="O", stopbits=1), 286458),   # 11 bits
    (dict(bytesize=7, parity="N", stopbits=1), 234375),   # 9 bits
])
def test_framing_sets_the_character_time(opened, clock, settings, char_ns):
    assert wire.char_time_ns(38400, settings["bytesize"], settings["parity"], settings["stopbits"]) == char_ns
    a, b = pair(opened, clock, baudrate=38400, **settings)
    a.write(b"\xff\x41")
    clock.now = char_ns - 1
    assert b.in_waiting == 0
    clock.now = 2 * char_ns
    expected = b"\x7f\x41" if settings["bytesize"] == 7 else b"\xff\x41"
    assert b.read(2) == expected


def test_the_senders_settings_decide(opened, clock):
    name = fresh()
    slow = opened(f"sim://{name}", clock, baudrate=9600)
    fast = opened(f"sim://{name}", clock, baudrate=38400)
    slow.write(b"ab")
    fast.write(b"cd")
    clock.now = 2 * CHAR_38400
    assert slow.read(2) == b"cd" and fast.read(2) == b""
    clock.now = 2 * 1_041_667
    assert fast.read(2) == b"ab"
    # changing the baud rate of an open port applies to its next write
    slow.baudrate = 38400
    slow.write(b"e")
    clock.now += CHAR_38400
    assert fast.read(1) == b"e"


def test_unlimited_rate(opened, clock):
    a, b = pair(opened, clock, "?rate=unlimited", baudrate=300)
    a.write(b"x" * 10_000)
    assert a.out_waiting == 0 and b.in_waiting == 10_000
    assert b.read(10_000) == b"x" * 10_000


def test_unlimited_rate_moves_megabytes_intact(opened, clock):
    # Throughput is measured in benchmarks/bench_comgenius_ports.py, not asserted here.
    a, b = pair(opened, None, "?rate=unlimited")
    blocks = [bytes((k + j) & 0xFF for j in range(4096)) for k in range(256)]  # 1 MiB, no two blocks equal
    got = bytearray()
    for block in blocks:
        a.write(block)
        got += b.read(len(block))
    assert bytes(got) == b"".join(blocks)


def test_third_end_is_rejected_and_name_reusable(opened, clock):
    name = fresh()
    a = opened(f"sim://{name}", clock)
    b = opened(f"sim://{name}", clock)
    with pytest.raises(serial.SerialException, match=f"link {name} already has two ends"):
        serial.serial_for_url(f"sim://{name}")
    a.close()
    assert name in simlink.link_names()
    b.close()
    assert name not in simlink.link_names()
    c, d = opened(f"sim://{name}", clock), opened(f"sim://{name}", clock)
    c.write(b"again")
    clock.now = 10**9
    assert d.read(5) == b"again"


def test_bytes_sent_with_nobody_listening_are_lost(opened, clock):
    name = fresh()
    a = opened(f"sim://{name}", clock)
    a.write(b"lost")
    clock.now = 10**9
    b = opened(f"sim://{name}", clock)
    assert b.in_waiting == 0
    a.write(b"kept")
    clock.now *= 2
    assert b.read(10) == b"kept"


def test_reset_buffers(opened, clock):
    a, b = pair(opened, clock, baudrate=38400)
    a.write(b"abcd")
    clock.now = 2 * CHAR_38400
    b.reset_input_buffer()  # drops the 2 arrived bytes; c, d still on the wire
    clock.now = 4 * CHAR_38400
    assert b.read(10) == b"cd"
    a.write(b"efgh")
    clock.now += CHAR_38400
    a.reset_output_buffer()  # 'e' has arrived, f g h are dropped
    assert a.out_waiting == 0
    a.write(b"i")
    clock.now += CHAR_38400
    assert b.read(10) == b"ei"


def test_closed_port_raises(opened, clock):
    a, _ = pair(opened, clock)
    a.close()
    for op in (lambda: a.read(1), lambda: a.write(b"x"), lambda: a.in_waiting,
               lambda: a.out_waiting, a.reset_input_buffer, a.reset_output_buffer):
        with pytest.raises(serial.PortNotOpenError):
            op()
    assert not a.is_open


def test_repr_names_link_and_settings(opened, clock):
    name = fresh()
    a, _ = opened(f"sim://{name}", clock, baudrate=38400, parity="E"), opened(f"sim://{name}", clock)
    assert repr(a) == f"<sim port 'sim://{name}' 38400 8E1: end 0 of link '{name}' to end 1>"
    e = opened(f"sim://{fresh()}?device=echo&rate=unlimited", clock)
    assert "to echo device" in repr(e) and "unlimited rate" in repr(e)
    a.close()
    assert repr(a) == f"<sim port 'sim://{name}' closed>"


@pytest.mark.parametrize("url,message", [
    ("sim://", "bad link name ''"),
    ("sim://a b", "bad link name"),
    ("sim://x?foo=1", "unknown option 'foo'"),
    ("sim://x?rate=fast", "rate must be unlimited or wire"),
    ("sim://x?device=nope", r"unknown device kind 'nope' \(known: echo"),
    ("sim://x?device=echo&foo=2", r"echo device: unknown option 'foo' \(known: delay_ms\)"),
    ("sim://x?device=echo&delay_ms=-1", "delay_ms must be a number >= 0"),
    ("sim://x?device=echo&delay_ms=soon", "delay_ms must be a number"),
    ("sim://x?rate=wire&rate=wire", "given twice"),
])
def test_bad_urls(url, message):
    with pytest.raises(serial.SerialException) as info:
        serial.serial_for_url(url)
    assert "sim://NAME[?device=KIND[&KEY=VALUE...]][&rate=unlimited]" in str(info.value)
    assert re.search(message, str(info.value)), str(info.value)
    assert "x" not in simlink.link_names()


def test_device_links_are_per_port_and_apart_from_port_links(opened, clock):
    name = fresh()
    first = opened(f"sim://{name}?device=echo", clock, baudrate=38400)
    second = opened(f"sim://{name}?device=echo", clock, baudrate=38400)  # its own link and echo device
    first.write(b"one")
    clock.now += 5_000_000
    assert second.read(10) == b"" and first.read(10) == b"one"
    assert len(simlink.device_links(name)) == 2
    with pytest.raises(serial.SerialException, match="already has two ends"):
        serial.serial_for_url(f"sim://{name}")
    other = fresh()
    opened(f"sim://{other}", clock)
    with pytest.raises(serial.SerialException, match="is in use between two ports"):
        serial.serial_for_url(f"sim://{other}?device=echo")
    first.close()
    second.close()
    assert name not in simlink.link_names()


def test_echo_timing(opened, clock):
    port = opened(f"sim://{fresh()}?device=echo", clock, baudrate=38400)
    port.write(QUERY)
    last = 8 * CHAR_38400
    start = last + simdevices.silence_ns(CHAR_38400)
    assert simdevices.silence_ns(CHAR_38400) == 911_460
    clock.now = start + CHAR_38400 - 1
    assert port.in_waiting == 0
    clock.now += 1
    assert port.read(10) == QUERY[:1]
    clock.now = start + 8 * CHAR_38400 - 1
    assert port.read(10) == QUERY[1:7]
    clock.now += 1
    assert port.read(10) == QUERY[7:]


def test_echo_delay_and_late_polling(opened, clock):
    port = opened(f"sim://{fresh()}?device=echo&delay_ms=5", clock, baudrate=38400)
    port.write(QUERY)
    # the port looks only at 100 ms: the echo was timed from the device's turnaround
    clock.now = 100_000_000
    assert port.out_waiting == 0
    assert port.read(100) == QUERY
    port.write(b"\x01")
    start = clock.now + CHAR_38400 + 5_000_000
    clock.now = start + CHAR_38400 - 1
    assert port.in_waiting == 0
    clock.now += 1
    assert port.read(5) == b"\x01"


def test_echo_splits_bursts_on_silence(opened, clock):
    device = EchoDevice()
    end = simlink.open_device_end(fresh(), device)
    try:
        end.configure(38400, 8, "N", 1, False)
        gap = simdevices.silence_ns(CHAR_38400)
        # one receive() with two bursts: b arrives just within the gap, c just after it
        device.receive(b"abc", [1000, 1000 + gap, 1000 + 2 * gap + 1])
        first_start = 1000 + gap + gap
        assert end.read(10, first_start + 2 * CHAR_38400) == b"ab"
        second_start = 1000 + 2 * gap + 1 + gap
        assert end.read(10, second_start + CHAR_38400 - 1) == b""
        assert end.read(10, second_start + CHAR_38400) == b"c"
    finally:
        end.close()


def test_echo_at_unlimited_rate_answers_at_once(opened, clock):
    port = opened(f"sim://{fresh()}?device=echo&rate=unlimited", clock)
    port.write(b"hello")
    assert port.read(10) == b"hello"


def test_echo_masks_to_the_ports_data_bits(opened, clock):
    port = opened(f"sim://{fresh()}?device=echo", clock, baudrate=38400, bytesize=7, parity="E")
    port.write(b"\xc1")
    clock.now = 10_000_000
    assert port.read(1) == b"\x41"


def test_register_device_rejects_a_taken_kind():
    simdevices.register_device("echo", simdevices.DEVICES["echo"])  # same factory: fine
    with pytest.raises(ValueError, match="already registered"):
        simdevices.register_device("echo", lambda options: EchoDevice())
    with pytest.raises(ValueError, match="letters, digits"):
        simdevices.register_device("bad kind", lambda options: EchoDevice())


def test_default_clock_read_waits_for_real_time(opened):
    name = fresh()
    a = opened(f"sim://{name}", baudrate=9600, timeout=1)
    b = opened(f"sim://{name}", baudrate=9600, timeout=1)
    t = time.monotonic()
    a.write(b"hi")
    assert b.read(2) == b"hi"
    assert time.monotonic() - t >= 2 * 1_041_667 / 1e9
    b.timeout = 0.03
    t = time.monotonic()
    assert b.read(1) == b""
    assert time.monotonic() - t >= 0.03
    b.timeout = 0
    a.write(b"!")
    assert b.read(1) == b""  # non-blocking: not there yet


def test_runs_are_deterministic():
    steps = [0, 150_000, 900_000, 2_100_000, 2_100_001, 5_000_000, 9_999_999, 70_000_000]

    def run() -> list[tuple[int, bytes, int]]:
        clock = Clock()
        name = fresh()
        a = serial.serial_for_url(f"sim://{name}", baudrate=38400)
        b = serial.serial_for_url(f"sim://{name}", baudrate=38400)
        e = serial.serial_for_url(f"sim://{fresh()}?device=echo&delay_ms=1.5", baudrate=19200)
        for port in (a, b, e):
            port.set_clock(clock)
        seen = []
        try:
            for i, t in enumerate(steps):
                clock.now = t
                a.write(bytes([i]) * (i + 1))
                e.write(bytes([i]))
                seen.append((t, b.read(b.in_waiting), e.in_waiting))
                seen.append((t, e.read(3), b.out_waiting))
        finally:
            for port in (a, b, e):
                port.close()
        return seen

    first = run()
    assert first == run()
    assert sum(len(data) for _, data, _ in first) > 20


def test_wire_module_doctests():
    for module in (wire, simdevices):
        result = doctest.testmod(module)
        assert result.failed == 0
    assert doctest.testmod(wire).attempted > 0


def test_bad_baud_rate_frees_the_link():
    name = fresh()
    with pytest.raises(ValueError, match="invalid baudrate: 0"):
        serial.serial_for_url(f"sim://{name}?device=echo", baudrate=0)
    assert name not in simlink.link_names()


def test_a_port_collected_while_the_registry_is_locked_does_not_deadlock():
    """A sim:// port left in a reference cycle (a Runner whose start failed)
    is closed by its finalizer, which may run inside an allocation made
    under the link registry's lock (opening another link): it takes no
    lock, and the next registry operation releases the end."""
    import gc
    import threading

    def body(result: list) -> None:
        port = serial.serial_for_url("sim://collected-under-lock", baudrate=9600)
        cycle: list = [port]
        cycle.append(cycle)
        port._cycle = cycle  # only the collector frees it
        del port, cycle
        gc.disable()
        try:
            with simlink.REGISTRY.lock:  # where open_device_end stands when an allocation starts a collection
                gc.collect()
        finally:
            gc.enable()
        result.append(simlink.link_names())
        again = serial.serial_for_url("sim://collected-under-lock", baudrate=9600)  # the name is free again
        result.append(simlink.link_names())
        again.close()

    result: list = []
    worker = threading.Thread(target=body, args=(result,), daemon=True)
    worker.start()
    worker.join(10)
    assert not worker.is_alive(), "deadlock: a finalizer waited for the registry lock its own thread held"
    assert "collected-under-lock" not in result[0]
    assert "collected-under-lock" in result[1]
