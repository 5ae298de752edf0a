"""Memory of a large data table, against the same data as plain Python lists.

Builds 100 N files x 1000 words, 20 ST files x 1000 full 82-character
strings and 10 F files x 1000 floats (every element a non-zero value written
through ``DataTable.write``) in a fresh subprocess, and measures what it
retains above the interpreter's baseline (taken after the imports):

* tracemalloc: peak during the build, and current after ``gc.collect()``
  (the retained size), with and without the address parser's lru cache
  (``parse_address`` caches up to 4096 parsed addresses; they belong to the
  process, not to the table);
* RSS: /proc/self/status VmRSS after the build minus VmRSS before it, in a
  separate child without tracemalloc (tracemalloc's own bookkeeping would
  inflate RSS); median of several children;
* structural: ``sys.getsizeof`` of the arrays, DataFile objects and dict.

The same-run baseline builds the same values as plain lists of int / str /
float in the same way.

Target: at most 8 MB (8 000 000 bytes) retained above baseline. A miss is
reported, never turned into a non-zero exit status.

    python benchmarks/bench_datatable_memory.py
"""

from __future__ import annotations

import gc
import json
import statistics
import subprocess
import sys
import time

import _common as C

TARGET_BYTES = 8_000_000
RSS_CHILDREN = 3
NAME = "bench_datatable_memory"


# -- child side -----------------------------------------------------------------


def _clear_parse_cache() -> bool:
    try:
        from softplc_lite.datatable.address import _parse_cached
    except ImportError:
        return False
    _parse_cached.cache_clear()
    return True


def _type_of(name: str) -> str:
    letters = name.rstrip("0123456789")
    return letters if letters in ("N", "ST", "F") else "other"


def _structural_table(table) -> dict[str, int]:
    """Bytes by file type (N, ST, F; "other" = the default files and the
    table's own dict)."""
    sizes = {"N": 0, "ST": 0, "F": 0, "other": sys.getsizeof(table) + sys.getsizeof(table._files)}
    for f in table.files():
        key = _type_of(f.name) if f.number >= C.N_FIRST else "other"
        sizes[key] += sys.getsizeof(f) + sys.getsizeof(f.data) + sys.getsizeof(f.name)
    return sizes


def _structural_plain(plain: dict) -> dict[str, int]:
    seen: set[int] = set()
    sizes = {"N": 0, "ST": 0, "F": 0, "other": sys.getsizeof(plain)}
    for key, values in plain.items():
        t = _type_of(key)
        sizes[t] += sys.getsizeof(key) + sys.getsizeof(values)
        for v in values:
            if id(v) not in seen:  # small ints are shared objects
                seen.add(id(v))
                sizes[t] += sys.getsizeof(v)
    return sizes


def child(kind: str, mode: str) -> dict:
    out: dict = {"kind": kind, "mode": mode}
    out["rss_interpreter"] = C.vm_rss_bytes()
    import struct  # noqa: F401  (used by the float32 helper; import before the baseline)
    import tracemalloc

    import softplc_lite.datatable  # noqa: F401

    gc.collect()
    out["rss_after_imports"] = C.vm_rss_bytes()
    build = C.build_table if kind == "table" else C.build_plain
    if mode == "trace":
        tracemalloc.start()
    rss0 = C.vm_rss_bytes()
    t0 = time.perf_counter_ns()
    obj = build()
    out["build_ms"] = C.ms(time.perf_counter_ns() - t0)
    gc.collect()
    rss1 = C.vm_rss_bytes()
    if mode == "trace":
        current, peak = tracemalloc.get_traced_memory()
        out["trace_current"] = current
        out["trace_peak"] = peak
    else:
        out["rss_delta"] = rss1 - rss0
    if kind == "table":
        out["structural"] = _structural_table(obj)
        if _clear_parse_cache():
            gc.collect()
            if mode == "trace":
                out["trace_current_no_cache"] = tracemalloc.get_traced_memory()[0]
            else:
                out["rss_delta_no_cache"] = C.vm_rss_bytes() - rss0
        # Sanity: the table really holds the values.
        assert obj.read(f"N{C.N_FIRST}:1") == C.n_value(0, 1)
        assert obj.read(f"ST{C.ST_FIRST + 3}:999") == C.st_value(3, 999)
    else:
        out["structural"] = _structural_plain(obj)
    if mode == "trace":
        tracemalloc.stop()
    return out


# -- parent side ----------------------------------------------------------------


