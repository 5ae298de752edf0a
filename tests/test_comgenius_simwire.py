"""Two runtimes joined by the simulated wire (``sim://``), on simulated
time: COMPRINT on one, COMSCAN on the other, with the bytes arriving at the
configured baud over several scans, the same every run."""

from __future__ import annotations

import itertools

import pytest

from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder.engine import SimulatedClock
from softplc_lite.tlm.comgenius import ComGenius
from softplc_lite.tlm.comgenius.config import parse_config
from softplc_lite.tlm.registry import instruction_set

_LINKS = itertools.count()

STRINGS = r"""
[STRINGS]
1 "\x02\x03\xfa%.250C%#R"     example 4: a Read Holding Registers reply of 125 words
2 "%s"
3 "%.6s"
"""

SENDER = """
DATA N10 125
DATA ST9 1
XIC B3/0 COMPRINT R6:0 0 1 N10:0
XIC B3/1 COMPRINT R6:2 0 2 ST9:0
"""

RECEIVER = """
DATA N11 125
DATA ST9 1
XIC B3/0 COMSCAN R6:1 0 1 N11:0
XIC B3/1 COMSCAN R6:3 0 3 ST9:0
COMRCVSTS 0 C5:0
"""


def runtime(program: str, url: str, executor: str, line: str = "38400, 8, N, 1, 500",
            encoding: str = "ISO-8859-1") -> Engine:
    config = parse_config(f"[DRIVER]\nDEBUG=0\n[PORTS]\n0, {url}, {encoding}, {line}\n{STRINGS}")
    module = ComGenius(config)
    e = Engine(load_text(program, instructions=instruction_set([module])), DataTable(), clock=SimulatedClock(10),
               executor=executor, modules=[module])
    e.set_mode(Mode.RUN)
    return e


@pytest.fixture(params=["compiled", "reference"])
def pair(request):
    made: list[Engine] = []

    def make(**kw) -> tuple[Engine, Engine]:
        url = f"sim://wire{next(_LINKS)}"
        a = runtime(SENDER, url, request.param, **kw)
        made.append(a)
        b = runtime(RECEIVER, url, request.param, **kw)
        made.append(b)
        return a, b
    yield make
    for e in made:
        e.close()


def step(a: Engine, b: Engine) -> None:
    a.scan()
    b.scan()


def reply_exchange(pair) -> tuple[list[int], int]:
    a, b = pair()
    words = [(k * 2654435761) & 0x7FFF for k in range(125)]
    for k, w in enumerate(words):
        a.table.write(f"N10:{k}", w)
    a.table.write("B3/0", 1)
    b.table.write("B3/0", 1)
    waiting = []
    for _ in range(12):
        step(a, b)
        waiting.append(b.table.read("C5:0.ACC"))
        if b.table.read("R6:1/DN"):
            break
    assert b.table.read("R6:1/ER") == 0
    assert [b.table.read(f"N11:{k}") for k in range(125)] == words
    return waiting, b.clock.now_ms


def test_a_255_byte_reply_at_38400_arrives_over_several_scans(pair):
    waiting, done_ms = reply_exchange(pair)
    # Sent at the output point of the scan at t=10 ms; 255 characters of 10 bits
    # at 38400 baud take 66.41 ms, so they are all there at the input of t=80 ms.
    # Each 10 ms scan sees 38 or 39 more (10 ms / 260.4 us).
    assert done_ms == 80
    assert waiting == [0, 38, 76, 115, 153, 191, 230, 0]  # at 80 ms COMSCAN took all 255 first


def test_the_simulated_wire_is_the_same_every_run(pair):
    assert reply_exchange(pair) == reply_exchange(pair)


def test_slower_baud_and_more_bits_per_character_take_longer(pair):
    a, b = pair(line="9600, 7, E, 2, 500")  # 1 + 7 + 1 + 2 = 11 bits a character
    a.table.write("ST9:0", "abcdef")
    a.table.write("B3/1", 1)
    b.table.write("B3/1", 1)
    seen = []
    for _ in range(4):
        step(a, b)
        seen.append(b.modules[0].ports.ports[0].rx)
    # 6 characters x 11 bits / 9600 baud = 6.875 ms: all there at the next scan
    assert seen[0] == "" and b.table.read("ST9:0") == "abcdef"
    assert b.table.read("R6:3.LEN") == 6


def test_comscan_times_out_when_the_rest_never_comes(pair):
    a, b = pair(line="38400, 8, N, 1, 50")
    a.table.write("ST9:0", "abc")  # "%.6s" wants six
    a.table.write("B3/1", 1)
    b.table.write("B3/1", 1)
    states = []
    for _ in range(8):
        step(a, b)
        r = b.table.read("R6:3")
        states.append((r["DN"], r["ER"], r["EM"], r["LEN"]))
    # started at t=10; 3 characters there from t=20; 50 ms after the start: t=60
    assert states[:5] == [(0, 0, 0, 0)] + [(0, 0, 0, 3)] * 4
    assert states[5] == (1, 1, 1, 3)


def test_utf8_characters_split_across_scans_wait_for_their_last_byte(pair):
    a, b = pair(line="1200, 8, N, 1, 500", encoding="UTF-8")  # 8.33 ms a byte: about one a scan
    a.table.write("ST9:0", "Жж")  # 4 bytes
    a.table.write("B3/1", 1)
    seen = []
    for _ in range(6):
        step(a, b)
        seen.append(b.modules[0].ports.ports[0].rx)
    assert seen == ["", "", "Ж", "Ж", "Жж", "Жж"]
