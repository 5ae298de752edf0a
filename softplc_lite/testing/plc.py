"""The Python API: ``PLC.load(app)`` gives an app on a fresh data table with
simulated time, its state directory in a temp dir (the app is only read),
driven scan by scan through a ``Runner`` it owns."""

from __future__ import annotations

import dataclasses
import functools
import shutil
import tempfile
from pathlib import Path
from typing import Mapping

from ..app import load_app
from ..datatable import DataTableError, ValueKind
from ..datatable.table import WORD_MAX, WORD_MIN
from ..ladder.ast import Program
from ..ladder.engine import Mode
from ..ladder.symbols import resolve_name
from ..runner import Runner, RunOptions
from ..tlm.api import TLM
from ..watch.forces import Force, Forces, _bit_address
from .coverage import Coverage
from .devices import Attached, attach, device_on, port_key
from .scenario import DeviceCounter


class PLC:
    def __init__(self, runner: Runner, state_dir: str, attached: Attached | None = None) -> None:
        self.runner = runner
        self._attached = attached
        self.engine = runner.engine
        self.table = runner.table
        self.symbols = runner.app.program.symbols
        self.forces = Forces(self.engine)
        self._state_dir = state_dir
        self._addresses: dict[str, object] = {}  # name -> address, resolved once
        self._readers: dict[str, object] = {}  # name -> a function giving its value
        self._writers: dict[str, object] = {}  # name -> a function setting it
        if self.engine.mode is not Mode.RUN:
            self.engine.set_mode(Mode.RUN)

    @classmethod
    def load(cls, path: str | Path, ports: tuple[str, ...] = (), program: Program | None = None,
             devices: Mapping | None = None, configured_tcp_ports: bool = False,
             coverage: Coverage | None = None, code_cache: tuple[str | Path, str] | None = None) -> "PLC":
        """``ports``: ``--port`` overrides, e.g. ``("1=sim://...")``;
        ``program``: a parsed program run in place of the app's own (a
        mutant), with the app's modules, settings and data; ``devices``:
        {PORT: DEVICE} simulated devices on the app's ports (devices.py);
        a network server listens on a port the system picks
        (``server_port()``) unless ``configured_tcp_ports``; ``coverage``:
        a Coverage the scans record into (testing/coverage.py: the
        reference interpreter instead of the compiled code); ``code_cache``:
        (DIRECTORY, KEY) keeps ``program`` checked and compiled in DIRECTORY
        under KEY for the next load of it (the directory is the caller's)."""
        state_dir = tempfile.mkdtemp(prefix="softplc-test-")
        cache_dir, program_key = code_cache if code_cache is not None else (state_dir, None)
        attached = None
        try:
            app = load_app(path, state_dir=cache_dir, program=program, program_key=program_key)
            if not configured_tcp_ports:
                _ephemeral_servers(app.modules)
            attached = attach(app.modules, devices or {}, ports)
            ports = tuple(ports) + attached.overrides
            executor = "compiled"
            if coverage is not None:
                coverage.learn_modules(app.modules)
                executor = coverage.executor
            runner = Runner(app, RunOptions(fresh=True, ports=tuple(ports), save_state=False, executor=executor),
                            log=lambda msg: None)
        except BaseException:
            shutil.rmtree(state_dir, ignore_errors=True)
            if attached is not None:
                attached.release()
            raise
        return cls(runner, state_dir, attached)

    def device(self, port):
        """The simulated device on ``port`` (a number, or ``MODULE:N``): the
        app's own (its config's ``sim://...?device=``) or one ``load`` attached."""
        return device_on(self.engine.modules, port)

    def server_port(self, module: str | None = None) -> int | None:
        """The TCP port the app's network server (of ``module``) listens on,
        once the first scan has started it; None before or when it failed."""
        for m in self.engine.modules:
            if (module is None or m.name.upper() == module.upper()) and m.network_servers():
                return getattr(m, "port", None)
        return None

    def address(self, name: str):
        address = self._addresses.get(name)
        if address is None:
            address = self._addresses[name] = resolve_name(name, self.symbols)
        return address

    def __getitem__(self, name: str):
        if isinstance(name, DeviceCounter):  # a scenario's ``device PORT NAME``
            return getattr(self.device(port_key(name.port)), name.attribute)
        read = self._readers.get(name)
        if read is None:
            read = self._readers[name] = self._reader(name)
        return read()

    def _reader(self, name: str):
        """A direct bit, word or float is read straight from its file's array,
        as compiled rungs read it (the arrays stay in place for the table's
        life): a scenario reads the same names scan after scan. Anything else
        goes through ``table.read``."""
        address, table = self.address(name), self.table
        try:
            if address.is_direct and address.kind is ValueKind.BIT:
                data, index, mask = table.bit_ref(address)
                return lambda: 1 if data[index] & mask else 0
            if address.is_direct and address.kind in (ValueKind.WORD, ValueKind.FLOAT, ValueKind.LONG):
                data, index = table.word_ref(address)
                return lambda: data[index]
        except DataTableError:
            pass  # past the end of its file: table.read says why
        return lambda: table.read(address)

    def set(self, name: str, value) -> None:
        write = self._writers.get(name)
        if write is None:
            write = self._writers[name] = self._writer(name)
        write(value)

    def _writer(self, name: str):
        """As ``_reader``: a direct bit, or a word of a number file, takes an
        int it can hold straight into its array; any other value or address
        goes through ``table.write``, which checks it and says why not."""
        address, table = self.address(name), self.table
        slow = functools.partial(table.write, address)
        try:
            if address.is_direct and address.kind is ValueKind.BIT:
                data, index, mask = table.bit_ref(address)

                def write_bit(value) -> None:
                    if value.__class__ is int and (value == 0 or value == 1):
                        data[index] = (data[index] | mask) if value else (data[index] & ~mask)
                    else:
                        slow(value)
                return write_bit
            if address.is_direct and address.kind is ValueKind.WORD and not table.resolve(address)[0].ftype.is_string:
                data, index = table.word_ref(address)

                def write_word(value) -> None:
                    if value.__class__ is int and WORD_MIN <= value <= WORD_MAX:
                        data[index] = value
                    else:
                        slow(value)
                return write_word
        except DataTableError:
            pass
        return slow

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
            if self._attached is not None:
                self._attached.release()

    def __enter__(self) -> "PLC":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _ephemeral_servers(modules) -> None:
    """Every network server of the app listens on a port the system picks
    (0) at its configured address: a test never depends on a fixed port,
    nor fails beside a PLC that serves the app's port already."""
    for m in modules:
        config = getattr(m, "config", None)
        if type(m).network_servers is not TLM.network_servers and dataclasses.is_dataclass(config) and \
                "port" in {f.name for f in dataclasses.fields(config)} and hasattr(config, "host"):
            m.config = dataclasses.replace(config, port=0)