def run_child(kind: str, mode: str) -> dict:
    proc = subprocess.run(
        [sys.executable, __file__, "--child", kind, mode],
        capture_output=True, text=True, check=False, timeout=120,
    )
    if proc.returncode != 0:
        raise SystemExit(f"child {kind}/{mode} failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def mb(n: float) -> str:
    return f"{n / 1e6:7.2f} MB"


def main() -> None:
    t_start = time.perf_counter()
    print(f"{NAME}: {C.describe_data()}")
    print("each build runs in a fresh subprocess; sizes are above the post-import baseline")
    results: dict[str, dict] = {}
    for kind in ("table", "plain"):
        trace = run_child(kind, "trace")
        rss_runs = [run_child(kind, "rss") for _ in range(RSS_CHILDREN)]
        r: dict = {
            "tracemalloc_current": trace["trace_current"],
            "tracemalloc_peak": trace["trace_peak"],
            "rss_delta_median": int(statistics.median(x["rss_delta"] for x in rss_runs)),
            "rss_delta_runs": [x["rss_delta"] for x in rss_runs],
            "structural_getsizeof": sum(trace["structural"].values()),
            "structural_by_type": trace["structural"],
            "build_ms_median": statistics.median(x["build_ms"] for x in rss_runs),
            "rss_interpreter": rss_runs[0]["rss_interpreter"],
            "rss_after_imports": rss_runs[0]["rss_after_imports"],
        }
        if "trace_current_no_cache" in trace:
            r["tracemalloc_current_no_parse_cache"] = trace["trace_current_no_cache"]
            r["rss_delta_no_parse_cache_median"] = int(
                statistics.median(x["rss_delta_no_cache"] for x in rss_runs)
            )
        results[kind] = r

    t, p = results["table"], results["plain"]
    print()
    print(f"{'':40} {'DataTable':>12} {'plain lists':>12} {'table/plain':>11}")

    def row(label: str, a: float, b: float | None) -> None:
        ratio = f"{a / b:10.2f}x" if b else ""
        right = mb(b) if b is not None else ""
        print(f"{label:40} {mb(a):>12} {right:>12} {ratio:>11}")

    row("retained, tracemalloc current after gc", t["tracemalloc_current"], p["tracemalloc_current"])
    if "tracemalloc_current_no_parse_cache" in t:
        row("  same, parse cache cleared", t["tracemalloc_current_no_parse_cache"], None)
    row("retained, RSS delta (median of 3)", t["rss_delta_median"], p["rss_delta_median"])
    if "rss_delta_no_parse_cache_median" in t:
        row("  same, parse cache cleared", t["rss_delta_no_parse_cache_median"], None)
    row("peak during build, tracemalloc", t["tracemalloc_peak"], p["tracemalloc_peak"])
    row("structural (sys.getsizeof)", t["structural_getsizeof"], p["structural_getsizeof"])
    for key, label in (("N", "100 N files"), ("ST", "20 ST files"), ("F", "10 F files")):
        row(f"  {label}", t["structural_by_type"][key], p["structural_by_type"][key])
    print(
        f"{'build time (ms, median)':40} {t['build_ms_median']:12.0f} {p['build_ms_median']:12.0f}"
    )
    print(
        f"interpreter baseline RSS: {mb(t['rss_interpreter']).strip()} at start, "
        f"{mb(t['rss_after_imports']).strip()} after importing softplc_lite.datatable"
    )

    retained = max(t["tracemalloc_current"], t["rss_delta_median"])
    verdict = "PASS" if retained <= TARGET_BYTES else "MISS"
    print(
        f"\n{verdict}: DataTable retains {mb(retained).strip()} (larger of tracemalloc current "
        f"and RSS delta); target <= {mb(TARGET_BYTES).strip()}"
    )
    print(
        f"compactness: plain lists retain {p['tracemalloc_current'] / t['tracemalloc_current']:.1f}x "
        f"the DataTable's memory (tracemalloc current)"
    )
    figures = {
        "data": C.describe_data(),
        "target_bytes": TARGET_BYTES,
        "verdict": verdict,
        "retained_bytes_for_verdict": retained,
        "table": t,
        "plain_lists": p,
        "ratio_plain_over_table_tracemalloc": p["tracemalloc_current"] / t["tracemalloc_current"],
        "ratio_plain_over_table_rss": p["rss_delta_median"] / max(t["rss_delta_median"], 1),
        "wall_s": time.perf_counter() - t_start,
    }
    path = C.write_results(NAME, figures)
    print(f"results: {path.relative_to(C.REPO)} ({figures['wall_s']:.1f} s)")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "--child":
        print(json.dumps(child(sys.argv[2], sys.argv[3])))
    else:
        main()
