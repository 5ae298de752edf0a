"""ENIPS.XML: the EtherNet/IP server's configuration (docs/enips.md, "The
configuration file: ENIPS.XML").

There is no SoftPLC manual for this module: the file is softplc_lite's own,
in MODBTCPS.XML's style and checked by the same machinery (tlm/xmlcheck.py,
tlm/netconfig.py): every problem at once, each with file, line, column and
what was expected; unknown elements and attributes are errors.

Every data file is readable (a PLC-5 or SLC on a network serves its whole
table); a client may write only the elements a ``<Writable>`` names. The
result is a ``ServerConfig``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ...datatable.address import Address
from ...textfile import read_bytes
from ..api import find_file
from ..errors import ModuleError, ModuleErrors
from ..netconfig import (ALLOW, Writable, check_allow, check_host, check_status, check_writable, element_references,
                         listen_attributes, listen_warning, writable_attributes)
from ..xmlcheck import MANY, Attr, XmlChecker

CONFIG_FILE = "ENIPS.XML"
ROOT = "EtherNetIpServer"
PORT = 44818  # EtherNet/IP's registered port (CIP Volume 2, 2-2), TCP and UDP
STATUS_WORDS = 16
MAX_CIP_CONNECTIONS = 32  # a ControlLogix L6x's class-3 connection count: a choice


@dataclass(frozen=True)
class ServerConfig:
    path: str = CONFIG_FILE
    host: str = "127.0.0.1"
    port: int = PORT
    allow: tuple = ()  # ipaddress networks; parse_config fills the default loopback pair
    max_connections: int = 32
    max_requests_per_second: int = 1000
    idle_timeout_ms: int = 60_000
    max_cip_connections: int = MAX_CIP_CONNECTIONS
    list_identity_udp: bool = True
    status: Address | None = None
    debug: int = 0
    writable: tuple[Writable, ...] = ()
    warnings: list[str] = field(default_factory=list)


ATTRIBUTES: dict[str, tuple[Attr, ...]] = {
    ROOT: (*listen_attributes(PORT, 32, 1000, STATUS_WORDS),
           Attr("maxCipConnections", 1, 1000, default=MAX_CIP_CONNECTIONS),
           Attr("udpListIdentity", choices=("yes", "no"), default="yes")),
    "Allow": ALLOW,
    "Writable": writable_attributes("N7:0, B3:2, F8:0, T4:0, ST9:0"),
}


def parse_config(data: bytes, path: str = CONFIG_FILE) -> ServerConfig:
    """Check ENIPS.XML's bytes; ModuleErrors listing every problem."""
    c = XmlChecker(path, ATTRIBUTES, ROOT, ("Allow", "Writable"))
    root = c.read_root(data, "docs/enips.md")
    a = c.attributes(root)
    host = check_host(c, root, a)
    status = check_status(c, root, a["status"], STATUS_WORDS) if "status" in a else None
    allow_nodes, writable_nodes = c.children(root, [("Allow", 0, MANY), ("Writable", 0, MANY)])
    allow = check_allow(c, allow_nodes)
    writable = [w for w in (check_writable(c, node, status, root.line, STATUS_WORDS, "word and bit") for node in writable_nodes) if w]
    if c.problems:
        raise ModuleErrors(c.found())
    return ServerConfig(path=path, host=host, port=a.get("port", PORT), allow=allow,
                        max_connections=a.get("maxConnections", 32),
                        max_requests_per_second=a.get("maxRequestsPerSecond", 1000),
                        idle_timeout_ms=a.get("idleTimeout", 60_000),
                        max_cip_connections=a.get("maxCipConnections", MAX_CIP_CONNECTIONS),
                        list_identity_udp=a.get("udpListIdentity", "yes") == "yes", status=status,
                        debug=a.get("debug", 0), writable=tuple(writable),
                        warnings=listen_warning(path, root, host, bool(allow_nodes)))


def load_config(app_dir: Path) -> ServerConfig:
    path = find_file(app_dir, CONFIG_FILE)
    if path is None:
        raise ModuleError(f"ENIPS is enabled in MODULES.LST but {app_dir / CONFIG_FILE} does not exist: it "
                          f"holds the <{ROOT}> configuration (the address and port to listen on, the clients "
                          "allowed, and the elements clients may write; docs/enips.md)")
    try:
        data = read_bytes(path)
    except OSError as e:
        raise ModuleError(str(e)) from None
    return parse_config(data, str(path))


def config_references(config: ServerConfig) -> list[Address]:
    """What the engine creates before the first scan (netconfig.element_references)."""
    return element_references(config, STATUS_WORDS)
