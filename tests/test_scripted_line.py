"""The scripted serial line (ports/scripted.py) on real sim:// ports, on a
hand-moved clock: replies timed from the match's last byte, several rules,
the score, and every bad option refused by the URL."""

import pytest
import serial

import softplc_lite.ports.urlhandler  # noqa: F401 - registers sim://
from softplc_lite.ports.scripted import ScriptedLine

CHAR = 260_417  # ns, 38400 8N1


def _port(url, now):
    port = serial.serial_for_url(url, baudrate=38400)
    port.set_clock(lambda: now[0])
    return port


def test_a_match_is_answered_after_the_delay_timed_from_its_last_byte():
    now = [0]
    port = _port("sim://scripted-a?device=scripted&match=%3F&reply=OK%0D%0A&delay_ms=5", now)
    port.write(b"x?")                         # the "?" arrives at 2 character times
    first = 2 * CHAR + 5_000_000 + CHAR       # then the delay, then the first reply byte's time
    now[0] = first - 1
    assert port.in_waiting == 0
    now[0] = first
    assert port.read(10) == b"O"
    now[0] = first + 3 * CHAR
    assert port.read(10) == b"K\r\n"
    port.close()


def test_rules_in_order_the_score_and_the_log():
    now = [0]
    port = _port("sim://scripted-b?device=scripted&match=READ%0D&reply=42%0D%0A&match2=STOP%0D&reply2=", now)
    port.write(b"noise READ\rSTOP\rREA")
    now[0] = 100_000_000
    assert port.read(100) == b"42\r\n"
    device = port.sim_link.device
    assert (device.received, device.replies, device.hits, device.unmatched) == (19, 2, [1, 1], 3)
    assert list(device.log) == [(b"noise READ\r", b"42\r\n"), (b"STOP\r", b"")]
    port.close()


@pytest.mark.parametrize("query, reason", [
    ("match=a", "scripted device: match needs reply"),
    ("reply2=a", "scripted device: reply2 needs match2"),
    ("match=&reply=x", "rule 1's match is empty"),
    ("match=a&reply=b&delay_ms=-1", "delay_ms must be a number >= 0"),
    ("match=a&reply=b&speed=3", "unknown option 'speed'"),
    ("", "expected at least one (match, reply) rule"),
])
def test_bad_options_are_refused_with_the_reason(query, reason):
    with pytest.raises(serial.SerialException) as e:
        serial.serial_for_url(f"sim://scripted-c?device=scripted&{query}".rstrip("&"))
    assert reason in str(e.value)


def test_python_rules_are_checked():
    with pytest.raises(ValueError, match="must be a .match, reply. pair"):
        ScriptedLine([b"?"])
    with pytest.raises(ValueError, match="bytes 0-255"):
        ScriptedLine([("\u20ac", "x")])
