"""A Logix export's tasks, program inhibit and JSR/SBR/RET with parameters
(logix/tasks.py, ladder/instr/logix_task.py, docs/logix.md "Tasks"), on
both executors: hand-written exports built in tmp_path, loaded as an app
and run by the runner as ``softplc run`` runs them."""

from __future__ import annotations

import pytest

from helpers.logix_l5x import Prog, Task, write_l5x
from softplc_lite.app import load_app
from softplc_lite.ladder import Mode
from softplc_lite.ladder.instr.logix_task import MAX_RUNS
from softplc_lite.runner import Runner, RunOptions

EXECUTORS = ["compiled", "reference"]


def start(path, executor: str, **options) -> Runner:
    app = load_app(path)
    return Runner(app, RunOptions(executor=executor, fresh=True, save_state=False, **options), log=lambda m: None)


def tag(runner: Runner, path: str):
    return runner.engine.table.read(str(runner.app.logix.directory.resolve(path).address))


def set_tag(runner: Runner, path: str, value) -> None:
    runner.engine.table.write(str(runner.app.logix.directory.resolve(path).address), value)


def obj(runner: Runner, cls: str, name: str, attribute: str) -> str:
    """The address of a task's or program's attribute, as GSV/SSV reach it."""
    return str(runner.app.logix.directory.objects[(cls.upper(), name.upper(), attribute.upper())])


def counting_export(tmp_path, *tasks: Task, programs=()):
    """A continuous task counting its scans in Scans, and a program per
    periodic task counting its runs in a tag of the program's name."""
    progs = [Prog("Main", {"Main": ["ADD(Scans,1,Scans);"]})] + list(programs)
    names = {p.name for p in progs}
    for t in tasks:
        for name in t.programs:
            if name not in names:
                progs.append(Prog(name, {"Main": [f"ADD({name}Runs,1,{name}Runs);"]}))
                names.add(name)
    tags = [("Scans", "DINT")] + [(f"{n}Runs", "DINT") for n in sorted(names - {"Main"})]
    return write_l5x(tmp_path / "tasks.L5X", tags, progs, [Task("MainTask", ["Main"]), *tasks])


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_periodic_task_of_50_ms_runs_20_times_in_100_scans_of_10_ms(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50, priority=5))
    r = start(path, executor)
    assert r.app.warnings == []
    r.run(100)
    assert r.engine.fault is None and r.engine.clock.now_ms == 1000
    assert (tag(r, "Scans"), tag(r, "FastRuns")) == (100, 20)
    assert r.engine.table.read(obj(r, "Task", "Every50", "OverlapCount")) == 0
    r.run(3)  # 1030 ms: the 21st period ends at 1050
    assert tag(r, "FastRuns") == 20
    r.run(2)
    assert tag(r, "FastRuns") == 21


