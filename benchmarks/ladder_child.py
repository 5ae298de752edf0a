"""A child process of bench_ladder.py: one softplc_lite work tree, one
program, in a fresh interpreter (so a baseline commit imports its own
package, and a memory or cold-load figure starts from nothing).

    python benchmarks/ladder_child.py TREE MODE PROGRAM_FILE

MODE:

- ``serve``: load the program (timed), build a compiled Engine with the
  benchmark's initial table and input hook (ladder_programs), print one JSON
  line, then answer commands read from stdin, one JSON line each:
  ``scan N`` (N scans, each timed: ``{"ns": [...]}``), ``baseline N`` (the
  same with the straight-line baseline, built at its first use; boolean
  programs only), ``digest`` (a hash of
  the table without the status file, and the mode), ``quit``. The parent
  drives two or more children in turn, so their scans interleave.
- ``memory``: tracemalloc's current size after loading (parse, validate,
  Engine construction) and gc.collect(), the program tree kept alive as a
  runner keeps it (``Runner`` holds the engine, the engine its program);
  after a one-rung load, so lazy imports and parser tables are not counted.
- ``load``: the cold load times: parser set-up (a first one-rung parse),
  then parse, validate, compile (Engine construction) of the program; it
  leaves the code cache (where the tree has one) in PROGRAM_FILE's
  ``.cache`` directory for ``warm``.
- ``warm``: the load through that cache (wall and CPU seconds).

Only the public API is used (parse_program, validate, Engine), the same in
every tree compared.
"""

from __future__ import annotations

import gc
import json
import sys
import time
from pathlib import Path

TREE = Path(sys.argv[1]).resolve()
sys.path.insert(0, str(TREE))

import softplc_lite

if not softplc_lite.__file__.startswith(str(TREE)):
    raise SystemExit(f"imported {softplc_lite.__file__}, not the tree {TREE}")

import ladder_programs as L

from softplc_lite.ladder import parse_program, validate


def reply(doc: dict) -> None:
    sys.stdout.write(json.dumps(doc) + "\n")
    sys.stdout.flush()


def load(text: str):
    t0 = time.perf_counter()
    parsed = parse_program(text, "<bench>")
    t1 = time.perf_counter()
    program = validate(parsed)
    t2 = time.perf_counter()
    engine = L.make_engine(program)
    t3 = time.perf_counter()
    times = {"parse_s": t1 - t0, "validate_s": t2 - t1, "compile_s": t3 - t2, "total_s": t3 - t0}
    return program, engine, times


def timed_scans(scan, count: int, clock=time.perf_counter_ns) -> list[int]:
    """``count`` consecutive scans, each timed (ns) by ``clock``: wall time,
    or thread CPU time (time.thread_time_ns: what the scan itself costs,
    whatever else the machine runs)."""
    samples = []
    gc.collect()
    gc.disable()
    try:
        for _ in range(count):
            t0 = clock()
            scan()
            samples.append(clock() - t0)
    finally:
        gc.enable()
    return samples


def straight_line_scan(program):
    """The straight-line baseline (straight_line.py) on its own copy of the
    initial table, with its own input hook: one call is one scan."""
    import types

    import straight_line

    table = L.initial_table(L.SEED)
    function = straight_line.build(program, table).scan
    hook = L.input_hook(L.SEED)
    holder = types.SimpleNamespace(table=table)

    def scan() -> None:
        hook(holder)
        function()

    return scan


def serve(text: str) -> None:
    program, engine, times = load(text)
    rungs, instructions = L.count_instructions(program)
    del text
    reply({"load": times, "rungs": rungs, "instructions": instructions})
    baseline_scan = None
    for line in sys.stdin:
        command, _, arg = line.strip().partition(" ")
        if command == "scan":
            reply({"ns": timed_scans(engine.scan, int(arg)), "mode": engine.mode.name})
        elif command == "cpuscan":
            reply({"ns": timed_scans(engine.scan, int(arg), time.thread_time_ns), "mode": engine.mode.name})
        elif command == "baseline":
            if baseline_scan is None:
                baseline_scan = straight_line_scan(program)
            reply({"ns": timed_scans(baseline_scan, int(arg)), "mode": "RUN"})
        elif command == "digest":
            reply({"digest": L.table_digest(engine.table), "mode": engine.mode.name,
                   "fault": str(engine.fault) if engine.fault else None})
        elif command == "quit":
            break


