"""Timers add the time since their own last update, and the SLC free-running
clock S:4 (docs/instructions.md, timer rules, and
docs/engine.md, the status file). Every test runs on both executors."""

from __future__ import annotations

import time

import pytest

from softplc_lite.datatable import DataTable
from softplc_lite.ladder import Engine, Mode, RealClock, Settings, load_text, run_text
from softplc_lite.ladder.semantics import STAMP_MODULO


@pytest.fixture(params=["compiled", "reference"])
def executor(request):
    return request.param


def _acc_by_scan(text: str, scans: int, executor: str, addr: str = "T4:0", **kw) -> list[int]:
    e = run_text(text, scans=0, executor=executor, **kw)
    out = []
    for _ in range(scans):
        e.scan()
        out.append(e.table.read(f"{addr}.ACC"))
    return out


# A subroutine called twice a scan: the second evaluation adds nothing (adding at each evaluation counts the scan twice).
TWICE = "JSR 3\nJSR 3\nFILE 3\n{timer}\n"


@pytest.mark.parametrize("timer", ["TON T4:0 0.01 100 0", "RTO T4:0 0.01 100 0"])
def test_ton_and_rto_evaluated_twice_a_scan_count_the_scan_once(executor, timer):
    assert _acc_by_scan(TWICE.format(timer=timer), 5, executor) == [0, 1, 2, 3, 4]


def test_ton_evaluated_twice_a_scan_is_done_after_its_preset_in_time(executor):
    e = run_text(TWICE.format(timer="TON T4:0 0.01 3 0"), scans=3, executor=executor)
    assert e.table.read("T4:0/DN") == 0
    e.scan()
    assert e.table.read("T4:0") == {"EN": 1, "TT": 0, "DN": 1, "PRE": 3, "ACC": 3}


def test_tof_evaluated_twice_a_scan_counts_the_scan_once(executor):
    e = run_text("JSR 3\nJSR 3\nFILE 3\nXIC B3/0 TOF T4:0 0.01 100 0", scans=1, executor=executor,
                 values={"B3/0": 1})
    e.table.write("B3/0", 0)
    seen = []
    for _ in range(4):
        e.scan()
        seen.append(e.table.read("T4:0.ACC"))
    assert seen == [0, 1, 2, 3]


def test_ton_evaluated_every_other_scan_adds_both_scans(executor):
    # B3/1 toggles every scan; the subroutine with the timer runs only when it is on.
    text = "XIO B3/1 OTE B3/2\nXIC B3/2 OTE B3/1\nXIC B3/1 JSR 3\nFILE 3\nTON T4:0 0.01 100 0\n"
    acc = _acc_by_scan(text, 7, executor)
    # Evaluated on scans 1, 3, 5, 7: enabled on 1, then 20 ms (2 ticks) at each later evaluation.
    assert acc == [0, 0, 2, 2, 4, 4, 6]


def test_enabling_scan_adds_nothing_even_when_evaluated_twice(executor):
    e = run_text(TWICE.format(timer="XIC B3/0 TON T4:0 0.01 100 0"), scans=3, executor=executor)
    e.table.write("B3/0", 1)
    e.scan()
    assert e.table.read("T4:0") == {"EN": 1, "TT": 1, "DN": 0, "PRE": 100, "ACC": 0}
    e.scan()
    assert e.table.read("T4:0.ACC") == 1


def test_one_second_base_counts_the_milliseconds_short_of_a_tick(executor):
    # 10 ms scans, base 1.0: enabled on scan 1, ACC 1 after 100 more scans (exactly 1 s), not before.
    acc = _acc_by_scan("TON T4:0 1.0 10 0", 201, executor)
    assert (acc[99], acc[100], acc[199], acc[200]) == (0, 1, 1, 2)


def test_timer_keeps_its_last_update_in_bits_0_to_12_of_word_0(executor):
    e = run_text("TON T4:0 0.01 100 0", scans=3, executor=executor, settings=Settings(scan_ms=7))
    # now 21 ms; ACC 1 (14 ms timed since the enabling scan at 7 ms): the stamp trails now by the
    # 4 ms short of a tick; EN and TT stay in bits 15 and 14.
    raw = e.table.file("T4").data[0]
    assert e.table.read("T4:0.ACC") == 1 and raw & 0x1FFF == 21 - 4 and raw & 0xE000 == 0xC000


def test_a_timer_not_evaluated_for_8192_ms_loses_them(executor):
    # Documented limit: evaluated on scan 1 (enable) and 2, then skipped; after a gap of
    # 8230 ms it adds only the 38 ms (3 ticks) beyond one whole 8192 ms period.
    text = "XIC B3/0 JSR 3\nFILE 3\nTON T4:0 0.01 30000 0\n"
    e = run_text(text, scans=2, executor=executor, values={"B3/0": 1})
    assert e.table.read("T4:0.ACC") == 1
    e.table.write("B3/0", 0)
    e.run(822)
    e.table.write("B3/0", 1)
    e.scan()
    assert 823 * 10 - STAMP_MODULO == 38
    assert e.table.read("T4:0.ACC") == 1 + 3