@pytest.mark.parametrize("executor", EXECUTORS)
def test_the_higher_priority_task_runs_first_when_both_are_due(tmp_path, executor):
    # Each task stamps the order it ran in; the export lists the low-priority task first.
    low = Prog("Low", {"Main": ["ADD(Order,1,Order)MOV(Order,LowAt)ADD(LowRuns,1,LowRuns);"]})
    high = Prog("High", {"Main": ["ADD(Order,1,Order)MOV(Order,HighAt)ADD(HighRuns,1,HighRuns);"]})
    path = write_l5x(tmp_path / "prio.L5X",
                     [("Scans", "DINT"), ("Order", "DINT"), ("LowAt", "DINT"), ("HighAt", "DINT"),
                      ("LowRuns", "DINT"), ("HighRuns", "DINT")],
                     [Prog("Main", {"Main": ["ADD(Scans,1,Scans);"]}), low, high],
                     [Task("MainTask", ["Main"]), Task("Slow", ["Low"], "PERIODIC", 50, priority=12),
                      Task("Quick", ["High"], "PERIODIC", 25, priority=3)])
    r = start(path, executor)
    r.run(100)  # 1000 ms: both are due at the last scan
    assert (tag(r, "HighRuns"), tag(r, "LowRuns")) == (40, 20)
    assert tag(r, "LowAt") == tag(r, "HighAt") + 1 == tag(r, "Order")
    r.run(3)  # 1030 ms: Quick ran at 1025, Slow did not
    assert tag(r, "HighAt") == tag(r, "LowAt") + 1


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_task_faster_than_the_scan_runs_once_for_every_period(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every4", ["Fast"], kind="PERIODIC", rate_ms=4, priority=1))
    r = start(path, executor)
    r.run(100)  # 1000 ms of 10 ms scans: 250 periods of 4 ms
    assert tag(r, "FastRuns") == 250


@pytest.mark.parametrize("executor", EXECUTORS)
def test_periods_past_the_runs_of_one_scan_are_counted_as_overlaps(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every1", ["Fast"], kind="PERIODIC", rate_ms=1, priority=1))
    r = start(path, executor, scan_ms=250)
    r.run(4)  # 1000 periods; at most MAX_RUNS in a scan
    overlaps = r.engine.table.read(obj(r, "Task", "Every1", "OverlapCount"))
    assert tag(r, "FastRuns") == 4 * MAX_RUNS
    assert tag(r, "FastRuns") + overlaps == 1000


@pytest.mark.parametrize("executor", EXECUTORS)
def test_time_in_program_mode_is_not_caught_up_the_schedule_starts_anew(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50, priority=5))
    r = start(path, executor)
    r.run(100)
    r.engine.set_mode(Mode.PROGRAM)
    r.engine.run(30)  # 300 ms of PROGRAM: the clock runs, the ladder does not
    r.run(100)
    assert tag(r, "FastRuns") == 40 and tag(r, "Scans") == 200
    assert r.engine.table.read(obj(r, "Task", "Every50", "OverlapCount")) == 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_inhibited_program_is_not_run_and_its_disable_flag_is_settable(tmp_path, executor):
    off = Prog("Off", {"Main": ["ADD(OffRuns,1,OffRuns);"]}, disabled=True)
    path = counting_export(tmp_path, Task("Every50", ["Fast", "Off"], kind="PERIODIC", rate_ms=50),
                           programs=[off, Prog("Idle", {"Main": ["ADD(IdleRuns,1,IdleRuns);"]}, disabled=True)])
    text = path.read_text().replace('<ScheduledProgram Name="Main"/>',
                                    '<ScheduledProgram Name="Main"/><ScheduledProgram Name="Idle"/>')
    path.write_text(text)
    r = start(path, executor)
    r.run(10)
    assert (tag(r, "FastRuns"), tag(r, "OffRuns"), tag(r, "IdleRuns")) == (2, 0, 0)
    flag = obj(r, "Program", "Idle", "DisableFlag")
    assert r.engine.table.read(flag) == 1
    r.engine.table.write(flag, 0)  # as SSV(Program, Idle, DisableFlag, 0) does
    r.engine.table.write(obj(r, "Program", "Off", "DisableFlag"), 0)
    r.engine.table.write(obj(r, "Program", "Main", "DisableFlag"), 1)
    r.run(10)
    assert (tag(r, "Scans"), tag(r, "IdleRuns"), tag(r, "OffRuns"), tag(r, "FastRuns")) == (10, 10, 2, 4)


@pytest.mark.parametrize("executor", EXECUTORS)
def test_an_inhibited_task_is_not_run_and_starts_a_period_after_it_is_uninhibited(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50, inhibited=True))
    r = start(path, executor)
    r.run(20)
    assert tag(r, "FastRuns") == 0
    r.engine.table.write(obj(r, "Task", "Every50", "InhibitTask"), 0)
    r.run(4)
    assert tag(r, "FastRuns") == 0
    r.run(1)
    assert tag(r, "FastRuns") == 1 and r.engine.table.read(obj(r, "Task", "Every50", "OverlapCount")) == 0


