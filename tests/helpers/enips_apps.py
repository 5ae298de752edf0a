"""Building ENIPS apps for tests: an app directory with MODULES.LST,
ENIPS.XML and a ladder file, scanned by a Runner in a thread of the test
process (the server is its own process either way), stopped and closed
after the test; and a few raw EtherNet/IP exchanges on a socket, for what
no client library sends."""

from __future__ import annotations

import socket
import struct
from pathlib import Path

from softplc_lite.cip import cpf, encap
from softplc_lite.cip.encap import EncapMessage
from softplc_lite.cip.mr import MessageRouterRequest, MessageRouterResponse

from helpers.apps import make_app
from helpers.modbtcps_apps import LIMIT_S, Apps, Running
from helpers.modbus_peer import free_tcp_port

# An HMI-facing table: symbols over N7, F8, T4, ST9, and some of it writable.
LADDER = """SYMBOL COUNT N7:5
SYMBOL SPEED F8:1
SYMBOL NOTE ST9:0
SYMBOL RUN B3:0/4
SYMBOL DWELL T4:0
ADD N7:5 1 N7:5
XIC B3:0/4 OTE O:0/1
TON T4:0 0.01 500 0
MOV N7:1 N11:0
"""
WRITABLE = """  <Writable address="N7:0" count="5"/>
  <Writable address="F8:0" count="4"/>
  <Writable address="B3:0" count="2"/>
  <Writable address="ST9:0"/>
  <Writable address="T4:0"/>
  <Writable address="L12:0" count="2"/>
"""
REFERENCES = "MOV N7:49 N7:45\nMOV F8:9 F8:8\nMOV ST9:3.LEN N7:48\nMOV L12:9 L12:8\nMOV N11:99 N7:47\n"


def enips_xml(body: str = WRITABLE, port: int | None = None, **root: object) -> str:
    attrs = {"port": port or free_tcp_port(), "status": "N40:0", **root}
    text = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return f'<?xml version="1.0"?>\n<EtherNetIpServer {text}>\n{body}</EtherNetIpServer>\n'


class EnipApps(Apps):
    """ENIPS apps started by a test, each stopped after it."""

    def write(self, directory: Path, xml: str | None, ladder: str) -> Path:
        return make_app(directory, ladder, MODULES_LST="ENIPS\n", ENIPS_XML=xml or enips_xml())

    def start(self, xml: str | None = None, ladder: str = LADDER + REFERENCES, **kw) -> Running:
        return super().start(xml, ladder, module="ENIPS", **kw)


def exchange(sock: socket.socket, message: EncapMessage) -> EncapMessage:
    """Send one message, receive its whole reply."""
    sock.sendall(message.encode())
    return receive(sock)


def receive(sock: socket.socket) -> EncapMessage:
    data = b""
    while len(data) < encap.HEADER_SIZE or len(data) < encap.HEADER_SIZE + struct.unpack_from("<H", data, 2)[0]:
        chunk = sock.recv(65536)
        assert chunk, "the server closed the connection"
        data += chunk
    return EncapMessage.decode(data)


def register(sock: socket.socket) -> int:
    reply = exchange(sock, EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 1, 0)))
    assert reply.status == encap.SUCCESS and reply.session
    return reply.session


def unconnected(sock: socket.socket, session: int, service: int, path: bytes,
                data: bytes = b"") -> tuple[EncapMessage, MessageRouterResponse | None]:
    """One Message Router request by SendRRData: the encapsulation reply, and
    the Message Router response it holds (None if it holds none)."""
    body = struct.pack("<IH", 0, 10) + cpf.encode([cpf.Item(cpf.NULL_ADDRESS), cpf.Item(
        cpf.UNCONNECTED_DATA, MessageRouterRequest(service, path, data).encode())])
    reply = exchange(sock, EncapMessage(encap.SEND_RR_DATA, body, session=session))
    if reply.status != encap.SUCCESS:
        return reply, None
    items = cpf.decode(reply.data[6:])
    return reply, MessageRouterResponse.decode(items[1].data)


def connect(port: int, source: str = "127.0.0.1") -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=LIMIT_S, source_address=(source, 0))
    return sock


def forward_open(sock: socket.socket, session: int, serial: int, rpi_us: int = 2_000_000,
                 multiplier: int = 1) -> MessageRouterResponse:
    """A Forward_Open (CIP Vol. 1, 3-5.5.2) to the Message Router by
    SendRRData, connection serial ``serial``; our O->T id is the reply's
    first four bytes."""
    data = struct.pack("<BBIIHHIB3xIHIHB", 0x0A, 0x05, 0, 0x7700 + serial, serial, 1, 9, multiplier, rpi_us, 0x43F4,
                       rpi_us, 0x43F4, 0xA3)
    data += bytes((2,)) + bytes.fromhex("20022401")
    return unconnected(sock, session, 0x54, bytes.fromhex("20062401"), data)[1]


def connected(sock: socket.socket, session: int, o_t_id: int, service: int, path: bytes,
              sequence: int = 1) -> EncapMessage:
    """One Message Router request by SendUnitData on connection ``o_t_id``."""
    body = struct.pack("<IH", 0, 0) + cpf.encode([
        cpf.Item(cpf.CONNECTED_ADDRESS, struct.pack("<I", o_t_id)),
        cpf.Item(cpf.CONNECTED_DATA, struct.pack("<H", sequence) + MessageRouterRequest(service, path).encode())])
    return exchange(sock, EncapMessage(encap.SEND_UNIT_DATA, body, session=session))


TANK_LINE = Path(__file__).resolve().parents[2] / "programs" / "logix" / "tank_line.L5X"
TANK_LINE_WRITABLE = """  <Writable tag="Start"/>
  <Writable tag="Stop"/>
  <Writable tag="Tanks"/>
  <Writable tag="SettleTimer"/>
  <Writable tag="Banner"/>
  <Writable tag="Program:MainProgram.Overview"/>
"""


def tank_line(directory: Path, body: str = TANK_LINE_WRITABLE, edit=None, source: Path = TANK_LINE) -> Path:
    """programs/logix/tank_line.L5X (or ``source``) copied into
    ``directory`` (``edit`` changes its text), with its ``STEM.ENIPS.XML``
    beside it serving on a free port; the export's path."""
    directory.mkdir(parents=True, exist_ok=True)
    text = source.read_text(encoding="utf-8")
    export = directory / source.name
    export.write_text(edit(text) if edit else text, encoding="utf-8")
    xml = f'<?xml version="1.0"?>\n<EtherNetIpServer port="{free_tcp_port()}">\n{body}</EtherNetIpServer>\n'
    (directory / f"{source.stem}.ENIPS.XML").write_text(xml, encoding="utf-8")
    return export
