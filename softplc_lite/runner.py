"""Running an app: the data table's life cycle around the scan engine.

Start: program initial values (DATA, timer/counter presets); then the
retentive snapshot if there is one (unless fresh), otherwise the app's
datatable.json; then --load files and --set values. While running, the
snapshot is saved between scans every [retentive] save_ms (retentive.py);
storage trouble (a save, a --record trace) is a minor fault, not a stop.
Stop: the final save (``finish``).

Between two scans ``Runner.run`` calls each callable of ``between_scans``
(with the runner): the one place where something may change the program or
the table at a scan boundary (an online edit): after a scan that did not
fault, before the retentive save that may follow it and the next scan.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .app import App, save_code_cache
from .datatable import DataTable, DataTableError, jsonio
from .ladder import status as S
from .ladder.engine import Engine, Mode, RealClock, SimulatedClock
from .ladder.symbols import SymbolError, resolve_name
from .ports import parse_port_overrides
from .ports.recorder import MAX_PENDING
from .ports.trace import covered_scans
from .retentive import Retentive, StorageFaults, restore_snapshot
from .tlm.api import attach_options


def apply_assignment(table: DataTable, text: str, symbols=None) -> None:
    """``--set TEXT`` into ``table``; any problem is a DataTableError that
    names the option as typed: ``--set StopOk=abc: I:0/1 holds a bit (0 or
    1), got abc``."""
    name = text.partition("=")[0].strip()
    # as typed, or, too long to quote, the address it sets (the message says where in the value)
    shown = text if len(text) <= 60 else name if len(name) <= 60 else f"{text[:40]}... ({len(text)} characters)"
    try:
        addr, value = parse_assignment(text, symbols)
        table.write(addr, value)
    except SymbolError as e:  # its text is the name, which the option shows already
        raise DataTableError(f"--set {shown}: {e.reason}") from None
    except DataTableError as e:
        raise DataTableError(f"--set {shown}: {e}") from None


def parse_assignment(text: str, symbols=None) -> tuple[object, object]:
    """``ADDR=VALUE`` (ADDR may be a program symbol): VALUE is JSON (5, 1.5, "text", {"PRE": 10}) or, failing
    that, taken as a plain string (for ST elements)."""
    if "=" not in text:
        raise DataTableError("expected ADDR=VALUE, e.g. N7:0=5")
    name, _, raw = text.partition("=")
    name = name.strip()
    addr = resolve_name(name, symbols)
    problem = jsonio.json_limit_problem(raw)
    if problem is not None:
        raise DataTableError(f"the value at {problem}")
    try:
        value = json.loads(raw)
    except (ValueError, RecursionError):
        value = raw
    return addr, value


@dataclass
class RunOptions:
    scan_ms: int | None = None
    realtime: bool = False
    fresh: bool = False
    load: tuple[str, ...] = ()
    sets: tuple[str, ...] = ()
    executor: str = "compiled"
    ports: tuple[str, ...] = ()  # --port [MODULE:]N=DEVICE (port N on DEVICE or a URL)
    record: str | None = None  # --record TRACE: write every port's traffic
    replay: str | None = None  # --replay TRACE: play every port back from a recording
    save_state: bool = True  # False: the retentive snapshot is read at start but never written

    def module_options(self) -> dict[str, object]:
        """What modules get at attach (see tlm.api.TLM.attach)."""
        return {"ports": parse_port_overrides(self.ports), "record": self.record, "replay": self.replay}


def module_engine(program, table: DataTable | None = None, settings=None, clock=None, *, modules=(),
                  module_options: dict | None = None, **engine_args) -> Engine:
    """An Engine whose modules attach with the run's options (``module_options``:
    "ports", "record", "replay", as RunOptions.module_options gives them): the
    --port overrides go to the module that has each port (ModuleError when
    none or two do, or two ports would share a device), and a --record trace
    gets a recorder the modules' ports share, which the engine opens once
    they have attached and closes after them."""
    modules = list(modules)
    per_module, recorder = attach_options(modules, module_options or {})
    return Engine(program, table, settings, clock, modules=modules, module_options=per_module,
                  recorder=recorder, **engine_args)


class Runner:
    def __init__(self, app: App, options: RunOptions | None = None, log: Callable[[str], None] | None = None) -> None:
        self.app = app
        self.options = options = options or RunOptions()
        self.log = log or (lambda msg: print(msg, file=sys.stderr))
        settings = app.settings
        if options.scan_ms is not None:
            settings.scan_ms = options.scan_ms
        clock = RealClock() if options.realtime else SimulatedClock(settings.scan_ms)
        self.table = DataTable()
        self.engine = module_engine(app.program, self.table, settings, clock, executor=options.executor,
                                    modules=app.modules, module_options=options.module_options(), code=app.code)
        if options.executor == "compiled":
            save_code_cache(app, self.engine)  # before a table is restored into it: the program's own layout
        for warning in self.engine.module_warnings:
            self.log(f"warning: {warning}")
        self.faults = StorageFaults(self.engine.s, self.log)
        self.recorder = self.engine.recorder  # kept: the engine lets go of it when it closes
        if self.recorder is not None:
            self.recorder.on_problem = self._record_problem
        self.restored_from: Path | None = None
        path = app.snapshot_path
        if path is not None and not options.fresh:
            restored = restore_snapshot(self.table, path)  # a snapshot that does not fit says so, suggests --fresh
            for problem in restored.problems:
                self.log(f"warning: {problem}")
            if restored.table is not None:
                self.restored_from = restored.source
        if self.restored_from is None and app.datatable_json is not None:
            jsonio.load_file(self.table, str(app.datatable_json))
        for f in options.load:
            jsonio.load_file(self.table, f)
        for text in options.sets:
            apply_assignment(self.table, text, app.program.symbols)
        # Removes the temp files of a save a killed run left; saves from the first scan on.
        self.retentive = Retentive(path, settings.save_ms, self.faults) \
            if path is not None and options.save_state else None
        # A --replay trace's "# scans: N" comment: the scans it covers (None: until its last event)
        self.replay_scans = covered_scans(options.replay) if options.replay else None
        self.replay_differences = 0  # output differences of every replay port (set by ``close``)
        # callables run between two scans, each given this runner (see the module docstring)
        self.between_scans: list[Callable[[Runner], None]] = []
        self.after_scan: list[Callable[[Engine], None]] = []  # right after each scan, a faulted one too (trends)
        self.stop_requested = False  # request_stop(): end ``run`` at the next scan boundary
        # Real time: scans that started a whole period or more after they were due (they missed
        # their slot, as a periodic task's overlap does), and the latest start seen, in ms.
        self.late_scans = 0
        self.max_lateness_ms = 0.0

    @property
    def realtime(self) -> bool:
        return self.options.realtime

    def save(self) -> None:
        """The final save (durable) once scanning has stopped; OSError, with
        the path and the reason, when it fails (``finish`` reports instead)."""
        problem = self.retentive.finish(self.table) if self.retentive is not None else None
        if problem is not None:
            raise OSError(problem)

    def finish(self) -> list[str]:
        """The end of a run, after ``engine.close()``: the final save, and
        whether the --record trace is complete. Each problem is logged as an
        error (with its path and reason) and returned; the minor fault is
        set in the table (S:17/4, S:102)."""
        problems = []
        if self.retentive is not None:
            problem = self.retentive.finish(self.table)
            if problem is not None:
                problems.append(problem)
        rec = self.recorder
        if rec is not None and not rec.complete:
            lost = f"; {rec.dropped} events were not recorded" if rec.dropped else ""
            problems.append(f"--record: the trace {rec.path} is incomplete: "
                            f"{rec.problem or 'it could not be written for a while'}{lost}")
        for problem in problems:
            self.log(f"error: {problem}")
        return problems

    def _record_problem(self, problem: str | None) -> None:
        """The recorder's report, from the scan thread: a failed trace write,
        or (None) the first good one after."""
        rec = self.recorder
        if problem is None:
            lost = f" ({rec.dropped} events were not recorded; a comment in the trace says where)" \
                if rec.dropped else ""
            self.faults.ok("record", f"--record: {rec.path} is written again{lost}")
        else:
            self.faults.failed("record", S.MINOR_CODE_RECORD, f"--record: {problem}",
                               f"; the run goes on, the trace waits in memory (up to "
                               f"{MAX_PENDING // (1024 * 1024)} MB) and is written when the file takes it")

    def replay_ports(self) -> list:
        """The open ``replay://`` serial ports of every module (they have ``mismatches``)."""
        found = []
        for module in self.engine.modules:
            for port in module.serial_ports():
                serial = getattr(port, "serial", None)
                if serial is not None and hasattr(serial, "mismatches"):
                    found.append(serial)
        return found

    def replay_done(self) -> bool:
        """Every replay port has delivered its last recorded byte to the
        program, and the program has written every recorded one (true at
        once when no port plays anything back: there is nothing to wait for)."""
        return all(p.finished and not p.in_waiting for p in self.replay_ports())

    def _lateness(self, late_s: float, period: float) -> None:
        """Keep count of late starts (``late_scans``, ``max_lateness_ms``)."""
        if late_s > self.max_lateness_ms / 1000:
            self.max_lateness_ms = late_s * 1000
        if late_s >= period:
            self.late_scans += 1

    def request_stop(self) -> None:
        """End ``run`` after the scan under way (safe from a signal handler)."""
        self.stop_requested = True

    def close(self) -> None:
        """Close the engine (the modules report each replay port first);
        ``replay_differences`` counts the replay output differences."""
        self.replay_differences = sum(len(p.mismatches) for p in self.replay_ports())
        self.engine.close()

    def run(self, scans: int | None = None, on_scan: Callable[[Engine], None] | None = None) -> None:
        """Run in RUN mode for ``scans`` scans, or until ``request_stop``
        (at a scan boundary), Ctrl-C (KeyboardInterrupt, wherever it comes:
        return normally, the caller saves and exits cleanly) or a major
        fault. With ``--replay`` and ``scans`` None: the scans the
        trace says it covers, else until ``replay_done``."""
        engine = self.engine
        until_replay_end = scans is None and self.options.replay is not None
        if until_replay_end and self.replay_scans is not None:
            scans, until_replay_end = self.replay_scans, False
        if engine.mode is not Mode.RUN:
            engine.set_mode(Mode.RUN)
        period = engine.settings.scan_ms / 1000 if self.realtime else 0.0
        next_at = time.monotonic()
        retentive = self.retentive
        save_at = retentive.due if retentive is not None else float("inf")
        done = 0
        try:
            after_scan = self.after_scan
            while scans is None or done < scans:
                engine.scan()
                done += 1
                for hook in after_scan:
                    hook(engine)
                if on_scan is not None:
                    on_scan(engine)
                if engine.mode is Mode.FAULTED:
                    break
                for hook in self.between_scans:
                    hook(self)
                if self.stop_requested or (until_replay_end and self.replay_done()):
                    break
                now = time.monotonic()
                if now >= save_at:  # between two scans: the snapshot is one whole scan's table
                    retentive.tick(self.table, now)
                    save_at = retentive.due
                if period > 0:
                    next_at += period
                    delay = next_at - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                        self._lateness(time.monotonic() - next_at, period)  # woken late
                    else:
                        self._lateness(-delay, period)  # the scan overran its period
                        next_at = time.monotonic()  # overran: don't try to catch up
        except KeyboardInterrupt:
            pass
