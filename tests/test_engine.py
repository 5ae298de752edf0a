"""The scan engine: modes, hooks, status file, watchdog, faults, clocks."""

from __future__ import annotations

import time

import pytest

from softplc_lite.ladder import Engine, Mode, ModeError, RealClock, Settings, SimulatedClock, load_text, run_text
from softplc_lite.ladder import status as S


def engine(text: str, **kw) -> Engine:
    return Engine(load_text(text), **kw)


def test_modes_and_transitions():
    e = engine("ADD N7:0 1 N7:0\n")
    assert e.mode is Mode.PROGRAM
    e.scan()
    assert e.table.read("N7:0") == 0  # no ladder in PROGRAM
    e.set_mode(Mode.TEST)
    e.scan()
    assert e.table.read("N7:0") == 1  # TEST runs the ladder
    e.set_mode(Mode.RUN)
    e.scan()
    assert e.table.read("N7:0") == 2 and e.table.read("S:105") == Mode.RUN.value
    e.set_mode(Mode.PROGRAM)
    with pytest.raises(ModeError):
        e.set_mode(Mode.FAULTED)


def test_hooks_run_in_order_and_outputs_are_idle_outside_run():
    e = engine("XIC I:0/0 OTE O:0/0\n")
    calls = []
    e.input_hooks.append(lambda eng: (calls.append("in"), eng.table.write("I:0/0", 1)))
    e.output_hooks.append(lambda eng, enabled: calls.append(("out", enabled, eng.table.read("O:0/0"))))
    e.scan()
    e.set_mode(Mode.TEST)
    e.scan()
    e.set_mode(Mode.RUN)
    e.scan()
    assert calls == ["in", ("out", False, 0), "in", ("out", False, 1), "in", ("out", True, 1)]


def test_mode_hooks_see_every_change_including_faults():
    e = engine("MOV 5 N7:1\nMOV N7:[N7:1] N7:2\n")
    seen = []
    e.mode_hooks.append(lambda eng, old, new: seen.append((old, new)))
    e.set_mode(Mode.RUN)
    e.scan()
    assert seen == [(Mode.PROGRAM, Mode.RUN), (Mode.RUN, Mode.FAULTED)]


def test_first_pass_bit_only_on_the_first_scan():
    e = engine("XIC S:1/15 ADD N7:0 1 N7:0\n")
    e.set_mode(Mode.RUN)
    e.run(5)
    assert e.table.read("N7:0") == 1 and e.table.read("S:1/15") == 0
    e.set_mode(Mode.PROGRAM)
    e.set_mode(Mode.RUN)
    e.run(2)
    assert e.table.read("N7:0") == 2


def test_status_words_scan_time_and_counter():
    e = engine("ADD N7:0 1 N7:0\n", settings=Settings(scan_ms=25))
    e.set_mode(Mode.RUN)
    e.run(70000)
    t = e.table
    assert t.read("S:8") == 25 and t.read("S:9") == 25
    count = (t.read_word("S:101") & 0xFFFF) << 16 | (t.read_word("S:100") & 0xFFFF)
    assert count == 70000 == e.scans
    assert t.read("S:28") == S.DEFAULT_WATCHDOG_MS


def test_major_fault_records_code_file_rung_and_instruction():
    e = engine("MOV 1 N7:0\nJSR 3\nFILE 3\nSBR\nMOV 50 N7:1\nMOV N7:[N7:1] N7:2\nRET\n")
    e.set_mode(Mode.RUN)
    e.scan()
    assert e.mode is Mode.FAULTED
    f = e.fault
    assert (f.code, f.file, f.rung) == (S.FAULT_INDIRECT_RANGE, 3, 2)
    assert f.instruction.startswith("MOV N7:[N7:1] N7:2 at <program>:6:1")
    assert "element 50 (from N7:1) is past the end of N7" in f.message
    t = e.table
    assert (t.read("S:12"), t.read("S:13"), t.read("S:14")) == (20, 3, 2)
    assert t.read("S:11") & (1 << S.MAJOR_RUNTIME_BIT)
    n = t.read("N7:0")
    e.scan()  # a faulted processor does not scan
    assert t.read("N7:0") == n
    with pytest.raises(ModeError, match="clear the fault first"):
        e.set_mode(Mode.RUN)
    e.set_mode(Mode.PROGRAM)
    assert e.fault is None and t.read("S:12") == 0


