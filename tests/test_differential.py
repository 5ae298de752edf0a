"""Differential tests: the compiled fast path against the reference
interpreter on random programs, and fmt round trips.

(a) Random valid programs (tests/helpers/ladder_strategies.py) run for SCANS scans
    through ``Engine(program, executor="compiled")`` and
    ``Engine(program, executor="reference")`` from the same initial table,
    with the same input words written into I:0 and B3:0 before every scan
    (an input hook). After every scan the data tables, the modes and the
    fault records (code, file, rung, instruction, message) must be
    identical. The compiler's block size is drawn too, so rungs compiled
    in separate blocks (as in big files: words held in locals written back
    at each block's end) are covered, and after the first scan some rungs
    are made blocks of their own (as a watch-view breakpoint does).
(b) ``parse_program(format_program(p, style)) == p`` for random programs in
    both styles, and the two printed forms parse to the same program.
(c) The same round trip for every .lad file under programs/ (skipped while
    there are none), and both executors on each of them.
(d) Regression cases for the mismatches the random programs found.
"""

from __future__ import annotations

import dataclasses

from pathlib import Path
from unittest import mock

import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from helpers.ladder_strategies import ADDRESS_SPACE, F8_FLOATS, N7_WORDS, input_seeds, input_words, programs
from softplc_lite.datatable import DataTable, to_signed
from softplc_lite.ladder import Engine, Mode, blocks, validate
from softplc_lite.ladder.fmt import format_program
from softplc_lite.app import app_instructions, load_app
from softplc_lite.ladder.parser import parse_program
from softplc_lite.tlm import load_modules
from helpers.modbus_peer import free_tcp_port

SCANS = 50
REPO = Path(__file__).resolve().parent.parent
LAD_FILES = sorted((REPO / "programs").rglob("*.lad"))
# What runs: a stand-alone .lad, or an app directory whose program is several files.
PROGRAMS = sorted({p.parent if len(list(p.parent.glob("*.lad"))) > 1 else p for p in LAD_FILES})

FAST = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def table_diff(a, b, limit: int = 12) -> str:
    """The words that differ between two tables, for the failure message."""
    lines = []
    fa, fb = {f.number: f for f in a.files()}, {f.number: f for f in b.files()}
    for n in sorted(set(fa) | set(fb)):
        if n not in fa or n not in fb:
            lines.append(f"file {n} only in {'compiled' if n in fa else 'reference'}")
            continue
        da, db = fa[n].data, fb[n].data
        if len(da) != len(db):
            lines.append(f"{fa[n].name}: {len(da)} vs {len(db)} words")
        for k, (x, y) in enumerate(zip(da, db)):
            if x != y and not (x != x and y != y):
                lines.append(f"{fa[n].name} word {k}: compiled {x!r} reference {y!r}")
            if len(lines) >= limit:
                return "\n".join(lines)
    return "\n".join(lines)


def fault_of(engine):
    f = engine.fault
    return None if f is None else (f.code, f.file, f.rung, f.instruction, f.message)


def run_pair(program, initial: dict, words: list[tuple[int, int | None]], space=ADDRESS_SPACE, modules=lambda: ()):
    """Both executors side by side; yields (scan, compiled, reference).
    ``words``: per scan, the raw I:0 word and B3:0 word (None: leave B3:0).
    ``modules``: makes each engine its own plug-in modules (TLMs)."""
    engines = []
    for executor in ("compiled", "reference"):
        table = DataTable()
        for addr in [*space, *initial]:
            table.reference(addr)
        engine = Engine(program, table=table, executor=executor, modules=modules())
        for addr, value in initial.items():
            engine.table.write(addr, value)
        scan = iter(words)

        def hook(e, scan=scan):
            i0, b30 = next(scan)
            e.table.file(1).data[0] = to_signed(i0)
            if b30 is not None:
                e.table.file(3).data[0] = to_signed(b30)

        engine.input_hooks.append(hook)
        engine.set_mode(Mode.RUN)
        engines.append(engine)

    compiled, reference = engines
    assert compiled.table == reference.table, "tables differ before the first scan"
    for k in range(len(words)):
        compiled.scan()
        reference.scan()
        yield k, compiled, reference


