"""Online program edit: Engine.replace_program on both
executors, program_changes, and ProgramWatcher on real files."""

from __future__ import annotations

import os
import time
import weakref

import pytest

from helpers.apps import make_app
from softplc_lite.app import load_app
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder import status as S
from softplc_lite.ladder.instructions import InstructionSpec, K, OperandSpec
from softplc_lite.ladder.online import EditRefused, precompile, program_changes
from softplc_lite.program_watcher import ProgramWatcher
from softplc_lite.tlm import TLM
from softplc_lite.tlm.registry import instruction_set

EXECUTORS = ["compiled", "reference"]
# "precompiled": the compiled executor given the code compiled beforehand, as the watcher's thread does
HOW = [*EXECUTORS, "precompiled"]
# the engines built "precompiled": weak, because an id() outlives its engine and is reused
# (a reference engine once got a dead precompiled engine's id)
PRECOMPILED: weakref.WeakSet[Engine] = weakref.WeakSet()


def replace(e: Engine, program):
    """Engine.replace_program, with the code precompiled for a "precompiled" engine."""
    if e not in PRECOMPILED:
        return e.replace_program(program)
    code = precompile(program, e.settings)
    assert code is not None
    old_files = e.files
    changes = e.replace_program(program, code)
    if e.files is not old_files:  # taken: bound from the code (a compiler is made only when needed), not compiled
        assert all(callable(compiled._compiler) for compiled, _ in e.files.values())
    return changes


def running(text: str, how: str, scans: int = 0, **values) -> Engine:
    e = Engine(load_text(text), executor="reference" if how == "reference" else "compiled")
    if how == "precompiled":
        PRECOMPILED.add(e)
    for address, value in values.items():
        e.table.write(address, value)
    e.set_mode(Mode.RUN)
    e.run(scans)
    return e


BASE = """\
XIC B3/0 TON T4:0 0.01 100 0
XIC B3/1 CTU C5:0 100 0
ADD N7:0 1 N7:0
"""


# -- program_changes ----------------------------------------------------------------------------


def test_an_inserted_rung_is_one_added_not_every_later_one_changed():
    old = load_text(BASE)
    new = load_text("OTE B3/9\n" + BASE)
    changes = program_changes(old, new)
    assert changes.summary() == "file 2: 1 rung added (0)"
    assert [changes.new_rung(2, k) for k in range(3)] == [1, 2, 3]


def test_removed_changed_and_moved_rungs_are_named_by_number():
    old = load_text(BASE + "OTE B3/9\n")
    new = load_text("OTE B3/9\nXIC B3/0 TON T4:0 0.01 100 0\nADD N7:0 2 N7:0\n")
    changes = program_changes(old, new)
    fc = changes.files[2]
    assert fc.moved == [0] and fc.removed == [1] and fc.changed == [2] and fc.added == []
    assert changes.summary() == "file 2: 1 rung removed (was 1), 1 changed (2), 1 moved (0)"
    assert changes.new_rung(2, 0) == 1 and changes.new_rung(2, 1) is None and changes.new_rung(2, 3) == 0


def test_same_program_is_no_change_and_files_added_or_deleted_are_said():
    assert not program_changes(load_text(BASE), load_text(BASE))
    assert program_changes(load_text(BASE), load_text(BASE)).summary() == "no rung changed"
    two = BASE + "JSR 3\nFILE 3 SUB\nOTE B3/5\nOTE B3/6\n"
    assert program_changes(load_text(BASE), load_text(two)).summary() == \
        "file 2: 1 rung added (3); file 3: new, 2 rungs"
    assert program_changes(load_text(two), load_text(BASE)).summary() == \
        "file 2: 1 rung removed (was 3); file 3: deleted (2 rungs)"


# -- Engine.replace_program -------------------------------------------------------------------------


@pytest.mark.parametrize("executor", HOW)
def test_rungs_added_removed_changed_keep_the_table_and_timers_and_counters_run_on(executor):
    e = running(BASE, executor, scans=5, **{"B3:0/0": 1})
    e.table.write("B3/1", 1)
    e.scan()
    assert e.table.read("T4:0.ACC") == 5 and e.table.read("C5:0.ACC") == 1 and e.table.read("N7:0") == 6
    new = "XIC B3/0 TON T4:0 0.01 100 0\nXIC B3/1 CTU C5:0 100 0\nSUB N7:1 1 N7:1\n"
    changes = replace(e, load_text(new))
    assert changes.summary() == "file 2: 1 rung changed (2); created N7:1"
    assert e.table.read("T4:0.ACC") == 5 and e.table.read("N7:0") == 6  # kept, not scanned meanwhile
    e.table.write("B3/1", 0)
    e.scan()
    e.table.write("B3/1", 1)
    e.scan()
    assert e.table.read("T4:0.ACC") == 7  # still timing
    assert e.table.read("C5:0.ACC") == 2  # counted the new transition, from where it was
    assert e.table.read("N7:0") == 6 and e.table.read("N7:1") == -2  # old rung gone, new one runs
    assert e.mode is Mode.RUN


