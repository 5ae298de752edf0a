"""What a Structured Text routine costs a scan: against the same logic
written as a Logix ladder routine in the same export shape on the same
engine (target: ST at most 1.5x the ladder's scan time), and against a
straight-line Python rendering of the same statements over plain Python
variables and lists (the CPython limit), all measured in the same run.

    python benchmarks/bench_st.py             # 8 units of the logic; about 30 s
    python benchmarks/bench_st.py --units 1   # one unit
    python benchmarks/bench_st.py --quick     # a smoke run, results not written

A miss of the target prints MISS and exits 0, as the other benchmarks do;
exit 2 says the renderings did not do the same work (a fault, or values
that differ), so no figure was measured.

The logic, one block per unit (a suffix on every tag): a scan counter,
a mode from it, start/stop bits and a seal-in, a level ramp, a ring buffer
of flows written at an index made of an expression, a FOR over the buffer
summing it, an average, IF/ELSIF/ELSE on the level, a CASE on the mode
with a list, a range and ELSE, and a clamped proportional output (REAL).
The ladder is that logic as a ladder programmer writes it (ADD, MOD, the
comparisons as inputs, a seal-in branch, LBL/JMP for the loop, LIM for
the range); the export's Main routine JSRs the Calc routine in both, so
only Calc's language differs. Scan time is the scan thread's CPU time
(time.thread_time) over blocks of scans, the two exports alternating,
ratios per round with their spread. Before timing, the three renderings
run the same scans and must end with the same values (the integer tags;
REALs are float32 in the data table, Python's are doubles), so the
yardstick measures the same work.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import _common as C

from helpers.logix_l5x import Prog, Task, export_runner, read_tag, write_l5x

TARGET = 1.5
FULL = {"rounds": 7, "scans": 2000, "units": 8}
QUICK = {"rounds": 2, "scans": 50, "units": 2}
CHECK_SCANS = 250  # scans the three renderings run before timing, to compare their values

DINTS = ("Count", "Mode", "Total", "Avg", "Speed", "i", "k", "t1", "t2")
REALS = ("Level", "Err", "Out")
BOOLS = ("Start", "Stop", "Run", "Pump", "Alarm")
COMPARED = ("Count", "Mode", "Total", "Avg", "Speed", "Run", "Start", "Stop")

ST_UNIT = """\
// unit {n}
Count{X} := Count{X} + 1;
IF Count{X} >= 1000 THEN Count{X} := 0; END_IF;
Mode{X} := (Count{X} + {n}) MOD 6;
Start{X} := (Count{X} MOD 50) = 0;
Stop{X} := (Count{X} MOD 200) = 199;
Run{X} := (Start{X} OR Run{X}) AND NOT Stop{X};
Level{X} := Level{X} + 0.7;
IF Level{X} > 100.0 THEN Level{X} := 0.0; END_IF;
Flow{X}[Count{X} MOD 10] := Count{X} * 3;
Total{X} := 0;
FOR i{X} := 0 TO 9 DO
    Total{X} := Total{X} + Flow{X}[i{X}];
END_FOR;
Avg{X} := Total{X} / 10;
IF Level{X} > 90.0 THEN
    Pump{X} := 0;
    Alarm{X} := 1;
ELSIF Level{X} < 10.0 THEN
    Pump{X} := Run{X};
    Alarm{X} := 0;
ELSE
    Alarm{X} := 0;
END_IF;
CASE Mode{X} OF
    0: Speed{X} := 0;
    1: Speed{X} := 300 + Avg{X};
    2..4: Speed{X} := 600 + Mode{X} * 100;
ELSE
    Speed{X} := 1500;
