"""Cost of one word/bit access on the path compiled rungs will use.

``data, i = table.word_ref("N7:5")`` (and ``data, i, m =
table.bit_ref("B3/17")``) are bound once; generated source text is then
``exec``-ed into a function that takes them as default arguments, so inside
the loop they are plain locals (LOAD_FAST), as in compiled rung code. The loop
body is one statement unrolled 100 times inside ``for _ in range(n)``:

    read       x = d[i]
    write      d[i] = v                 (v = 1234, a local)
    bit read   x = (d[i] & m) != 0
    bit set    d[i] = d[i] | m
    empty      x = 0                    (overhead: loop + one trivial statement)

ns per access = (time(body) - time(empty)) / (n * 100), i.e. the empty-loop
overhead is subtracted; the gross figure (nothing subtracted) is also saved.
Each case runs against the table's ``array('h')`` and, in the same run,
against a plain Python list holding the same values; the ratio is
array/list. F-file floats (``array('f')`` from ``word_ref("F8:0")``) are
measured the same way, as an extra.

For comparison, the typed API: ``table.read("N7:5")``, ``table.write("N7:5",
v)``, ``table.read("B3/17")`` per call (string address, hitting the parser's
cache), and the same with a pre-parsed ``Address``.

Best of 7 interleaved repeats (median also saved).

    python benchmarks/bench_word_access.py
"""

from __future__ import annotations

import gc
import statistics
import time

import _common as C

from softplc_lite.datatable import DataTable, parse_address

NAME = "bench_word_access"
UNROLL = 100
REPEATS = 9
TARGET_SAMPLE_NS = 25_000_000  # aim for ~25 ms per timed sample

BODIES = {
    "empty": "x = 0",
    "read": "x = d[i]",
    "write": "d[i] = v",
    "bit_read": "x = (d[i] & m) != 0",
    "bit_set": "d[i] = d[i] | m",
}


def compile_loop(body: str, **bound):
    """A function ``run(n)`` whose loop body is ``body`` unrolled UNROLL times,
    with ``bound`` names as default arguments (locals, like compiled rungs)."""
    params = "".join(f", {name}={name}" for name in bound)
    lines = [f"def run(n{params}):", "    for _ in range(n):"]
    lines += [f"        {body}"] * UNROLL
    namespace = dict(bound)
    exec(compile("\n".join(lines) + "\n", f"<bench {body}>", "exec"), namespace)
    return namespace["run"]


def time_once(fn, n: int) -> int:
    gc_was = gc.isenabled()
    gc.disable()
    try:
        t0 = time.perf_counter_ns()
        fn(n)
        return time.perf_counter_ns() - t0
    finally:
        if gc_was:
            gc.enable()


def calibrate(fn) -> int:
    n = 1
    while True:
        t = time_once(fn, n)
        if t >= TARGET_SAMPLE_NS // 4:
            return max(1, int(n * TARGET_SAMPLE_NS / max(t, 1)))
        n *= 4


def measure(cases: dict[str, tuple], repeats: int = REPEATS) -> dict[str, dict]:
    """cases: name -> (fn, accesses per unit n). Interleaved repeats; returns
    per-case best/median ns per access (gross)."""
    ns_n = {name: calibrate(fn) for name, (fn, _) in cases.items()}
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeats):
        for name, (fn, per_n) in cases.items():
            n = ns_n[name]
            samples[name].append(time_once(fn, n) / (n * per_n))
    return {
        name: {"best": min(s), "median": statistics.median(s), "n": ns_n[name]}
        for name, s in samples.items()
    }