def subroutine_export(tmp_path):
    main = ["JSR(Scale,2,Raw,Gain,Result);",  # two inputs, one return value
            "JSR(Scale,2,7,0.5,Half);",  # numbers as inputs; 3.5 rounds half to even into a DINT
            "JSR(Limit,1,Result,Clamped);",
            "JSR(Plain,0);"]
    routines = {
        "Main": main,
        "Scale": ["SBR(In,K);", "MUL(In,K,Out);", "RET(Out);", "MOV(99,Out);"],  # RET ends the routine
        "Limit": ["SBR(In);", "GRT(In,100)RET(100);", "RET(In);"],
        "Plain": ["SBR();", "ADD(Calls,1,Calls);", "RET();"],
    }
    tags = [("In", "DINT"), ("K", "REAL"), ("Out", "REAL")]
    return write_l5x(tmp_path / "subs.L5X",
                     [("Raw", "DINT"), ("Gain", "REAL"), ("Result", "DINT"), ("Half", "DINT"),
                      ("Clamped", "DINT"), ("Calls", "DINT")],
                     [Prog("Calc", routines, main="Main", tags=tags)], [Task("MainTask", ["Calc"])])


@pytest.mark.parametrize("executor", EXECUTORS)
def test_jsr_passes_two_inputs_and_receives_one_return_value(tmp_path, executor):
    r = start(subroutine_export(tmp_path), executor)
    assert r.app.warnings == []
    set_tag(r, "Raw", 30)
    set_tag(r, "Gain", 2.5)
    r.run(1)
    assert r.engine.fault is None
    assert tag(r, "Result") == 75 and tag(r, "Program:Calc.Out") == 3.5  # the last call's RET
    assert tag(r, "Half") == 4  # 3.5 into a DINT: half to even (1756-RM003, REAL to an integer)
    assert tag(r, "Clamped") == 75 and tag(r, "Calls") == 1
    set_tag(r, "Gain", 10.0)
    r.run(1)
    assert tag(r, "Result") == 300 and tag(r, "Clamped") == 100 and tag(r, "Calls") == 2


def test_both_executors_leave_the_same_table(tmp_path):
    tables = []
    for executor in EXECUTORS:
        path = counting_export(tmp_path, Task("Every30", ["Fast"], kind="PERIODIC", rate_ms=30, priority=2),
                               Task("Every7", ["Faster"], kind="PERIODIC", rate_ms=7, priority=9))
        r = start(path, executor)
        r.run(57)
        tables.append({f.name: list(f.data) for f in r.engine.table.files()})
    assert tables[0] == tables[1]


def test_a_dint_passed_to_a_bool_parameter_is_a_warning_and_the_call_is_not_run(tmp_path):
    path = write_l5x(tmp_path / "bool.L5X", [("Flag", "BOOL"), ("Count", "DINT"), ("N", "DINT")],
                     [Prog("P", {"Main": ["JSR(Take,1,N);", "ADD(Count,1,Count);"],
                                 "Take": ["SBR(B);", "ADD(Count,100,Count);"]}, main="Main",
                           tags=[("B", "BOOL")])], [Task("T", ["P"])])
    r = start(path, "compiled")
    warnings = "\n".join(r.app.warnings)
    assert "routine P.Main: rung 0: JSR parameter 'N': a DINT passed to a BOOL parameter" in warnings
    r.run(2)
    assert tag(r, "Count") == 2  # the rest runs


def test_an_event_task_is_a_warning_and_its_programs_do_not_run(tmp_path):
    path = counting_export(tmp_path, Task("OnInput", ["Fast"], kind="EVENT"))
    r = start(path, "compiled")
    assert any("event task OnInput: not run: softplc_lite raises no event" in w for w in r.app.warnings)
    r.run(10)
    assert tag(r, "FastRuns") == 0 and tag(r, "Scans") == 10


