"""How much of the Studio 5000 exports out there softplc_lite runs: over a
set of exports, the share of files that load, the share of their RLL rungs
that are made into rungs that run, the share of their Structured Text
statements that run, and the share of files that run 1,000 scans without a
major fault; with the causes of the rest, counted (those in ST routines
apart, by the construct or instruction they name).

    python benchmarks/logix_corpus.py                       # the exports in this repository
    python benchmarks/logix_corpus.py --list FILES.txt      # a gathered corpus: one path a line
    python benchmarks/logix_corpus.py DIR_OR_FILE ...

The repository holds the public exports whose licences allow it
(tests/fixtures/logix/public/, their sources in its README) and the
project's own (programs/logix/, tests/fixtures/logix/). The wider corpus
the figures in docs/logix.md come from was gathered from public
repositories with tools/logix_census.py's help (not shipped: most of it
may not be redistributed). Each file runs in a process of its own, with
a time limit, so one export that hangs or exhausts memory is a cause in
the table, not the end of the measurement. Writes
benchmarks/results/logix_corpus.json unless --no-save.
"""

from __future__ import annotations

import argparse
import multiprocessing
import re
import sys
import time
from collections import Counter
from pathlib import Path

import _common as C

SCANS = 1000
TIME_LIMIT_S = 120


def _exports(paths: list[str], listed: str | None) -> list[Path]:
    found: list[Path] = []
    if listed:
        base = Path(listed).parent
        for line in Path(listed).read_text(encoding="utf-8").splitlines():
            if line.strip():
                p = Path(line.strip())
                found.append(p if p.is_absolute() else base / p)
    for text in paths or ([] if listed else [str(C.REPO / "programs" / "logix"), str(C.REPO / "tests" / "fixtures" / "logix")]):
        p = Path(text)
        found += sorted(x for x in p.rglob("*") if x.suffix.lower() in (".l5x", ".l5k")) if p.is_dir() else [p]
    return found


def _cause(text: str) -> str:
    """A problem's message reduced to its kind: names, numbers and places
    taken out, so that like problems count together."""
    text = re.sub(r"^.*?:\d+:\d+: ", "", text)
    text = re.sub(r"routine \S+: rung \d+: ", "", text)
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", text)
    text = re.sub(r"\b(tag|program|routine|task|data type|string type|member|Add-On Instruction) \S+", r"\1 …", text)
    text = re.sub(r"\d+", "N", text)
    return text[:110]


def _st_cause(text: str) -> str:
    """An ST problem's kind: as ``_cause``, the tag path it starts with
    taken out too, so the construct or instruction it names is what counts."""
    text = re.sub(r"^routine \S+: ", "", text)
    text = re.sub(r"^[A-Za-z_][\w:]*(?:\.[\w.]*|\[[^\]]*\])[\w.\[\]]*: ", "", text)
    return _cause(text)


def _st_spans(project) -> list[tuple[int, int]]:
    """The export's lines each Structured Text routine (a program's or an
    Add-On Instruction's) spans: a problem placed there is the ST's."""
    spans = []
    routines = [r for p in project.programs for r in p.routines]
    routines += [r for a in project.add_on_instructions for r in a.routines]
    for r in routines:
        if r.kind == "ST" and r.lines:
            lines = [x.pos.line for x in r.lines if x.pos.line]
            if lines:
                last = r.lines[-1]
                spans.append((min(lines + [r.pos.line or lines[0]]), max(lines) + last.text.count("\n")))
    return spans


def _in_st(problem, spans) -> bool:
    line = getattr(getattr(problem, "pos", None), "line", 0) or 0
    return any(a <= line <= b for a, b in spans)


def _st_fault(app, fault) -> str | None:
    """The ST line a fault happened on (``routine:line: text``), if its
    program file is a Structured Text routine."""
    pfile = app.program.files.get(fault.file) if fault.file is not None else None
    listing = getattr(pfile, "listing", None)
    if listing is None or fault.rung is None or fault.rung >= len(listing.rung_lines):
        return None
    pos, text = listing.lines[listing.rung_lines[fault.rung]]
    return f"{pfile.name}:{pos.line}: {text.strip()[:80]}"


