"""What every network server module's XML configuration says the same way
(MODBTCPS.XML, ENIPS.XML, OPCUAS.XML): where to listen, who may connect,
the limits, the status block, what clients may write (``<Writable>``: data
table elements, or a Studio 5000 export's tags) and how each is checked
(docs/modbtcps.md, "Safe by default"; docs/enips.md, "The configuration
file" and "Logix tags").

The rules are softplc_lite's own choices, one set for every server so that
an engineer who has configured one has configured them all: listen on
127.0.0.1 unless told otherwise, serve only this machine's clients unless
``<Allow>`` names others, and warn when a server listens beyond this machine
with no ``<Allow>``.
"""

from __future__ import annotations

import ipaddress
import re
from dataclasses import dataclass

from ..datatable import DataTableError, parse_address
from ..datatable.address import Address
from ..datatable.filetypes import MAX_ELEMENTS
from .errors import ModuleError, ModuleErrors
from .xmlcheck import Attr, XmlChecker
from .xmlreader import XmlNode

LOOPBACK = (ipaddress.ip_network("127.0.0.0/8"), ipaddress.ip_network("::1/128"))
EVERYONE = (ipaddress.ip_network("0.0.0.0/0"), ipaddress.ip_network("::/0"))
STATUS_FILES = ("N", "B")
HOST_WHAT = "an IPv4 or IPv6 address or a host name to listen on"
ALLOW = (Attr("network", text=True, required=True,
              what='a client network (192.168.1.0/24), an address (10.0.0.5), or "any"'),)

_LABEL = re.compile(r"^(?!-)[A-Za-z0-9-]{1,63}(?<!-)$")


def listen_attributes(port: int, max_connections: int, max_rate: int, status_words: int) -> tuple[Attr, ...]:
    """The root element's attributes every server has, with its defaults."""
    return (Attr("address", text=True, default="127.0.0.1", what=HOST_WHAT),
            Attr("port", 1, 65535, default=port),
            Attr("maxConnections", 1, 1000, default=max_connections),
            Attr("maxRequestsPerSecond", 1, 100_000, default=max_rate),
            Attr("idleTimeout", 100, 3_600_000, default=60_000),
            Attr("status", text=True, what=f"a word address of an N or B file, the first of {status_words} "
                                            "status words (N40:0)"),
            Attr("debug", 0, 2, default=0))


def host_to_listen(text: str) -> str | None:
    """The host an ``address`` names (an IPv6 literal loses its brackets),
    or None when it is neither an IP address nor a valid host name
    (RFC 1123 labels; a last label of digits only is a mistyped IPv4)."""
    host = text[1:-1] if text.startswith("[") and text.endswith("]") else text
    try:
        ipaddress.ip_address(host)
        return host
    except ValueError:
        pass
    name = host[:-1] if host.endswith(".") else host
    labels = name.split(".")
    if not name or len(name) > 253 or not all(_LABEL.match(label) for label in labels) or labels[-1].isdigit():
        return None
    return host


def allowed_networks(text: str) -> tuple | None:
    """The networks an <Allow network> names ("any": every IPv4 and IPv6
    client), or None when it names none."""
    if text.lower() == "any":
        return EVERYONE
    try:
        return (ipaddress.ip_network(text, strict=False),)
    except ValueError:
        return None


def ipaddress_is_loopback(host: str) -> bool:
    """Is ``host`` a loopback address (or "localhost")?"""
    if host.lower().rstrip(".") == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_host(c: XmlChecker, root: XmlNode, a: dict) -> str:
    """The host to listen on (127.0.0.1 when absent or wrong: the error is recorded)."""
    if "address" not in a:
        return "127.0.0.1"
    host = host_to_listen(a["address"])
    if host is None:
        c.error(root, f"address={a['address']!r}: expected {HOST_WHAT} (127.0.0.1: only this machine; "
                      "0.0.0.0: every IPv4 interface)", "address")
        return "127.0.0.1"
    return host


def check_allow(c: XmlChecker, nodes: list[XmlNode]) -> tuple:
    """The networks the <Allow> elements name; none given: this machine only."""
    if not nodes:
        return LOOPBACK
    allow: list = []
    for node in nodes:
        n = c.attributes(node)
        c.children(node, [])
        if "network" in n:
            networks = allowed_networks(n["network"])
            if networks is None:
                c.error(node, f"network={n['network']!r}: expected a client network (192.168.1.0/24), an address "
                              '(10.0.0.5), or "any" (every client)', "network")
            else:
                allow.extend(networks)
    return tuple(allow)


def listen_warning(path: str, root: XmlNode, host: str, allow_given: bool) -> list[str]:
    if allow_given or ipaddress_is_loopback(host):
        return []
    return [f"{path}:{root.line}: listening on {host} but no <Allow> is given: only clients on this machine "
            "(127.0.0.0/8, ::1) are served; add <Allow network=\"...\"/> for others"]