def test_on_the_wall_clock_the_runs_and_overlaps_count_the_periods_that_ended(tmp_path):
    path = counting_export(tmp_path, Task("Every10", ["Fast"], kind="PERIODIC", rate_ms=10, priority=1))
    r = start(path, "compiled", realtime=True, scan_ms=2)

    started = []

    def stop_after_six_periods(engine):
        if not started:  # the schedule starts at the clock of the scan before the first (here: RUN entered)
            started.append(engine.clock.now_ms - engine.machine.dt)
        if engine.clock.now_ms - started[0] >= 60:
            r.request_stop()
    r.run(on_scan=stop_after_six_periods)
    periods = (r.engine.clock.now_ms - started[0]) // 10
    overlaps = r.engine.table.read(obj(r, "Task", "Every10", "OverlapCount"))
    assert tag(r, "FastRuns") + overlaps == periods >= 6


@pytest.mark.parametrize("executor", EXECUTORS)
def test_lper_is_true_once_per_period_ended_and_a_false_rung_unschedules_it(executor):
    from softplc_lite.ladder import run_text

    rung = "DATA L9 3\nLBL 0 XIO B3/0 LPER 25 L9:0 L9:1 L9:2 500 ADD N7:0 1 N7:0 JMP 0"
    e = run_text(rung, scans=10, executor=executor, values={"B3/0": 0})
    assert (e.table.read("N7:0"), e.table.read("L9:1"), e.table.read("L9:0")) == (4, 125, 1)
    e.table.write("B3/0", 1)
    e.run(10)  # unscheduled: nothing runs, nothing is counted as an overlap
    assert (e.table.read("N7:0"), e.table.read("L9:0"), e.table.read("L9:2")) == (4, 0, 0)
    e.table.write("B3/0", 0)
    e.run(2)  # scheduled in the scan of 210 ms: the period ends at 225 (the previous scan's 200 ms + 25)
    assert e.table.read("N7:0") == 4 and e.table.read("L9:1") == 225
    e.run(1)
    assert e.table.read("N7:0") == 5


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_restored_run_keeps_the_counts_and_schedules_its_tasks_anew(tmp_path, executor):
    path = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50))
    state = tmp_path / "state"
    for run in range(2):
        app = load_app(path, state_dir=state)
        r = Runner(app, RunOptions(executor=executor, fresh=run == 0), log=lambda m: None)
        r.engine.table.write(obj(r, "Program", "Main", "DisableFlag"), run)  # Scans keeps the first run's 100
        r.run(100)
        r.close()
        r.save()
    # The second run's clock starts again from 0: a schedule kept from the first run's clock would
    # catch up nothing or everything; anew, it runs 20 more times.
    assert (tag(r, "FastRuns"), tag(r, "Scans")) == (40, 100)
    assert r.engine.table.read(obj(r, "Task", "Every50", "OverlapCount")) == 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_a_periodic_run_longer_than_the_tasks_watchdog_is_a_major_fault(tmp_path, executor, monkeypatch):
    from softplc_lite.ladder.instr import logix_task
    from softplc_lite.ladder.status import FAULT_WATCHDOG

    ticks = []

    def two_ms_a_reading():  # every reading of the watchdog's clock is 2 ms after the one before
        ticks.append(None)
        return len(ticks) * 0.002
    monkeypatch.setattr(logix_task, "clock", two_ms_a_reading)
    within = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50, watchdog_ms=3))
    r = start(within, executor)
    r.run(20)
    assert r.engine.fault is None and tag(r, "FastRuns") == 4
    over = counting_export(tmp_path, Task("Every50", ["Fast"], kind="PERIODIC", rate_ms=50, watchdog_ms=1))
    r = start(over, executor)
    r.run(20)
    fault = r.engine.fault
    assert fault is not None and fault.code == FAULT_WATCHDOG and (fault.file, fault.rung) == (2, 1)
    assert "task watchdog: a run of the periodic task took 2.0 ms, more than its Watchdog of 1 ms" in fault.message
    assert tag(r, "FastRuns") == 1 and r.engine.mode is Mode.FAULTED
