"""The COMGENIUS module (TLM): its config, its instructions, its driver.

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    COMGENIUS = "softplc_lite.tlm.comgenius:ComGenius"
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Mapping

from ...ladder.ast import Const, Instruction
from ...ladder.errors import LadderError
from ...ladder.instructions import InstructionSpec
from ...ports import PortClaim
from ..api import TLM, InstructionContext, Instance
from .config import CONFIG_FILE, ComGeniusConfig, load_config
from .com import (COMPRINT, COMRCVCLEAR, COMRCVSTS, COMSCAN, COMXMITCLEAR, ComPrint, ComRcvClear, ComRcvSts,
                  ComScan, ComXmitClear)
from .instructions import STRPRINT, STRSCAN, StrPrint, StrScan, check_format_use
from .ports import PortSet


class ComGenius(TLM):
    name = "COMGENIUS"
    title = "serial ports and string formatting (COMPRINT, COMSCAN, STRPRINT, STRSCAN, ...)"
    config_file = CONFIG_FILE

    def __init__(self, config: ComGeniusConfig | None = None) -> None:
        self.config = config or ComGeniusConfig()
        self.ports: PortSet | None = None
        self.engine = None
        self.recorder = None

    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
        return list(self.config.warnings)

    def instructions(self) -> list[InstructionSpec]:
        return [COMPRINT, COMSCAN, COMRCVCLEAR, COMXMITCLEAR, COMRCVSTS, STRPRINT, STRSCAN]

    def check(self, instr: Instruction) -> list[LadderError]:
        m = instr.mnemonic
        found = []
        if m in ("COMPRINT", "COMSCAN", "COMRCVCLEAR", "COMXMITCLEAR", "COMRCVSTS"):
            found += check_port_use(instr, 1 if m in ("COMPRINT", "COMSCAN") else 0, self.config)
        if m == "STRPRINT":
            found += check_format_use(instr, self.config.strings, 1, scan=False)
        elif m == "STRSCAN":
            found += check_format_use(instr, self.config.strings, 2, scan=True)
        elif m in ("COMPRINT", "COMSCAN"):
            found += check_format_use(instr, self.config.strings, 2, scan=m == "COMSCAN")
        return found

    # -- the driver ------------------------------------------------------------------------
    def port_claims(self) -> list[PortClaim]:
        return PortSet(self.config, self.debug, lambda: 0).claims(self.name)

    def serial_ports(self) -> list:
        return list(self.ports.ports.values()) if self.ports is not None else []

    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        """Open the ports (manual: at start). ``options``: "ports" {logical:
        device or URL} replaces physical fields, "recorder" records every
        port's traffic, "replay" a trace file to play every port from."""
        self.engine = engine
        clock = engine.clock
        if getattr(clock, "realtime", False):
            now_ns = time.monotonic_ns
        else:
            def now_ns(clock=clock) -> int:
                return clock.now_ms * 1_000_000
        self.now_ns = now_ns
        overrides = dict(options.get("ports") or {})
        replay = options.get("replay")
        if replay:
            for number in self.config.ports:
                overrides.setdefault(number, f"replay://{replay}?port={number}")
        self.ports = PortSet(self.config, self.debug, now_ns, overrides, given=set(options.get("ports") or {}))
        warnings = self.ports.open_all()
        self.recorder = options.get("recorder")
        if self.recorder is not None:
            for p in self.ports.ports.values():
                c = p.config
                self.recorder.add_port(p, f"{c.physical} -> {p.url} {p.settings} {c.encoding}", now_ns)
        return warnings

    def on_input(self, engine) -> None:
        ports = self.ports
        if ports is not None:
            for port in ports.port_list:  # a down port is retried (ports.py)
                if port.error is None:
                    port.poll_input()
                elif port.error != "closed":
                    port.retry()

    def on_output(self, engine, outputs_enabled: bool) -> None:
        # Ports are communication, not outputs: TEST mode still talks (as a
        # SoftPLC does in its test mode, where only the I/O image is held).
        ports = self.ports
        if ports is not None:
            for port in ports.port_list:  # most scans have nothing to send
                if port.tx:
                    port.flush_output()
        if self.recorder is not None:
            self.recorder.flush()

    def close(self) -> None:
        if self.ports is not None:
            for p in self.ports.ports.values():
                report = p.replay_report()
                if report is not None:
                    self.log(report)
            self.ports.close()
        self.recorder = None  # the engine closes the run's recorder

    def create(self, instr: Instruction, ctx: InstructionContext) -> Instance:
        m = instr.mnemonic
        if m == "STRPRINT":
            return StrPrint(ctx, self.config.strings, self.debug)
        if m == "STRSCAN":
            return StrScan(ctx, self.config.strings, self.debug)
        if self.ports is None:  # created outside an engine that attached us
            self.ports = PortSet(self.config, self.debug, lambda: ctx.now_ms * 1_000_000)
        if m == "COMPRINT":
            return ComPrint(ctx, self.ports, self.config.strings, self.debug)
        if m == "COMSCAN":
            return ComScan(ctx, self.ports, self.config.strings, self.debug)
        if m == "COMRCVCLEAR":
            return ComRcvClear(ctx, self.ports, self.debug)
        if m == "COMXMITCLEAR":
            return ComXmitClear(ctx, self.ports, self.debug)
        if m == "COMRCVSTS":
            return ComRcvSts(ctx, self.ports, self.debug)
        return super().create(instr, ctx)

    def debug(self, level: int, message: str) -> None:
        """DEBUG=1 logs port events and errors, DEBUG=2 also every frame in
        hex and each result (manual 5.1); DEBUG=0 is silent."""
        if self.config.debug >= level:
            self.log_stamped(message, self.engine)


def check_port_use(instr: Instruction, port_at: int, config: ComGeniusConfig) -> list[LadderError]:
    """A constant port with no [PORTS] line: ER (or a minor fault) at run time."""
    op = instr.operands[port_at]
    if isinstance(op, Const) and op.value not in config.ports:
        have = ", ".join(str(n) for n in config.ports) or "none"
        return [LadderError(op.pos, f"{instr.mnemonic}: port {op.value} is not configured in [PORTS] of "
                            f"{config.path} (configured: {have}); it will set "
                            f"{'ER' if port_at else 'a minor fault'}")]
    return []