def test_watchdog_stops_a_backward_jump_loop():
    e = engine("LBL 1 ADD N7:0 1 N7:0\nJMP 1\n", settings=Settings(watchdog_ms=50))
    e.set_mode(Mode.RUN)
    started = time.monotonic()
    e.scan()
    assert time.monotonic() - started < 5
    assert e.mode is Mode.FAULTED and e.fault.code == S.FAULT_WATCHDOG
    assert e.table.read("S:11") & (1 << S.MAJOR_WATCHDOG_BIT)


def test_watchdog_setpoint_comes_from_s28():
    e = engine("LBL 1 JMP 1\n")
    e.table.write("S:28", 20)
    e.set_mode(Mode.RUN)
    started = time.monotonic()
    e.scan()
    assert e.fault.code == S.FAULT_WATCHDOG and "S:28 = 20 ms" in e.fault.message
    assert time.monotonic() - started < 2


def test_tnd_ends_the_scan():
    e = engine("ADD N7:0 1 N7:0\nXIC B3/0 TND\nADD N7:1 1 N7:1\n")
    e.set_mode(Mode.RUN)
    e.scan()
    e.table.write("B3/0", 1)
    e.scan()
    assert (e.table.read("N7:0"), e.table.read("N7:1")) == (2, 1)


def test_internal_errors_become_faults_not_tracebacks():
    def broken(*args):
        raise ValueError("kernel bug")

    # Simulate a bug inside a kernel (the reference interpreter looks kernels
    # up at run time, so replacing one on the machine reaches it).
    e = Engine(load_text("TON T4:0 0.01 10 0\n"), executor="reference")
    e.machine.ton = broken
    e.set_mode(Mode.RUN)
    e.scan()
    assert e.mode is Mode.FAULTED and "internal error: ValueError: kernel bug" in e.fault.message
    assert e.fault.instruction.startswith("TON T4:0 0.01 10 0")


def test_simulated_clock_is_deterministic_and_real_clock_follows_the_wall():
    sim = SimulatedClock(7)
    assert [sim.advance() for _ in range(3)] == [7, 7, 7] and sim.now_ms == 21
    real = RealClock()
    time.sleep(0.03)
    dt = real.advance()
    assert 25 <= dt <= 1000
    e = engine("TON T4:0 0.01 100 0\n", clock=RealClock())
    e.set_mode(Mode.RUN)
    e.scan()
    time.sleep(0.05)
    e.scan()
    assert 3 <= e.table.read("T4:0.ACC") <= 100


def test_a_module_hook_that_raises_faults_the_plc_instead_of_ending_the_run():
    """A bug in a plug-in's driver hook becomes major fault 255 naming the
    module and the error; the engine keeps scanning (and keeps its data)."""
    from softplc_lite.tlm import TLM

    class Broken(TLM):
        name = "BROKEN"
        calls = 0

        def on_input(self, engine):
            Broken.calls += 1
            raise KeyError("slave 9")

    engine = run_text("XIC S:1/15 OTL B3/0", scans=0, modules=[Broken()])
    engine.set_mode(Mode.RUN)
    engine.run(3)
    assert engine.mode is Mode.FAULTED and engine.fault.code == 255
    assert engine.fault.message == "internal error in BROKEN's on_input: KeyError: 'slave 9'"
    assert Broken.calls == 3 and engine.scans == 0 and engine.table.read("B3/0") == 0