def main() -> None:
    t_start = time.perf_counter()
    table = DataTable()
    table.create_file("N", 7, 1000)  # the default N7 has 1 element
    table.create_file("B", 3, 1000)  # the default B3 has 1 word; B3/17 is word 1
    table.create_file("F", 8, 1000)
    for e in range(1000):
        table.write(f"N7:{e}", C.n_value(0, e) or 1)
        table.write(f"B3:{e}", C.n_value(1, e) & 0x7FF5)  # bit 1 clear to start
        table.write(f"F8:{e}", C.f_value(0, e))

    v, fv = 1234, 2.5
    # Start N7:5 and F8:0 at the values the write cases store, so every read
    # sees the same value whatever ran before it. 1234 is outside CPython's
    # small-int cache, so reading it from the array allocates an int (as most
    # PLC values would); the list hands out the stored object.
    table.write("N7:5", v)
    table.write("F8:0", fv)

    d_arr, i = table.word_ref("N7:5")
    b_arr, bi, m = table.bit_ref("B3/17")
    f_arr, fi = table.word_ref("F8:0")
    d_list, b_list, f_list = d_arr.tolist(), b_arr.tolist(), f_arr.tolist()

    cases: dict[str, tuple] = {"empty": (compile_loop(BODIES["empty"]), UNROLL)}
    containers = {"array": (d_arr, b_arr, f_arr), "list": (d_list, b_list, f_list)}
    for cname, (dw, db, df) in containers.items():
        cases[f"read/{cname}"] = (compile_loop(BODIES["read"], d=dw, i=i), UNROLL)
        cases[f"write/{cname}"] = (compile_loop(BODIES["write"], d=dw, i=i, v=v), UNROLL)
        cases[f"bit_read/{cname}"] = (compile_loop(BODIES["bit_read"], d=db, i=bi, m=m), UNROLL)
        cases[f"bit_set/{cname}"] = (compile_loop(BODIES["bit_set"], d=db, i=bi, m=m), UNROLL)
        cases[f"float_read/{cname}"] = (compile_loop(BODIES["read"], d=df, i=fi), UNROLL)
        cases[f"float_write/{cname}"] = (compile_loop(BODIES["write"], d=df, i=fi, v=fv), UNROLL)

    n7_5 = parse_address("N7:5")
    b3_17 = parse_address("B3/17")
    api = {
        "table.read('N7:5')": ("x = r('N7:5')", {"r": table.read}),
        "table.write('N7:5', v)": ("w('N7:5', v)", {"w": table.write, "v": v}),
        "table.read('B3/17')": ("x = r('B3/17')", {"r": table.read}),
        "table.read(Address)": ("x = r(a)", {"r": table.read, "a": n7_5}),
        "table.write(Address, v)": ("w(a, v)", {"w": table.write, "a": n7_5, "v": v}),
        "table.read(Address bit)": ("x = r(a)", {"r": table.read, "a": b3_17}),
    }
    for label, (body, bound) in api.items():
        cases[f"api/{label}"] = (compile_loop(body, **bound), UNROLL)

    res = measure(cases)
    empty_best, empty_med = res["empty"]["best"], res["empty"]["median"]

    def net(name: str, which: str = "best") -> float:
        return res[name][which] - (empty_best if which == "best" else empty_med)

    print("bench_word_access: ns per access, best of "
          f"{REPEATS} interleaved repeats, {UNROLL}x unrolled body, locals bound as "
          "default args")
    print(f"empty-loop overhead ('x = 0' unrolled): {empty_best:.2f} ns per statement, "
          "subtracted from every figure below")
    print(f"\n{'':26} {'net (overhead subtracted)':^31} {'gross (loop included)':^31}")
    print(f"{'access':26} {'array':>9} {'list':>9} {'array/list':>11} "
          f"{'array':>9} {'list':>9} {'array/list':>11}")
    table_rows = {}
    for op, label in (
        ("read", "word read    x = d[i]"),
        ("write", "word write   d[i] = v"),
        ("bit_read", "bit read     (d[i]&m)!=0"),
        ("bit_set", "bit set      d[i]=d[i]|m"),
        ("float_read", "float read   x = d[i]"),
        ("float_write", "float write  d[i] = v"),
    ):
        a, lst = net(f"{op}/array"), net(f"{op}/list")
        ratio = a / lst if lst > 0 else float("nan")
        table_rows[op] = {
            "array_ns": a, "list_ns": lst, "ratio_array_over_list": ratio,
            "array_ns_median": net(f"{op}/array", "median"),
            "list_ns_median": net(f"{op}/list", "median"),
            "array_ns_gross": res[f"{op}/array"]["best"],
            "list_ns_gross": res[f"{op}/list"]["best"],
        }
        ga, gl = res[f"{op}/array"]["best"], res[f"{op}/list"]["best"]
        table_rows[op]["ratio_gross"] = ga / gl
        print(f"{label:26} {a:9.2f} {lst:9.2f} {ratio:10.2f}x {ga:9.2f} {gl:9.2f} {ga / gl:10.2f}x")

    print("(the net list figures are a few ns, a small difference of two larger timings, so the "
          "net ratio swings between runs; the gross ratio is steadier)")
    print(f"\n{'typed API, per call (net)':26} {'ns':>9} {'/ word_ref':>11}")
    api_rows = {}
    for label in api:
        t = net(f"api/{label}")
        ref_op = "bit_read" if "B3" in label or "bit" in label else (
            "write" if "write" in label else "read")
        ref = table_rows[ref_op]["array_ns"]
        api_rows[label] = {"ns": t, "ns_median": net(f"api/{label}", "median"),
                           "ratio_over_word_ref": t / ref if ref > 0 else None}
        print(f"{label:26} {t:9.1f} {t / ref:10.0f}x")

    figures = {
        "method": (
            f"generated code, body unrolled {UNROLL}x in 'for _ in range(n)', d/i/m/v bound as "
            "default args (locals); empty-loop overhead ('x = 0') subtracted; best of "
            f"{REPEATS} interleaved repeats of ~{TARGET_SAMPLE_NS / 1e6:.0f} ms"
        ),
        "empty_overhead_ns": {"best": empty_best, "median": empty_med},
        "access_ns": table_rows,
        "typed_api_ns": api_rows,
        "raw": res,
        "wall_s": time.perf_counter() - t_start,
    }
    path = C.write_results(NAME, figures)
    print(f"\nresults: {path.relative_to(C.REPO)} ({figures['wall_s']:.1f} s)")


if __name__ == "__main__":
    main()