@pytest.mark.parametrize("executor", HOW)
def test_new_files_and_elements_are_created_with_their_data_values(executor):
    e = running("ADD N7:0 1 N7:0\nDATA N10 2 = 7 8\n", executor, scans=2)
    e.table.write("N10:0", 70)
    new = "ADD N7:0 1 N7:0\nMOV N11:3 N7:20\nMOV F12:1 F12:0\nDATA N10 4 = 1 2 3 4\nDATA N11 4 = 5 6 7 9\n"
    changes = replace(e, load_text(new))
    assert "created N7:1-N7:20, N10:2-N10:3, N11 (4 elements), F12 (2 elements)" in changes.summary()
    assert [e.table.read(f"N10:{k}") for k in range(4)] == [70, 8, 3, 4]  # live values kept, new get DATA
    e.scan()
    assert e.table.read("N7:20") == 9 and e.table.read("N7:0") == 3


@pytest.mark.parametrize("executor", HOW)
def test_a_changed_preset_writes_pre_and_keeps_acc(executor):
    e = running(BASE, executor, scans=10, **{"B3:0/0": 1})
    e.table.write("T4:0.PRE", 500)  # an online data change, later overwritten by the edit's new preset
    e.table.write("C5:0.PRE", 77)  # a preset the edit does not touch: kept
    replace(e, load_text(BASE.replace("100 0\nXIC B3/1", "20 0\nXIC B3/1")))
    assert e.table.read("T4:0.PRE") == 20 and e.table.read("T4:0.ACC") == 9
    assert e.table.read("C5:0.PRE") == 77
    e.run(10)
    assert e.table.read("T4:0.ACC") == 19 and e.table.read("T4:0/DN") == 0
    e.scan()
    assert e.table.read("T4:0/DN") == 1  # 20 reached with the new preset


@pytest.mark.parametrize("executor", HOW)
def test_a_timer_new_to_the_program_gets_pre_and_acc_a_kept_one_keeps_its_acc(executor):
    e = running("XIC B3/0 TON T4:1 0.01 100 5\n", executor, scans=1)  # rung false: ACC reset to 0
    replace(e, load_text("XIC B3/0 TON T4:1 0.01 100 5\nXIC B3/0 TON T4:0 0.01 30 4\n"
                                "XIC B3/0 TON T4:2 0.01 40 3\n"))
    assert [e.table.read(f"T4:{k}.PRE") for k in range(3)] == [30, 100, 40]
    # T4:0 existed (T4:1 made the file) but no instruction used it: as a download
    assert [e.table.read(f"T4:{k}.ACC") for k in range(3)] == [4, 0, 3]


@pytest.mark.parametrize("executor", HOW)
def test_an_edit_the_table_cannot_take_is_refused_and_nothing_changes(executor):
    e = running("ADD N7:0 1 N7:0\nMOV 5 N10:0\n", executor, scans=3)
    before = [(f.name, f.size) for f in e.table.files()]
    program = e.program
    with pytest.raises(EditRefused) as refused:
        replace(e, load_text("ADD N7:0 1 N7:0\nMOV 1.5 F10:0\nMOV 1 N12:40\n", source="main.lad"))
    assert "main.lad:2:" in str(refused.value) and "N10" in str(refused.value)
    assert [(f.name, f.size) for f in e.table.files()] == before  # N12 not created
    assert e.program is program
    e.scan()
    assert e.table.read("N7:0") == 4 and e.table.read("N10:0") == 5  # the old program runs on


