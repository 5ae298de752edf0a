"""Shared helpers for the benchmark scripts (stdlib only).

The scripts are run as ``python benchmarks/NAME.py``, so this directory is on
``sys.path`` and they import this module as ``_common``.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
REPO = HERE.parent

# Let the scripts run from a checkout even when the package is not installed,
# and import the tests' helpers (ptypair, modbus_peer, the apps' test helpers).
for _path in (REPO, REPO / "tests"):
    if str(_path) not in sys.path:
        sys.path.insert(1, str(_path))

# -- the standard table: 100 N x 1000, 20 ST x 1000, 10 F x 1000 ---------------

N_FILES, N_WORDS = 100, 1000
ST_FILES, ST_ELEMENTS = 20, 1000
F_FILES, F_ELEMENTS = 10, 1000
STRING_LEN = 82

# File numbers must be unique across types; keep clear of the default files
# (O0 I1 S2 B3 T4 C5 R6 N7 F8).
N_FIRST = 10  # N10..N109
ST_FIRST = N_FIRST + N_FILES  # ST110..ST129
F_FIRST = ST_FIRST + ST_FILES  # F130..F139


def n_value(k: int, e: int) -> int:
    """Element ``e`` of the ``k``-th N file: non-zero, distinct within a file.

    100 x 1000 = 100 000 words cannot all be distinct in 16 bits (65 535
    non-zero values), so the sequence wraps once across files.
    """
    raw = ((k * N_WORDS + e) % 0xFFFF) + 1  # 1..65535
    return raw - 0x10000 if raw & 0x8000 else raw


def st_value(k: int, e: int) -> str:
    """A distinct 82-character ASCII string for element ``e`` of ST file ``k``."""
    stem = f"ST{ST_FIRST + k}:{e:04d}|"
    # Fill with a run of letters whose start depends on the index, so strings
    # differ all along their length, not only in the stem.
    fill_len = STRING_LEN - len(stem)
    start = (k * ST_ELEMENTS + e) % 26
    fill = "".join(chr(65 + (start + j) % 26) for j in range(fill_len))
    return stem + fill


def f_value(k: int, e: int) -> float:
    """A distinct non-zero float for element ``e`` of F file ``k`` (the value
    the table reads back is this rounded to float32)."""
    return (k * F_ELEMENTS + e + 1) / 7.0


def float32(x: float) -> float:
    import struct

    return struct.unpack("<f", struct.pack("<f", x))[0]


def build_table():
    """The standard table, every element written through ``DataTable.write``."""
    from softplc_lite.datatable import DataTable

    table = DataTable()
    for k in range(N_FILES):
        number = N_FIRST + k
        table.create_file("N", number, N_WORDS)
        for e in range(N_WORDS):
            table.write(f"N{number}:{e}", n_value(k, e))
    for k in range(ST_FILES):
        number = ST_FIRST + k
        table.create_file("ST", number, ST_ELEMENTS)
        for e in range(ST_ELEMENTS):
            table.write(f"ST{number}:{e}", st_value(k, e))
    for k in range(F_FILES):
        number = F_FIRST + k
        table.create_file("F", number, F_ELEMENTS)
        for e in range(F_ELEMENTS):
            table.write(f"F{number}:{e}", f_value(k, e))
    return table


def build_plain() -> dict[str, list]:
    """The same values as plain Python lists of ints, strs and floats."""
    plain: dict[str, list] = {}
    for k in range(N_FILES):
        plain[f"N{N_FIRST + k}"] = [n_value(k, e) for e in range(N_WORDS)]
    for k in range(ST_FILES):
        plain[f"ST{ST_FIRST + k}"] = [st_value(k, e) for e in range(ST_ELEMENTS)]
    for k in range(F_FILES):
        plain[f"F{F_FIRST + k}"] = [float32(f_value(k, e)) for e in range(F_ELEMENTS)]
    return plain


def describe_data() -> str:
    return (
        f"{N_FILES} N files x {N_WORDS} words, {ST_FILES} ST files x {ST_ELEMENTS} "
        f"{STRING_LEN}-char strings, {F_FILES} F files x {F_ELEMENTS} floats"
    )


# -- environment and results ----------------------------------------------------


def environment() -> dict:
    return {
        "python": platform.python_version(),
        "implementation": platform.python_implementation(),
        "executable": sys.executable,
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu_count": os.cpu_count(),
        "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def write_results(name: str, figures: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    doc = {"benchmark": name, "environment": environment(), **figures}
    path.write_text(json.dumps(doc, indent=2, sort_keys=False) + "\n", encoding="utf-8")
    return path


def save_figures(name: str, figures: dict, quick: bool, json_path: str | None) -> None:
    """What every benchmark does at its end: the results file (not for a
    --quick run) and, when asked, a copy of the figures at ``json_path``."""
    if not quick:
        print(f"wrote {write_results(name, figures)}")
    if json_path:
        doc = {"benchmark": name, "environment": environment(), **figures}
        Path(json_path).write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {json_path}")


def summarize_ns(samples: list[int]) -> dict:
    return {
        "best_ns": min(samples),
        "median_ns": int(statistics.median(samples)),
        "repeats": len(samples),
    }


def ms(ns: float) -> float:
    return ns / 1e6


def vm_rss_bytes() -> int:
    """Resident set size of this process from /proc/self/status (Linux)."""
    with open("/proc/self/status", encoding="ascii") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                parts = line.split()
                return int(parts[1]) * 1024  # kB
    raise RuntimeError("no VmRSS in /proc/self/status")


def sample_rounds(bodies: dict, numbers: dict[str, int], rounds: int) -> dict[str, list[float]]:
    """ns per call of each body (``body(number)`` runs ``number`` calls), one
    sample per round, the bodies interleaved and their order rotating every
    round so a slow spell of this shared machine lands on all of them; the
    garbage collector paused while sampling. Each body runs once first (warm-up)."""
    import gc
    import time

    for name, body in bodies.items():
        body(numbers[name])
    names = list(bodies)
    samples: dict[str, list[float]] = {name: [] for name in names}
    gc.collect()
    gc.disable()
    try:
        for r in range(rounds):
            for name in names[r % len(names):] + names[:r % len(names)]:
                number = numbers[name]
                t0 = time.perf_counter_ns()
                bodies[name](number)
                samples[name].append((time.perf_counter_ns() - t0) / number)
    finally:
        gc.enable()
    return samples


def median(samples: list[float]) -> float:
    import statistics

    return statistics.median(samples)


def ratio(samples: dict[str, list[float]], slow: str, fast: str) -> float:
    """Median of the per-round ratios slow / fast."""
    import statistics

    return statistics.median(s / f for s, f in zip(samples[slow], samples[fast]))


def print_profile(body, title: str, lines: int = 12) -> None:
    """Runs ``body()`` under cProfile and prints the functions that took the most time
    of their own: what to look at before optimising."""
    import cProfile
    import pstats

    prof = cProfile.Profile()
    prof.enable()
    body()
    prof.disable()
    stats = pstats.Stats(prof)
    print(f"--- cProfile of {title} (times under the profiler, total {stats.total_tt:.2f} s)")
    stats.sort_stats("tottime").print_stats(lines)
