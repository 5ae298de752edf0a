"""The ENIPS module (TLM): an EtherNet/IP server over the data table, for
Allen-Bradley tools, HMIs and Python clients (docs/enips.md).

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    ENIPS = "softplc_lite.tlm.enips:EnipServer"

It reads ENIPS.XML (config.py): an app directory's, or for a Studio 5000
export the ``<export stem>.ENIPS.XML`` beside it (``configure_export``),
which serves the export's tags (logixview.py, logixconfig.py) in place of
the data files. An engine that takes it (``attach``) only
lays out the image of its data table: a program that is compiled, checked
or rendered starts no server. The server is the network-server layer's
(its process, the shared image, writes applied at the input point, the
limits and the counters) serving EtherNet/IP (protocol.py, handler.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from ...textfile import read_bytes
from ..errors import ModuleError
from ..netconfig import refuse_tags
from ..netmodule import NetServerModule
from . import status as S
from .config import CONFIG_FILE, ServerConfig, config_references, load_config, parse_config
from .identity import Identity
from .logixconfig import export_ranges
from .logixview import build_view
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
        self.logix = None  # a Logix app's tags (logixview.LogixView)
        self.open_ranges: dict = {}  # items <Writable tag> opens; items the export keeps Read Only
        self.closed: dict = {}

    # -- configuration ----------------------------------------------------------------------
    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
            self.app_name = Path(app_dir).resolve().name
            refuse_tags(self.config)
        return list(self.config.warnings)

    def configure_export(self, config_path: Path, app_name: str, directory, programs=()) -> list[str]:
        """A Studio 5000 export's server: ``config_path`` its ENIPS.XML
        (``<export stem>.ENIPS.XML``), ``directory`` its tag directory
        (logix/tags.py), ``programs`` its programs' names. ModuleErrors
        lists every problem of the file."""
        try:
            data = read_bytes(config_path)
        except OSError as e:
            raise ModuleError(f"{config_path}: cannot read it: {e.strerror or e}") from None
        self.config = parse_config(data, str(config_path))
        self.app_name = app_name
        self.logix = build_view(directory, programs)
        self.open_ranges, self.closed = export_ranges(self.logix, self.config)
        return list(self.config.warnings) + [f"{config_path}: tag {why}: not served to clients"
                                             for why in self.logix.skipped]

    def config_references(self) -> list:
        return config_references(self.config)

    # -- the server ---------------------------------------------------------------------------
    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        self.engine = engine
        table = engine.table
        self.reference_config(table)
        program = getattr(engine, "program", None)
        symbols = symbol_addresses(program.symbols) if program is not None and self.logix is None else {}
        slots = build_slots(table, self.config, self.open_ranges, self.closed)
        protocol = EnipProtocol(self.config, slots, Identity(self.app_name), symbols, self.logix)
        self.serve(table, protocol, WHERE, S.LAYOUT)
        return []