def test_a_timer_skipped_for_less_than_8192_ms_loses_nothing(executor):
    text = "XIC B3/0 JSR 3\nFILE 3\nTON T4:0 0.01 30000 0\n"
    e = run_text(text, scans=2, executor=executor, values={"B3/0": 1})
    e.table.write("B3/0", 0)
    e.run(499)
    e.table.write("B3/0", 1)
    e.scan()
    assert e.table.read("T4:0.ACC") == 1 + 500


def test_rto_paused_keeps_the_part_of_a_tick(executor):
    # base 1.0, 300 ms scans: 600 ms timed, paused, then 400 ms more complete the first second.
    e = run_text("XIC B3/0 RTO T4:0 1.0 5 0", scans=0, executor=executor, settings=Settings(scan_ms=300))
    seen = []
    for b in [1, 1, 1, 0, 0, 1, 1, 1]:
        e.table.write("B3/0", b)
        e.scan()
        seen.append(e.table.read("T4:0.ACC"))
    assert seen == [0, 0, 0, 0, 0, 0, 0, 1]


# -- S:4, the SLC 500 free-running clock ---------------------------------------------------------


def test_s4_free_running_clock_counts_10_ms_steps(executor):
    e = run_text("NOP", scans=0, executor=executor)
    seen = []
    for _ in range(3):
        e.scan()
        seen.append(e.table.read("S:4"))
    assert seen == [1, 2, 3]
    e = run_text("NOP", scans=0, executor=executor, settings=Settings(scan_ms=25))
    seen = []
    for _ in range(4):
        e.scan()
        seen.append(e.table.read("S:4"))
    assert seen == [2, 5, 7, 10]  # 25, 50, 75, 100 ms


def test_s4_bits_toggle_at_the_slc_rates(executor):
    # 1763-RM001: S:4/0 on/off 10 ms (cycle 20 ms), S:4/1 20 ms, ...
    e = run_text("XIC S:4/0 OTE B3/0\nXIC S:4/1 OTE B3/1", scans=0, executor=executor)
    bits = []
    for _ in range(4):
        e.scan()
        bits.append((e.table.read("B3/0"), e.table.read("B3/1")))
    assert bits == [(1, 0), (0, 1), (1, 1), (0, 0)]


def test_s4_wraps_after_65535_and_counts_on_from_a_written_value(executor):
    e = run_text("NOP", scans=1, executor=executor)
    e.table.write("S:4", -1)  # 0xFFFF
    e.scan()
    assert e.table.read("S:4") == 0
    e.table.write("S:4", 1000)
    e.run(2)
    assert e.table.read("S:4") == 1002


def test_s4_is_cleared_on_entering_run(executor):
    e = run_text("NOP", scans=5, executor=executor)
    assert e.table.read("S:4") == 5
    e.set_mode(Mode.PROGRAM)
    e.run(3)
    e.set_mode(Mode.RUN)
    assert e.table.read("S:4") == 0
    e.scan()
    assert e.table.read("S:4") == 1


def test_s4_follows_the_real_clock(executor):
    e = Engine(load_text("NOP"), table=DataTable(), clock=RealClock(), executor=executor)
    e.set_mode(Mode.RUN)
    e.scan()
    first_ms, first = e.clock.now_ms, e.table.read("S:4")
    time.sleep(0.06)
    e.scan()
    steps = (e.table.read("S:4") - first) & 0xFFFF
    assert steps >= 5 and abs(steps - (e.clock.now_ms - first_ms) / 10) < 1


def test_time_in_program_mode_is_not_timed(executor):
    e = run_text("TON T4:0 0.01 100 0", scans=3, executor=executor)
    assert e.table.read("T4:0.ACC") == 2
    e.set_mode(Mode.PROGRAM)
    e.run(50)  # 500 ms in PROGRAM: the ladder does not run
    e.set_mode(Mode.RUN)
    e.scan()
    assert e.table.read("T4:0.ACC") == 3


def test_a_restored_timing_timer_times_from_the_new_run(executor):
    # A table saved while T4:0 was timing (a retentive snapshot): its stamp is a time of the old run.
    old = run_text("TON T4:0 0.01 1000 0", scans=400, executor=executor, settings=Settings(scan_ms=13))
    assert old.table.read("T4:0.ACC") == 518
    table = DataTable()
    table.assign(old.table)
    e = Engine(load_text("TON T4:0 0.01 1000 0"), table=table, executor=executor, fresh=False)
    e.set_mode(Mode.RUN)
    e.scan()
    assert e.table.read("T4:0.ACC") == 519  # one 10 ms scan, not the old stamp's distance to now
