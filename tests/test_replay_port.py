"""replay:// ports: recorded RX played back relative to the program's writes."""

from __future__ import annotations

from pathlib import Path

import pytest
import serial

import softplc_lite.ports.urlhandler  # noqa: F401  (registers replay://)
from softplc_lite.ports.urlhandler.protocol_replay import Mismatch

from helpers.clocks import Clock

QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")

TRACE = """\
# softplc_lite port trace 1
# port 0: COM1 -> sim://bus?device=echo 38400 8N1 ISO-8859-1
# time_ms port dir bytes
0.000 0 TX 02 03 00 00 00 7D 85 D8
70.312 0 RX 02 03 FA 00 01
75.000 1 TX 55
100.000 0 TX 02 03 00 00 00 7D 85 D8
170.000 0 RX 02 03 FA
170.500 0 RX 00 02
"""




@pytest.fixture
def trace_file(tmp_path: Path) -> Path:
    path = tmp_path / "modbus.trace"
    path.write_text(TRACE)
    return path


@pytest.fixture
def replay(trace_file):
    ports = []

    def open_(clock: Clock, url: str | None = None):
        port = serial.serial_for_url(url or f"replay://{trace_file}")
        port.set_clock(clock)
        ports.append(port)
        return port

    yield open_
    for port in ports:
        port.close()


def test_rx_follows_the_programs_writes_with_recorded_delays(replay):
    clock = Clock(1_000_000_000)
    port = replay(clock)
    clock.now += 50_000_000
    assert port.in_waiting == 0  # nothing before the program writes the query
    port.write(QUERY)
    written = clock.now
    clock.now = written + 70_312_000 - 1
    assert port.read(10) == b""
    clock.now += 1
    assert port.read(10) == bytes.fromhex("02 03 FA 00 01")
    # the program is slower than the recording: the second reply moves with it
    clock.now = written + 500_000_000
    port.write(QUERY)
    second = clock.now
    clock.now = second + 70_000_000
    assert port.read(10) == bytes.fromhex("02 03 FA")
    clock.now = second + 70_500_000
    assert port.in_waiting == 2
    assert port.finished
    assert port.mismatches == []
    assert port.report() == f"replay port 0 of {port.path}: 2 of 2 exchanges, output matched"


def test_bytes_count_across_writes(replay):
    clock = Clock()
    port = replay(clock)
    port.write(QUERY[:3])
    clock.now = 5_000_000
    port.write(QUERY[3:])  # completes TX 0: the reply is timed from here
    clock.now = 5_000_000 + 70_312_000 - 1
    assert port.in_waiting == 0
    clock.now += 1
    assert port.in_waiting == 5
    port.write(QUERY)
    assert not port.finished
    clock.now += 70_500_000
    assert port.read(20) == bytes.fromhex("02 03 FA 00 01 02 03 FA 00 02")
    assert port.finished


def test_finished_needs_all_rx_and_all_tx(replay):
    clock = Clock()
    port = replay(clock)
    port.write(QUERY)
    clock.now = 10**9
    assert not port.finished  # TX 1 not written yet
    assert "1 of 2 exchanges, output matched so far (next: TX 1, line 7)" in port.report()
    port.write(QUERY)
    assert not port.finished  # its replies are 70 ms away
    clock.now += 70_500_000
    assert port.finished


def test_other_port_of_the_trace(replay, trace_file):
    clock = Clock()
    port = replay(clock, f"replay://{trace_file}?port=1")
    assert not port.finished
    port.write(b"\x55")
    assert port.finished and port.mismatches == []
    assert port.report().endswith("1 of 1 exchanges, output matched")


def test_rx_before_any_tx_is_timed_from_open(tmp_path):
    path = tmp_path / "greeting.trace"
    path.write_text("2.000 1 TX 00\n12.000 0 RX 48 49\n15.000 0 TX 06\n15.250 0 RX 0D\n")
    clock = Clock(7_000_000)
    port = serial.serial_for_url(f"replay://{path}", do_not_open=True)
    port.open()
    port.set_clock(clock)  # the first set_clock after opening sets the start
    try:
        # the trace's first event (of any port) is time 0: HI is due 10 ms after the start
        clock.now = 7_000_000 + 10_000_000 - 1
        assert port.in_waiting == 0
        clock.now += 1
        assert port.read(5) == b"HI"
        port.write(b"\x06")
        clock.now += 250_000
        assert port.read(5) == b"\r"
        assert port.finished
    finally:
        port.close()


