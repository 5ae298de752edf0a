"""The figures of bench_ladder.py that need fresh processes:

- against the commit before the block compiler (``baseline_speedup``):
  a child per tree loads the same program text and the parent drives them
  in turn, a block of scans each, so the two trees' scans interleave; the
  figure is the median of the per-block ratios baseline / current, and the
  two tables must agree after the same scans;
- scaling (``scaling``): ns per instruction at 1,000, 10,000, 100,000 rungs,
  one child per size, interleaved the same way;
- memory (``memory``): bytes per instruction after load, tracemalloc in a
  fresh child;
- cold load (``cold_load``): parse, validate, compile in a fresh child.

The children are ladder_child.py; the program text goes to them as a file
written here, so every tree loads exactly the same text.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
CHILD = HERE / "ladder_child.py"


class ChildFailed(RuntimeError):
    """A child process died or answered nonsense; the message holds the end of its stderr."""


class Child:
    """One ladder_child.py process; ``ask`` sends a command, returns its JSON reply."""

    def __init__(self, tree: Path, mode: str, program_file: Path, argv: list[str] | None = None) -> None:
        """ladder_child.py on ``tree``, or any other ``argv`` speaking the same protocol."""
        self.tree = tree
        self.stderr = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 - lives as long as the child; close() ends it
        argv = argv or [sys.executable, str(CHILD), str(tree), mode, str(program_file)]
        self.proc = subprocess.Popen(argv, cwd=str(HERE), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self.stderr, text=True)

    def read(self) -> dict:
        line = self.proc.stdout.readline()
        if not line:
            self.proc.wait(timeout=60)
            self.stderr.seek(0)
            tail = "\n".join(self.stderr.read().strip().splitlines()[-6:])
            raise ChildFailed(f"child on {self.tree} ended (exit {self.proc.returncode}):\n{tail}")
        return json.loads(line)

    def ask(self, command: str) -> dict:
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()
        return self.read()

    def close(self) -> None:
        try:
            if self.proc.poll() is None:
                self.proc.stdin.write("quit\n")
                self.proc.stdin.flush()
                self.proc.wait(timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait()
        self.stderr.close()


def run_child(tree: Path, mode: str, program_file: Path) -> dict:
    """A one-shot child (memory, load): its one JSON reply."""
    child = Child(tree, mode, program_file)
    try:
        return child.read()
    finally:
        child.close()


def write_program(directory: Path, name: str, text: str) -> Path:
    path = directory / f"{name}.lad"
    path.write_text(text, encoding="utf-8")
    return path


def interleaved_blocks(children: dict, blocks: int, scans: dict, commands: dict | None = None) -> dict[str, list[float]]:
    """Per key, the median scan (ns) of each block; the keys take turns
    block by block, their order rotating every block. A key names a child
    (``children[key]``) and what it runs (``commands[key]``, default
    ``scan``: the engine; ``baseline``: the straight-line baseline)."""
    names = list(children)
    commands = commands or {}
    out: dict = {name: [] for name in names}
    for b in range(blocks):
        for name in names[b % len(names):] + names[:b % len(names)]:
            r = children[name].ask(f"{commands.get(name, 'scan')} {scans[name]}")
            if r["mode"] != "RUN":
                raise ChildFailed(f"{name}: the program left RUN ({r['mode']})")
            out[name].append(statistics.median(r["ns"]))
    return out


BEST_ROUNDS, BEST_SCANS = 8, 10


def best_scans(children: dict, rounds: int, scans: int) -> dict[str, list[int]]:
    """Per child, its best scan (thread CPU ns) of ``scans`` consecutive
    ones, each of ``rounds`` rounds taken in turn."""
    out: dict = {name: [] for name in children}
    for _ in range(rounds):
        for name, child in children.items():
            r = child.ask(f"cpuscan {scans}")
            if r["mode"] != "RUN":
                raise ChildFailed(f"{name}: the program left RUN ({r['mode']})")
            out[name].append(min(r["ns"]))
    return out


def baseline_speedup(base_tree: Path, current_tree: Path, program_file: Path, warmup_scans: int,
                     blocks: int, scans_per_block: int) -> dict:
    """Scans of one program on the baseline tree and the current tree,
    interleaved: per-block medians and the median of the per-block ratios."""
    children: dict[str, Child] = {}
    loaded: dict[str, dict] = {}
    try:
        # one load at a time: on two cores, loads side by side would slow each other
        for name, tree in (("baseline", base_tree), ("current", current_tree)):
            children[name] = Child(tree, "serve", program_file)
            loaded[name] = children[name].read()
        for child in children.values():
            child.ask(f"scan {warmup_scans}")
        per_block = interleaved_blocks(children, blocks, {name: scans_per_block for name in children})
        best = best_scans(children, BEST_ROUNDS, BEST_SCANS)
        digests = {name: child.ask("digest") for name, child in children.items()}
    finally:
        for child in children.values():
            child.close()
    base, cur = per_block["baseline"], per_block["current"]
    ratios = [b / c for b, c in zip(base, cur)]
    instructions = loaded["current"]["instructions"]
    return {
        "instructions": instructions,
        "baseline_scan_ns_median": int(statistics.median(base)),
        "current_scan_ns_median": int(statistics.median(cur)),
        "baseline_ns_per_instruction": round(statistics.median(base) / instructions, 1),
        "current_ns_per_instruction": round(statistics.median(cur) / instructions, 1),
        "speedup": round(statistics.median(ratios), 2),
        "speedup_range": [round(min(ratios), 2), round(max(ratios), 2)],
        # The stricter measure: the best of BEST_SCANS consecutive scans in
        # thread CPU time, each round; the old engine's scans vary more than
        # this one's, so its median block is further from its best scan.
        "best_scan_ns": {name: min(v) for name, v in best.items()},
        "speedup_best_scans": round(min(best["baseline"]) / min(best["current"]), 2),
        "speedup_best_scans_rounds": round(statistics.median(
            b / c for b, c in zip(best["baseline"], best["current"])), 2),
        "blocks": blocks,
        "scans_per_block": scans_per_block,
        "tables_equal": digests["baseline"]["digest"] == digests["current"]["digest"],
        "digests": {name: d["digest"] for name, d in digests.items()},
        "load_s": {name: round(r["load"]["total_s"], 2) for name, r in loaded.items()},
    }


def scaling(tree: Path, program_files: dict[int, Path], warmup_scans: int, blocks: int,
            instructions_per_block: int) -> dict:
    """ns per instruction of the compiled scan at each size (rungs ->
    program file), one child each, and of the straight-line baseline built
    from the same rungs in the same child, all interleaved; the ratio of the
    largest size to the smallest as the median of per-block ratios, for the
    engine and for the baseline (what CPython itself does at that size)."""
    children: dict[int, Child] = {}
    loaded: dict[int, dict] = {}
    try:
        for rungs, path in sorted(program_files.items()):  # one load at a time, as in baseline_speedup
            children[rungs] = Child(tree, "serve", path)
            loaded[rungs] = children[rungs].read()
            children[rungs].ask(f"scan {warmup_scans}")
            children[rungs].ask(f"baseline {warmup_scans}")  # builds it
        # about the same work per block for every size, so each block of the
        # small program is not a handful of microseconds of timer noise
        scans = {rungs: max(3, instructions_per_block // loaded[rungs]["instructions"]) for rungs in children}
        keys = [(rungs, what) for rungs in children for what in ("scan", "baseline")]
        per_block = interleaved_blocks({k: children[k[0]] for k in keys}, blocks, {k: scans[k[0]] for k in keys},
                                       {k: k[1] for k in keys})
    finally:
        for child in children.values():
            child.close()
    small, large = min(children), max(children)
    ns = {k: [x / loaded[k[0]]["instructions"] for x in per_block[k]] for k in keys}

    def growth(what: str) -> list[float]:
        return [a / b for a, b in zip(ns[(large, what)], ns[(small, what)])]

    def med(k) -> float:
        return round(statistics.median(ns[k]), 1)

    engine_growth, baseline_growth = growth("scan"), growth("baseline")
    return {
        "sizes": {str(rungs): {"instructions": loaded[rungs]["instructions"],
                               "ns_per_instruction": med((rungs, "scan")),
                               "ns_per_instruction_range": [round(min(ns[(rungs, "scan")]), 1),
                                                            round(max(ns[(rungs, "scan")]), 1)],
                               "baseline_ns_per_instruction": med((rungs, "baseline")),
                               "engine_over_baseline": round(statistics.median(
                                   a / b for a, b in zip(ns[(rungs, "scan")], ns[(rungs, "baseline")])), 2),
                               "scans_per_block": scans[rungs],
                               "load_s": round(loaded[rungs]["load"]["total_s"], 1)}
                  for rungs in children},
        "largest_over_smallest": round(statistics.median(engine_growth), 2),
        "ratio_range": [round(min(engine_growth), 2), round(max(engine_growth), 2)],
        "baseline_largest_over_smallest": round(statistics.median(baseline_growth), 2),
        "baseline_ratio_range": [round(min(baseline_growth), 2), round(max(baseline_growth), 2)],
        "largest": large,
        "smallest": small,
        "blocks": blocks,
    }


def memory(tree: Path, program_file: Path) -> dict:
    r = run_child(tree, "memory", program_file)
    r["bytes_per_instruction"] = round(r["bytes"] / r["instructions"])
    r["bytes_per_instruction_engine_only"] = round(r["bytes_engine_only"] / r["instructions"])
    return r


def cold_load(tree: Path, program_file: Path, runs: int) -> dict:
    """``runs`` fresh processes, cold then warm (through the code cache the
    cold one left) each time; the median and best of each stage."""
    import shutil

    results, warm = [], []
    try:
        for _ in range(runs):
            results.append(run_child(tree, "load", program_file))
            if results[-1].get("cache_saved"):
                w = run_child(tree, "warm", program_file)
                if "error" not in w:
                    warm.append(w)
    finally:
        shutil.rmtree(program_file.with_suffix(".cache"), ignore_errors=True)
    out: dict = {"runs": runs}
    for key in ("parser_setup_s", "parse_s", "validate_s", "compile_s", "total_s", "total_cpu_s"):
        values = [r[key] for r in results]
        out[key] = round(statistics.median(values), 3)
        out[key[:-2] + "_best_s"] = round(min(values), 3)
    # None for a tree without the code cache (or when it could not be used)
    out["warm"] = {"total_s": round(statistics.median(w["total_s"] for w in warm), 3),
                   "total_best_s": round(min(w["total_s"] for w in warm), 3),
                   "total_cpu_s": round(statistics.median(w["total_cpu_s"] for w in warm), 3),
                   "runs": len(warm)} if warm else None
    return out
