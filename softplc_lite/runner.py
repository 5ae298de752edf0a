"""Running an app: the data table's life cycle around the scan engine.

Start: program initial values (DATA, timer/counter presets); then the
retentive snapshot if there is one (unless fresh), otherwise the app's
datatable.json; then --load files and --set values. Stop: save the
snapshot. While running, the snapshot is also saved every few seconds.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .app import App
from .datatable import DataTable, DataTableError, parse_address
from .datatable import jsonio, snapshot
from .ladder.engine import Engine, Mode, RealClock, SimulatedClock
from .ports import parse_port_overrides

SAVE_EVERY_S = 5.0


def parse_assignment(text: str, symbols=None) -> tuple[object, object]:
    """``ADDR=VALUE`` (ADDR may be a program symbol): VALUE is JSON (5, 1.5, "text", {"PRE": 10}) or, failing
    that, taken as a plain string (for ST elements)."""
    if "=" not in text:
        raise DataTableError(f"--set {text!r}: expected ADDR=VALUE, e.g. N7:0=5")
    name, _, raw = text.partition("=")
    name = name.strip()
    addr = symbols[name].address if symbols and name in symbols else parse_address(name)
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
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

    def module_options(self) -> dict[str, object]:
        """What modules get at attach (see tlm.api.TLM.attach)."""
        return {"ports": parse_port_overrides(self.ports), "record": self.record, "replay": self.replay}


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
        self.engine = Engine(app.program, self.table, settings, clock, executor=options.executor,
                             modules=app.modules, module_options=options.module_options())
        for warning in self.engine.module_warnings:
            self.log(f"warning: {warning}")
        self.restored_from: Path | None = None
        path = app.snapshot_path
        if path is not None and not options.fresh:
            restored = snapshot.restore(path)
            for problem in restored.problems:
                self.log(f"warning: {problem}")
            if restored.table is not None:
                self.table.assign(restored.table)
                self.restored_from = restored.source
        if self.restored_from is None and app.datatable_json is not None:
            jsonio.load_file(self.table, str(app.datatable_json))
        for f in options.load:
            jsonio.load_file(self.table, f)
        for text in options.sets:
            addr, value = parse_assignment(text, app.program.symbols)
            self.table.write(addr, value)
        self._last_save = time.monotonic()

    @property
    def realtime(self) -> bool:
        return self.options.realtime

    def save(self) -> None:
        if self.app.snapshot_path is not None:
            snapshot.save(self.table, self.app.snapshot_path)
        self._last_save = time.monotonic()

    def run(self, scans: int | None = None, on_scan: Callable[[Engine], None] | None = None) -> None:
        """Run in RUN mode for ``scans`` scans, or until Ctrl-C (then return
        normally: the caller saves and exits cleanly) or a major fault."""
        engine = self.engine
        if engine.mode is not Mode.RUN:
            engine.set_mode(Mode.RUN)
        period = engine.settings.scan_ms / 1000 if self.realtime else 0.0
        next_at = time.monotonic()
        done = 0
        try:
            while scans is None or done < scans:
                engine.scan()
                done += 1
                if on_scan is not None:
                    on_scan(engine)
                if engine.mode is Mode.FAULTED:
                    break
                now = time.monotonic()
                if now - self._last_save >= SAVE_EVERY_S and self.app.snapshot_path is not None:
                    self.save()
                if period > 0:
                    next_at += period
                    delay = next_at - time.monotonic()
                    if delay > 0:
                        time.sleep(delay)
                    else:
                        next_at = time.monotonic()  # overran: don't try to catch up
        except KeyboardInterrupt:
            pass
