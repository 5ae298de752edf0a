"""The code cache: a program loaded before runs from its cached
tree and compiled code exactly as it runs when compiled afresh, and any
change of what the code depends on makes a new cache."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers.shipped_apps import copy_app
from softplc_lite.app import load_app
from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.ladder import codecache
from softplc_lite.ladder.codecache import CodeCache, cache_key, export_engine
from softplc_lite.runner import Runner, RunOptions

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"

# Every kind of name compiled code binds: arrays, kernels, inline timers and
# counters, a bound instruction (BSL), a resolver (indirect address), JSR
# with parameters (_calls), MCR zone, labels and jumps, an expression.
VARIED = """\
SYMBOL Start B3/0
XIC Start TON T4:0 0.01 5 0
XIC T4:0/DN CTU C5:0 3 0
XIC T4:0/DN RES T4:0
ADD N7:0 1 N7:0
MOV N7:0 N7:[N7:5]
BSL B3:2 R6:0 B3/1 16
CPT N7:3 "N7:0 * 2 - N7:1 | 3"
XIC Start COP #N7:0 #N7:40 4
XIC B3/5 MCR
XIC B3/6 OTE B3/7
MCR
XIO B3/8 JMP 9
OTE B3/9
LBL 9 XIC C5:0/DN OTL B3/10
JSR 3 1 N7:0 N7:20
FILE 3
SBR N7:30
ADD N7:30 100 N7:31
RET N7:31
"""


def _engine(program, code=None):
    e = Engine(program, code=code)
    e.table.write("B3/0", 1)
    if "N7:5" in str(program.main.rungs):
        e.table.write("N7:5", 25)
    e.set_mode(Mode.RUN)
    return e


def _round_trip(text: str, tmp_path: Path):
    """The program compiled, cached, and read back: (fresh engine, cached engine)."""
    program = load_text(text, "prog.lad")
    fresh = _engine(program)
    code = export_engine(fresh)
    assert code is not None
    cache = CodeCache(tmp_path)
    key = cache_key([("prog.lad", text)])
    assert cache.save(key, program, ["a warning"], code), cache.problem
    loaded = cache.load(key)
    assert loaded is not None, cache.problem
    cached_program, warnings, cached_code = loaded
    assert cached_program == program and warnings == ["a warning"]
    return fresh, _engine(cached_program, cached_code)


def test_cached_code_runs_as_freshly_compiled_code(tmp_path):
    fresh, cached = _round_trip(VARIED, tmp_path)
    assert all(callable(compiled._compiler) for compiled, _ in cached.files.values())  # from the cache, not compiled
    for scan in range(40):
        fresh.scan()
        cached.scan()
        assert cached.table == fresh.table, f"scan {scan}"
    assert fresh.table.read("N7:20") == fresh.table.read("N7:0") + 100  # the JSR ran
    assert fresh.table.read("N7:40") == fresh.table.read("N7:0")  # the COP ran (its slices bound again)
    assert fresh.table.read("C5:0.ACC") > 0 and fresh.fault is None and cached.fault is None
    # Positions survive: the watch view and messages point at the same text.
    rung = cached.program.files[3].rungs[1].elements[0]
    assert str(rung.pos) == "prog.lad:19:1"


def test_a_fault_in_cached_code_names_its_rung_and_instruction(tmp_path):
    text = "MOV 9 N7:0\nXIC B3/0 ADD 1 2 N7:2 MOV N7:[N7:0] N7:1 OTE B3/1\n"
    fresh, cached = _round_trip(text, tmp_path)
    for e in (fresh, cached):
        e.table.write("N7:0", 0)
        e.scan()
        e.scan()
    assert cached.fault is not None and cached.fault.message == fresh.fault.message
    assert (cached.fault.file, cached.fault.rung, cached.fault.instruction) == \
        (fresh.fault.file, fresh.fault.rung, fresh.fault.instruction) == (2, 1, "MOV N7:[N7:0] N7:1 at prog.lad:2:23")
    assert cached.table == fresh.table


def test_breakpoints_and_source_work_on_cached_code(tmp_path):
    from softplc_lite.watch.breakpoints import Breakpoints

    fresh, cached = _round_trip(VARIED, tmp_path)
    assert cached.files[2][0].source == fresh.files[2][0].source
    breaks = Breakpoints(cached)
    assert breaks.toggle(2, 4)
    cached.scan()
    fresh.scan()
    assert cached.table == fresh.table and breaks.after_scan() is not None


def _run(app_dir: Path, scans: int = 30):
    app = load_app(app_dir)
    runner = Runner(app, RunOptions(fresh=True))
    try:
        runner.engine.set_mode(Mode.RUN)
        runner.engine.run(scans)
        return app, runner.engine.table
    finally:
        runner.engine.close()


def test_an_app_loads_from_its_cache_the_second_time(tmp_path):
    app_dir = copy_app("blinker", tmp_path)
    first, table1 = _run(app_dir)
    assert first.code is None and first.source_program is not None  # compiled, then cached
    assert (app_dir / ".softplc" / codecache.CACHE_FILE).exists()
    second, table2 = _run(app_dir)
    assert second.code is not None and second.source_program is None
    assert second.program == first.program and second.warnings == first.warnings
    assert table2 == table1


@pytest.mark.parametrize("change", ["program", "settings", "version"])
def test_any_change_of_what_the_code_depends_on_makes_a_new_cache(tmp_path, change, monkeypatch):
    app_dir = copy_app("blinker", tmp_path)
    _run(app_dir)
    if change == "program":
        lad = sorted(app_dir.glob("*.lad"))[0]
        lad.write_text(lad.read_text() + "XIC B3/100 OTE B3/101\n")
    elif change == "settings":
        toml = app_dir / "softplc.toml"
        toml.write_text((toml.read_text() if toml.exists() else "") + "\n# changed\n")
    else:
        monkeypatch.setattr(codecache, "softplc_version", lambda: "99.0")
    again = load_app(app_dir)
    assert again.code is None  # not the stale cache
    _, table = _run(app_dir)
    if change == "program":
        assert "B3/101" in str(load_app(app_dir).program.main.rungs[-1].elements)
    assert load_app(app_dir).code is not None  # the new one


def test_the_module_set_is_part_of_the_key():
    parts = [("main.lad", b"XIC B3/0 OTE B3/1\n")]
    assert cache_key(parts) != cache_key(parts + [("module COMGENIUS 1.0 x", b"")])
    assert cache_key(parts) == cache_key(list(parts))


@pytest.mark.parametrize("damage", [b"", b"\x00garbage\xff" * 50, "truncate"])
def test_a_damaged_cache_is_ignored_and_replaced(tmp_path, damage):
    app_dir = copy_app("blinker", tmp_path)
    _, table1 = _run(app_dir)
    path = app_dir / ".softplc" / codecache.CACHE_FILE
    blob = path.read_bytes()
    path.write_bytes(blob[: len(blob) // 2] if damage == "truncate" else damage)
    app = load_app(app_dir)
    assert app.code is None and app.code_cache.problem is not None or damage == b""
    _, table2 = _run(app_dir)
    assert table2 == table1
    assert load_app(app_dir).code is not None  # rewritten


def test_an_unwritable_state_directory_only_loses_the_cache(tmp_path):
    app_dir = copy_app("blinker", tmp_path)
    cache = CodeCache(app_dir / "plain-file" / "sub")
    (app_dir / "plain-file").write_text("not a directory")
    program = load_text("XIC B3/0 OTE B3/1\n")
    assert not cache.save("k", program, [], export_engine(Engine(program)))
    assert "not written" in cache.problem


@pytest.mark.parametrize("app_name", sorted(p.name for p in PROGRAMS.iterdir() if any(p.glob("*.lad"))))
def test_every_shipped_app_caches_and_compiles_the_same_code(tmp_path, app_name):
    app_dir = copy_app(app_name, tmp_path)
    app = load_app(app_dir)
    engine = Engine(app.program, modules=app.modules)
    try:
        code = export_engine(engine)
        assert code is not None, f"{app_name}: some name of its code has no recipe"
        cache = CodeCache(tmp_path / "cache")
        assert cache.save("k", app.program, [], code), cache.problem
        program, _, cached = cache.load("k")
    finally:
        engine.close()
    again = Engine(program, modules=app.modules, code=cached)
    try:
        for number, (compiled, _) in engine.files.items():
            assert again.files[number][0].source == compiled.source
    finally:
        again.close()


def test_code_that_does_not_fit_the_program_is_compiled_afresh():
    program = load_text("XIC B3/0 TON T4:0 0.01 5 0\nXIC T4:0/DN OTE B3/1\n")
    fresh = _engine(program)
    odd = _engine(program, {"files": {2: ("not", "a", "compiled", "file")}, "layout": ()})
    for _ in range(10):
        fresh.scan()
        odd.scan()
    assert odd.table == fresh.table and odd.table.read("B3/1") == 1
