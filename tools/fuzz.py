#!/usr/bin/env python3
"""A fuzz campaign against softplc: the generators of tests/helpers/fuzz_inputs.py and
the oracle of tests/helpers/fuzz_oracle.py, for a time budget, in several processes.

    python tools/fuzz.py --minutes 10 --seed 1 [--out fuzz-findings] [--jobs 2]
    python tools/fuzz.py --replay fuzz-findings/exception/ab12cd34ef   # re-run one finding

Each worker process draws cases (hypothesis, seeded from --seed, the worker's
number and its batch) and runs every command of each through
``softplc_lite.cli.main`` in-process with a watchdog; every --subprocess-every
cases it also runs one case through the real ``softplc`` command. The parent
restarts a worker that stops answering (a hang the watchdog could not break)
or dies (a crash, or the memory limit), and records that case as a finding.

Four kinds are run by a driver of the oracle rather than command by command:
``special_files`` and ``state_damage`` change a file between commands (a FIFO,
a link to /dev/zero, a sparse 20 GiB file... in place of each file softplc
reads; flipped bytes in a real snapshot or code cache), ``signals`` sends
SIGINT/SIGTERM to a real ``softplc run`` at a random moment, ``modbus_tcp``
sends hostile requests to a live MODBTCPS server. Their ``repro.sh`` replays
the whole case.

A finding is saved once per signature (class, command, exception type and
last frame, or normalised message) under OUT/CLASS/HASH/: ``files/`` (the
case's files), ``case.json``, ``finding.txt`` (the command, its output and
traceback) and ``repro.sh``. docs/fuzzing.md says how to read them.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

PREFIX = "@@FUZZ "


def _emit(msg: dict) -> None:
    sys.__stdout__.write(PREFIX + json.dumps(msg) + "\n")
    sys.__stdout__.flush()


# -- saving a finding -------------------------------------------------------------------------


def _signature_dir(out: Path, cls: str, signature: str) -> Path:
    digest = hashlib.sha1(signature.encode("utf-8", "surrogatepass")).hexdigest()[:10]
    return out / cls / digest


def save_finding(out: Path, finding, case, root: str) -> bool:
    """Save ``finding`` (of ``case``, run under ``root``) unless its signature
    is already saved; True when it is new. mkdir is the lock between workers."""
    target = _signature_dir(out, finding.cls, finding.signature)
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        target.mkdir()
    except FileExistsError:
        return False
    files = target / "files"
    files.mkdir()
    case.write(files)
    (target / "case.json").write_text(json.dumps(case.to_json(), indent=1), encoding="utf-8")
    argv = [a.replace(root, "{d}") for a in finding.argv]
    r = finding.result
    text = [f"class: {finding.cls}", f"signature: {finding.signature}", f"kind: {case.kind}", f"note: {case.note}",
            f"command: softplc {' '.join(shlex.quote(a) for a in argv)}", f"detail: {finding.detail}"]
    if r is not None:
        text += [f"how: {r.how}", f"exit: {r.code}", f"seconds: {r.seconds:.2f}", "--- stdout", r.out[-20000:],
                 "--- stderr", r.err[-20000:]]
        if r.traceback:
            text += ["--- traceback", r.traceback]
    (target / "finding.txt").write_text("\n".join(text).replace(root, "{d}") + "\n", encoding="utf-8",
                                        errors="backslashreplace")
    if case.driver:  # the files change between commands, or a process is signalled, or a server is sent requests
        repro = ["#!/bin/sh", f"# A {case.kind} case: its driver ({case.driver}) does more than one command on the files,",
                 "# so the whole case is replayed, in-process (add --real for the softplc command).",
                 f'python "{Path(__file__).resolve()}" --replay "$(dirname "$0")"', ""]
    else:
        repro = ["#!/bin/sh", "# The command of this finding, on the files next to this script.",
                 'D="$(cd "$(dirname "$0")/files" && pwd)"',
                 "softplc " + " ".join(shlex.quote(a).replace("{d}", "'\"$D\"'") for a in argv), ""]
    (target / "repro.sh").write_bytes("\n".join(repro).encode("utf-8", "surrogateescape"))
    (target / "finding.json").write_text(json.dumps({"class": finding.cls, "signature": finding.signature,
                                                     "argv": argv, "detail": finding.detail}, indent=1))
    return True


# -- the worker ---------------------------------------------------------------------------------


def worker(args) -> int:
    from helpers import fuzz_inputs as fi
    from helpers import fuzz_oracle as fo
    from hypothesis import HealthCheck, Phase, Verbosity, given, seed, settings

    if args.memory_mb:
        limit = args.memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    out = Path(args.out)
    work = Path(tempfile.mkdtemp(prefix=f"softplc-fuzz-w{args.worker}-"))
    current = Path(args.current)
    profile = fi.EVERYTHING if args.profile == "all" else fi.MUST_PASS
    kinds = args.kinds.split(",") if args.kinds else None
    deadline = time.monotonic() + args.seconds
    count = {"cases": 0, "commands": 0}

    class Stop(Exception):
        pass

    def runner(argv, timeout):
        _emit({"cmd": argv[0], "t": time.time()})
        count["commands"] += 1
        return fo.run_main(argv, timeout)

    def sub_runner(argv, timeout):
        _emit({"cmd": argv[0], "t": time.time(), "sub": True})
        count["commands"] += 1
        return fo.run_command(argv, timeout * 3)

    @settings(max_examples=args.batch, database=None, deadline=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck), report_multiple_bugs=False, verbosity=Verbosity.quiet)
    @given(fi.cases(kinds, profile))
    def one(case):
        if time.monotonic() > deadline:
            raise Stop
        count["cases"] += 1
        root = work / f"c{count['cases']}"
        current.write_text(json.dumps(case.to_json()), encoding="utf-8")
        _emit({"case": count["cases"], "kind": case.kind, "t": time.time()})
        use_sub = args.subprocess_every and count["cases"] % args.subprocess_every == 0
        try:
            try:
                findings, results = fo.check_case(case, root, args.timeout, sub_runner if use_sub else runner)
            except Exception as e:  # a bug in the harness itself: report it, keep going
                findings = [fo.Finding("harness-error", f"harness-error:{type(e).__name__}:{str(e)[:60]}", [],
                                       repr(e)[:300], case.kind)]
                results = []
            new = []
            for f in findings:
                if save_finding(out, f, case, str(root)):
                    new.append(f.signature)
            _emit({"done": count["cases"], "kind": case.kind, "commands": len(results), "sub": bool(use_sub),
                   "findings": [[f.cls, f.signature] for f in findings], "new": new})
        finally:
            shutil.rmtree(root, ignore_errors=True)

    batch = 0
    try:
        while time.monotonic() < deadline:
            s = hash((args.seed, args.worker, args.restart, batch)) % (2 ** 32)
            batch += 1
            try:
                seed(s)(one)()
            except Stop:
                break
            except Exception as e:  # noqa: BLE001 - a bug in a generator: report it, go on with the next batch
                _emit({"harness": f"{type(e).__name__}: {str(e)[:200]}"})
    finally:
        shutil.rmtree(work, ignore_errors=True)
    _emit({"exit": True, "cases": count["cases"], "commands": count["commands"]})
    return 0


# -- the parent -----------------------------------------------------------------------------------


class Worker:
    def __init__(self, index: int, restart: int, args, seconds: float) -> None:
        self.index, self.restart = index, restart
        self.current = Path(args.out) / ".work" / f"w{index}.current.json"
        self.current.parent.mkdir(parents=True, exist_ok=True)
        cmd = [sys.executable, __file__, "--worker", str(index), "--restart", str(restart), "--seed", str(args.seed),
               "--out", args.out, "--current", str(self.current), "--seconds", str(seconds),
               "--timeout", str(args.timeout), "--batch", str(args.batch), "--profile", args.profile,
               "--memory-mb", str(args.memory_mb), "--subprocess-every", str(args.subprocess_every)]
        if args.kinds:
            cmd += ["--kinds", args.kinds]
        env = dict(os.environ, PYTHONHASHSEED="0")
        self.log = open(self.current.with_suffix(".log"), "a")  # the worker's stderr, for a crash
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=self.log, stdin=subprocess.DEVNULL,
                                     env=env, start_new_session=True, text=True, errors="replace")
        self.last = time.monotonic()
        self.last_cmd: str | None = None
        self.kind: str | None = None
        self.done = False
        self.messages: list[dict] = []
        self.lock = threading.Lock()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            if line.startswith(PREFIX):
                try:
                    msg = json.loads(line[len(PREFIX):])
                except ValueError:
                    continue
                with self.lock:
                    self.messages.append(msg)
                    self.last = time.monotonic()

    def take(self) -> list[dict]:
        with self.lock:
            msgs, self.messages = self.messages, []
        return msgs

    def kill(self) -> None:
        try:
            os.killpg(self.proc.pid, 9)
        except ProcessLookupError:
            pass
        self.proc.wait()


def campaign(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    end = start + args.minutes * 60
    stats = Counter()
    by_class: Counter = Counter()  # occurrences
    signatures: dict[str, list] = {}  # signature -> [class, count]
    kinds = Counter()
    restarts = 0
    workers = [Worker(i, 0, args, end - time.monotonic()) for i in range(args.jobs)]
    hard = args.timeout * 3 + 15

    def note(cls: str, sig: str) -> None:
        by_class[cls] += 1
        signatures.setdefault(sig, [cls, 0])[1] += 1

    last_report = time.monotonic()
    while workers:
        time.sleep(0.2)
        for w in list(workers):
            for msg in w.take():
                if "cmd" in msg:
                    w.last_cmd = msg["cmd"]
                elif "case" in msg:
                    w.kind = msg["kind"]
                elif "done" in msg:
                    stats["cases"] += 1
                    stats["commands"] += msg["commands"]
                    stats["subprocess cases"] += msg["sub"]
                    kinds[msg["kind"]] += 1
                    for cls, sig in msg["findings"]:
                        note(cls, sig)
                elif "harness" in msg:
                    note("harness-error", f"harness-error:{msg['harness'][:80]}")
                elif "exit" in msg:
                    w.done = True
            alive = w.proc.poll() is None
            stalled = alive and time.monotonic() - w.last > hard
            if not alive or stalled:
                if stalled:
                    w.kill()
                if not w.done:  # a hang the watchdog could not break, or a crash: the current case is the finding
                    cls = "hang" if stalled else "crash"
                    sig = f"{cls}:{w.last_cmd}:{w.kind}" + ("" if stalled else f":exit {w.proc.returncode}")
                    note(cls, sig)
                    stats["cases"] += 1
                    _save_worker_finding(out, w, cls, sig, args)
                workers.remove(w)
                if time.monotonic() < end - 5:
                    restarts += 1
                    workers.append(Worker(w.index, w.restart + 1, args, end - time.monotonic()))
        if time.monotonic() > end + hard:  # workers past their budget: stop them
            for w in workers:
                w.kill()
            break
        if args.progress and time.monotonic() - last_report > 30:
            last_report = time.monotonic()
            print(f"[{(last_report - start) / 60:5.1f} min] {stats['cases']} inputs, {stats['commands']} commands, "
                  f"{len(signatures)} distinct findings", flush=True)
    minutes = (time.monotonic() - start) / 60
    summary = {"minutes": round(minutes, 2), "seed": args.seed, "jobs": args.jobs, "inputs": stats["cases"],
               "commands": stats["commands"], "subprocess_inputs": stats["subprocess cases"],
               "worker_restarts": restarts, "kinds": dict(kinds), "findings_by_class": dict(by_class),
               "distinct": {cls: sum(1 for c, _ in signatures.values() if c == cls) for cls in by_class},
               "signatures": {s: n for s, (c, n) in sorted(signatures.items())}}
    (out / "summary.json").write_text(json.dumps(summary, indent=1), encoding="utf-8")
    print(f"softplc fuzz: {minutes:.1f} min, seed {args.seed}, {args.jobs} processes")
    print(f"inputs tried: {stats['cases']} ({stats['subprocess cases']} also as the softplc command)")
    print(f"commands run: {stats['commands']}")
    print(f"worker restarts (hang or crash): {restarts}")
    print("inputs by kind: " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))
    if not by_class:
        print("findings: none")
    else:
        print("findings by class (distinct signatures / occurrences):")
        for cls, n in by_class.most_common():
            print(f"  {cls}: {summary['distinct'][cls]} / {n}")
        print(f"saved under {out}/CLASS/HASH/ (finding.txt, repro.sh); summary in {out}/summary.json")
    return 1 if by_class else 0


def _save_worker_finding(out: Path, w: Worker, cls: str, sig: str, args) -> None:
    from helpers import fuzz_inputs as fi
    from helpers import fuzz_oracle as fo

    try:
        case = fi.Case.from_json(json.loads(w.current.read_text(encoding="utf-8")))
    except (OSError, ValueError):
        return
    detail = ("the worker stopped answering: a command ran past the watchdog and could not be interrupted"
              if cls == "hang" else f"the worker process died (exit {w.proc.returncode}): memory limit, or a crash")
    finding = fo.Finding(cls, sig, [w.last_cmd or "?"], detail, case.kind)
    save_finding(out, finding, case, "{d}")


# -- replaying a saved finding ----------------------------------------------------------------------


def replay(args) -> int:
    from helpers import fuzz_inputs as fi
    from helpers import fuzz_oracle as fo

    path = Path(args.replay)
    case = fi.Case.from_json(json.loads((path / "case.json").read_text(encoding="utf-8")))
    with tempfile.TemporaryDirectory(prefix="softplc-fuzz-replay-") as d:
        runner = fo.run_command if args.real else fo.run_main
        findings, results = fo.check_case(case, Path(d), args.timeout, runner)
        for r in results:
            print(f"$ softplc {' '.join(shlex.quote(a.replace(d, '{d}')) for a in r.argv)}  -> exit {r.code}"
                  f" ({r.seconds:.2f} s{', hung' if r.hung else ''})")
        print()
        for f in findings:
            print(str(f).replace(d, "{d}"))
        if not findings:
            print("no findings: fixed, or it depends on timing")
    return 1 if findings else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--minutes", type=float, default=10.0, help="time budget (default 10)")
    p.add_argument("--seed", type=int, default=0, help="base seed: the same seed draws the same inputs (default 0)")
    p.add_argument("--out", default=str(ROOT / "fuzz-findings"), help="where findings are saved (default fuzz-findings/)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--kinds", help="comma-separated input kinds (default all): ladder, toml, datatable_json, load_json, "
                                   "modules_lst, comgenius_lst, modbmast_xml, cli_args, trace, snapshot_file, "
                                   "snapshot_app, address, watch, special_files, state_damage, signals, modbus_tcp")
    p.add_argument("--profile", choices=("all", "must-pass"), default="all",
                   help="all: every feature, the known-open classes too (default); must-pass: what the test suite uses")
    p.add_argument("--timeout", type=float, default=20.0, help="seconds per command before it counts as a hang (default 20)")
    p.add_argument("--batch", type=int, default=100, help=argparse.SUPPRESS)
    p.add_argument("--memory-mb", type=int, default=4096, help="address-space limit per worker, MB (default 4096)")
    p.add_argument("--subprocess-every", type=int, default=20,
                   help="run every Nth input as the real softplc command too (default 20; 0: never)")
    p.add_argument("--progress", action="store_true", help="a progress line every 30 s")
    p.add_argument("--replay", metavar="FINDING_DIR", help="re-run a saved finding and print what the oracle says")
    p.add_argument("--real", action="store_true", help="with --replay: run the real softplc command")
    p.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    p.add_argument("--restart", type=int, default=0, help=argparse.SUPPRESS)
    p.add_argument("--current", help=argparse.SUPPRESS)
    p.add_argument("--seconds", type=float, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.kinds:
        from helpers import fuzz_inputs as fi
        unknown = set(args.kinds.split(",")) - set(fi.KINDS)
        if unknown:
            p.error(f"unknown kinds {', '.join(sorted(unknown))} (kinds: {', '.join(fi.KINDS)})")
    if args.replay:
        return replay(args)
    if args.worker is not None:
        return worker(args)
    return campaign(args)


if __name__ == "__main__":
    sys.exit(main())
