"""OPCUAS.XML: the OPC UA server's configuration (docs/opcuas.md, "The
configuration file: OPCUAS.XML").

There is no SoftPLC manual for this module: the file is softplc_lite's own,
in MODBTCPS.XML's and ENIPS.XML's style and checked by the same machinery
(tlm/xmlcheck.py, tlm/netconfig.py): every problem at once, each with file,
line, column and what was expected; unknown elements and attributes are
errors. It says where to listen, which parts of the PLC the address space
exposes, what clients may write (none unless a ``<Writable>`` names it: data
table elements, or a Studio 5000 export's tags, checked as ENIPS.XML's are), the limits on sessions, subscriptions and monitored items, and the
status block. The result is a ``ServerConfig``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ...datatable.address import Address
from ...textfile import read_bytes
from ..api import find_file
from ..errors import ModuleError, ModuleErrors
from ..netconfig import (HOST_WHAT, LOOPBACK, Writable, check_host, check_status, check_writable, element_references,
                         ipaddress_is_loopback, writable_attributes)
from ..xmlcheck import MANY, Attr, XmlChecker

CONFIG_FILE = "OPCUAS.XML"
ROOT = "OpcUaServer"
PORT = 4840  # OPC UA's registered port for opc.tcp (OPC 10000-6, 7.2)
STATUS_WORDS = 16
YES_NO = ("yes", "no")

ATTRIBUTES: dict[str, tuple[Attr, ...]] = {
    ROOT: (Attr("address", text=True, default="127.0.0.1", what=HOST_WHAT),
           Attr("port", 1, 65535, default=PORT),
           Attr("symbols", choices=YES_NO, default="yes"),
           Attr("dataFiles", choices=YES_NO, default="yes"),
           Attr("tags", choices=YES_NO, default="yes"),
           Attr("maxSessions", 1, 1000, default=10),
           Attr("maxSubscriptions", 1, 10_000, default=100),
           Attr("maxMonitoredItems", 1, 1_000_000, default=10_000),
           Attr("idleTimeout", 100, 3_600_000, default=5_000),
           Attr("status", text=True, what=f"a word address of an N or B file, the first of {STATUS_WORDS} "
                                           "status words (N40:0)"),
           Attr("debug", 0, 2, default=0),
           Attr("securityNone", choices=YES_NO, default="no"),
           Attr("securitySign", choices=YES_NO, default="no"),
           Attr("anonymous", choices=YES_NO, default="yes"),
           Attr("trustedClientsOnly", choices=YES_NO, default="no")),
    "Writable": writable_attributes("N7:0, B3:0, F8:0, T4:0, ST9:0"),
}


@dataclass(frozen=True)
class ServerConfig:
    path: str = CONFIG_FILE
    host: str = "127.0.0.1"
    port: int = PORT
    symbols: bool = True  # the program's SYMBOLs, each a variable
    data_files: bool = True  # the data table, by file, element and bit
    tags: bool = True  # a Studio 5000 export's tags, by their paths
    max_sessions: int = 10
    max_subscriptions: int = 100
    max_monitored_items: int = 10_000
    status: Address | None = None
    debug: int = 0
    writable: tuple[Writable, ...] = ()  # none: every node read-only
    # security (security.py): the defaults are the secure ones; each "yes" but anonymous loosens it
    allow_none: bool = False  # an endpoint with SecurityPolicy None beside the encrypted ones
    allow_sign: bool = False  # Sign-only endpoints beside SignAndEncrypt
    anonymous: bool = True  # anonymous sessions, read only
    trusted_clients_only: bool = False  # a channel's certificate must be one of OPCUAS.PKI/trusted/
    line: int = 0  # the root element's, where a security problem is located
    warnings: list[str] = field(default_factory=list)

    # a connection with no session activated this long after it opened is closed, counted idle
    # (asyncua_glue.py): garbage, or a client stalled before its session, holds a slot of maxSessions
    # only this long; an OPC UA client activates its session within a second (a choice)
    idle_timeout_ms: int = 5_000
    # what the network-server layer's Settings take (tlm/netmodule.settings_of); asyncua accepts the
    # connections and answers the requests, so the layer's allow-list and rate rules are not consulted
    allow: tuple = LOOPBACK
    max_requests_per_second: int = 100_000

    @property
    def max_connections(self) -> int:
        return self.max_sessions  # one session a connection: asyncua's connection limit holds the sessions


def parse_config(data: bytes, path: str = CONFIG_FILE) -> ServerConfig:
    """Check OPCUAS.XML's bytes; ModuleErrors listing every problem."""
    c = XmlChecker(path, ATTRIBUTES, ROOT, ("Writable",))
    root = c.read_root(data, "docs/opcuas.md")
    a = c.attributes(root)
    host = check_host(c, root, a)
    status = check_status(c, root, a["status"], STATUS_WORDS) if "status" in a else None
    writable_nodes, = c.children(root, [("Writable", 0, MANY)])
    writable = [w for w in (check_writable(c, node, status, root.line, STATUS_WORDS, "member and bit")
                            for node in writable_nodes) if w]
    if a.get("symbols") == a.get("dataFiles") == a.get("tags") == "no":
        c.error(root, 'symbols, dataFiles and tags are all "no": the server would expose nothing of the PLC '
                      "but its mode, fault code and scan time; say yes to one", "symbols")
    if c.problems:
        raise ModuleErrors(c.found())
    warnings = [] if ipaddress_is_loopback(host) else [
        f"{path}:{root.line}: listening on {host}: OPC UA clients beyond this machine can read the PLC "
        "(anonymous sessions read only; docs/opcuas.md)"]
    if a.get("securityNone") == "yes" and not ipaddress_is_loopback(host):
        warnings.append(f"{path}:{root.line}: securityNone=\"yes\" on {host}: clients beyond this machine may "
                        "connect unencrypted, unsigned (docs/opcuas.md, Security)")
    return ServerConfig(path=path, host=host, port=a.get("port", PORT), symbols=a.get("symbols") == "yes",
                        data_files=a.get("dataFiles") == "yes", tags=a.get("tags") == "yes",
                        max_sessions=a.get("maxSessions", 10), max_subscriptions=a.get("maxSubscriptions", 100),
                        max_monitored_items=a.get("maxMonitoredItems", 10_000), status=status,
                        idle_timeout_ms=a.get("idleTimeout", 5_000),
                        debug=a.get("debug", 0), writable=tuple(writable), warnings=warnings,
                        allow_none=a.get("securityNone") == "yes", allow_sign=a.get("securitySign") == "yes",
                        anonymous=a.get("anonymous", "yes") == "yes",
                        trusted_clients_only=a.get("trustedClientsOnly") == "yes", line=root.line)


def read_config(path: Path) -> ServerConfig:
    try:
        data = read_bytes(path)
    except OSError as e:
        raise ModuleError(f"{path}: cannot read it: {e.strerror or e}") from None
    return parse_config(data, str(path))


def load_config(app_dir: Path) -> ServerConfig:
    path = find_file(app_dir, CONFIG_FILE)
    if path is None:
        raise ModuleError(f"OPCUAS is enabled in MODULES.LST but {app_dir / CONFIG_FILE} does not exist: it "
                          f"holds the <{ROOT}> configuration (the address and port to listen on, what the "
                          "address space exposes, the limits; docs/opcuas.md)")
    return read_config(path)


def config_references(config: ServerConfig) -> list[Address]:
    """What the engine creates before the first scan (netconfig.element_references)."""
    return element_references(config, STATUS_WORDS)
