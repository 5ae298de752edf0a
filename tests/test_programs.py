"""The example programs in programs/ do what their comments say."""

from __future__ import annotations

from pathlib import Path

import pytest

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.runner import RunOptions, Runner

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"


def runner(name: str, executor: str = "compiled", sets=()) -> Runner:
    app = load_app(PROGRAMS / name, use_cache=False)  # no code cache written in the repository
    app.state_dir = None  # nor a snapshot
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


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_modbus_scada_polls_two_slaves_and_reports_the_missing_one(executor):
    """programs/modbus_scada: MODBMAST on a simulated line with slaves 1 and
    2 (values=index), slave 3 missing; the rungs as its comments say."""
    from softplc_lite.ports.modbus_slave import find_slave

    r = runner("modbus_scada", executor)
    t = r.table
    failed = []
    r.run(100, on_scan=lambda e: failed.append(e.table.read("B13/3")))  # 1 s
    slave = find_slave("scada")
    assert slave.unit(1).holding_registers[:2] == [100, 300]  # the start-up write
    assert [t.read(f"N10:{k}") for k in (0, 1, 10, 11)] == [0, 1, 2, 3]  # one read, scattered
    assert t.read_word("I:0") == 0b1010101010101010 - 0x10000  # discretes 1, 3, 5 ... on
    assert [t.read(f"N11:{k}") for k in range(6)] == [0, 1, 2, 3, 4, 5]
    assert slave.unit(2).holding_registers[100:102] == [1500, 1]  # gathered: SpeedSet, then the constant
    assert slave.unit(1).coils[:4] == [True, False, False, False] and t.read("B3/16") == 1  # PumpRunning
    assert t.read_word("B13:0") == 8  # only slave 3 Not Present
    first = failed.index(1)  # slave 3's first timeout: it is Not Present from then on
    assert failed[first:] == [1] * (100 - first) and 0 < first < 20
    assert t.read("C5:1.ACC") == 1 and t.read("C5:0.ACC") == 100 - first  # rung 0 counts every failed scan
    blocks = [[t.read(f"N20:{5 * k + w}") for w in range(5)] for k in range(3)]
    assert blocks[0][1:] == [0, 0, 0, 0] and blocks[1][1:] == [0, 0, 0, 0]
    assert blocks[2][3:] == [4, -3] and blocks[2][1] >= 5  # a timeout on each pass (~8 a second)
    t.write("B3/0", 1)  # ClearStats
    r.run(1)
    assert t.read("N20:11") >= 5  # rung 2 copied the block before rung 3 cleared it ...
    r.run(1)
    assert t.read("N20:11") <= 1  # ... so the next scan shows it cleared (a new timeout may have come since)
    r.engine.set_mode(Mode.PROGRAM)  # leaving RUN: the stop request turns the pumps off
    for _ in range(10):
        r.engine.scan()
    assert slave.unit(1).coils[:4] == [False] * 4
    r.engine.close()


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_tank_pid_settles_at_its_setpoint(executor):
    r = runner("tank", executor)
    levels = []
    r.run(1000, on_scan=lambda e: levels.append(e.table.read("N11:0")))
    t = r.table
    # Kp 2 and Ki = Kp / tau (tau = 2 s) cancel the tank's pole: a first-order
    # closed loop with a 1 s time constant, sampled every 0.1 s. After 10 s the
    # level is at the setpoint within 0.5 %; it never overshoots by 1 %.
    assert abs(t.read("N11:0") - 2000) <= 10
    assert max(levels) <= 2020 and levels[0] < 100
    assert t.read("O:0/0") == 1 and 48.5 <= t.read("F8:1") <= 49.2
    # 63 % of the step (1260 counts) about 1 s in, as the hand calculation says
    first = next(k for k, v in enumerate(levels) if v >= 1260)
    assert 90 <= first <= 140
    assert r.engine.mode is Mode.RUN
