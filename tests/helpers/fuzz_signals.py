"""Fuzz inputs: Ctrl-C and SIGTERM at random moments of a real run.

A ``signals`` case copies a shipped app into the case directory, runs it once
to have a retentive snapshot, then starts the real ``softplc run APP`` (wall
clock, until stopped) in its own session and sends SIGINT or SIGTERM, once or
twice a few milliseconds apart, at a random moment from its first instant to
about 1.5 s after (the first 0.3 s or so are the start-up imports).

The oracle (docs/cli.md "Signals" and "Exit codes"): no ``Traceback`` in the
output through softplc's code (Python's own start is Python's: docs/cli.md);
an exit status of 0 (a run ended by either signal saves and ends normally) or
130 (stopped outside the scan loop, while loading: the run handles Ctrl-C and
SIGTERM alike), or death by the signal before softplc said anything (while
Python itself starts, before any handler can exist: nothing has been written); no process of its
session left behind; no ``datatable.snap.tmp`` left; and the retentive state
loads: a following ``softplc run APP --scans 1`` without ``--fresh`` says
nothing about the snapshot and exits 0.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from pathlib import Path

APPS = ["blinker", "motor", "strings", "subroutines", "tank", "modbus_master", "hmi_server"]
SIGNALS = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM}
END_LIMIT_S = 20.0  # from the last signal to the process's end


def case_signals(draw, rnd, profile):
    from helpers.fuzz_inputs import Case, program_files

    app = rnd.choice(APPS)
    sigs = [rnd.choice(list(SIGNALS))]
    if rnd.randrange(2):
        sigs.append(rnd.choice(list(SIGNALS)) if rnd.randrange(3) == 0 else sigs[0])
    delay = rnd.uniform(0.0, 0.3) if rnd.randrange(5) < 2 else rnd.uniform(0.3, 1.5)
    params = {"app": app, "signals": sigs, "delay": round(delay, 4), "gap": round(rnd.uniform(0.002, 0.05), 4),
              "args": rnd.choice([[], [], ["--scan-ms", "1"], ["--scan-ms", "0"], ["--fresh"]])}
    files = program_files(app)
    files.pop("app/pymodbus-session.trace", None)
    return Case("signals", files, [], note=f"{app}: {'+'.join(sigs)} at {delay:.3f} s", driver="signals", params=params)


def _free_port_xml(app: Path) -> None:
    """A MODBTCPS app listens on a port found free, not the shipped 5020 (a user's PLC may hold it)."""
    xml = app / "MODBTCPS.XML"
    if xml.is_file():
        from helpers.modbus_peer import free_tcp_port

        xml.write_text(re.sub(r'port="\d+"', f'port="{free_tcp_port()}"', xml.read_text()))


def _default_signals() -> None:
    """In the child before exec: SIGINT and SIGTERM as a terminal's user has them. A process started
    in the background by a shell without job control inherits SIGINT ignored, and Python then
    installs no KeyboardInterrupt: a Ctrl-C while softplc loads would be lost, the harness's doing."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover
        return True
    return True


def run_signals_case(case, root: Path, timeout: float, runner):
    from helpers.fuzz_oracle import CaseRun, Finding, Result, _first_error, softplc_command

    d = str(root)
    p = case.params
    app = root / "app"
    _free_port_xml(app)
    run = CaseRun(case, d, timeout, runner)
    findings, results, do = run.findings, run.results, run.do

    do(["run", "{d}/app", "--scans", "5", "--fresh"])  # a snapshot to keep or damage
    argv = ["run", str(app), *p["args"]]
    start = time.monotonic()
    proc = subprocess.Popen(softplc_command() + argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True, env=dict(os.environ, COLUMNS="100"),
                            preexec_fn=_default_signals)
    sent = []
    try:
        time.sleep(max(0.0, p["delay"] - (time.monotonic() - start)))
        for k, name in enumerate(p["signals"]):
            if k:
                time.sleep(p["gap"])
            if proc.poll() is None:
                proc.send_signal(SIGNALS[name])
                sent.append(f"{name}@{time.monotonic() - start:.3f}")
        hung = False
        try:
            out, err = proc.communicate(timeout=END_LIMIT_S)
        except subprocess.TimeoutExpired:
            hung = True
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    r = Result(argv, proc.returncode, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"),
               seconds=time.monotonic() - start, hung=hung, how="subprocess")
    r.argv = argv + [f"<{' '.join(sent) or 'no signal: it had ended'}>"]
    # A traceback through softplc's code is a finding; one from Python's own start, before softplc's
    # first line runs, is Python's (docs/cli.md "Signals": ended "as Python ends", its message or status).
    # (pip's editable-install finder, imported by site, has softplc_lite in its name, not in a directory)
    pythons_start = "Traceback (most recent call last)" in r.err and not re.search(r'File "[^"]*/softplc_lite/', r.err)
    if "Traceback (most recent call last)" in r.err and not pythons_start:
        last = [line for line in r.err.strip().splitlines() if line and not line.startswith(" ")]
        r.exception, r.traceback = (last[-1][:300] if last else "Traceback"), r.err[-4000:]
    results.append(r)

    def add(cls: str, sig: str, detail: str, res=r) -> None:
        findings.append(Finding(cls, f"{cls}:run:{sig}", res.argv, detail, case.kind, res))

    what = "+".join(p["signals"])
    if r.hung:
        add("hang", f"signals:{what}", f"the run did not end within {END_LIMIT_S:.0f} s of {what}")
    elif r.exception:
        add("exception", f"signals:{what}:{r.exception.split(':', 1)[0]}", r.exception)
    else:
        allowed = {0, 130}  # 130: stopped while loading, SIGTERM as Ctrl-C ("handles Ctrl-C and SIGTERM alike")
        if not (r.out or r.err):  # killed by a signal before any handler (Python starting): nothing written
            allowed |= {-SIGNALS[name] for name in p["signals"]}
        if pythons_start:
            allowed |= {1, -signal.SIGINT}  # Python's own ending of a KeyboardInterrupt in its start
        if sent and r.code not in allowed:
            said = "having said nothing" if not (r.out or r.err) else f"after: {_first_error(r.err)[:150]!r}"
            add("exit-code", f"signals:{what}:{r.code}", f"exit status {r.code} on {what} {said}")
        if r.code == 4 or "internal error" in r.err:
            add("internal-error", f"signals:{what}", _first_error(r.err)[:300])
    time.sleep(0.2)
    if _group_alive(proc.pid):
        add("orphan", f"signals:{p['app']}", "a process of the run's session outlived it (a server process?)")
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    tmp = app / ".softplc" / "datatable.snap.tmp"
    if tmp.exists() and r.code in (0, 130):
        add("temp-left", f"signals:{what}", f"{tmp.name} left behind by a run that ended with status {r.code}")
    after = do(["run", "{d}/app", "--scans", "1"])
    if not after.hung and not after.exception and (after.code != 0 or "datatable.snap" in after.err):
        add("state-damaged", f"signals:{what}:{after.code}",
            f"after {what}, the next run without --fresh: exit {after.code}: {_first_error(after.err)[:200]}", after)
    return findings, results
