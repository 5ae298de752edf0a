"""The ladder benchmark programs: seeded generators of
program text, the initial data table, the per-scan input hook, and an engine
set up to scan them.

This module is imported by bench_ladder.py and by the child processes it
starts, including children that import softplc_lite from another commit's
work tree (a baseline): so it uses only the public API that commit has too
(parse_program, validate, Engine, Settings, Mode, DataTable), and it does not
import _common (which puts this checkout on sys.path).

- boolean: XIC/XIO contacts (I:0..7 and B3 bits) with nested branches, and
  OTE/OTL/OTU outputs (some rungs with parallel output branches);
- mixed: TON, CTU, ADD, MOV, EQU (+OTE), CPT, COP rungs, most behind an XIC;
  sources in N7, results in N10..N12, so nothing overflows every scan.
"""

from __future__ import annotations

import random

SEED = 20240503
B3_WORDS = 256
INPUT_WORDS = 8
N7_WORDS = 1000


# -- program text ----------------------------------------------------------------------------


def _bit(rng: random.Random) -> str:
    if rng.random() < 0.3:
        return f"I:{rng.randrange(INPUT_WORDS):o}/{rng.randrange(16):o}"
    return f"B3/{rng.randrange(B3_WORDS * 16)}"


def _contacts(rng: random.Random, depth: int, n_min: int, n_max: int) -> list[str]:
    out: list[str] = []
    for _ in range(rng.randint(n_min, n_max)):
        if depth > 0 and rng.random() < 0.3:
            legs = [" ".join(_contacts(rng, depth - 1, 1, 2)) for _ in range(rng.randint(2, 3))]
            out.append("BST " + " NXB ".join(legs) + " BND")
        else:
            out.append(f"{rng.choice(('XIC', 'XIC', 'XIO'))} {_bit(rng)}")
    return out


def _coil(rng: random.Random) -> str:
    return f"{rng.choice(('OTE', 'OTE', 'OTE', 'OTL', 'OTU'))} B3/{rng.randrange(B3_WORDS * 16)}"


def boolean_program(rungs: int, seed: int = SEED) -> str:
    rng = random.Random(seed)
    lines = []
    for _ in range(rungs):
        parts = _contacts(rng, 2, 1, 3)
        if rng.random() < 0.15:  # parallel outputs
            parts.append("BST " + " NXB ".join(_coil(rng) for _ in range(rng.randint(2, 3))) + " BND")
        else:
            parts.append(_coil(rng))
        lines.append(" ".join(parts))
    return "\n".join(lines) + "\n"


def mixed_program(rungs: int, seed: int = SEED + 1) -> str:
    rng = random.Random(seed)
    words = N7_WORDS

    def n() -> str:
        return f"N7:{rng.randrange(words)}"

    def cond() -> str:
        return f"XIC {_bit(rng)} " if rng.random() < 0.7 else ""

    # N7 (sources) keeps its initial 0..3; results go to N10..N12, so no
    # rung overflows every scan (which would add a minor fault each time).
    lines = ["DATA N10 1000", "DATA N11 1000", "DATA N12 1000"]
    for k in range(rungs):
        kind = k % 7
        if kind == 0:
            lines.append(f"{cond()}TON T4:{rng.randrange(1000)} 0.01 {rng.randint(5, 200)} 0")
        elif kind == 1:
            lines.append(f"{cond()}CTU C5:{rng.randrange(1000)} {rng.randint(10, 30000)} 0")
        elif kind == 2:
            lines.append(f"{cond()}ADD {n()} {rng.randint(1, 9)} N12:{rng.randrange(words)}")
        elif kind == 3:
            lines.append(f"{cond()}MOV {n()} N10:{rng.randrange(words)}")
        elif kind == 4:
            lines.append(f"EQU {n()} {rng.randint(0, 3)} OTE B3/{rng.randrange(B3_WORDS * 16)}")
        elif kind == 5:
            lines.append(f'{cond()}CPT N12:{rng.randrange(words)} "({n()} + {n()}) * 2 - {n()}"')
        else:
            lines.append(f"{cond()}COP #N10:{rng.randrange(words - 8)} #N11:{rng.randrange(words - 8)} 8")
    return "\n".join(lines) + "\n"


