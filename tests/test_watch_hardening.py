"""The watch view against sizes that could hang or crash a naive layout:
deep, wide and long rungs, huge snapshot sizes, an app with no rungs,
watch files too big or not text, expressions nested too deep. Layout is
checked through the library, the command line through ``softplc``'s
main() in this process (tests/helpers/cli.py)."""

from __future__ import annotations

import gc
import io
import subprocess
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rich.cells import cell_len
from rich.console import Console

from softplc_lite.datatable import DataTable, parse_address
from softplc_lite.ladder import validate
from softplc_lite.ladder.ast import AddressRef, Branch, Instruction, Rung, address_refs, walk
from softplc_lite.ladder.instructions import BUILTIN
from softplc_lite.watch import cells, layout as layout_module
from softplc_lite.watch.power import rung_power
from softplc_lite.watch.rungs import RungView

from helpers.cli import softplc_here
from helpers.ladder_strategies import programs
from helpers.apps import make_app

ROOT = Path(__file__).resolve().parent.parent


# -- helpers ------------------------------------------------------------------------------------


def ins(mnemonic: str, address: str) -> Instruction:
    return Instruction(mnemonic, [AddressRef(parse_address(address))])


def nested(depth: int, second_leg: bool = True) -> Rung:
    """``XIC B3/0 BST XIC B3/3 NXB ... XIC B3/1 BND ... OTE B3/2``: ``depth``
    branches, each holding the next in its last leg (with
    ``second_leg=False``, each branch has that one leg only: the checker
    refuses it, but the library can build it)."""
    inner: list = [ins("XIC", "B3/1")]
    for _ in range(depth):
        inner = [Branch([[ins("XIC", "B3/3")], inner] if second_leg else [inner])]
    return Rung([ins("XIC", "B3/0"), *inner, ins("OTE", "B3/2")])


def table_for(*rungs_: Rung) -> DataTable:
    table = DataTable()
    for rung in rungs_:
        for instruction in walk(rung.elements):
            for op in instruction.operands:
                for ref in address_refs(op):
                    table.reference(ref.address)
    return table


def draw(rung: Rung, width: int, table: DataTable | None = None, **view) -> list[str]:
    """The rung's lines at ``width`` (no colour, trailing spaces kept)."""
    console = Console(width=width, color_system=None, file=io.StringIO(), record=True)
    console.print(RungView(rung, 0, table or table_for(rung), **view))
    return console.export_text().splitlines()


def layout(rung: Rung, width: int, table: DataTable) -> cells._Block:
    """The rung's body block itself: its width is not cut to a console's."""
    ctx = cells._Context(table, rung_power(rung, table), cells._SymbolNames(None), frozenset(), BUILTIN, True)
    return layout_module._Layout(ctx, rung.elements).rung(width)


def best_time(fn, repeat: int = 5, number: int = 3) -> float:
    """The fastest of ``repeat`` timings of ``number`` calls, per call; the
    garbage collector off meanwhile (its passes cost what the whole test
    process holds, not what ``fn`` does)."""
    best = float("inf")
    gc.collect()
    gc.disable()
    try:
        for _ in range(repeat):
            start = time.perf_counter()
            for _ in range(number):
                fn()
            best = min(best, (time.perf_counter() - start) / number)
    finally:
        gc.enable()
    return best


def app(tmp_path: Path, text: str, name: str = "app") -> Path:
    return make_app(tmp_path / name, text)


# -- layout: linear in the rung's size -----------------------------------------------------------


@pytest.mark.parametrize("width", [64, 100])
@pytest.mark.parametrize("second_leg", [True, False])
def test_deep_rung_layout_grows_linearly(width, second_leg, monkeypatch):
    # A layout that lays each level out twice (at its budget, then narrower)
    # once the rung stops fitting grows exponentially with depth: 14 levels
    # take 5 s at 64 columns, 16 levels 22 s, 23 levels at 100 columns never
    # finish. This checks the work grows linearly. The work is
    # counted (the layout's measurements), not timed: a count holds
    # whatever else the machine runs.
    measured = {}
    real = layout_module._Layout.width

    def counting(self, el, budget, level):
        measured[depth] = measured.get(depth, 0) + 1
        return real(self, el, budget, level)

    monkeypatch.setattr(layout_module._Layout, "width", counting)
    for depth in (8, 16, 32):
        rung = nested(depth, second_leg)
        draw(rung, width, table_for(rung))
    # twice the levels is twice the instructions: about twice the work
    # (doubling the work at each level is 2**8 a step)
    assert 0 < measured[8] and measured[16] < 3 * measured[8], measured
    assert measured[32] < 3 * measured[16], measured


