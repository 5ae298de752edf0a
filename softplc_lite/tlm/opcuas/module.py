"""The OPCUAS module (TLM): an OPC UA server over the data table, for SCADA
and IIoT platforms (docs/opcuas.md).

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    OPCUAS = "softplc_lite.tlm.opcuas:OpcUaServer"

It reads OPCUAS.XML (config.py). An engine that takes it (``attach``) lays
out the address space (space.py) over its data table and program symbols:
a program that is compiled, checked or rendered starts no server. The
server is the network-server layer's (its process, the shared image, the
counters) with asyncua serving OPC UA (asyncua_glue.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from ..enips.logixconfig import export_ranges
from ..enips.logixview import build_view
from ..errors import ModuleError
from ..netconfig import refuse_tags
from ..netmodule import NetServerModule
from . import status as S
from .config import CONFIG_FILE, ServerConfig, config_references, load_config, read_config
from .protocol import OpcUaProtocol
from .security import CertPaths
from .space import build_space, rung_comments

WHERE = "OPCUAS.XML address and port; docs/opcuas.md"


class OpcUaServer(NetServerModule):
    name = "OPCUAS"
    title = "OPC UA server over the data table and symbols (for SCADA and IIoT)"
    config_file = CONFIG_FILE
    libraries = ("asyncua",)  # imported by the server process only: the load checks it is installed (registry)

    def __init__(self, config: ServerConfig | None = None) -> None:
        self.config = config or ServerConfig()
        self.app_name = "APP"
        self.engine = None
        self.server = None
        self.space = None
        self.directory = None  # a Studio 5000 export's tags (logix/tags.py)
        self.tag_ranges = None  # its storage <Writable tag>s open, and what its External Access closes

    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
            self.app_name = Path(app_dir).resolve().name
            refuse_tags(self.config)
            check_certificate(self.config)
        return list(self.config.warnings)

    def configure_export(self, config_path: Path, app_name: str, directory, programs=()) -> list[str]:
        """A Studio 5000 export's server: ``config_path`` its OPCUAS.XML
        (``<export stem>.OPCUAS.XML``), ``directory`` its tag directory
        (logix/tags.py), whose tags the address space holds; ``<Writable
        tag>``s are checked against them as ENIPS checks its own (every
        problem at once, located in the file)."""
        self.config = read_config(Path(config_path))
        self.app_name = app_name
        self.directory = directory
        self.tag_ranges = export_ranges(build_view(directory, programs), self.config)
        check_certificate(self.config)
        unseen = [f"{config_path}:{w.line}:{w.column}: <Writable address={w.address}> opens nothing a client "
                  "sees beside an export (its address space holds tags, not data files): open a tag with "
                  "<Writable tag=...>" for w in self.config.writable if w.address is not None]
        return list(self.config.warnings) + unseen

    def config_references(self) -> list:
        return config_references(self.config)

    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        self.engine = engine
        table = engine.table
        self.reference_config(table)
        program = getattr(engine, "program", None)
        symbols = program.symbols if program is not None and self.directory is None else {}
        comments = rung_comments(program) if self.directory is None else {}
        self.space = build_space(table, self.app_name, self.config, symbols, self.directory, comments,
                                 self.tag_ranges)
        self.serve(table, OpcUaProtocol(self.config, self.space), WHERE, S.LAYOUT)
        return [f"OPCUAS: {why}: not served to clients" for why in self.space.skipped]



def check_certificate(config: ServerConfig) -> None:
    """A ModuleError at the config's root when the server could offer no
    endpoint: no certificate (so no encrypted endpoint) and None not allowed.
    Said by ``softplc check`` and before a run, not by the server process."""
    paths = CertPaths.for_app(Path(config.path).parent)
    if config.allow_none or (paths.cert.exists() and paths.key.exists()):
        return
    raise ModuleError(f"no server certificate {paths.cert} and key {paths.key.name}: the server offers only "
                      "encrypted endpoints (securityNone=\"no\"); `softplc opcua-cert APP` makes them "
                      "(docs/opcuas.md, Security)", config.path, config.line, 1)
