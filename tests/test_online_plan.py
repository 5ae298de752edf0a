"""An online edit in two steps: plan_edit checks it against the live data
table and changes nothing; Engine.apply_edit applies the plan at a scan
boundary. Both executors."""

from __future__ import annotations

import pytest

from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder.online import EditPlan, EditRefused, plan_edit

OLD = "XIC B3/0 TON T4:0 0.01 100 0\nADD N7:0 1 N7:0\n"
NEW = "DATA N9 2 = 5 0x9C40\nXIC B3/0 TON T4:0 0.01 100 0\nADD N7:0 1 N7:0\nMOV N9:1 N7:5\n"


def running(executor: str) -> Engine:
    e = Engine(load_text(OLD), executor=executor)
    e.set_mode(Mode.RUN)
    e.run(3)
    return e


def snapshot(e: Engine) -> tuple:
    return e.program, e.files, [(f.name, f.size, list(f.data)) for f in e.table.files()]


@pytest.mark.parametrize("executor", ["compiled", "reference"])
def test_a_plan_changes_nothing_and_apply_edit_runs_it(executor):
    e = running(executor)
    before = snapshot(e)
    plan = plan_edit(e, load_text(NEW))
    assert isinstance(plan, EditPlan) and snapshot(e) == before  # planned: the engine and its table as they were
    assert [str(a) for a, _, _ in plan.writes] == ["N9:0", "N9:1"]
    changes = e.apply_edit(plan)
    assert changes is plan.changes and changes.created == ["N7:1-N7:5", "N9 (2 elements)"]
    assert changes.files[2].added == [2] and e.program is plan.program
    e.run(1)
    # a hex DATA value above 0x7FFF in a word file is kept as its 16 bits, as a download writes it
    assert e.table.read("N9:0") == 5 and e.table.read("N7:5") == 0x9C40 - 0x10000
    assert e.table.read("N7:0") == 4  # the running state carried over: 3 scans before, 1 after


def test_a_refused_plan_leaves_the_engine_as_it_was():
    e = running("compiled")
    e.table.create_file("F", 9, 1)  # the edit needs N9: file 9 exists with another type
    before = snapshot(e)
    with pytest.raises(EditRefused):
        plan_edit(e, load_text(NEW))
    assert snapshot(e) == before
