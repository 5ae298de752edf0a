"""The COMGENIUS module (TLM): its config, its instructions, its driver.

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    COMGENIUS = "softplc_lite.tlm.comgenius:ComGenius"
"""

from __future__ import annotations

import time
from pathlib import Path

from ...ladder.ast import Instruction
from ...ladder.errors import LadderError
from ...ladder.instructions import InstructionSpec
from ..api import TLM, InstructionContext, Instance
from .config import CONFIG_FILE, ComGeniusConfig, load_config
from .instructions import STRPRINT, STRSCAN, StrPrint, StrScan, check_format_use


class ComGenius(TLM):
    name = "COMGENIUS"
    title = "serial ports and string formatting (COMPRINT, COMSCAN, STRPRINT, STRSCAN, ...)"
    config_file = CONFIG_FILE

    def __init__(self, config: ComGeniusConfig | None = None) -> None:
        self.config = config or ComGeniusConfig()

    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
        return list(self.config.warnings)

    def instructions(self) -> list[InstructionSpec]:
        return [STRPRINT, STRSCAN]

    def check(self, instr: Instruction) -> list[LadderError]:
        if instr.mnemonic == "STRPRINT":
            return check_format_use(instr, self.config.strings, 1, scan=False)
        if instr.mnemonic == "STRSCAN":
            return check_format_use(instr, self.config.strings, 2, scan=True)
        return []

    def create(self, instr: Instruction, ctx: InstructionContext) -> Instance:
        if instr.mnemonic == "STRPRINT":
            return StrPrint(ctx, self.config.strings, self.debug)
        if instr.mnemonic == "STRSCAN":
            return StrScan(ctx, self.config.strings, self.debug)
        return super().create(instr, ctx)

    def debug(self, level: int, message: str) -> None:
        """DEBUG=1 logs errors, DEBUG=2 also each result (manual 5.1)."""
        if self.config.debug >= level:
            self.log(f"{time.strftime('%H:%M:%S')} {message}")
