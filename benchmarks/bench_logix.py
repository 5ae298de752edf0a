"""What a Logix export costs: its load time, and its scan time against the
same rungs written as PLC-5 text, loaded and scanned by the same engine in
the same run (target: the export at most 1.5x the text's scan time).

    python benchmarks/bench_logix.py                   # a real whole-controller export; about 30 s
    python benchmarks/bench_logix.py --export X.L5X    # another export
    python benchmarks/bench_logix.py --quick           # a smoke run, results not written

The PLC-5 text is the export's program as softplc fmt prints it (every
rung, its DATA, the Logix instructions by their ladder names; a DINT used
as an index becomes a 16-bit word, as PLC-5 text wants, and a string's
initial text printable ASCII): the same rungs, so the ratio is what the
export's own path adds (loading aside).
Beside it, the instructions whose Logix rules are written apart
(ladder/instr/logix.py): 100 rungs of Logix TON (LTON on three L items)
against 100 of PLC-5's TON on T4 elements, and the same for CTU, in the
same engine, so the cost of Logix's timers and counters over PLC-5's is
measured on its own.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import _common as C

from softplc_lite.app import load_app
from softplc_lite.ladder.fmt import format_program
from softplc_lite.runner import RunOptions, Runner

TARGET = 1.5
FULL = {"rounds": 7, "scans": 2000, "loads": 5}
QUICK = {"rounds": 2, "scans": 300, "loads": 1}


# The largest whole-controller export in this repository (135 rungs over 10 routines, a real
# project's: tests/fixtures/logix/public/README.md says whose); the gathered corpus's largest is
# measured with --export (docs/logix.md, "Measured").
DEFAULT_EXPORT = (C.REPO / "tests" / "fixtures" / "logix" / "public" / "andreenko-repo__rockwell_logic_l5x_extractor"
                  / "BoosterCompressor_20260128.L5X")


def plc5_text(program) -> str:
    """The program as .lad text: its file names (``MainProgram.MainRoutine``)
    made names a FILE header takes."""
    import copy
    import re

    twin = copy.copy(program)
    twin.files = {n: copy.copy(f) for n, f in program.files.items()}
    for f in twin.files.values():
        f.name = re.sub(r"\W", "_", f.name) if f.name else f.name
    # a string's initial text in .lad DATA is one line of printable ASCII: others' characters as '?'
    twin.data = [copy.copy(d) for d in program.data]
    for d in twin.data:
        d.values = [re.sub(r"[^ -~]", "?", v).replace('"', "'") if isinstance(v, str) else v for v in d.values]
    return _word_indexes(format_program(twin))


def _word_indexes(text: str) -> str:
    """PLC-5 text takes a 16-bit word as an indirect reference (N12:[N7:1]),
    Logix a DINT: each DINT an index names (L14:370 in F12:[L14:370]) becomes
    a word of a file of its own everywhere the text names it, with its
    initial value (the same rungs, in PLC-5's terms)."""
    import re

    used = sorted(set(re.findall(r"\[(L\d+:\d+)\]", text)))
    if not used:
        return text
    data = {m.group(1): m.group(2).split() for m in re.finditer(r"^DATA (L\d+) \d+ = (.*)$", text, re.M)}
    numbers = [int(n) for n in re.findall(r"^DATA [A-Z]+(\d+) ", text, re.M)]
    shadow_file = max(numbers + [9]) + 1
    values = []
    for k, address in enumerate(used):
        file, item = address.split(":")
        values.append((data.get(file) or ["0"] * (int(item) + 1))[int(item)])
        text = re.sub(rf"\b{address}\b(?![0-9])", f"N{shadow_file}:{k}", text)
    return f"DATA N{shadow_file} {len(used)} = {' '.join(values)}\n" + text


def scan_us(runner: Runner, scans: int) -> float:
    t0 = time.thread_time()
    runner.run(scans)
    return (time.thread_time() - t0) / scans * 1e6


def paired(a: Runner, b: Runner, rounds: int, scans: int) -> tuple[list, list]:
    """Per-scan µs of ``a`` and ``b`` in alternating blocks (the machine's
    noise falls on both)."""
    xs, ys = [], []
    a.run(200)
    b.run(200)
    for k in range(rounds):
        for first in ((a, b) if k % 2 == 0 else (b, a)):
            (xs if first is a else ys).append(scan_us(first, scans))
    return xs, ys


def runner(path: Path) -> Runner:
    return Runner(load_app(path), RunOptions(fresh=True, save_state=False))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--export")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json")
    args = ap.parse_args()
    cfg = QUICK if args.quick else FULL
    export = Path(args.export) if args.export else DEFAULT_EXPORT
    loads = []
    for _ in range(cfg["loads"]):
        t0 = time.perf_counter()
        app = load_app(export)
        loads.append(time.perf_counter() - t0)
    rungs = sum(len(f.rungs) for f in app.program.files.values())
    with tempfile.TemporaryDirectory(prefix="bench_logix_") as tmp:
        text = Path(tmp) / "same_rungs.lad"
        text.write_text(plc5_text(app.program), encoding="utf-8")
        twin_loads = []
        for _ in range(cfg["loads"]):
            t0 = time.perf_counter()
            load_app(text)
            twin_loads.append(time.perf_counter() - t0)
        logix, plc5 = runner(export), runner(text)
        ex, tx = paired(logix, plc5, cfg["rounds"], cfg["scans"])
        logix.close()
        plc5.close()
        micro = {}
        for name, logix_rung, plc5_rung in (
                ("TON", "XIC B3/{b} LTON L9:{c} L9:{p} L9:{a}\n", "XIC B3/{b} TON T4:{k} 0.001 1000 0\n"),
                ("CTU", "XIC S:4/{b} LCTU L9:{c} L9:{p} L9:{a}\n", "XIC S:4/{b} CTU C5:{k} 1000 0\n")):
            lx = Path(tmp) / f"logix_{name}.lad"
            px = Path(tmp) / f"plc5_{name}.lad"
            lx.write_text("DATA L9 300\nOTE B3/0\n" + "".join(logix_rung.format(b=k % 16, c=3 * k, p=3 * k + 1, a=3 * k + 2)
                                                               for k in range(100)), encoding="utf-8")
            px.write_text("OTE B3/0\n" + "".join(plc5_rung.format(b=k % 16, k=k) for k in range(100)), encoding="utf-8")
            a, b = runner(lx), runner(px)
            micro[name] = paired(a, b, cfg["rounds"], cfg["scans"])
            a.close()
            b.close()
    ratio = [x / y for x, y in zip(ex, tx)]
    med = statistics.median
    print(f"export {export.name}: {rungs} rungs in {len(app.program.files)} program files")
    print(f"  load: {med(loads) * 1000:.1f} ms (the same rungs as PLC-5 text: {med(twin_loads) * 1000:.1f} ms)")
    print(f"  scan: {med(ex):.1f} us, the same rungs as PLC-5 text {med(tx):.1f} us: export / text "
          f"{med(ratio):.2f} [{min(ratio):.2f}..{max(ratio):.2f}] (target at most {TARGET})")
    for name, (xs, ys) in micro.items():
        r = [x / y for x, y in zip(xs, ys)]
        print(f"  100 rungs of Logix {name} {med(xs):.1f} us a scan, of PLC-5 {name} {med(ys):.1f} us: "
              f"{med(r):.2f} [{min(r):.2f}..{max(r):.2f}]")
    verdict = med(ratio) <= TARGET
    print(f"target: the export's scan at most {TARGET}x its rungs as PLC-5 text: {'PASS' if verdict else 'MISS'}")
    figures = {"export": export.name, "rungs": rungs, "load_s": loads, "text_load_s": twin_loads,
               "scan_us": ex, "text_scan_us": tx, "ratio": ratio, "target": TARGET, "verdict": verdict,
               "micro": {k: {"logix_us": v[0], "plc5_us": v[1]} for k, v in micro.items()}, "config": cfg}
    C.save_figures("bench_logix", figures, args.quick, args.json)
    return 0 if verdict else 1


if __name__ == "__main__":
    sys.exit(main())