initial_values = st.fixed_dictionaries({
    # N7:0..3 serve as indexes too (N7:[N7:1]): mostly in range.
    **{a: st.one_of(*[st.integers(0, 9)] * 4, st.integers(-32768, 32767)) for a in N7_WORDS},
    **{a: st.floats(-1e4, 1e4, allow_nan=False, width=32) for a in F8_FLOATS},
})


@settings(max_examples=300, **FAST)
@given(prog=programs(), initial=initial_values, seed=input_seeds, chunk=st.sampled_from([200, 1, 2, 3]),
       isolated=st.lists(st.tuples(st.integers(2, 4), st.integers(0, 12)), max_size=3))
def test_compiled_and_reference_agree(prog, initial, seed, chunk, isolated):
    note(format_program(prog, "mnemonic"))
    program = validate(prog)
    # Small blocks: rungs compiled a few at a time, as in big files.
    with mock.patch.object(blocks, "CHUNK_RUNGS", chunk):
        for k, compiled, reference in run_pair(program, initial, input_words(seed, SCANS)):
            if k == 0:  # rungs made blocks of their own while running, as breakpoints do
                for number, rung in isolated:
                    if number in compiled.files and rung < compiled.files[number][0].rung_count:
                        compiled.files[number][0].isolate(rung)
            assert fault_of(compiled) == fault_of(reference), f"scan {k}: faults differ"
            assert compiled.mode is reference.mode, f"scan {k}: modes differ"
            assert compiled.table == reference.table, f"scan {k}: tables differ\n" + table_diff(
                compiled.table, reference.table)
            if compiled.mode is Mode.FAULTED:
                break


@settings(max_examples=150, **FAST)
@given(prog=programs())
def test_fmt_round_trip_random_programs(prog):
    texts = {}
    for style in ("mnemonic", "neutral"):
        texts[style] = format_program(prog, style)
        note(f"--- {style} ---\n{texts[style]}")
        again = parse_program(texts[style], f"<{style}>")
        assert again == prog, style
        assert format_program(again, style) == texts[style]
    mnemonic = parse_program(texts["mnemonic"])
    assert parse_program(format_program(mnemonic, "neutral")) == mnemonic


def _round_trip(path: Path) -> None:
    # The app's instruction set: the built-in instructions and those of the
    # modules its MODULES.LST enables.
    instructions = app_instructions(path)
    program = parse_program(path.read_text(encoding="utf-8"), str(path), instructions)
    for style in ("mnemonic", "neutral"):
        text = format_program(program, style)
        assert parse_program(text, f"<{style} of {path.name}>", instructions) == program, style
        assert format_program(parse_program(text, instructions=instructions), style) == text, style


@pytest.mark.parametrize("path", LAD_FILES or [None], ids=lambda p: str(p.relative_to(REPO)) if p else "none")
def test_fmt_round_trip_programs_dir(path):
    if path is None:
        pytest.skip("no .lad files under programs/ yet")
    _round_trip(path)


@pytest.mark.parametrize("path", PROGRAMS or [None], ids=lambda p: str(p.relative_to(REPO)) if p else "none")
def test_programs_dir_executors_agree(path):
    """Each program under programs/ (a stand-alone .lad, or an app of several)
    runs the same on both executors."""
    if path is None:
        pytest.skip("no .lad files under programs/ yet")
    app = load_app(path)
    words = [((k * 40503) & 0xFFFF, None) for k in range(SCANS)]
    app_dir = path if path.is_dir() else path.parent
    def modules():  # fresh modules for each engine
        found = load_modules(app_dir)[0]
        for m in found:
            if m.name in ("MODBTCPS", "ENIPS", "OPCUAS"):  # two engines at once: two servers, each on a port of its own
                m.config = dataclasses.replace(m.config, port=free_tcp_port())
        return found
    for k, compiled, reference in run_pair(app.program, {}, words, space=(), modules=modules):
        assert fault_of(compiled) == fault_of(reference), f"scan {k}"
        assert compiled.table == reference.table, f"scan {k}\n" + table_diff(compiled.table, reference.table)


