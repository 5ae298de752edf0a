"""The MODBMAST module (TLM): a Modbus RTU/ASCII serial master driver.

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    MODBMAST = "softplc_lite.tlm.modbmast:Modbmast"

It reads MODBMAST.XML (config.py), opens one port per <Port> through the
shared port layer (softplc_lite.ports), and drives each port's scan list at
the engine's input and output points (portdriver.py): read replies land in
the data table at the input point, before the ladder; write requests carry
the outputs the last scan left. It keeps every slave's status (status.py)
for the three MBR_ instructions (instructions.py).

Port numbers: ``num`` N is the machine's COM(N+1), as COMGENIUS's bare port
number is (num 0 is COM1, /dev/ttyS0 on Linux); the softplc_lite attribute
``device`` names another device or a URL, and ``softplc run --port N=...``
(``--port MODBMAST:N=...`` when COMGENIUS also has a port N) replaces it
for one run.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Mapping

import serial

from ...ladder import status as S
from ...ladder.ast import Instruction
from ...ladder.host import Mode
from ...ladder.errors import LadderError
from ...ladder.instructions import InstructionSpec
from ...modbus.framing import FRAMERS
from ...ports import LineSettings, PortClaim, SerialPort, com_url, physical_url
from ..api import TLM, Instance, InstructionContext
from ..errors import ModuleError
from . import instructions
from .config import CONFIG_FILE, ModbmastConfig, PortConfig, load_config
from .portdriver import MS, PortDriver
from .prepared import Prepared
from .status import NO_XMIT_ROOM, SlaveStatus


class Modbmast(TLM):
    name = "MODBMAST"
    title = "Modbus RTU/ASCII serial master driver (MBR_GETFAULTMAP, MBR_GETSTATUS, MBR_CLEARSTATUS)"
    config_file = CONFIG_FILE

    def __init__(self, config: ModbmastConfig | None = None) -> None:
        self.config = config or ModbmastConfig()
        self.app_dir: Path | None = None
        self.engine = None
        self.options: Mapping[str, object] = {}
        self.drivers: list[PortDriver] = []
        self.status: dict[int, dict[int, SlaveStatus]] = {}
        self.recorder = None

    # -- configuration --------------------------------------------------------------------
    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.app_dir = app_dir
            self.config = load_config(app_dir)
        return list(self.config.warnings)

    def instructions(self) -> list[InstructionSpec]:
        return list(instructions.SPECS)

    def check(self, instr: Instruction) -> list[LadderError]:
        return instructions.check(instr, self.config.ports)

    def references(self, instr: Instruction) -> list:
        return instructions.references(instr)

    def port_url(self, pc: PortConfig) -> str:
        """The device or URL of a <Port>: its ``device``, else COM(num+1)."""
        return physical_url(pc.device) if pc.device else com_url(pc.num + 1)

    def port_claims(self) -> list[PortClaim]:
        return [PortClaim(self.name, n, self.port_url(pc), f"{self.config.path}:{pc.line}")
                for n, pc in sorted(self.config.ports.items())]

    def port_numbers(self) -> list[int]:
        return sorted(self.config.ports)

    def port_status(self, number: int) -> dict[int, SlaveStatus] | None:
        """The slaves' statuses of port ``number`` (None: not configured)."""
        return self.status.get(number)

    def serial_ports(self) -> list:
        return [d.port for d in self.drivers]

    # -- the driver -------------------------------------------------------------------------
    def config_references(self) -> list:
        """The first and last word of every data block of the XML config."""
        found = []
        for pc in self.config.ports.values():
            for slave in pc.slaves.values():
                for request in slave.requests:
                    for block in request.to_blocks + request.from_blocks:
                        if block.address is not None:
                            found.append(block.address)
                            found.append(block.address.with_element(block.address.element + block.words - 1))
        return found

    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        """Open the ports and start their scan lists. ``options``: "ports"
        {num: device or URL}, "recorder", "replay" (see tlm.api)."""
        self.engine = engine
        self.options = options
        self.recorder = options.get("recorder")
        return self._start(engine)

    def _start(self, engine) -> list[str]:
        from ...ports.urlhandler import register  # sim:// and replay:// join pyserial's URL schemes

        register()
        config, table = self.config, engine.table
        for address in self.config_references():  # the files the blocks reach exist before anything is bound
            table.reference(address)
        overrides = dict(self.options.get("ports") or {})
        replay = self.options.get("replay")
        self.status = {n: {sid: SlaveStatus() for sid in pc.slaves} for n, pc in config.ports.items()}
        self.drivers = []
        warnings: list[str] = []
        for number, pc in sorted(config.ports.items()):
            url = overrides.get(number) or (f"replay://{replay}?port={self.name}:{number}" if replay else None)
            url = physical_url(url) if url else self.port_url(pc)
            settings = LineSettings(pc.baud, pc.data_bits, pc.parity, pc.stop_bits)
            port = SerialPort(f"{self.name}:{number}", url, settings, self.debug, lambda: 0, config.retry_ms,
                              log_frames=config.debug >= 2)
            framer = FRAMERS[pc.framing]
            prepared = {id(r): Prepared(r, framer, table) for s in pc.slaves.values() for r in s.requests}
            driver = PortDriver(pc, port, prepared, self.status[number], lambda: engine.mode, self.debug)
            port.now_ns = driver.clock
            self.drivers.append(driver)
            try:
                port.open()
            except serial.SerialException:
                message = f"port {number}: cannot open {url}: {port.error}"
                if config.port_errors != "retry":
                    why = port.error
                    self._close_ports()
                    retry = "(set portErrors=\"retry\" on <ModbusSerial> to run on without it)"
                    if overrides.get(number):  # the device is a --port option's, not the <Port>'s
                        raise ModuleError(f"--port {self.name}:{number}={overrides[number]}: cannot open {url}: "
                                          f"{why} {retry}") from None
                    raise ModuleError(f"<Port>: {message} {retry}", config.path, pc.line) from None
                warnings.append(f"{config.path}:{pc.line}: <Port>: {message}; running on: its slaves are Not "
                                f"Present and it is retried every {config.retry_ms} ms")
                for s in self.status[number].values():
                    s.present, s.last_code = False, NO_XMIT_ROOM
                driver.vt = self._now(driver)  # its clock until it comes back (then started() sets it)
            else:
                driver.started(self._now(driver))
            if self.recorder is not None:  # a port that comes back later is recorded too
                self.recorder.add_port(port, f"{self.port_url(pc)} -> {url} {settings} {pc.framing}", driver.clock)
        return warnings

    def _now(self, driver: PortDriver) -> int:
        """A port's time: the engine's on a simulated port with simulated
        engine time, the wall clock otherwise (a real wire runs on real time)."""
        clock = self.engine.clock
        if driver.port.clocked and not clock.realtime:
            return clock.now_ms * MS
        return time.monotonic_ns()

    def on_input(self, engine) -> None:
        for driver in self.drivers:
            driver.advance(self._now(driver), True)

    def on_output(self, engine, outputs_enabled: bool) -> None:
        for driver in self.drivers:
            driver.advance(self._now(driver), False)
        if self.recorder is not None:
            self.recorder.flush()

    def on_mode(self, engine, old: Mode, new: Mode) -> None:
        if old is Mode.PROGRAM and new is Mode.PROGRAM:
            self.reload(engine)
            return
        for driver in self.drivers:
            driver.mode_changed(old, new, self._now(driver))

    def reload(self, engine) -> None:
        """PROGRAM -> PROGRAM (manual 5.2): read MODBMAST.XML again and start
        over with it. A file that fails to load faults the PLC (Table 4:
        "an error in one of your driver configurations") and the driver goes
        on with the configuration it had."""
        if self.app_dir is None:
            return
        try:
            config = load_config(self.app_dir)
        except ModuleError as e:
            self.log(f"configuration not reloaded:\n{e.report()}")
            engine.module_fault(S.FAULT_MODULE_CONFIG, f"{self.name} configuration did not reload: {e.report()}")
            return
        old = self.config
        self._close_ports()
        self.config = config
        try:
            warnings = self._start(engine)
        except ModuleError as e:
            self.config = old
            self._start(engine)
            engine.module_fault(S.FAULT_MODULE_CONFIG, f"{self.name} configuration did not reload: {e.report()}")
            return
        for w in config.warnings + warnings:
            self.log(f"warning: {w}")
        self.log(f"configuration reloaded from {config.path}: {len(config.ports)} port(s), "
                 f"{sum(len(pc.slaves) for pc in config.ports.values())} slave(s)")

    def _close_ports(self) -> None:
        for driver in self.drivers:
            driver.port.close()
        self.drivers = []

    def close(self) -> None:
        for driver in self.drivers:
            report = driver.port.replay_report()
            if report is not None:
                self.log(report)
        self._close_ports()
        self.recorder = None  # the engine closes the run's recorder

    def create(self, instr: Instruction, ctx: InstructionContext) -> Instance:
        make = instructions.INSTANCES.get(instr.mnemonic)
        if make is None:
            return super().create(instr, ctx)
        return make(ctx, self)

    def debug(self, level: int, message: str) -> None:
        """debug="1" logs port events, slaves going Not Present and failed
        requests; "2" adds every transaction with its frames and timing
        (manual 6.2); "0" is silent."""
        if self.config.debug >= level:
            self.log_stamped(message, self.engine)
