"""The shortcuts of issue 17 in COMSCAN, each with a test that fails if the
work it skips was needed:

- COMSCAN does not repeat a match on the same receive buffer when the last
  attempt needed more input and took no Param; a changed buffer, a
  re-armed instruction or a Param-taking partial match is matched again,
  and the timeout still fires.
"""

from __future__ import annotations

import pytest

from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder.engine import SimulatedClock
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.tlm.comgenius.scanf import ScanFormat
from softplc_lite.tlm.registry import instruction_set

from reference_checks import crc16_modbus_ref


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