def test_rx_never_overtakes_the_one_before(tmp_path):
    path = tmp_path / "order.trace"
    path.write_text("0.000 0 TX 01\n0.000 0 RX AA\n0.000 1 RX 00\n50.000 0 RX BB\n60.000 0 TX 02\n61.000 0 RX CC\n")
    clock = Clock()
    port = serial.serial_for_url(f"replay://{path}")
    port.set_clock(clock)
    try:
        port.write(b"\x01\x02")  # the program is 60 ms early with its second query
        clock.now = 1_000_000
        assert port.read(5) == b"\xaa"  # CC is due now, but BB (50 ms after 01) comes first
        clock.now = 50_000_000
        assert port.read(5) == b"\xbb\xcc"
    finally:
        port.close()


def test_relative_path_is_from_the_cwd(trace_file, monkeypatch):
    monkeypatch.chdir(trace_file.parent)
    port = serial.serial_for_url(f"replay://{trace_file.name}")
    try:
        assert port.path == trace_file.name
    finally:
        port.close()


def test_wrong_byte_is_reported_with_its_line(replay):
    clock = Clock()
    port = replay(clock)
    port.write(QUERY)
    clock.now = 100_000_000
    assert port.read(10) == bytes.fromhex("02 03 FA 00 01")
    bad = QUERY[:5] + b"\x7e" + QUERY[6:7] + b"\xd9"
    port.write(bad)
    assert port.mismatches == [
        Mismatch(tx_index=1, offset=5, expected=b"\x7d\x85\xd8", got=b"\x7e\x85\xd9", t_ns=100_000_000, line=7),
    ]
    # replay goes on: the second reply still comes
    clock.now += 70_500_000
    assert port.read(10) == bytes.fromhex("02 03 FA 00 02")
    assert port.finished
    assert port.report() == (
        f"replay port 0 of {port.path}: 2 of 2 exchanges, 1 output difference(s):\n"
        "  line 7: TX 1 byte 5: expected 7D 85 D8, got 7E 85 D9")


def test_extra_bytes_beyond_the_recording(replay):
    clock = Clock()
    port = replay(clock)
    port.write(QUERY)
    port.write(QUERY + b"\x01\x02")
    port.write(b"\x03")
    assert port.mismatches == [
        Mismatch(tx_index=2, offset=0, expected=b"", got=b"\x01\x02", t_ns=0, line=0),
        Mismatch(tx_index=2, offset=2, expected=b"", got=b"\x03", t_ns=0, line=0),
    ]
    assert "after the recording: 2 extra byte(s) 01 02" in port.report()


def test_many_differences_are_summarised(replay):
    clock = Clock()
    port = replay(clock)
    for _ in range(8):
        port.write(b"\xee")  # one byte a write: one difference each
    assert [(m.tx_index, m.offset, m.got) for m in port.mismatches] == [(0, k, b"\xee") for k in range(8)]
    report = port.report().splitlines()
    assert report[0].endswith("0 of 2 exchanges, 8 output difference(s):")
    assert report[1] == "  line 4: TX 0 byte 0: expected 02, got EE"
    assert len(report) == 1 + 5 + 1 and report[-1] == "  ... and 3 more"


def test_closed_replay_port_raises(replay):
    port = replay(Clock())
    port.close()
    with pytest.raises(serial.PortNotOpenError):
        port.write(b"x")
    with pytest.raises(serial.PortNotOpenError):
        port.report()


@pytest.mark.parametrize("text,where", [
    ("0.000 0 TX 02\n1.000 0 XX 03\n", ":2:9: expected TX or RX, found 'XX'"),
    ("# softplc_lite port trace 1\n\n5.0 0 TX 1\n", ":3:10: expected a two-digit hex byte, found '1'"),
    ("5.0 0 TX 01\n4.0 0 RX 01\n", ":2:1: time 4.0 is before the previous event's 5.000"),
])
def test_bad_trace_file_names_line_and_column(tmp_path, text, where):
    path = tmp_path / "bad.trace"
    path.write_text(text)
    with pytest.raises(serial.SerialException) as info:
        serial.serial_for_url(f"replay://{path}")
    assert f"{path}{where}" in str(info.value)


@pytest.mark.parametrize("url,message", [
    ("replay://", "no trace file path"),
    ("replay://x.trace?port=36", "port must be 0-35 or MODULE:N"),
    ("replay://x.trace?port=MODBMAST:99", "port must be 0-35 or MODULE:N"),
    ("replay://x.trace?speed=2", "unknown option 'speed=2'"),
])
def test_bad_urls(url, message):
    with pytest.raises(serial.SerialException) as info:
        serial.serial_for_url(url)
    assert 'expected a string in the form "replay://PATH[?port=N|MODULE:N]"' in str(info.value)
    assert message in str(info.value)


def test_missing_file_and_missing_port(tmp_path, trace_file):
    with pytest.raises(serial.SerialException, match="nope.trace: cannot read trace file"):
        serial.serial_for_url(f"replay://{tmp_path / 'nope.trace'}")
    with pytest.raises(serial.SerialException, match=r"no events for port 3 \(ports in the trace: 0, 1\)"):
        serial.serial_for_url(f"replay://{trace_file}?port=3")
