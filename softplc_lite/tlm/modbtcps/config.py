"""MODBTCPS.XML: the Modbus TCP server's configuration (docs/modbtcps.md,
"The configuration file: MODBTCPS.XML").

There is no SoftPLC manual for this module: the file is softplc_lite's own,
written in MODBMAST.XML's style and checked by the same machinery
(tlm/xmlcheck.py): every problem at once, each with file, line, column and
what was expected; unknown elements and attributes are errors.

The result is a ``ServerConfig``: where to listen, who may connect, the
limits, the optional status block, and per unit id the regions that map the
four Modicon tables (coils, discrete inputs, holding and input registers)
onto data table addresses. Rules the file must keep beyond each attribute's
own range (a region inside the Modbus address space and inside its data
table file, no two regions of one kind at one address, no writable region
over the status words) are checked here too, so ``softplc check`` reports
them before anything runs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from ...datatable import DataTableError, parse_address
from ...datatable.address import Address
from ...datatable.filetypes import MAX_ELEMENTS, STRING, STRING_CHARS, WORD_BITS
from ...textfile import read_bytes
from ..api import find_file
from ..errors import ModuleError, ModuleErrors
from ..netconfig import (ALLOW, check_allow, check_host, check_status, listen_attributes,
                         listen_warning, status_references)
from ..xmlcheck import MANY, Attr, XmlChecker, parse_integer
from ..xmlreader import XmlNode

CONFIG_FILE = "MODBTCPS.XML"
ROOT = "ModbusTcpServer"
KINDS = ("coils", "discrete_inputs", "holding_registers", "input_registers")
ELEMENT_OF_KIND = {"Coils": "coils", "DiscreteInputs": "discrete_inputs",
                   "HoldingRegisters": "holding_registers", "InputRegisters": "input_registers"}
KIND_ELEMENT = {kind: element for element, kind in ELEMENT_OF_KIND.items()}
STATUS_WORDS = 16
MODBUS_ADDRESSES = 65536  # protocol addresses 0..65535 in each table
WORD_ORDERS = ("high-low", "low-high")
WORD_FILES = ("O", "I", "S", "B", "N")  # registers and bits come from 16-bit words of these files
READ_ONLY_KINDS = ("discrete_inputs", "input_registers")  # Modbus has no function that writes them
REGISTERS_PER_ITEM = {"bit": 1, "word": 1, "float": 2, "string": STRING.words_per_element}
STRING_FORMATS = ("ucs2", "packed")
PACKED_STRING_REGISTERS = STRING_CHARS // 2  # two 8-bit characters a register


@dataclass(frozen=True)
class Region:
    """One region of a unit: ``count`` items of the ``kind`` table from
    protocol address ``start``, mapped onto the data table from ``address``."""

    kind: str  # one of KINDS
    start: int  # protocol address of the first item (0-based, as on the wire)
    count: int  # bits, or data table elements
    address: Address  # the first bit / element (direct)
    writable: bool
    value: str  # "bit", "word", "float" or "string"
    word_order: str  # "high-low" or "low-high" (meaningful for floats)
    line: int
    column: int
    string_format: str = "ucs2"  # strings: "ucs2" (LEN, then one code unit a register) or "packed"

    @property
    def registers_per_item(self) -> int:
        """Protocol items one data table item takes: 1 for a bit or word, 2
        for a float, 83 for a string (its LEN, then 82 UCS-2 code units)."""
        if self.value == "string" and self.string_format == "packed":
            return PACKED_STRING_REGISTERS
        return REGISTERS_PER_ITEM[self.value]

    @property
    def span(self) -> int:
        """Protocol addresses the region covers (bits: ``count``)."""
        return self.count * self.registers_per_item

    @property
    def end(self) -> int:
        """The protocol address just past the region."""
        return self.start + self.span

    @property
    def element(self) -> str:
        """The region's element name in the file: "HoldingRegisters"."""
        return KIND_ELEMENT[self.kind]


@dataclass(frozen=True)
class Unit:
    id: int
    regions: tuple[Region, ...]
    line: int