def measure_one(path: str) -> dict:
    """One export: read, made into a program, checked, run; what happened."""
    from softplc_lite.app import AppError, load_app
    from softplc_lite.logix.load import read_export
    from softplc_lite.logix.model import ExportError
    from softplc_lite.logix.project import build_program
    from softplc_lite.runner import RunOptions, Runner

    out: dict = {"file": path, "rungs": {"total": 0, "run": 0, "not run": 0, "errors": 0}}
    t0 = time.perf_counter()
    try:
        project = read_export(path)
    except ExportError as e:
        out.update(stage="read", causes=[_cause(p.message) for p in e.problems][:20])
        return out
    made = build_program(project)
    spans = _st_spans(project)
    out["st_routines"] = len(spans)
    out["rungs"] = dict(made.rungs)
    # None where the loader does not count ST statements (one that does not run ST)
    out["statements"] = dict(made.statements) if hasattr(made, "statements") else None
    out["warnings"] = [_cause(w.message) for w in made.warnings if not _in_st(w, spans)]
    out["st_warnings"] = [_st_cause(w.message) for w in made.warnings if _in_st(w, spans)]
    out["st_errors"] = [_st_cause(p.message) for p in made.problems if _in_st(p, spans)]
    out["st_first_error"] = next((f"{p.pos.line}:{p.pos.column}: {p.message}"[:200]
                                  for p in made.problems if _in_st(p, spans)), None)
    try:
        app = load_app(path)
    except AppError as e:
        errors = e.errors or [str(e)]
        out.update(stage="load", causes=[_cause(getattr(x, "message", str(x))) for x in errors if not _in_st(x, spans)][:50])
        out["st_causes"] = [_st_cause(getattr(x, "message", str(x))) for x in errors if _in_st(x, spans)][:50]
        out["st_first_error"] = out["st_first_error"] or next(
            (f"{x.pos.line}:{x.pos.column}: {x.message}"[:200] for x in errors if _in_st(x, spans)), None)
        return out
    out["load_s"] = time.perf_counter() - t0
    runner = Runner(app, RunOptions(fresh=True, save_state=False))
    try:
        t1 = time.perf_counter()
        runner.run(SCANS)
        out["scan_us"] = (time.perf_counter() - t1) / max(runner.engine.scans, 1) * 1e6
        fault = runner.engine.fault
        out.update(stage="ran" if fault is None else "faulted", scans=runner.engine.scans,
                   causes=[] if fault is None else [_cause(str(fault))])
        if fault is not None:
            out["st_fault"] = _st_fault(app, fault)
            out["fault"] = str(fault)[:200]
    finally:
        runner.close()
    return out


def _worker(path: str, queue) -> None:
    try:
        queue.put(measure_one(path))
    except BaseException as e:  # noqa: BLE001 - a bug of softplc_lite is a finding of the measurement
        queue.put({"file": path, "stage": "crashed", "causes": [f"{type(e).__name__}: {_cause(str(e))}"],
                   "rungs": {"total": 0, "run": 0, "not run": 0, "errors": 0}})


def measure(path: Path) -> dict:
    """``measure_one`` in a process of its own: its result is taken from the
    queue before the process is joined (a child cannot end while what it
    put is unread), within the time limit."""
    import queue as queues

    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_worker, args=(str(path), queue))
    proc.start()
    try:
        result = queue.get(timeout=TIME_LIMIT_S)
    except queues.Empty:
        result = {"file": str(path), "stage": "timed out" if proc.is_alive() else "crashed",
                  "causes": [f"over {TIME_LIMIT_S} s" if proc.is_alive() else f"exit status {proc.exitcode}"],
                  "rungs": {"total": 0, "run": 0, "not run": 0, "errors": 0}}
    proc.kill()
    proc.join()
    return result


def _print_st(results: list[dict], statements: Counter) -> None:
    with_st = [r for r in results if r.get("st_routines")]
    routines = sum(r["st_routines"] for r in with_st)
    print(f"  Structured Text: {routines} routines in {len(with_st)} exports", end="")
    if not any(r.get("statements") is not None for r in results):
        print(": this version does not count ST statements (it runs none)")
        return
    total = statements["total"]
    print(f"; ST statements: {total}: run {statements['run']} ({100 * statements['run'] / max(total, 1):.1f}%), "
          f"not run {statements['not run']} ({100 * statements['not run'] / max(total, 1):.1f}%), "
          f"with errors {statements['errors']} ({100 * statements['errors'] / max(total, 1):.1f}%)")