END_CASE;
Err{X} := 50.0 - Level{X};
Out{X} := Out{X} + 0.1 * Err{X};
IF Out{X} > 100.0 THEN Out{X} := 100.0;
ELSIF Out{X} < 0.0 THEN Out{X} := 0.0;
END_IF;
"""

LADDER_UNIT = """\
ADD(Count{X},1,Count{X});
GEQ(Count{X},1000)MOV(0,Count{X});
ADD(Count{X},{n},t1{X})MOD(t1{X},6,Mode{X});
MOD(Count{X},50,t1{X})EQU(t1{X},0)OTE(Start{X});
MOD(Count{X},200,t2{X})EQU(t2{X},199)OTE(Stop{X});
[XIC(Start{X}),XIC(Run{X})]XIO(Stop{X})OTE(Run{X});
ADD(Level{X},0.7,Level{X});
GRT(Level{X},100.0)MOV(0.0,Level{X});
MOD(Count{X},10,k{X})MUL(Count{X},3,Flow{X}[k{X}]);
MOV(0,Total{X})MOV(0,i{X});
LBL(Top{X})GRT(i{X},9)JMP(Done{X});
ADD(Total{X},Flow{X}[i{X}],Total{X})ADD(i{X},1,i{X})JMP(Top{X});
LBL(Done{X})DIV(Total{X},10,Avg{X});
GRT(Level{X},90.0)OTU(Pump{X})OTL(Alarm{X});
LEQ(Level{X},90.0)LES(Level{X},10.0)[XIC(Run{X})OTL(Pump{X}),XIO(Run{X})OTU(Pump{X})]OTU(Alarm{X});
LEQ(Level{X},90.0)GEQ(Level{X},10.0)OTU(Alarm{X});
EQU(Mode{X},0)MOV(0,Speed{X});
EQU(Mode{X},1)ADD(300,Avg{X},Speed{X});
LIM(2,Mode{X},4)CPT(Speed{X},600+Mode{X}*100);
GRT(Mode{X},4)MOV(1500,Speed{X});
SUB(50.0,Level{X},Err{X});
CPT(Out{X},Out{X}+0.1*Err{X});
GRT(Out{X},100.0)MOV(100.0,Out{X});
LES(Out{X},0.0)MOV(0.0,Out{X});
"""

PYTHON_UNIT = """\
    Count{X} = Count{X} + 1
    if Count{X} >= 1000:
        Count{X} = 0
    Mode{X} = (Count{X} + {n}) % 6
    Start{X} = 1 if Count{X} % 50 == 0 else 0
    Stop{X} = 1 if Count{X} % 200 == 199 else 0
    Run{X} = (Start{X} | Run{X}) & (Stop{X} ^ 1)
    Level{X} = Level{X} + 0.7
    if Level{X} > 100.0:
        Level{X} = 0.0
    Flow{X}[Count{X} % 10] = Count{X} * 3
    Total{X} = 0
    i{X} = 0
    while i{X} <= 9:
        Total{X} = Total{X} + Flow{X}[i{X}]
        i{X} += 1
    Avg{X} = int(Total{X} / 10)
    if Level{X} > 90.0:
        Pump{X} = 0
        Alarm{X} = 1
    elif Level{X} < 10.0:
        Pump{X} = Run{X}
        Alarm{X} = 0
    else:
        Alarm{X} = 0
    if Mode{X} == 0:
        Speed{X} = 0
    elif Mode{X} == 1:
        Speed{X} = 300 + Avg{X}
    elif 2 <= Mode{X} <= 4:
        Speed{X} = 600 + Mode{X} * 100
    else:
        Speed{X} = 1500
    Err{X} = 50.0 - Level{X}
    Out{X} = Out{X} + 0.1 * Err{X}
    if Out{X} > 100.0:
        Out{X} = 100.0
    elif Out{X} < 0.0:
        Out{X} = 0.0