@dataclass(frozen=True)
class ServerConfig:
    path: str = CONFIG_FILE
    host: str = "127.0.0.1"
    port: int = 502
    allow: tuple = ()  # ipaddress networks; parse_config fills the default loopback pair
    max_connections: int = 16
    max_requests_per_second: int = 100
    idle_timeout_ms: int = 60000
    status: Address | None = None
    word_order: str = "high-low"
    debug: int = 0
    units: dict[int, Unit] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)


# -- attributes ------------------------------------------------------------------------------

_REGION = (Attr("start", 0, MODBUS_ADDRESSES - 1, required=True),
           Attr("count", 1, MODBUS_ADDRESSES, required=True),
           Attr("address", text=True, required=True, what="a data table address"))
_WRITABLE = Attr("writable", choices=("yes", "no"), default="no")
_REGION_WORD_ORDER = Attr("wordOrder", choices=WORD_ORDERS)  # absent: the root's
_STRING_FORMAT = Attr("stringFormat", choices=STRING_FORMATS, default="ucs2")

ATTRIBUTES: dict[str, tuple[Attr, ...]] = {
    ROOT: (*listen_attributes(502, 16, 100, STATUS_WORDS), Attr("wordOrder", choices=WORD_ORDERS, default="high-low")),
    "Allow": ALLOW,
    "Unit": (Attr("id", 0, 255, required=True),),
    "Coils": (*_REGION, _WRITABLE),
    "DiscreteInputs": (*_REGION, _WRITABLE),
    "HoldingRegisters": (*_REGION, _WRITABLE, _REGION_WORD_ORDER, _STRING_FORMAT),
    "InputRegisters": (*_REGION, _WRITABLE, _REGION_WORD_ORDER, _STRING_FORMAT),
}
HINT_NAMES = ("Allow", "Unit", *ELEMENT_OF_KIND)

# -- addresses -------------------------------------------------------------------------------

def item_address(region: Region, k: int) -> Address:
    """The data table address of item ``k`` of the region: bits run on into
    the next word (B3/15 then B3/16, N7:0/15 then N7:1/0), elements one by
    one (N7:0 + 5 = N7:5, F8:0 + 1 = F8:1, ST9:0 + 1 = ST9:1)."""
    address = region.address
    if region.value == "bit":
        element, bit = divmod(address.element * WORD_BITS + address.bit + k, WORD_BITS)
        return dataclasses.replace(address, element=element, bit=bit)
    return address.with_element(address.element + k)


def _words(region: Region) -> tuple[int, int]:
    """The first and last element (word) of the data table the region maps."""
    last = item_address(region, region.count - 1).element
    return region.address.element, last


def _region_value(address: Address, bits: bool) -> str | None:
    """What a region at ``address`` holds ("bit", "word", "float",
    "string"), or None when a region of that table cannot map there."""
    if address.member is not None:
        return None
    if bits:
        return "bit" if address.bit is not None and address.type_letter in WORD_FILES else None
    if address.bit is not None:
        return None
    return {**{letter: "word" for letter in WORD_FILES}, "F": "float", "ST": "string"}.get(address.type_letter)


def _what_maps(element: str) -> str:
    if element in ("Coils", "DiscreteInputs"):
        return (f"<{element}> map bits: a bit address of an O, I, S, B or N file (B3/0, N7:0/0, I:0/0, O:0/0); "
                "the bits run on into the next words")
    return (f"<{element}> map whole elements: a word of an O, I, S, B or N file (N7:0, B3:0, I:0), a float "
            "of an F file (F8:0) or a string of an ST file (ST9:0)")