@pytest.mark.timeout(60)
def test_a_32_level_rung_renders_quickly_with_its_outer_instructions():
    text = "XIC B3/0 " + "BST XIC B3/3 NXB " * 32 + "XIC B3/1 " + "BND " * 32 + "OTE B3/2\n"
    from softplc_lite.ladder import load_text

    rung = load_text(text).main.rungs[0]
    table = table_for(rung)
    start = time.perf_counter()
    lines = draw(rung, 100, table)
    elapsed = time.perf_counter() - start
    assert elapsed < 1.0
    assert lines[0].rstrip() == "   Rung 0"
    assert lines[1].startswith("| B3/0 ") and lines[2].startswith("|-] [--")  # the first contact, at the rail
    assert "B3/2" in lines[-3] and "( )--|" in lines[-2]  # the coil, at the right rail
    # levels too deep for 100 columns are summed up in one box, with what it holds
    assert any("+-BST-" in line for line in lines)
    assert any("levels," in line for line in lines)
    assert all(cell_len(line) == 100 for line in lines[1:])  # nothing cut off, every row as wide


@pytest.mark.timeout(60)
@pytest.mark.parametrize("width", [40, 100, 1000])
@pytest.mark.parametrize("second_leg", [True, False])
def test_200_levels_built_by_the_library_render_quickly(width, second_leg):
    rung = nested(200, second_leg)
    table = table_for(rung)
    start = time.perf_counter()
    lines = draw(rung, width, table)
    assert time.perf_counter() - start < 5.0
    assert "B3/0" in lines[1] and any("B3/2" in line for line in lines) and lines[-1].endswith("|")
    block = layout(rung, width, table)
    assert {cells._width(line) for line in block.lines} == {width}


def test_power_flow_of_a_very_deep_rung_needs_no_recursion():
    rung = nested(5000, second_leg=False)
    table = DataTable()
    table.write("B3/0", 1)
    table.write("B3/1", 1)
    power = rung_power(rung, table)  # RecursionError before
    assert power.out is True
    innermost = rung.elements[1]
    for _ in range(4999):
        innermost = innermost.legs[0][0]
    assert power[innermost].power_in is True and power[innermost].legs == (True,)


@pytest.mark.timeout(60)
def test_many_legs_and_long_rungs_render_quickly():
    legs = Rung([ins("XIC", "B3/0"), Branch([[ins("XIC", f"B3/{k}")] for k in range(300)]), ins("OTE", "B3/2")])
    long = Rung([ins("XIC", f"B3/{k}") for k in range(1999)] + [ins("OTE", "O:0/0")])
    for rung in (legs, long):
        table = table_for(rung)
        for width in (40, 100, 1000):
            assert best_time(lambda: draw(rung, width, table), repeat=1, number=1) < 2.0
    # the 300 legs: the bus down the left joins every one of them
    lines = draw(legs, 100)
    assert sum(line[:9] == "|       +" and "] [" in line for line in lines) == 299


def cells_built(monkeypatch) -> list[Instruction]:
    """The instructions whose cells the layout builds from now on: the
    work a drawing does, counted rather than timed (a count does not
    depend on what else the machine is running)."""
    built: list[Instruction] = []
    real = layout_module._bit_cell

    def counting(el, ctx):
        built.append(el)
        return real(el, ctx)

    monkeypatch.setattr(layout_module, "_bit_cell", counting)
    return built