def check_status(c: XmlChecker, root: XmlNode, text: str, words: int) -> Address | None:
    """The status block's first word, or None (the problem recorded)."""
    problem = None
    try:
        address = parse_address(text)
    except DataTableError as e:
        c.error(root, f"status={text!r}: {getattr(e, 'message', str(e))}", "status")
        return None
    if not address.is_direct or address.type_letter not in STATUS_FILES or address.member is not None \
            or address.bit is not None:
        problem = (f"expected a direct word address of an N or B file (N40:0, B3:0): the first of the "
                   f"{words} status words")
    elif address.element + words > MAX_ELEMENTS:
        problem = f"the {words} status words from here run past the end of a file (elements 0..{MAX_ELEMENTS - 1})"
    if problem:
        c.error(root, f"status={text!r}: {problem}", "status")
        return None
    return address


def check_writable_elements(c: XmlChecker, node: XmlNode, a: dict, status: Address | None, status_line: int,
                            status_words: int, parts: str) -> tuple[Address, int] | None:
    """A ``<Writable address=... count=...>``'s first element and count, or
    None (the problem recorded): whole elements (a client may write every one
    of their ``parts``), inside one file, and none of the server's status
    words (the block ``status=`` on line ``status_line`` names)."""
    text = a["address"]
    try:
        address = parse_address(text)
    except DataTableError as e:
        c.error(node, f"address={text!r}: {getattr(e, 'message', str(e))}", "address")
        return None
    if not address.is_direct or address.bit is not None or address.member is not None:
        c.error(node, f"address={text!r}: expected a whole element (N7:0, T4:0, ST9:0): a client may write every "
                      f"{parts} of the elements a <Writable> names", "address")
        return None
    count = a.get("count", 1)
    if address.element + count > MAX_ELEMENTS:
        c.error(node, f"count={count}: {count} elements from {address} run past the end of a file (elements "
                      f"0..{MAX_ELEMENTS - 1})", "count")
        return None
    last = address.element + count - 1
    if status is not None and (status.type_letter, status.file) == (address.type_letter, address.file) \
            and address.element <= status.element + status_words - 1 and status.element <= last:
        c.error(node, f"<Writable> {address}..{address.with_element(last)} covers the status words "
                      f"{status}..{status.with_element(status.element + status_words - 1)} (status= on line "
                      f"{status_line}): a client must not write the server's counters", "address")
        return None
    return address, count


@dataclass(frozen=True)
class Writable:
    """``count`` elements from ``address`` that clients may write; or, in a
    Logix app's configuration, the tag path ``tag`` (enips/logixconfig.py
    checks it against the export's tags)."""

    address: Address | None  # an element of a file (N7:0, T4:0, ST9:0); None with ``tag``
    count: int
    line: int
    column: int
    tag: str | None = None  # a Logix tag path (Tanks, Tanks[1].Setpoint, SettleTimer.PRE)

    @property
    def file(self) -> str:
        return f"{self.address.type_letter}{self.address.file}"

    @property
    def last(self) -> int:
        return self.address.element + self.count - 1 if self.address is not None else 0


def writable_attributes(elements: str) -> tuple[Attr, ...]:
    """``<Writable>``'s attributes; ``elements``: examples of the first element."""
    return (Attr("address", text=True, what=f"the first element clients may write ({elements})"),
            Attr("tag", text=True, extension=True,
                 what="a Logix app's tag clients may write (Tanks, Tanks[1].Setpoint, SettleTimer.PRE)"),
            Attr("count", 1, MAX_ELEMENTS, default=1))


def check_writable(c: XmlChecker, node: XmlNode, status: Address | None, status_line: int, status_words: int,
                   parts: str) -> Writable | None:
    """One ``<Writable>``: ``address=`` (and ``count=``, checked by
    ``check_writable_elements``) or ``tag=``, one of them; None if refused
    (the problem recorded)."""
    a = c.attributes(node)
    c.children(node, [])
    if ("address" in node.attrs) == ("tag" in node.attrs):
        c.error(node, "<Writable> needs the attribute address (a data table element: N7:0) or, in a Logix "
                      "app's configuration, tag (a tag path: Tanks[1].Setpoint), one of them")
        return None
    if "address" not in a and "tag" not in a:
        return None  # its value was refused, and said
    if "tag" in a:
        if "count" in node.attrs:
            c.error(node, "<Writable tag=...> takes no count: the tag path names what clients may write", "count")
            return None
        return Writable(None, 1, node.line, node.column, tag=a["tag"])
    found = check_writable_elements(c, node, a, status, status_line, status_words, parts)
    return None if found is None else Writable(found[0], found[1], node.line, node.column)


def status_references(status: Address | None, words: int) -> list[Address]:
    """The first and last word of a status block of ``words`` words (none
    without one), so that the engine creates them before the first scan."""
    return [] if status is None else [status, status.with_element(status.element + words - 1)]


def element_references(config, status_words: int) -> list[Address]:
    """The first and last element of every ``<Writable address>`` region and
    of the status block (ENIPS's and OPCUAS's), created before the first scan."""
    found: list[Address] = []
    for w in config.writable:
        if w.address is not None:
            found += [w.address, w.address.with_element(w.last)]
    return found + status_references(config.status, status_words)


def refuse_tags(config) -> None:
    """ModuleErrors for each ``<Writable tag=...>`` of an app directory's
    configuration: its data table has no tags."""
    tagged = [ModuleError(f"<Writable tag={w.tag!r}>: tag= names a tag of a Studio 5000 export's app; "
                          "this app's data table elements are named by address=", config.path, w.line, w.column)
              for w in config.writable if w.tag is not None]
    if tagged:
        raise ModuleErrors(tagged)
