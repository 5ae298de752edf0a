"""MODBMAST.XML (also read as MODBUS.XML): the driver's configuration, manual
chapter 4.

The elements and what each may contain are Table 8; the attributes, their
ranges and defaults the attribute table of section 4.3 (docs/modbmast.md
lists both, with the softplc_lite extensions marked). ``load_config`` reads
the file and checks all of it, reporting every problem at once, each with
file, line, column and what was expected (``ModuleErrors``); unknown elements
and attributes are errors.

The result is a ``ModbmastConfig``: ports by number, each with its slaves and
their requests, every inherited attribute (``minPeriod``, ``requestTimeout``,
``attempts``: request -> slave -> port -> default) already resolved, refNums
turned into protocol addresses, and blocks into data table addresses.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path

from ...datatable import DataTableError, parse_address
from ...datatable.address import Address
from ...datatable.filetypes import MAX_ELEMENTS, WORD_BITS
from ...textfile import read_bytes
from ...ports.urlhandler.protocol_sim import url_problem as sim_url_problem
from ..api import find_file
from ..errors import ModuleError, ModuleErrors
from ..xmlcheck import MANY, Attr, XmlChecker, parse_integer
from ..xmlreader import XmlNode
from .requests import REQUEST_KINDS, RequestKind

CONFIG_FILE = "MODBMAST.XML"
ALIAS_FILE = "MODBUS.XML"  # the manual's other name for it (section 5.1)
ROOT = "ModbusSerial"
MAX_PORT = 31
TO_FILES = ("O", "I", "B", "N")  # where reply data may go (not S: a slave must not write the status file)
FROM_FILES = ("O", "I", "S", "B", "N")


@dataclass(frozen=True)
class Block:
    """A toBlock or fromBlock: ``count`` items of ``fmt`` at ``address``, or
    the ``const`` values sent instead of live data."""

    address: Address | None
    count: int
    fmt: str  # "i2" or "bit"
    const: tuple[int, ...] | None
    line: int
    column: int

    @property
    def bits(self) -> int:
        """Coils or discretes this block stands for (16 per word with i2)."""
        return self.count if self.fmt == "bit" else WORD_BITS * self.count

    @property
    def words(self) -> int:
        """Data table words the block covers (a bit block from its address's bit)."""
        if self.fmt == "i2":
            return self.count
        bit = (self.address.bit or 0) if self.address is not None else 0
        return (bit + self.count + WORD_BITS - 1) // WORD_BITS


@dataclass(frozen=True)
class Request:
    """One request of a slave's scan list."""

    kind: RequestKind
    slave: int
    when: str  # "run", "start" or "stop"
    min_period_ms: int
    timeout_ms: int
    attempts: int
    address: int  # protocol address (refNum element - 1)
    count: int  # coils/discretes or registers
    to_blocks: tuple[Block, ...]
    from_blocks: tuple[Block, ...]
    write_address: int = 0  # ReadWriteRegisters: the second refNum
    write_count: int = 0
    and_mask: int = 0xFFFF  # MaskWriteRegister
    line: int = 0
    column: int = 0

    @property
    def name(self) -> str:
        return self.kind.element


@dataclass(frozen=True)
class Slave:
    id: int
    requests: tuple[Request, ...]
    demote_after: int
    demote_period_ms: int
    line: int = 0


@dataclass(frozen=True)
class PortConfig:
    num: int
    framing: str  # "RTU" or "ASCII"
    baud: int
    data_bits: int
    parity: str  # "N", "E", "O", "M"
    stop_bits: int
    request_gap_ms: int
    wait_cts_ms: int | None  # ModemControl waitDelayCTS; None: no hardware handshaking
    slaves: dict[int, Slave]
    device: str | None  # softplc_lite extension: a device path or URL instead of COM(num+1)
    line: int = 0


@dataclass
class ModbmastConfig:
    path: str = CONFIG_FILE
    debug: int = 0
    ports: dict[int, PortConfig] = field(default_factory=dict)
    port_errors: str = "stop"  # softplc_lite extension: "stop" or "retry"
    retry_ms: int = 1000
    warnings: list[str] = field(default_factory=list)


# -- attributes ------------------------------------------------------------------------------

_ADDRESS = "a data table address"
_INHERITED = (Attr("minPeriod", 0, 3_600_000), Attr("requestTimeout", 1, 60_000), Attr("attempts", 1, 100))
_DEMOTE = (Attr("demoteAfter", 0, 1000, extension=True), Attr("demotePeriod", 10, 3_600_000, extension=True))
DEFAULTS = {"minPeriod": 0, "requestTimeout": 30, "attempts": 1, "demoteAfter": 0, "demotePeriod": 5000}

ATTRIBUTES: dict[str, tuple[Attr, ...]] = {
    ROOT: (Attr("debug", 0, 2, default=0), Attr("portErrors", choices=("stop", "retry"), default="stop",
                                                extension=True),
           Attr("retryMs", 10, 3_600_000, default=1000, extension=True)),
    "Port": (Attr("num", 0, MAX_PORT, required=True), Attr("framing", choices=("RTU", "ASCII"), default="RTU"),
             Attr("baudrate", 300, 230400, required=True), Attr("dataBits", 7, 8, default=8),
             Attr("parity", choices=("none", "even", "odd", "mark"), default="none"),
             Attr("stopBits", 1, 2, default=1), *_INHERITED, Attr("requestGap", 0, 250, default=3),
             Attr("device", text=True, extension=True, what="a device path or URL"), *_DEMOTE),
    "ModemControl": (Attr("waitDelayCTS", 0, 60_000, required=True),),
    "Slave": (Attr("id", 1, 247, required=True), *_INHERITED, *_DEMOTE),
    "toBlock": (Attr("dest", text=True, required=True, what=_ADDRESS), Attr("count", 1, 2000, required=True),
                Attr("fmt", choices=("i2", "bit"), required=True)),
    "fromBlock": (Attr("source", text=True, what=_ADDRESS), Attr("count", 1, 2000, required=True),
                  Attr("fmt", choices=("i2", "bit"), required=True)),
    "refNum": (), "andMask": (), "const": (),
}
REQUEST_ATTRIBUTES = (Attr("when", choices=("run", "start", "stop"), default="run"), *_INHERITED)
for _kind in REQUEST_KINDS:
    ATTRIBUTES[_kind] = REQUEST_ATTRIBUTES

_REFNUM = re.compile(r"^\s*([0-9])([0-9]{1,6})\s*$")


def _check_port(c: XmlChecker, node: XmlNode) -> PortConfig | None:
    a = c.attributes(node)
    modem_nodes, slave_nodes = c.children(node, [("ModemControl", 0, 1), ("Slave", 0, MANY)])
    wait_cts = None
    for modem in modem_nodes:
        m = c.attributes(modem)
        c.children(modem, [])
        wait_cts = m.get("waitDelayCTS", 0)
    framing = a.get("framing", "RTU")
    if a.get("framing") == "RTU" and a.get("dataBits") == 7:  # (not when framing itself is wrong)
        c.error(node, "dataBits=7 needs framing=\"ASCII\": RTU sends 8-bit bytes (manual 4.3: use 8 for RTU)",
                "dataBits")
    slaves: dict[int, Slave] = {}
    lines: dict[int, int] = {}
    for slave_node in slave_nodes:
        slave = _check_slave(c, slave_node, a)
        if slave is None:
            continue
        if slave.id in slaves:
            c.error(slave_node, f"slave id {slave.id} is used twice on port {a.get('num', '?')} (first on line "
                                f"{lines[slave.id]}); a slave id is unique within its port", "id")
            continue
        slaves[slave.id] = slave
        lines[slave.id] = slave_node.line
    if "num" not in a or "baudrate" not in a:
        return None
    return PortConfig(a["num"], framing, a["baudrate"], a.get("dataBits", 8),
                      {"none": "N", "even": "E", "odd": "O", "mark": "M"}[a.get("parity", "none")],
                      a.get("stopBits", 1), a.get("requestGap", 3), wait_cts, slaves, a.get("device"), node.line)


def _inherit(name: str, *levels: dict) -> int:
    for level in levels:
        if name in level:
            return level[name]
    return DEFAULTS[name]


def _check_slave(c: XmlChecker, node: XmlNode, port: dict) -> Slave | None:
    a = c.attributes(node)
    kids = []
    for kid in node.children:  # Table 8: any number of each request, in any order
        if kid.name in REQUEST_KINDS:
            kids.append(kid)
            continue
        close = difflib.get_close_matches(kid.name, list(REQUEST_KINDS), n=1)
        hint = f"; did you mean <{close[0]}>?" if close else ""
        what = "is not allowed here" if kid.name in ATTRIBUTES else "is not a request"
        c.error(kid, f"<{kid.name}> {what} (<Slave> contains requests: {', '.join(REQUEST_KINDS)}){hint}")
    requests = []
    for kid in kids:
        request = _check_request(c, kid, a.get("id", 0), a, port)
        if request is not None:
            requests.append(request)
    if "id" not in a:
        return None
    return Slave(a["id"], tuple(requests), _inherit("demoteAfter", a, port), _inherit("demotePeriod", a, port),
                 node.line)


def _check_request(c: XmlChecker, node: XmlNode, slave_id: int, slave: dict, port: dict) -> Request | None:
    kind = REQUEST_KINDS[node.name]
    a = c.attributes(node)
    ok = len(c.problems)  # (a content problem, too, leaves the quantities unchecked)
    groups = c.children(node, kind.model)

    def found(element: str) -> list[list[XmlNode]]:
        return [g for (name, _, _), g in zip(kind.model, groups) if name == element]

    addresses = [_check_refnum(c, g[0], kind, k) if g else None for k, g in enumerate(found("refNum"))]
    tos = [_check_block(c, b, kind, to=True) for g in found("toBlock") for b in g]
    froms = [_check_block(c, b, kind, to=False) for g in found("fromBlock") for b in g]
    and_mask = 0xFFFF
    for mask_node in (n for g in found("andMask") for n in g):
        value = c.text_integer(mask_node, 0, 0xFFFF, "an integer 0..0xFFFF (decimal, or hex as 0xFFFE)")
        and_mask = value if value is not None else and_mask
    if len(c.problems) > ok or None in addresses or None in tos or None in froms:
        return None
    read_units = sum(kind.units(b) for b in tos)
    write_units = sum(kind.units(b) for b in froms)
    counts = [read_units] if kind.reads else []
    if kind.writes:
        counts.append(write_units)
    for k, (units, (low, high), start) in enumerate(zip(counts, kind.limits(), addresses)):
        noun = kind.noun(k)
        if not low <= units <= high:
            exact = f"exactly {low}" if low == high else f"{low}..{high}"
            c.error(node, f"<{node.name}> {kind.verb(k)} {units} {noun} (the sum of its blocks' counts); "
                          f"function {kind.function} takes {exact} {noun}")
        elif start + units > 65536:
            c.error(node, f"<{node.name}>: {units} {noun} from refNum element {start + 1} run past element 65536")
    if len(c.problems) > ok:
        return None
    return Request(kind, slave_id, a.get("when", "run"), _inherit("minPeriod", a, slave, port),
                   _inherit("requestTimeout", a, slave, port), _inherit("attempts", a, slave, port),
                   addresses[0], read_units if kind.reads else write_units, tuple(tos), tuple(froms),
                   addresses[1] if len(addresses) > 1 else 0, write_units if kind.reads and kind.writes else 0,
                   and_mask, node.line, node.column)


def _check_refnum(c: XmlChecker, node: XmlNode, kind: RequestKind, k: int) -> int | None:
    """The protocol address of a refNum (Table 7: first digit the region,
    the rest the element number, from 1)."""
    c.attributes(node)
    c.children(node, [])
    m = _REFNUM.match(node.text)
    region = kind.region(k)
    names = {0: "0xxxx (coils)", 1: "1xxxx (input discretes)", 3: "3xxxx (input registers)",
             4: "4xxxx (holding registers)"}
    if m is None:
        c.error(node, f"refNum {node.text.strip()[:40]!r}: expected a Modicon reference number such as "
                      f"{ {0: '00001', 1: '10001', 3: '30001', 4: '40001'}[region]} (region digit, then the "
                      "element number from 1)")
        return None
    digit, element = int(m.group(1)), int(m.group(2))
    if digit != region:
        c.error(node, f"refNum {m.group(1)}{m.group(2)} is in region {digit}xxxx; <{kind.element}> "
                      f"{kind.verb(k)} {names[region]}")
        return None
    if not 1 <= element <= 65536:
        c.error(node, f"refNum {m.group(1)}{m.group(2)}: element {element} is outside 1..65536 (elements "
                      "start at 1)")
        return None
    return element - 1


def _check_block(c: XmlChecker, node: XmlNode, kind: RequestKind, to: bool) -> Block | None:
    a = c.attributes(node)
    consts = c.children(node, [] if to else [("const", 0, 1)])
    attr = "dest" if to else "source"
    ok = len(c.problems)
    const = None
    if not to and consts[0]:
        const_node = consts[0][0]
        c.attributes(const_node)
        c.children(const_node, [])
        const = _check_const(c, const_node, a.get("fmt"), a.get("count"))
    elif not to and "source" not in node.attrs:  # (an empty or bad one is reported as such)
        c.error(node, "<fromBlock> needs the attribute source (a data table address), or a <const> list "
                      "to send instead")
    fmt = a.get("fmt")
    if fmt == "bit" and not kind.bits:
        c.error(node, f'fmt="bit" in <{kind.element}>: registers are moved as 16-bit words, use fmt="i2" '
                      "(the bits of B3:0 are then B3/0..B3/15)", "fmt")
    address = None
    if attr in a:
        address = _check_address(c, node, attr, a[attr], kind, to, fmt, a.get("count"))
    if len(c.problems) > ok or "count" not in a or fmt is None:
        return None
    return Block(address, a["count"], fmt, const, node.line, node.column)


def _check_address(c: XmlChecker, node: XmlNode, attr: str, text: str, kind: RequestKind, to: bool,
                   fmt: str | None, count: int | None) -> Address | None:
    try:
        address = parse_address(text)
    except DataTableError as e:
        c.error(node, f"{attr}={text!r}: {getattr(e, 'message', str(e))}", attr)
        return None
    files = TO_FILES if to else FROM_FILES
    if not address.is_direct:
        c.error(node, f"{attr}={text!r}: a block address must be direct (no [..] or #)", attr)
        return None
    if address.type_letter not in files or address.member is not None:
        c.error(node, f"{attr}={text!r}: {'reply data goes into' if to else 'request data comes from'} a word of an "
                      f"{', '.join(files[:-1])} or {files[-1]} file", attr)
        return None
    if address.bit is not None:
        if not kind.bits:
            c.error(node, f"{attr}={text!r}: <{kind.element}> moves registers: {attr} must be a word address "
                          "(manual 4.3)", attr)
            return None
        if (to or fmt == "i2") and address.bit != 0:
            rule = ("a toBlock of coils or discretes starts at bit 0 of a word (manual 4.3)" if to
                    else 'fmt="i2" moves whole words: start at bit 0 or at a word address')
            c.error(node, f"{attr}={text!r}: {rule}", attr)
            return None
    if count is not None and fmt is not None:
        words = Block(address, count, fmt, None, 0, 0).words
        if address.element + words > MAX_ELEMENTS:
            c.error(node, f"{attr}={text!r}: {count} {'words' if fmt == 'i2' else 'bits'} from here run past "
                          f"the end of a file (elements 0..{MAX_ELEMENTS - 1})", attr)
            return None
    return address


def _check_const(c: XmlChecker, node: XmlNode, fmt: str | None, count: int | None) -> tuple[int, ...] | None:
    items = [t for t in re.split(r"[\s,;]+", node.text.strip()) if t]
    low, high, what = (0, 1, "0 or 1") if fmt == "bit" else (-32768, 65535, "an integer -32768..65535")
    values = []
    for item in items:
        value = parse_integer(item)
        if value is None or not low <= value <= high:
            c.error(node, f"<const> value {item[:20]!r}: expected {what} (hex as 0x...)")
            return None
        values.append(value & 0xFFFF)
    if count is not None and len(values) != count:
        c.error(node, f"<const> has {len(values)} value{'s' if len(values) != 1 else ''}; its fromBlock's "
                      f"count is {count}")
        return None
    return tuple(values)


def parse_config(data: bytes, path: str = CONFIG_FILE) -> ModbmastConfig:
    """Check MODBMAST.XML's bytes; ModuleErrors listing every problem."""
    c = XmlChecker(path, ATTRIBUTES, ROOT, REQUEST_KINDS)
    root = c.read_root(data, "manual Table 8")
    a = c.attributes(root)
    (port_nodes,) = c.children(root, [("Port", 0, MANY)])
    config = ModbmastConfig(path=path, debug=a.get("debug", 0), port_errors=a.get("portErrors", "stop"),
                            retry_ms=a.get("retryMs", 1000))
    lines: dict[int, int] = {}
    for node in port_nodes:
        port = _check_port(c, node)
        num = parse_integer(node.attrs.get("num", ""))  # a repeated num counts even on a port with other problems
        if num is not None and num in lines:
            c.error(node, f"port num {num} is used twice (first on line {lines[num]}); num is unique among ports",
                    "num")
            continue
        if num is not None:
            lines[num] = node.line
        if port is not None and port.device and port.device.lower().startswith("sim://") \
                and (problem := sim_url_problem(port.device)):
            c.error(node, f"MODBMAST port {port.num}: {problem}", "device")  # what run would refuse
            continue
        if port is not None:
            config.ports[port.num] = port
    if c.problems:
        raise ModuleErrors(c.found())
    return config


def config_path(app_dir: Path) -> tuple[Path | None, list[str]]:
    """MODBMAST.XML, or MODBUS.XML, in ``app_dir`` (names in any case), and
    a warning when both are there."""
    main, alias = find_file(app_dir, CONFIG_FILE), find_file(app_dir, ALIAS_FILE)
    if main is not None and alias is not None:
        return main, [f"{alias}: ignored: {main.name} is the configuration MODBMAST reads when both exist"]
    return main or alias, []


def load_config(app_dir: Path) -> ModbmastConfig:
    path, warnings = config_path(app_dir)
    if path is None:
        raise ModuleError(f"MODBMAST is enabled in MODULES.LST but {app_dir / CONFIG_FILE} (or {ALIAS_FILE}) "
                          "does not exist: it holds the <ModbusSerial> configuration (docs/modbmast.md)")
    try:
        data = read_bytes(path)  # xmlreader honours a BOM (UTF-8, UTF-16) and the declared encoding
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: permission denied"
        raise ModuleError(str(e)) from None
    config = parse_config(data, str(path))
    config.warnings += warnings
    return config