@pytest.mark.parametrize("executor", HOW)
def test_one_shots_and_fifo_and_shift_controls_are_kept(executor):
    text = ("XIC B3/0 ONS B3/1 ADD N7:0 1 N7:0\n"
            "XIC B3/2 FFL N7:1 #N7:10 R6:0 4 0\n"
            "XIC B3/3 BSL #B3:10 R6:1 B3/4 8\n")
    e = running(text, executor, scans=2, **{"B3:0/0": 1, "N7:1": 42, "B3:0/2": 1, "B3:0/3": 1, "B3:0/4": 1})
    assert e.table.read("N7:0") == 1 and e.table.read("R6:0.POS") == 1 and e.table.read("B3:10/0") == 1
    replace(e, load_text("OTE B3/15\n" + text.replace("R6:1 B3/4 8", "R6:1 B3/4 12")))
    e.run(2)
    assert e.table.read("N7:0") == 1  # the storage bit is kept: a rung still true does not fire again
    assert e.table.read("R6:0.POS") == 1  # EN kept: no new FFL load without a transition
    assert e.table.read("R6:1.LEN") == 12 and e.table.read("B3:10/1") == 0  # new length written, no shift
    e.table.write("B3/2", 0)
    e.table.write("B3/3", 0)
    e.scan()
    e.table.write("B3/2", 1)
    e.table.write("B3/3", 1)
    e.scan()
    assert e.table.read("R6:0.POS") == 2 and e.table.read("B3:10/1") == 1


@pytest.mark.parametrize("executor", HOW)
def test_first_pass_is_not_set_again_and_the_mode_stays(executor):
    e = running("XIC S:1/15 ADD N7:0 1 N7:0\n", executor, scans=3)
    e.set_mode(Mode.TEST)
    replace(e, load_text("XIC S:1/15 ADD N7:0 1 N7:0\nXIC S:1/15 ADD N7:1 1 N7:1\n"))
    e.run(2)
    assert e.mode is Mode.TEST and e.table.read("N7:0") == 1 and e.table.read("N7:1") == 0
    assert not e.table.read("S:1/15") and e.table.read(f"S:{S.MODE_WORD}") == Mode.TEST.value


COUNT = InstructionSpec("COUNTUP", "dest counts this instance's true scans", (OperandSpec("dest", K.WORD),),
                        True, 0, "KEEP")


class Keep(TLM):
    """Each instance counts its own calls: a new instance starts from 0."""

    name = "KEEP"

    def instructions(self):
        return [COUNT]

    def create(self, instr, ctx):
        dest = ctx.operands[0]
        calls = [0]

        def count(c):
            calls[0] += 1
            d, i, _ = dest.location()
            d[i] = calls[0]
            return c
        return count


@pytest.mark.parametrize("executor", HOW)
def test_module_instructions_of_unchanged_rungs_keep_their_instances(executor):
    module = Keep()
    instructions = instruction_set([module])
    e = Engine(load_text("COUNTUP N7:0\nCOUNTUP N7:1\n", instructions=instructions),
               executor="reference" if executor == "reference" else "compiled", modules=[module])
    e.set_mode(Mode.RUN)
    e.run(3)
    new = load_text("OTE B3/0\nCOUNTUP N7:0\nXIC B3/0 COUNTUP N7:1\n", instructions=instructions)
    code = precompile(new, e.settings) if executor == "precompiled" else None
    assert (code is not None) == (executor == "precompiled")
    e.replace_program(new, code)
    e.run(2)
    assert e.table.read("N7:0") == 5  # moved down a rung, same text: the same instance
    assert e.table.read("N7:1") == 2  # its rung changed: a new instance


# -- ProgramWatcher on real files ----------------------------------------------------------------


def write(path, text: str) -> None:
    """Write and move the mtime on, as an editor's save a moment later would."""
    path.write_text(text)
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10_000_000))