def test_a_long_rung_is_laid_out_only_as_far_as_it_is_drawn(monkeypatch):
    long = Rung([ins("XIC", f"B3/{k}") for k in range(3000)] + [ins("OTE", "O:0/0")])
    table = table_for(long)
    built = cells_built(monkeypatch)
    full = draw(long, 100, table)
    assert len(built) == 3001  # every contact and the coil, each once
    built.clear()
    top = draw(long, 100, table, max_lines=20)
    assert top == full[:20]
    # 20 lines hold a few rows of contacts: only those (and the row that
    # measures past them) are laid out, not the 3,000
    drawn = sum(line.count("] [") for line in top)
    assert 0 < drawn <= len(built) < 3 * drawn + 100, (drawn, len(built))


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(programs(max_rungs=4, subroutines=False), st.integers(40, 140))
def test_every_rung_line_is_exactly_the_width(program, width):
    # Widths are measured apart from building the blocks: the two must agree,
    # or the buses and the right rail would not line up.
    program = validate(program)
    rungs_ = program.main.rungs
    table = table_for(*rungs_)
    for rung in rungs_:
        block = layout(rung, width, table)
        assert {cells._width(line) for line in block.lines} == {width}


# -- the command line: sizes ---------------------------------------------------------------------


@pytest.mark.parametrize("args, message", [
    (("--width", "100000", "--height", "100000"), "argument --width: expected an integer from 40 to 1000, not '100000'"),
    (("--width", "39"), "argument --width: expected an integer from 40 to 1000, not '39'"),
    (("--width", "1001"), "argument --width: expected an integer from 40 to 1000"),
    (("--height", "100000"), "argument --height: expected an integer from 12 to 1000, not '100000'"),
    (("--height", "11"), "argument --height: expected an integer from 12 to 1000, not '11'"),
    (("--width", "wide"), "argument --width: expected an integer from 40 to 1000, not 'wide'"),
    (("--scans", "-1"), "argument --scans: expected an integer 0 or more, not '-1'"),
])
def test_snapshot_size_and_scans_out_of_range_are_usage_errors(tmp_path, args, message):
    # --width 100000 --height 100000 would be ten billion cells to render, a run that never ends: refused first
    out = tmp_path / "view.txt"
    proc = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"),
                        "--snapshot", str(out), *args)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("usage: softplc watch")
    assert f"softplc watch: error: {message}" in proc.stderr
    assert "Traceback" not in proc.stderr and proc.stdout == ""
    assert not out.exists() and not (tmp_path / "state").exists()  # nothing ran


@pytest.mark.parametrize("width, height", [(40, 12), (1000, 1000)])
def test_snapshots_at_the_ends_of_the_size_range(tmp_path, width, height):
    out = tmp_path / "view.txt"
    start = time.monotonic()
    proc = softplc_here("watch", "programs/modbus_master", "--fresh", "--state", str(tmp_path / "state"),
                        "--scans", "20", "--snapshot", str(out), "--width", str(width), "--height", str(height))
    assert proc.returncode == 0, proc.stderr
    assert time.monotonic() - start < 30
    lines = out.read_text(encoding="utf-8").splitlines()
    assert len(lines) == height and {cell_len(line) for line in lines} == {width}


def test_help_gives_the_size_ranges():
    proc = softplc_here("watch", "--help")
    assert proc.returncode == 0
    text = " ".join(proc.stdout.split())
    assert "--width COLS --snapshot width, 40..1000 (default 100)" in text
    assert "--height ROWS --snapshot height, 12..1000 (default 40)" in text
    assert "(0 or more; default 0)" in text


def test_render_refuses_a_size_out_of_range(tmp_path):
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions
    from softplc_lite.watch.snapshot import render
    from softplc_lite.watch.session import WatchOptions, WatchSession

    session = WatchSession(load_app(ROOT / "programs" / "blinker", tmp_path), WatchOptions(run=RunOptions(fresh=True)))
    try:
        with pytest.raises(ValueError, match="--width: expected an integer from 40 to 1000, not 100000"):
            render(session, 100000, 100000)
        with pytest.raises(ValueError, match="--height"):
            render(session, 80, 5)
        assert render(session, 80, 24).export_text().count("\n") == 24
    finally:
        session.quit()


