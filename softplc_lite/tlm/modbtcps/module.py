"""The MODBTCPS module (TLM): a Modbus TCP server over the data table, for
HMIs and SCADA (docs/modbtcps.md).

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    MODBTCPS = "softplc_lite.tlm.modbtcps:ModbTcpServer"

It reads MODBTCPS.XML (config.py). An engine that takes it (``attach``)
only places the map in its data table: a program that is compiled, checked
or rendered starts no server. The server is the network-server layer's
(softplc_lite/netserver: its process, the shared image, writes applied at
the input point, the limits and the counters) serving Modbus TCP
(protocol.py, handler.py: pymodbus's framing); the module holds its handle
and calls it at each scan, and lays out the status words (status.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from ..netmodule import NetServerModule
from . import status as C
from .config import CONFIG_FILE, ServerConfig, config_references, load_config
from .layout import Layout
from .protocol import ModbusProtocol

WHERE = "MODBTCPS.XML address and port; docs/modbtcps.md"


class ModbTcpServer(NetServerModule):
    name = "MODBTCPS"
    title = "Modbus TCP server over the data table (for HMIs and SCADA)"
    config_file = CONFIG_FILE
    libraries = ("pymodbus",)  # imported by the server process only: the load checks it is installed (registry)

    def __init__(self, config: ServerConfig | None = None) -> None:
        self.config = config or ServerConfig()
        self.engine = None
        self.layout: Layout | None = None
        self.server = None

    # -- configuration ----------------------------------------------------------------------
    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
        return list(self.config.warnings)

    def config_references(self) -> list:
        return config_references(self.config)

    # -- the server ---------------------------------------------------------------------------
    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        self.engine = engine
        table = engine.table
        self.reference_config(table)
        self.layout = Layout.build(self.config, table)
        self.serve(table, ModbusProtocol(self.config, self.layout), WHERE, C.LAYOUT)
        return []