PROGRAMS = {"boolean": boolean_program, "mixed": mixed_program}


def program_text(kind: str, rungs: int) -> str:
    """The benchmark program ``kind`` (boolean or mixed) of ``rungs`` rungs,
    with its own seed (the mixed one's is SEED + 1, so recorded figures stay comparable)."""
    return boolean_program(rungs, SEED) if kind == "boolean" else mixed_program(rungs, SEED + 1)


# -- counting ----------------------------------------------------------------------------------


def _instructions(elements) -> int:
    # Duck-typed (a branch has legs, anything else is an instruction): the
    # AST classes differ between commits and this must count the same on a
    # baseline commit's tree.
    count = 0
    for el in elements:
        legs = getattr(el, "legs", None)
        if legs is None:
            count += 1
        else:
            for leg in legs:
                count += _instructions(leg)
    return count


def count_instructions(program) -> tuple[int, int]:
    """(rungs, instructions) of a validated program; branches (BST/NXB/BND)
    are not instructions."""
    rungs = instructions = 0
    for pfile in program.files.values():
        rungs += len(pfile.rungs)
        for rung in pfile.rungs:
            instructions += _instructions(rung.elements)
    return rungs, instructions


# -- what the scans run against ----------------------------------------------------------------


def initial_table(seed: int = SEED):
    """B3 and N7 with random contents (the same for every executor)."""
    from softplc_lite.datatable import DataTable

    rng = random.Random(seed)
    table = DataTable()
    table.create_file("B", 3, B3_WORDS)
    table.create_file("N", 7, N7_WORDS)
    b3, n7 = table.file(3).data, table.file(7).data
    for k in range(B3_WORDS):
        b3[k] = rng.randrange(-32768, 32768)
    for k in range(N7_WORDS):
        n7[k] = rng.randrange(0, 4)  # EQU against 0..3 hits now and then
    return table


def input_rows(seed: int = SEED) -> list[list[int]]:
    """The 64 rows of I:0..7 words the input hook cycles through."""
    rng = random.Random(seed)
    return [[rng.randrange(-32768, 32768) for _ in range(INPUT_WORDS)] for _ in range(64)]


def input_hook(seed: int = SEED):
    """An input hook writing I:0..7 with the next of 64 seeded rows every
    scan. Each executor gets its own (the row counter is per hook), so two
    executors scanned the same number of times saw the same inputs."""
    words = input_rows(seed)
    state = {"scan": 0}

    def hook(engine) -> None:
        data = engine.table.file(1).data
        row = words[state["scan"] % len(words)]
        state["scan"] += 1
        for k in range(INPUT_WORDS):
            data[k] = row[k]

    return hook


def make_engine(program, executor: str = "compiled"):
    """An Engine on ``program`` in RUN, on simulated time (the default
    clock), with the initial table and the input hook."""
    from softplc_lite.ladder import Engine, Mode, Settings

    # The reference scan of 10,000 rungs takes far longer than the default
    # 500 ms watchdog: raise it (S:28 is a word, at most 32767 ms).
    settings = Settings(watchdog_ms=32767)
    engine = Engine(program, table=initial_table(SEED), settings=settings, executor=executor)
    engine.input_hooks.append(input_hook(SEED))
    engine.set_mode(Mode.RUN)
    return engine


STATUS_FILE = 2


def table_words(table) -> dict[str, list]:
    """Every file's words but the status file's (S:2 holds the scan count,
    scan times and the first-pass bit, which only an engine keeps)."""
    return {f.name: list(f.data) for f in table.files() if f.number != STATUS_FILE}


def table_digest(table) -> str:
    import hashlib

    words = table_words(table)
    return hashlib.sha256(repr(sorted(words.items())).encode()).hexdigest()[:16]