# -- a program with no rungs ---------------------------------------------------------------------


@pytest.mark.parametrize("scans", ["0", "3"])
def test_snapshot_of_a_program_with_no_rungs(tmp_path, scans):
    # IndexError before: the session took the first of no program files
    empty = app(tmp_path, "// nothing\n", "empty")
    out = tmp_path / "view.txt"
    proc = softplc_here("watch", str(empty), "--state", str(tmp_path / "state"), "--scans", scans,
                        "--snapshot", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    text = out.read_text(encoding="utf-8")
    assert " no program file" in text and "(no rungs)" in text
    assert " empty " in text.splitlines()[0]


def test_the_keys_on_a_program_with_no_rungs(tmp_path):
    """Every key of the interactive view (through its real key handling and
    drawing loop, onto a recording console) on an app without rungs."""
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions
    from softplc_lite.watch.screen import WatchScreen, rung_view
    from softplc_lite.watch.session import WatchOptions, WatchSession
    from softplc_lite.watch.terminal import ViewLoop

    empty = app(tmp_path, "// nothing\n", "empty")
    session = WatchSession(load_app(empty, tmp_path / "state"), WatchOptions(run=RunOptions(fresh=True)))
    screens = []

    def draw_(screen) -> None:
        console = Console(width=100, height=30, record=True, file=io.StringIO(), color_system=None)
        console.print(screen)
        screens.append(console.export_text())

    loop = ViewLoop(session, WatchScreen(session, rung_view), draw_)
    try:
        for k in ["j", "k", "down", "up", "pgdown", "pgup", "f", "f", "b", "g", "7", "\r", "n", " ", "\x7f", "\x7f",
                  "n", "+", "-", "r", "p", "F", "B", "3", "/", "1", "=", "1", "\r", "U", "B", "3", "/", "1", "\r"]:
            loop.tick(k)
            assert "(no rungs)" in screens[-1] and " no program file" in screens[-1]
        assert session.selected == 0 and session.top == 0 and session.file is None
        assert session.message == "force removed: B3/1"
        session.toggle_breakpoint()
        assert session.message == "no rung to set a breakpoint on"
        session.next_file()
        assert session.message == "no program file"
        assert session.engine.scans >= 2
        loop.tick("q")
        assert loop.done
    finally:
        session.quit()


def test_the_rung_views_with_an_empty_program_file():
    from softplc_lite.ladder.ast import ProgramFile
    from softplc_lite.watch.rungs import ProgramFileView

    view = ProgramFileView(ProgramFile(2, None, []), DataTable(), height=20, selected=0, first=3)
    console = Console(width=80, record=True, file=io.StringIO(), color_system=None)
    console.print(view)
    assert console.export_text().strip() == "(no rungs)"
    assert view.drawn == 0 and view.last_drawn is None
    assert view.rungs_that_fit(80, 20) == 0


# -- watch files, watch lists, forces, history -----------------------------------------------------


def test_a_watch_file_of_100000_lines_is_refused_at_the_line_past_the_limit(tmp_path):
    from softplc_lite.watch.watchlist import WATCH_MAX

    watch = tmp_path / "big.watch"
    watch.write_text("# N7 words\n" + "".join(f"N7:{k % 1000}\n" for k in range(100_000)), encoding="utf-8")
    start = time.monotonic()
    proc = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"),
                        "--watch-file", str(watch), "--snapshot", str(tmp_path / "view.txt"))
    assert time.monotonic() - start < 30
    assert proc.returncode == 1
    assert proc.stderr.strip() == (f"error: {watch}:{WATCH_MAX + 2}:1: one address too many: the watch list holds "
                                   f"at most {WATCH_MAX} (--watch and --watch-file together)")