def _check_address(c: XmlChecker, node: XmlNode, text: str, count: int | None) -> tuple[Address, str] | None:
    bits = node.name in ("Coils", "DiscreteInputs")
    try:
        address = parse_address(text)
    except DataTableError as e:
        c.error(node, f"address={text!r}: {getattr(e, 'message', str(e))}", "address")
        return None
    if not address.is_direct:
        c.error(node, f"address={text!r}: a region's address must be direct (no [..] or #)", "address")
        return None
    value = _region_value(address, bits)
    if value is None:
        c.error(node, f"address={text!r}: {_what_maps(node.name)}", "address")
        return None
    if count is not None:
        first = address.element * WORD_BITS + address.bit if bits else address.element
        last = (first + count - 1) // WORD_BITS if bits else first + count - 1
        if last >= MAX_ELEMENTS:
            noun = "bits" if bits else "elements"
            c.error(node, f"address={text!r}: {count} {noun} from here run past the end of a file "
                          f"(elements 0..{MAX_ELEMENTS - 1})", "address")
            return None
    return address, value


# -- elements --------------------------------------------------------------------------------

def _check_region(c: XmlChecker, node: XmlNode, root_order: str) -> Region | None:
    kind = ELEMENT_OF_KIND[node.name]
    a = c.attributes(node)
    c.children(node, [])
    ok = len(c.problems)
    writable = a.get("writable") == "yes"
    if writable and kind in READ_ONLY_KINDS:
        other = "Coils" if kind == "discrete_inputs" else "HoldingRegisters"
        c.error(node, f'writable="yes": <{node.name}> are read-only in Modbus (no function writes them); map '
                      f"them as <{other}> to let clients write", "writable")
    found = _check_address(c, node, a["address"], a.get("count")) if "address" in a else None
    value = found[1] if found else None
    if "wordOrder" in a and value is not None and value != "float":
        c.error(node, f"wordOrder applies to a float region (an F file address); {a['address']} holds "
                      f"{value}s", "wordOrder")
    if "stringFormat" in node.attrs and value is not None and value != "string":
        c.error(node, f"stringFormat applies to a string region (an ST file address); {a['address']} holds "
                      f"{value}s", "stringFormat")
    if len(c.problems) > ok or found is None or "start" not in a or "count" not in a:
        return None
    region = Region(kind, a["start"], a["count"], found[0], writable, value,
                    a.get("wordOrder", root_order) if value == "float" else root_order, node.line, node.column,
                    a.get("stringFormat", "ucs2"))
    if region.end > MODBUS_ADDRESSES:
        unit = "bits" if value == "bit" else "registers"
        c.error(node, f"<{node.name}> leaves the Modbus address space: {region.span} {unit} from start "
                      f"{region.start} reach address {region.end - 1}; the last is {MODBUS_ADDRESSES - 1}", "count")
        return None
    return region


def _describe(region: Region) -> str:
    return f"<{region.element}> {region.start}..{region.end - 1} on line {region.line}"


def _check_overlaps(c: XmlChecker, nodes: dict[int, XmlNode], regions: list[Region]) -> list[Region]:
    """The regions, less each one that shares protocol addresses with another
    of its kind (reported at the later one in the file, naming the other)."""
    bad: set[int] = set()
    for kind in KINDS:
        same = sorted((r for r in regions if r.kind == kind), key=lambda r: (r.start, r.line, r.column))
        reach: Region | None = None  # the region reaching furthest so far
        for region in same:
            if reach is not None and region.start < reach.end:
                later, earlier = (region, reach) if (region.line, region.column) > (reach.line, reach.column) \
                    else (reach, region)
                if id(later) not in bad:
                    c.error(nodes[id(later)], f"<{later.element}> {later.start}..{later.end - 1} overlaps "
                                              f"{_describe(earlier)}; two regions of one kind in a unit may not "
                                              "share an address", "start")
                    bad.add(id(later))
            if reach is None or region.end > reach.end:
                reach = region
    return [r for r in regions if id(r) not in bad]