# Cases the random programs found, or could find only rarely, kept as
# regression tests: each must run the same on both executors.
REGRESSIONS = {
    # The compiler's fast paths for N12:[N13:3], O:[N7:1]/[N7:2] and N[N9:0]:[N9:1]
    # (fixed shapes of indirect address) agree with the general resolver,
    # faults included: a file number naming no file or one of another type,
    # an element or a bit number out of range.
    "fast-file-indirect": "DATA N9 3 = 10 2 0\nDATA N10 3 = 5 6 7\nDATA F11 1\nADD N[N9:0]:[N9:1] 1 N9:2\n"
                          "ADD N9:1 1 N9:1\nEQU N9:1 4 MOV 11 N9:0\n",
    "fast-file-indirect-none": "DATA N9 2 = 10 0\nDATA N10 2\nMOV N[N9:0]:[N9:1] N7:0\nADD N9:0 1 N9:0\n",
    "fast-element-bit": "DATA N9 2 = 0 14\nXIC I:0/0 OTE O:[N9:0]/[N9:1]\nADD N9:1 1 N9:1\nXIC O:[N9:0]/[N9:1] OTE B3/0\n",
    "fast-element-range": "DATA N9 1 = 1\nDATA N10 3\nMOV N9:0 N10:[N9:0]\nADD N9:0 1 N9:0\n",
    # An out-of-range OTL/OTU address faults even on a false rung (as OTE, XIC do).
    "otl-false-rung": "DATA N9 1 = 70\nXIC B3/1 OTL B3/[N9:0]\n",
    "otu-false-rung": "DATA N9 1 = 70\nXIC B3/1 OTU N7:[N9:0]/1\n",
    # OSR writes its output bit into N7:0, the index word of its own storage
    # bit: the storage is resolved once, before the write.
    "osr-own-index": "MOV 0 N7:0\nXIC I:0/0 OSR N7:[N7:0]/1 N7:0/2\nXIC I:0/0 OTE N7:3/0\n",
    "osf-own-index": "MOV 0 N7:0\nXIO I:0/0 OSF N7:[N7:0]/1 N7:0/2\nXIC I:0/0 OTE N7:3/0\n",
    # Every address of an expression (and a CPT destination) is resolved
    # before the computation: the address fault comes first, and the
    # division by zero sets no minor fault bits.
    "cpt-fault-before-div0": 'DATA N9 1 = 70\nCPT N7:1 "N7:2 | 0 + N7:[N9:0]"\n',
    "cpt-dest-fault-before-div0": 'DATA N9 1 = 70\nCPT N7:[N9:0] "N7:2 | 0 + N7:1"\n',
    "cmp-fault-before-mod0": 'DATA N9 1 = 70\nCMP "N7:2 MOD 0 = N7:[N9:0]" OTE N7:1/0\n',
    # "5 MOD 3": MOD after a number was lexed as a name.
    "mod-after-number": 'CPT N7:0 "5 MOD 3"\nCPT(N7:1,7.5 MOD 2);\nCMP "0x7 MOD N7:0 = 1" OTE B3/0\n',
    # Floats stored into words at exact halves (random floats almost never are):
    # one rounding rule (ladder/rounding.py) on both executors, overflow included.
    "float-to-integer-halves": 'DATA N9 1\nDATA F10 4 = 2.5 -2.5 0.5 32767.5\nMOV F10:[N9:0] N7:0\n'
                               'CPT N7:1 "F10:[N9:0] * 3"\nADD F10:[N9:0] 0 N7:2\nTOD F10:0 N7:3\n'
                               'FLL F10:[N9:0] #N7:4 2\nSCP F10:[N9:0] 0.0 1.0 0.0 1.0 N7:6\n'
                               'CPT N7:7 "F10:[N9:0] OR 0"\nADD N9:0 1 N9:0\nAND N9:0 3 N9:0\n',
}


@pytest.mark.parametrize("name", sorted(REGRESSIONS))
def test_regressions_agree(name):
    text = REGRESSIONS[name]
    program = validate(parse_program(text, name))
    words = [(0x0001 if k % 3 else 0, None) for k in range(6)]
    for k, compiled, reference in run_pair(program, {}, words, space=()):
        assert fault_of(compiled) == fault_of(reference), f"scan {k}"
        assert compiled.table == reference.table, f"scan {k}\n" + table_diff(compiled.table, reference.table)
    for style in ("mnemonic", "neutral"):
        assert parse_program(format_program(program, style)) == program
