"""Load of the 10,000-rung boolean benchmark program, cold and through the
code cache (targets: at most 1.5 s cold, at most 0.3 s for a program
loaded before; docs/performance.md).

    python benchmarks/bench_load_cache.py [--rungs N] [--runs K]

Each figure is measured in a fresh Python process (imports done before the
clock starts, as a run has them), K runs interleaved cold / warm, median
and best; wall time and the process's CPU time (this machine is shared: CPU
time is the steadier of the two). Cold: parse + validate + Engine
construction (which compiles). Warm: the cache file read and decoded
(ladder/codecache.py) + Engine construction from the cached code. The
baseline in the same run is the cold load; the ratio cold / warm is
printed too. The script exits 0 even on MISS.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import _common as C
from ladder_programs import boolean_program

TARGET_COLD_S = 1.5
TARGET_WARM_S = 0.3

CHILD = r"""
import json, sys, time
sys.path.insert(0, {bench!r})
import _common
from softplc_lite.ladder import Engine, Settings
from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.validate import validate
from softplc_lite.ladder.codecache import CodeCache, cache_key, export_engine
import softplc_lite.ladder.compiler, softplc_lite.ladder.treecodec  # imports are not load
mode, program_file, cache_dir = sys.argv[1:4]
text = open(program_file).read()
key = cache_key([("prog.lad", text)])
cache = CodeCache(cache_dir)
parse_program("XIC B3/0 OTE B3/1\n")  # the parser's tables, built once a process
w0, c0 = time.perf_counter(), time.process_time()
if mode == "cold":
    program = validate(parse_program(text, "prog.lad"))
    engine = Engine(program, settings=Settings(watchdog_ms=32767))
else:
    program, warnings, code = cache.load(key)
    engine = Engine(program, settings=Settings(watchdog_ms=32767), code=code)
w1, c1 = time.perf_counter(), time.process_time()
if mode == "cold" and sys.argv[4:] == ["save"]:
    cache.save(key, program, [], export_engine(engine))
print(json.dumps({{"wall_s": w1 - w0, "cpu_s": c1 - c0}}))
"""


def child(mode: str, program: Path, cache: Path, *extra: str) -> dict:
    code = CHILD.format(bench=str(Path(__file__).resolve().parent))
    out = subprocess.run([sys.executable, "-c", code, mode, str(program), str(cache), *extra],
                         capture_output=True, text=True, check=True, cwd=C.ROOT if hasattr(C, "ROOT") else None)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rungs", type=int, default=10_000)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        program = Path(tmp) / "prog.lad"
        program.write_text(boolean_program(args.rungs))
        cache = Path(tmp) / "state"
        child("cold", program, cache, "save")  # writes the cache
        cold, warm = [], []
        for _ in range(args.runs):
            cold.append(child("cold", program, cache))
            warm.append(child("warm", program, cache))
        size = (cache / "codecache.bin").stat().st_size
    result = {"rungs": args.rungs, "runs": args.runs, "cache_bytes": size}
    print(f"load of the {args.rungs:,}-rung boolean program, {args.runs} fresh processes each, interleaved; "
          f"cache file {size / 1e6:.1f} MB")
    for name, runs, target in (("cold", cold, TARGET_COLD_S), ("warm", warm, TARGET_WARM_S)):
        for clock in ("cpu_s", "wall_s"):
            values = [r[clock] for r in runs]
            result[f"{name}_{clock}"] = {"median": statistics.median(values), "best": min(values),
                                         "all": values}
        med = result[f"{name}_cpu_s"]["median"]
        print(f"  {name}: CPU median {med:.2f} s (best {result[f'{name}_cpu_s']['best']:.2f}), wall median "
              f"{result[f'{name}_wall_s']['median']:.2f} s (best {result[f'{name}_wall_s']['best']:.2f})  "
              f"[{'PASS' if med <= target else 'MISS'} <= {target} s, judged on CPU time]")
    ratio = result["cold_cpu_s"]["median"] / result["warm_cpu_s"]["median"]
    result["cold_over_warm"] = ratio
    print(f"  cold / warm (CPU medians): {ratio:.1f}x")
    path = C.write_results("bench_load_cache", result)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