def _check_unit(c: XmlChecker, node: XmlNode, config: dict) -> Unit | None:
    a = c.attributes(node)
    regions: list[Region] = []
    nodes: dict[int, XmlNode] = {}
    for kid in c.any_order(node, ELEMENT_OF_KIND):
        region = _check_region(c, kid, config["word_order"])
        if region is not None:
            regions.append(region)
            nodes[id(region)] = kid
    regions = _check_overlaps(c, nodes, regions)
    status = config["status"]
    if status is not None:
        words = (status.element, status.element + STATUS_WORDS - 1)
        for region in regions:
            first, last = _words(region)
            if region.writable and (region.address.type_letter, region.address.file) == \
                    (status.type_letter, status.file) and first <= words[1] and words[0] <= last:
                c.error(nodes[id(region)], f"<{region.element}> is writable and maps {region.address}.."
                                           f"{item_address(region, region.count - 1)}, over the status words "
                                           f"{status}..{status.with_element(words[1])} (status= on line "
                                           f"{config['status_line']}): a client must not write the server's "
                                           "counters", "address")
    if "id" not in a:
        return None
    return Unit(a["id"], tuple(regions), node.line)


def parse_config(data: bytes, path: str = CONFIG_FILE) -> ServerConfig:
    """Check MODBTCPS.XML's bytes; ModuleErrors listing every problem."""
    c = XmlChecker(path, ATTRIBUTES, ROOT, HINT_NAMES)
    root = c.read_root(data, "docs/modbtcps.md")
    a = c.attributes(root)
    host = check_host(c, root, a)
    status = check_status(c, root, a["status"], STATUS_WORDS) if "status" in a else None
    allow_nodes, unit_nodes = c.children(root, [("Allow", 0, MANY), ("Unit", 1, MANY)])
    allow = check_allow(c, allow_nodes)
    shared = {"word_order": a.get("wordOrder", "high-low"), "status": status, "status_line": root.line}
    units: dict[int, Unit] = {}
    lines: dict[int, int] = {}
    warnings: list[str] = []
    for node in unit_nodes:
        unit = _check_unit(c, node, shared)
        uid = parse_integer(node.attrs.get("id", ""))  # a repeated id counts even on a unit with other problems
        if uid is not None and uid in lines:
            c.error(node, f"unit id {uid} is used twice (first on line {lines[uid]}); a unit id is unique in "
                          "the server", "id")
            continue
        if uid is not None:
            lines[uid] = node.line
        if unit is not None:
            units[unit.id] = unit
            if not unit.regions:
                warnings.append(f"{path}:{node.line}: <Unit id=\"{unit.id}\"> maps nothing: every request to it "
                                "is refused (exception 02)")
    if c.problems:
        raise ModuleErrors(c.found())
    warnings[:0] = listen_warning(path, root, host, bool(allow_nodes))
    return ServerConfig(path=path, host=host, port=a.get("port", 502), allow=allow, max_connections=a.get("maxConnections", 16),
                        max_requests_per_second=a.get("maxRequestsPerSecond", 100),
                        idle_timeout_ms=a.get("idleTimeout", 60_000), status=status,
                        word_order=a.get("wordOrder", "high-low"), debug=a.get("debug", 0), units=units,
                        warnings=warnings)


def config_path(app_dir: Path) -> Path | None:
    """MODBTCPS.XML in ``app_dir`` (the name in any case), or None."""
    return find_file(app_dir, CONFIG_FILE)


def load_config(app_dir: Path) -> ServerConfig:
    path = config_path(app_dir)
    if path is None:
        raise ModuleError(f"MODBTCPS is enabled in MODULES.LST but {app_dir / CONFIG_FILE} does not exist: it "
                          f"holds the <{ROOT}> configuration (the address and port to listen on, the clients "
                          "allowed, and the data table regions each unit id serves; docs/modbtcps.md)")
    try:
        data = read_bytes(path)  # xmlreader honours a BOM (UTF-8, UTF-16) and the declared encoding
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: permission denied"
        raise ModuleError(str(e)) from None
    return parse_config(data, str(path))


def config_references(config: ServerConfig) -> list[Address]:
    """The first and last data table address of every region and of the
    status block, so that the engine creates those words before the first
    scan (as MODBMAST's blocks are referenced)."""
    found: list[Address] = []
    for unit in config.units.values():
        for region in unit.regions:
            found.append(region.address)
            found.append(item_address(region, region.count - 1))
    return found + status_references(config.status, STATUS_WORDS)
