"""The executor differential test for Structured Text: random ST routines
(tests/helpers/st_strategies.py) in an export, run by the compiled path and
the reference interpreter from the same values, with the same tag written
before every scan; after every scan both data tables, modes and faults must
be the same. ST becomes ladder rungs (logix/st_routine.py), so this holds
the translation's every rung kind (CPT with ``//``, LSTB, CMP+JMP, LBL,
backward JMPs, LIDX) to both executors at once."""

from __future__ import annotations

from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from helpers.logix_l5x import Prog, Task, l5x_text, read_tag, write_tag
from helpers.st_strategies import INITIAL, TAGS, routines
from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner

SCANS = 4


def _tables(runner) -> dict[str, list]:
    return {f.name: list(f.data) for f in runner.table.files()}


def _fault(runner):
    f = runner.engine.fault
    return None if f is None else (f.code, f.file, f.rung, f.instruction)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.data_too_large])
@given(routine=routines, initial=st.lists(st.integers(-40, 40), min_size=len(INITIAL), max_size=len(INITIAL)),
       inputs=st.lists(st.integers(-100, 100), min_size=SCANS, max_size=SCANS))
def test_compiled_and_reference_agree_on_random_st(tmp_path_factory, routine, initial, inputs):
    note(routine)
    path = tmp_path_factory.mktemp("st") / "random.L5X"
    path.write_text(l5x_text(TAGS, [Prog("P", {"Main": ["JSR(Calc,0);"], "Calc": routine})], [Task("T", ["P"])]))
    app = load_app(path)
    runners = [Runner(app, RunOptions(executor=ex, fresh=True, save_state=False), log=lambda m: None)
               for ex in ("compiled", "reference")]
    for r in runners:
        for name, value in zip(INITIAL, initial):
            write_tag(r, name, value / 4 if name in ("x", "y") else value & 1 if name in ("p", "q") else value)
    for scan, value in enumerate(inputs):
        for r in runners:
            if r.engine.fault is None:
                write_tag(r, "b", value)
                r.run(1)
        compiled, reference = runners
        assert _fault(compiled) == _fault(reference), f"scan {scan}"
        assert compiled.engine.mode == reference.engine.mode
        a, b = _tables(compiled), _tables(reference)
        for name in a:
            same = [x == y or (x != x and y != y) for x, y in zip(a[name], b[name])]
            assert all(same), f"scan {scan}: {name} differs at {same.index(False)}"
    assert read_tag(runners[0], "c") == read_tag(runners[1], "c")
