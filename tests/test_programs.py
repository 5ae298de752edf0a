"""The example programs in programs/ do what their comments say."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.runner import RunOptions, Runner

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"


def runner(name: str, executor: str = "compiled", sets=()) -> Runner:
    app = load_app(PROGRAMS / name, state_dir=None)
    app.state_dir = None  # tests never touch the app's snapshot
    return Runner(app, RunOptions(fresh=True, executor=executor, sets=tuple(sets)))


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_blinker_blinks_at_one_hertz(executor):
    r = runner("blinker", executor)
    lamp = []
    r.run(1000, on_scan=lambda e: lamp.append(e.table.read("O:0/0")))
    # Each half lasts 500 ms plus the scan that starts its timer: 51 scans of 10 ms.
    rising = [k for k in range(1, len(lamp)) if lamp[k] and not lamp[k - 1]]
    assert rising[:3] == [50, 152, 254]
    assert all(b - a == 102 for a, b in zip(rising, rising[1:]))
    assert r.table.read("C5:0.ACC") == len(rising) == 10
    assert r.engine.mode is Mode.RUN


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_motor_seal_in_counters_and_trip(executor):
    r = runner("motor", executor, sets=["StopOk=1"])
    t = r.table
    r.run(5)
    assert t.read("O:0/0") == 0
    t.write("I:0/0", 1)  # press start
    r.run(1)
    t.write("I:0/0", 0)  # release: the seal-in holds
    r.run(300)
    assert t.read("O:0/0") == 1 and t.read("C5:0.ACC") == 1
    assert t.read("T4:0.ACC") == 3  # 301 scans x 10 ms of run time, in seconds
    t.write("I:0/2", 1)  # overload trips: latched after the seal-in rung,
    r.run(2)  # so the motor drops out on the next scan
    assert t.read("O:0/0") == 0 and t.read("O:0/1") == 1 and t.read("C5:1.ACC") == 1
    t.write("I:0/2", 0)
    t.write("I:0/0", 1)  # start is refused while tripped
    r.run(2)
    assert t.read("O:0/0") == 0
    t.write("I:0/0", 0)
    t.write("I:0/1", 0)  # stop pressed: resets the trip
    r.run(1)
    t.write("I:0/1", 1)
    t.write("I:0/0", 1)
    r.run(1)
    assert t.read("O:0/0") == 1 and t.read("O:0/1") == 0 and t.read("C5:0.ACC") == 2
    assert t.read("T4:0.ACC") == 3  # retentive: kept across the stop


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_subroutines(executor):
    r = runner("subroutines", executor)
    r.run(100)
    t = r.table
    assert t.read("N7:0") == 100
    assert t.read("N7:1") == 10  # file 4 ran every tenth scan
    assert t.read("N7:2") == sum(range(10, 101, 10))  # file 5, nested under file 4
    assert t.read("F8:0") == 10.0
    assert t.read("N7:3") == 100 and t.read("B3/1") == 1
    t.write("B3/0", 1)  # the JMP now skips the counting rung
    r.run(10)
    assert t.read("N7:3") == 100 and t.read("N7:0") == 110


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_loopback_prints_and_matches_its_echo_every_poll(executor):
    r = runner("loopback", executor)
    try:
        sent = []
        r.run(100, on_scan=lambda e: sent.append(e.table.read("R6:0/DN")))
        t = r.table
        good = t.read("C5:0.ACC")
        polls = sum(1 for k in range(1, len(sent)) if sent[k] and not sent[k - 1])
        assert good >= 10 and t.read("C5:1.ACC") == 0  # every echo matched
        assert polls in (good, good + 1)  # the last poll may still be waiting for its echo
        assert t.read("N7:0") == 5 + good and t.read("N7:10") == 5 + good - 1  # last rack matched back
        assert t.read("N7:11") == 2 and t.read("R6:1.LEN") == 30
    finally:
        r.engine.close()
