"""The Python API: ``PLC.load(app)`` gives an app on a fresh data table with
simulated time, its state directory in a temp dir (the app is only read),
driven scan by scan through a ``Runner`` it owns."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from ..app import load_app
from ..ladder.ast import Program
from ..ladder.engine import Mode
from ..ladder.symbols import resolve_name
from ..runner import Runner, RunOptions
from ..watch.forces import Force, Forces, _bit_address


class PLC:
    def __init__(self, runner: Runner, state_dir: str) -> None:
        self.runner = runner
        self.engine = runner.engine
        self.table = runner.table
        self.symbols = runner.app.program.symbols
        self.forces = Forces(self.engine)
        self._state_dir = state_dir
        if self.engine.mode is not Mode.RUN:
            self.engine.set_mode(Mode.RUN)

    @classmethod
    def load(cls, path: str | Path, ports: tuple[str, ...] = (), program: Program | None = None) -> "PLC":
        """``ports``: ``--port`` overrides, e.g. ``("1=sim://...")``;
        ``program``: a parsed program run in place of the app's own (a
        mutant), with the app's modules, settings and data."""
        state_dir = tempfile.mkdtemp(prefix="softplc-test-")
        try:
            app = load_app(path, state_dir=state_dir, program=program)
            runner = Runner(app, RunOptions(fresh=True, ports=tuple(ports), save_state=False),
                            log=lambda msg: None)
        except BaseException:
            shutil.rmtree(state_dir, ignore_errors=True)
            raise
        return cls(runner, state_dir)

    def address(self, name: str):
        return resolve_name(name, self.symbols)

    def __getitem__(self, name: str):
        return self.table.read(self.address(name))

    def set(self, name: str, value) -> None:
        self.table.write(self.address(name), value)

    def __setitem__(self, name: str, value) -> None:
        self.set(name, value)

    def force(self, name: str, on) -> None:
        self.forces.set(Force(_bit_address(self.address(name), f"force {name}"), bool(on)))

    def unforce(self, name: str) -> None:
        self.forces.remove(_bit_address(self.address(name), f"unforce {name}"))

    def scan(self, n: int = 1) -> None:
        for _ in range(n):
            self.engine.scan()

    def run(self, seconds: float) -> None:
        """Scans until ``seconds`` of simulated time have passed."""
        end = self.time_ms + round(seconds * 1000)
        while self.time_ms < end:
            self.engine.scan()

    @property
    def scan_number(self) -> int:
        return self.engine.scans

    @property
    def time_ms(self) -> int:
        return self.engine.clock.now_ms

    def close(self) -> None:
        try:
            self.runner.close()
        finally:
            shutil.rmtree(self._state_dir, ignore_errors=True)

    def __enter__(self) -> "PLC":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