def test_watch_file_problems_are_located(tmp_path):
    def run(raw: bytes, *extra: str) -> subprocess.CompletedProcess:
        watch = tmp_path / "list.watch"
        watch.write_bytes(raw)
        return softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"), *extra,
                            "--watch-file", str(watch), "--snapshot", str(tmp_path / "view.txt"))

    where = tmp_path / "list.watch"
    binary = run(b"N7:0\nC5:0.ACC  # counts\n\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    assert binary.returncode == 1 and "Traceback" not in binary.stderr
    assert binary.stderr.strip() == (f"error: {where}:3:1: byte 0x89 is not UTF-8 text (save the file as UTF-8, "
                                     "or as UTF-16 with a byte-order mark)")
    bad = run(b"# watch\nN7:0\n    N7:x  # a typo\n")
    assert bad.returncode == 1
    assert bad.stderr.startswith(f"error: {where}:3:8: bad address 'N7:x'")
    huge = run(b"#" * (2 << 20))
    assert huge.returncode == 1
    assert huge.stderr.strip() == (f"error: {where}: larger than 1024 KiB: a watch file lists at most 256 addresses, "
                                   "one a line")
    full = run(b"N7:0\nN7:1\n", *[a for k in range(255) for a in ("--watch", f"N7:{k}")])
    assert full.returncode == 1 and f"{where}:2:1: one address too many" in full.stderr
    fine = run(b"\xef\xbb\xbfN7:0\r\nLamp # a symbol\r\n\r\n")  # a BOM, CR LF line ends, a symbol
    assert fine.returncode == 0, fine.stderr
    text = (tmp_path / "view.txt").read_text(encoding="utf-8")
    assert "N7:0 " in text and "Lamp " in text


def test_too_many_watch_addresses_and_long_arguments_give_short_errors(tmp_path):
    many = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"),
                        *[a for k in range(300) for a in ("--watch", f"N7:{k}")], "--snapshot", str(tmp_path / "v.txt"))
    assert many.returncode == 1
    assert many.stderr.strip() == "error: --watch: 300 addresses; the watch list holds at most 256"
    long = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"),
                        "--break-when", "N7:0 + " * 10_000 + "1 > 2", "--snapshot", str(tmp_path / "v.txt"))
    assert long.returncode == 1 and "Traceback" not in long.stderr
    assert len(long.stderr) < 400, long.stderr[:400]
    force = softplc_here("watch", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"),
                         "--force", "B3/0=" + "1" * 50_000, "--snapshot", str(tmp_path / "v.txt"))
    assert force.returncode == 1 and len(force.stderr) < 400, force.stderr[:400]


def test_setting_thousands_of_forces_costs_the_same_for_each(tmp_path):
    # a force that resolves every force again makes 10,000 of them take minutes: each must cost the same
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions
    from softplc_lite.watch.forces import parse_force
    from softplc_lite.watch.session import WatchOptions, WatchSession

    session = WatchSession(load_app(ROOT / "programs" / "blinker", tmp_path), WatchOptions(run=RunOptions(fresh=True)))
    try:
        forces = session.forces
        start = time.perf_counter()
        for k in range(10_000):
            forces.set(parse_force(f"B20/{k}={k % 2}"))
        assert time.perf_counter() - start < 5
        session.scan()
        assert session.engine.table.read("B20/9999") == 1 and session.engine.table.read("B20/9998") == 0
        assert forces.remove("B20/9999") and not forces.remove("B20/9999")
        session.engine.table.write("B20/9999", 0)
        session.scan()
        assert session.engine.table.read("B20/9999") == 0 and session.engine.table.read("B20/9997") == 1
    finally:
        session.quit()


def test_history_keeps_fewer_scans_of_a_big_table(tmp_path):
    from softplc_lite.watch.history import MIN_DEPTH, History

    table = DataTable()
    for n in range(10, 30):  # 20 files of 10,000 words: 400 KB a scan
        table.reference(f"N{n}:9999")
    history = History(table, max_bytes=4 << 20)
    for scan in range(1, 201):
        table.write("N10:0", scan)  # every scan differs
        history.record(scan, scan * 10)
    size = len(history.frames[-1].raw)
    assert size >= 400_000
    assert history.kept_bytes == size * len(history.frames) <= 4 << 20
    assert MIN_DEPTH <= len(history.frames) == (4 << 20) // size
    while history.back() is not None:
        pass
    assert table.read("N10:0") == 201 - len(history.frames)  # the oldest kept
    history.latest()
    assert table.read("N10:0") == 200
    # scans that change nothing share one copy: the 1,000 scans fit
    still = History(table, max_bytes=4 << 20)
    for scan in range(1, 1201):
        still.record(scan, scan * 10)
    assert len(still.frames) == 1000 and still.kept_bytes == size