def scan_until_edit(watcher: ProgramWatcher, engine: Engine, timeout_s: float = 10.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        engine.scan()
        edit = watcher.apply(engine)
        if edit is not None:
            return edit
        time.sleep(0.01)
    return None


@pytest.fixture
def app_dir(tmp_path):
    return make_app(tmp_path / "app", "XIC B3/0 TON T4:0 0.01 1000 0\nADD N7:0 1 N7:0\n")


@pytest.mark.parametrize("executor", EXECUTORS)
def test_the_watcher_applies_a_saved_edit_at_a_scan_boundary(app_dir, executor):
    app = load_app(app_dir, use_cache=False)
    e = Engine(app.program, executor=executor)
    e.table.write("B3/0", 1)
    e.set_mode(Mode.RUN)
    watcher = ProgramWatcher(app, interval_s=0.05)
    e.run(3)
    write(app_dir / "main.lad", "XIC B3/0 TON T4:0 0.01 1000 0\nADD N7:0 1 N7:0\nMOV N7:0 N10:2\n")
    edit = scan_until_edit(watcher, e)
    assert edit is not None and edit.accepted and edit.applied
    assert edit.summary() == "online edit accepted: file 2: 1 rung added (2); created N10 (3 elements)"
    assert app.program is e.program
    n = e.table.read("N7:0")
    acc = e.table.read("T4:0.ACC")
    e.scan()
    assert e.table.read("N10:2") == n + 1 and e.table.read("T4:0.ACC") == acc + 1
    assert watcher.poll() is None  # the same version is not taken twice


def test_a_bad_edit_is_rejected_with_file_line_col_and_retried_only_after_a_new_save(app_dir):
    app = load_app(app_dir, use_cache=False)
    e = Engine(app.program)
    e.set_mode(Mode.RUN)
    watcher = ProgramWatcher(app, interval_s=0.05)
    program = e.program
    # a save caught half-written: the last rung cut in the middle
    write(app_dir / "main.lad", "XIC B3/0 TON T4:0 0.01 1000 0\nADD N7:0 1 N7:0\nMOV N7:0\n")
    edit = scan_until_edit(watcher, e)
    assert edit is not None and not edit.accepted and not edit.applied
    assert edit.errors[0].startswith(f"{app_dir / 'main.lad'}:3:") or ":3:" in edit.errors[0].splitlines()[0]
    assert edit.summary().startswith("online edit rejected, the program is unchanged: ")
    assert e.program is program and app.program is program
    n = e.table.read("N7:0")
    e.scan()
    assert e.table.read("N7:0") == n + 1  # the old program runs on
    assert scan_until_edit(watcher, e, timeout_s=0.5) is None  # not read again until it changes
    write(app_dir / "main.lad", "XIC B3/0 TON T4:0 0.01 1000 0\nADD N7:0 1 N7:0\nMOV N7:0 N7:1\n")
    edit = scan_until_edit(watcher, e)
    assert edit is not None and edit.accepted and edit.summary().endswith("file 2: 1 rung added (2); created N7:1")


def test_a_file_still_changing_is_not_read_and_a_touch_is_no_edit(app_dir):
    app = load_app(app_dir, use_cache=False)
    watcher = ProgramWatcher(app, interval_s=0.05)
    main = app_dir / "main.lad"
    text = main.read_text()
    write(main, text)  # same text, new mtime
    assert watcher.check(now=1.0) is False  # first sight of a new signature: wait for it to settle
    assert watcher.check(now=2.0) is False  # settled, same content: nothing to read
    write(main, text + "OTE B3/1\n")
    assert watcher.check(now=3.0) is False
    write(main, text + "OTE B3/2\n")  # saved again meanwhile
    assert watcher.check(now=4.0) is False  # changed since the last look: wait again
    assert watcher.check(now=5.0) is True  # settled: read in the background
    edit = watcher.wait(10.0)
    assert edit is not None and edit.accepted and edit.changes.summary() == "file 2: 1 rung added (2)"
    assert "B3/2" in str(edit.program.files[2].rungs[2].elements[0])


def test_a_new_lad_file_in_the_app_directory_is_an_edit(app_dir):
    app = load_app(app_dir, use_cache=False)
    e = Engine(app.program)
    e.set_mode(Mode.RUN)
    watcher = ProgramWatcher(app, interval_s=0.05)
    write(app_dir / "main.lad", "XIC B3/0 TON T4:0 0.01 1000 0\nADD N7:0 1 N7:0\nJSR 3\n")
    write(app_dir / "sub.lad", "FILE 3 SUB\nOTE B3/7\n")
    edit = scan_until_edit(watcher, e)
    assert edit is not None and edit.accepted, edit and edit.errors
    assert edit.changes.summary().startswith("file 2: 1 rung added (2); file 3: new, 1 rung")
    e.table.write("B3/7", 0)
    e.scan()
    assert e.table.read("B3/7") == 1


def test_a_valid_program_the_live_table_cannot_take_is_rejected_by_the_watcher(app_dir):
    (app_dir / "main.lad").write_text("MOV 5 N10:0\n")
    app = load_app(app_dir, use_cache=False)
    e = Engine(app.program)
    e.set_mode(Mode.RUN)
    watcher = ProgramWatcher(app, interval_s=0.05)
    write(app_dir / "main.lad", "MOV 1.5 F10:0\n")  # valid alone; the running table has N10
    edit = scan_until_edit(watcher, e)
    assert edit is not None and not edit.accepted and not edit.applied
    assert "main.lad:1:" in edit.errors[0] and "file number 10 is already N10" in edit.errors[0]
    assert app.program is e.program and e.table.read("N10:0") == 5
