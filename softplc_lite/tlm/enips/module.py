"""The ENIPS module (TLM): an EtherNet/IP server over the data table, for
Allen-Bradley tools, HMIs and Python clients (docs/enips.md).

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    ENIPS = "softplc_lite.tlm.enips:EnipServer"

It reads ENIPS.XML (config.py). An engine that takes it (``attach``) only
lays out the image of its data table: a program that is compiled, checked
or rendered starts no server. The server is the network-server layer's
(its process, the shared image, writes applied at the input point, the
limits and the counters) serving EtherNet/IP (protocol.py, handler.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from ..netmodule import NetServerModule
from . import status as S
from .config import CONFIG_FILE, ServerConfig, config_references, load_config
from .identity import Identity
from .protocol import EnipProtocol, build_slots
from .tagnames import symbol_addresses

WHERE = "ENIPS.XML address and port; docs/enips.md"


class EnipServer(NetServerModule):
    name = "ENIPS"
    title = "EtherNet/IP server: PCCC and CIP tags over the data table (for AB tools and HMIs)"
    config_file = CONFIG_FILE

    def __init__(self, config: ServerConfig | None = None) -> None:
        self.config = config or ServerConfig()
        self.app_name = "APP"
        self.engine = None
        self.server = None

    # -- configuration ----------------------------------------------------------------------
    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
            self.app_name = Path(app_dir).resolve().name
        return list(self.config.warnings)

    def config_references(self) -> list:
        return config_references(self.config)

    # -- the server ---------------------------------------------------------------------------
    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        self.engine = engine
        table = engine.table
        self.reference_config(table)
        program = getattr(engine, "program", None)
        symbols = symbol_addresses(program.symbols) if program is not None else {}
        protocol = EnipProtocol(self.config, build_slots(table, self.config), Identity(self.app_name), symbols)
        self.serve(table, protocol, WHERE, S.LAYOUT)
        return []