def test_a_prompt_takes_at_most_200_characters(tmp_path):
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions
    from softplc_lite.watch.session import WatchOptions, WatchSession
    from softplc_lite.watch.terminal import PROMPT_MAX, Controller

    session = WatchSession(load_app(ROOT / "programs" / "blinker", tmp_path), WatchOptions(run=RunOptions(fresh=True)))
    try:
        keys = Controller(session)
        for k in ["g", *("9" * 5000), "\r"]:
            keys.key(k)
        assert session.selected == len(session.rungs) - 1  # 999...9 (200 nines): the last rung
        keys.key("F")
        for k in "x" * 1000:
            keys.key(k)
        assert len(keys.buffer) == PROMPT_MAX == 200
    finally:
        session.quit()


def test_a_huge_rung_comment_is_wrapped_only_as_far_as_it_is_drawn(monkeypatch):
    from softplc_lite.watch import rungs as rungs_module

    comment = "\n".join(" ".join(f"word{k}" for k in range(12)) for _ in range(20_000))  # 1.4 MB, one paragraph
    rung = Rung([ins("XIC", "B3/0"), ins("OTE", "B3/1")], comment)
    table = table_for(rung)
    full = draw(rung, 100, table)
    wrapped: list[int] = []  # the characters handed to the wrapper: its work, counted rather than timed
    real = rungs_module._wrapped
    monkeypatch.setattr(rungs_module, "_wrapped", lambda console, text, *rest: (
        wrapped.append(len(text)), real(console, text, *rest))[1])
    top = draw(rung, 100, table, max_lines=30)
    assert top == full[:30] and top[1].startswith("    word0 word1")
    assert 0 < sum(wrapped) <= (30 + 2) * 100  # the drawn lines and two more, of the 1.4 MB


def test_thousands_of_forces_are_counted_not_listed(tmp_path):
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions
    from softplc_lite.watch.snapshot import render
    from softplc_lite.watch.screen import FORCES_SHOWN
    from softplc_lite.watch.session import WatchOptions, WatchSession

    forces = tuple(f"B20/{k}=1" for k in range(5000))
    session = WatchSession(load_app(ROOT / "programs" / "blinker", tmp_path),
                           WatchOptions(run=RunOptions(fresh=True), forces=forces))
    try:
        start = time.perf_counter()
        screen = render(session, 80, 24).export_text()
        assert time.perf_counter() - start < 2
        assert "Rung 0" in screen and "q quit" in screen  # the forces do not push the rungs off the screen
        wide = " ".join(render(session, 1000, 60).export_text().split())
        assert "forces: B20/0=ON B20/1=ON B20/10=ON" in wide and f"and {5000 - FORCES_SHOWN} more" in wide
        assert wide.count("=ON") == FORCES_SHOWN
    finally:
        session.quit()


@pytest.mark.parametrize("condition, message", [
    ("Reading < 1", "ST9:0 holds a string, not a number or a bit"),
    ("T4:0 > 1", "T4:0 is a whole timer; compare one of its words or bits (T4:0.ACC, ...)"),
])
def test_a_break_condition_on_a_string_or_a_whole_timer_is_refused_at_start(tmp_path, condition, message):
    # a TypeError at the first scan before (an internal error, exit 4)
    strings = app(tmp_path, "SYMBOL Reading ST9:0\nDATA ST9 1 = \"WT: 12\"\nXIC B3/0 TON T4:0 0.01 5 0\n")
    proc = softplc_here("watch", str(strings), "--fresh", "--state", str(tmp_path / "state"), "--scans", "2",
                        "--break-when", condition, "--snapshot", str(tmp_path / "view.txt"))
    assert proc.returncode == 1
    assert proc.stderr.strip() == f"error: --break-when {condition!r}: {message}"