def _print_st_causes(results: list[dict]) -> None:
    """What stops the ST: warnings (not run) and errors by kind, then each
    export that does not load or faults because of its ST, with the message."""
    for title, key in (("ST: what is not run (files with the warning)", "st_warnings"),
                       ("ST: errors of the translation (files with the error)", "st_errors"),
                       ("ST: errors of the check of its rungs (files with the error)", "st_causes")):
        counted = Counter(c for r in results for c in set(r.get(key, [])))
        if counted:
            print(f"  {title}:")
            for cause, count in counted.most_common(30):
                print(f"    {count:4}  {cause}")
    stopped = [r for r in results if r["stage"] == "load" and r.get("st_causes") or r.get("st_fault")]
    if stopped:
        print("  exports that do not load or fault because of their ST:")
        for r in stopped:
            if r.get("st_fault"):
                print(f"    faults  {r['file']}: {r['st_fault']}: {r['fault']}")
            else:
                alone = "" if not r.get("causes") else f" (and {len(r['causes'])} other problems)"
                print(f"    no load {r['file']}: {r['st_first_error']}{alone}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="*")
    ap.add_argument("--list", help="a file listing exports, one path a line (relative to the list's directory)")
    ap.add_argument("--no-save", action="store_true")
    ap.add_argument("--json")
    args = ap.parse_args()
    files = _exports(args.paths, args.list)
    results = []
    for k, f in enumerate(files, 1):
        r = measure(f)
        results.append(r)
        print(f"[{k}/{len(files)}] {r['stage']:9} {f}", file=sys.stderr)
    n = len(results)
    stages = Counter(r["stage"] for r in results)
    loaded = sum(1 for r in results if r["stage"] in ("ran", "faulted"))
    rungs, statements = Counter(), Counter()
    for r in results:
        rungs.update(r["rungs"])
        statements.update(r.get("statements") or {})
    print(f"{n} exports")
    print(f"  load: {loaded} ({100 * loaded / max(n, 1):.1f}%)   (read but not loaded: {stages['load']}, "
          f"not read: {stages['read']}, crashed: {stages['crashed']}, timed out: {stages['timed out']})")
    total = rungs["total"]
    print(f"  RLL rungs: {total}: made into rungs that run {rungs['run']} ({100 * rungs['run'] / max(total, 1):.1f}%), "
          f"kept as NOP (not run yet) {rungs['not run']} ({100 * rungs['not run'] / max(total, 1):.1f}%), "
          f"with errors {rungs['errors']} ({100 * rungs['errors'] / max(total, 1):.1f}%)")
    _print_st(results, statements)
    print(f"  ran {SCANS} scans without a major fault: {stages['ran']} ({100 * stages['ran'] / max(n, 1):.1f}% of all, "
          f"{100 * stages['ran'] / max(loaded, 1):.1f}% of those loaded); faulted: {stages['faulted']}")
    ran = [r for r in results if r["stage"] in ("ran", "faulted") and r["rungs"]["total"]]
    if ran:
        big = max(ran, key=lambda r: r["rungs"]["total"])
        print(f"  the largest export that loads: {Path(big['file']).name}, {big['rungs']['total']} rungs "
              f"({big['rungs']['run']} run): load {big['load_s']:.2f} s, {big.get('scan_us', 0):.0f} us a scan "
              f"(benchmarks/bench_logix.py --export compares it with its rungs as PLC-5 text)")
    for title, key, stage_set in (("why files do not load (files with the cause)", "causes", ("load", "read", "crashed", "timed out")),
                                  ("why loaded files fault", "causes", ("faulted",)),
                                  ("what is not run (files with the warning)", "warnings", ("ran", "faulted", "load"))):
        counted = Counter(c for r in results if r["stage"] in stage_set for c in set(r.get(key, [])))
        if counted:
            print(f"  {title}:")
            for cause, count in counted.most_common(25):
                print(f"    {count:4}  {cause}")
    _print_st_causes(results)
    figures = {"files": n, "stages": dict(stages), "rungs": dict(rungs), "statements": dict(statements),
               "results": results}
    C.save_figures("logix_corpus", figures, args.no_save, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