def memory(text: str) -> None:
    import tracemalloc

    # Imports done lazily at a first load and the parser's tables are paid
    # once per process, not per instruction: a one-rung load first, untraced.
    warm = load("XIC B3/0 OTE B3/1\n")
    del warm
    gc.collect()
    tracemalloc.start()
    program, engine, times = load(text)
    rungs, instructions = L.count_instructions(program)
    gc.collect()
    with_tree, peak = tracemalloc.get_traced_memory()
    # What the compiled engine alone holds, should it not keep the tree: the
    # same measure with this script's own reference to the program dropped.
    del program
    gc.collect()
    engine_only, _ = tracemalloc.get_traced_memory()
    top = tracemalloc.take_snapshot().statistics("filename")[:6]
    tracemalloc.stop()
    reply({"rungs": rungs, "instructions": instructions, "bytes": with_tree, "peak_bytes": peak,
           "bytes_engine_only": engine_only, "load_under_tracemalloc_s": times["total_s"],
           "top_files": [{"file": str(s.traceback[0].filename).rsplit("/", 2)[-1] if s.traceback else "?",
                          "bytes": s.size} for s in top],
           "alive": engine is not None})


def cold_load(text: str, cache_dir: Path) -> None:
    # A one-rung load first: the parser's tables and the modules a first
    # load imports are paid once a process, whatever the program (as
    # bench_load_cache.py, which imports them before its clock starts).
    t0 = time.perf_counter()
    load("XIC B3/0 OTE B3/1\n")
    setup = time.perf_counter() - t0
    cpu0 = time.process_time()
    program, engine, times = load(text)
    times["total_cpu_s"] = time.process_time() - cpu0
    rungs, instructions = L.count_instructions(program)
    # WARM LOAD (the code cache kept beside the retentive state):
    # this cold load leaves the cache in cache_dir, and the "warm" child, a
    # fresh process, loads the same text through it.
    saved = False
    try:
        from softplc_lite.ladder.codecache import CodeCache, cache_key, export_engine
    except ImportError:  # a tree before the code cache
        pass
    else:
        saved = CodeCache(cache_dir).save(cache_key([("prog.lad", text)]), program, [], export_engine(engine))
    reply({"parser_setup_s": setup, **times, "rungs": rungs, "instructions": instructions, "cache_saved": saved})


def warm_load(text: str, cache_dir: Path) -> None:
    """The load through the code cache the cold load left (codecache.py):
    the cache file read and decoded, and the Engine built from its code."""
    from softplc_lite.ladder import Engine, Mode, Settings
    from softplc_lite.ladder.codecache import CodeCache, cache_key

    parse_program("XIC B3/0 OTE B3/1\n", "<setup>")  # as in cold_load: not part of either figure
    t0, cpu0 = time.perf_counter(), time.process_time()
    cached = CodeCache(cache_dir).load(cache_key([("prog.lad", text)]))
    if cached is None:
        reply({"error": "no usable cache"})
        return
    program, _warnings, code = cached
    engine = Engine(program, table=L.initial_table(L.SEED), settings=Settings(watchdog_ms=32767), code=code)
    engine.set_mode(Mode.RUN)
    reply({"total_s": time.perf_counter() - t0, "total_cpu_s": time.process_time() - cpu0})


def main() -> int:
    mode, program_file = sys.argv[2], Path(sys.argv[3])
    text = program_file.read_text(encoding="utf-8")
    cache_dir = program_file.with_suffix(".cache")
    if mode == "load":
        cold_load(text, cache_dir)
    elif mode == "warm":
        warm_load(text, cache_dir)
    else:
        {"serve": serve, "memory": memory}[mode](text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