"""


def _units(template: str, units: int) -> str:
    return "".join(template.format(X=f"_{n}", n=n) for n in range(units))


def tags(units: int) -> list[tuple[str, str]]:
    out = []
    for n in range(units):
        out += [(f"{t}_{n}", "DINT") for t in DINTS] + [(f"{t}_{n}", "REAL") for t in REALS]
        out += [(f"{t}_{n}", "BOOL") for t in BOOLS] + [(f"Flow_{n}", "DINT[10]")]
    return out


def exports(directory: Path, units: int) -> tuple[Path, Path]:
    """The ST export and the ladder export: the same tags and task, Main
    JSRs Calc, Calc in ST or in RLL."""
    task = [Task("T", ["MainProgram"])]
    st = write_l5x(directory / "st.L5X", tags(units),
                   [Prog("MainProgram", {"Main": ["JSR(Calc,0);"], "Calc": _units(ST_UNIT, units)})], task)
    rll = write_l5x(directory / "ladder.L5X", tags(units),
                    [Prog("MainProgram", {"Main": ["JSR(Calc,0);"],
                                          "Calc": _units(LADDER_UNIT, units).splitlines()})], task)
    return st, rll


def python_scan(units: int):
    """The statements as straight-line Python over module-level variables
    and lists: (scan function, its namespace)."""
    names = [f"{t}_{n}" for n in range(units) for t in DINTS + REALS + BOOLS + ("Flow",)]
    source = f"def scan():\n    global {', '.join(names)}\n" + _units(PYTHON_UNIT, units)
    namespace: dict = {}
    for n in range(units):
        namespace.update({f"{t}_{n}": 0 for t in DINTS + BOOLS})
        namespace.update({f"{t}_{n}": 0.0 for t in REALS})
        namespace[f"Flow_{n}"] = [0] * 10
    exec(compile(source, "<bench_st straight-line>", "exec"), namespace)
    return namespace["scan"], namespace


def check_same(st_runner, rll_runner, namespace: dict, units: int) -> list[str]:
    """The tags where the three renderings differ after CHECK_SCANS scans."""
    differ = []
    for n in range(units):
        for t in COMPARED + tuple(f"Flow[{j}]" for j in range(10)):
            name = f"{t}_{n}" if "[" not in t else t.replace("Flow", f"Flow_{n}")
            a, b = read_tag(st_runner, name), read_tag(rll_runner, name)
            c = namespace[f"Flow_{n}"][int(t[5:-1])] if "[" in t else namespace[name]
            if not a == b == c:
                differ.append(f"{name}: ST {a}, ladder {b}, Python {c}")
    return differ


def engine_us(runner, scans: int) -> float:
    t0 = time.thread_time()
    runner.run(scans)
    return (time.thread_time() - t0) / scans * 1e6


def python_us(scan, scans: int) -> float:
    t0 = time.thread_time()
    for _ in range(scans):
        scan()
    return (time.thread_time() - t0) / scans * 1e6


def measure(cfg: dict) -> dict:
    units = cfg["units"]
    with tempfile.TemporaryDirectory(prefix="bench_st_") as tmp:
        st_path, rll_path = exports(Path(tmp), units)
        st, rll = export_runner(st_path), export_runner(rll_path)
        scan, namespace = python_scan(units)
        st.run(CHECK_SCANS)
        rll.run(CHECK_SCANS)
        for _ in range(CHECK_SCANS):
            scan()
        faults = [f"{name}: {r.engine.fault}" for name, r in (("ST", st), ("ladder", rll)) if r.engine.fault]
        differ = check_same(st, rll, namespace, units)
        rungs = {name: sum(len(f.rungs) for f in r.app.program.files.values()) for name, r in (("st", st), ("ladder", rll))}
        statements = sum(len(f.listing.statements) for f in st.app.program.files.values() if f.listing)
        xs, ys, zs = [], [], []
        for k in range(cfg["rounds"]):
            order = [("st", st), ("ladder", rll), ("python", scan)]
            for name, what in (order if k % 2 == 0 else order[::-1]):
                if name == "python":
                    zs.append(python_us(what, cfg["scans"]))
                else:
                    (xs if name == "st" else ys).append(engine_us(what, cfg["scans"]))
        st.close()
        rll.close()
    return {"units": units, "statements": statements, "st_us": xs, "ladder_us": ys, "python_us": zs, "rungs": rungs,
            "faults": faults, "differ": differ}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--units", type=int)
    ap.add_argument("--json")
    args = ap.parse_args()
    cfg = dict(QUICK if args.quick else FULL)
    if args.units:
        cfg["units"] = args.units
    m = measure(cfg)
    med = statistics.median
    xs, ys, zs = m["st_us"], m["ladder_us"], m["python_us"]
    r_ladder = [x / y for x, y in zip(xs, ys)]
    r_python = [x / z for x, z in zip(xs, zs)]
    print(f"{m['units']} units of the logic ({m['statements'] // m['units']} ST statements, "
          f"{LADDER_UNIT.count(';')} ladder rungs each); "
          f"the engine's program: ST {m['rungs']['st']} rungs, ladder {m['rungs']['ladder']}")
    if m["faults"] or m["differ"]:
        print("the renderings do not do the same work:", *(m["faults"] + m["differ"][:10]), sep="\n  ")
        return 2
    print(f"  the three renderings agree after {CHECK_SCANS} scans")
    print(f"  ST     {med(xs):8.1f} us a scan")
    print(f"  ladder {med(ys):8.1f} us a scan: ST / ladder {med(r_ladder):.2f} [{min(r_ladder):.2f}..{max(r_ladder):.2f}] "
          f"(target at most {TARGET})")
    print(f"  Python {med(zs):8.1f} us a scan (straight-line, plain variables): ST / Python {med(r_python):.1f} "
          f"[{min(r_python):.1f}..{max(r_python):.1f}]")
    verdict = med(r_ladder) <= TARGET
    print(f"target: ST's scan at most {TARGET}x the same logic as ladder: {'PASS' if verdict else 'MISS'} "
          f"({cfg['rounds']} rounds of {cfg['scans']} scans, scan-thread CPU time)")
    figures = {**m, "ratio_ladder": r_ladder, "ratio_python": r_python, "target": TARGET, "verdict": verdict,
               "config": cfg}
    C.save_figures("bench_st", figures, args.quick, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
