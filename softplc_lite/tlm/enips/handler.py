"""EtherNet/IP in the server process: encapsulation messages framed by their
header's length, one EncapSession per TCP connection (its session and the
CIP connections it opened end with it), each request routed by the Message
Router to the objects the app serves, over the image the scan publishes
(imageaccess.py). UDP answers ListIdentity on the same port, so a browse
finds the PLC (CIP Volume 2, 2-4.2).

Every refusal is counted: the layer's own (allow-list, limits, malformed,
idle), encapsulation errors, CIP statuses, PCCC statuses and writes refused
read-only (status.py).
"""

from __future__ import annotations

import asyncio

from ...cip import encap
from ...cip import status as st
from ...cip.encap import EncapMessage
from ...netserver import Handler, Malformed
from ...netserver import counters as C
from ...netserver.connection import PEER, admitted
from ...netserver.tcp import TcpListener
from .connmgr import ConnectionManager
from .identity import Identity, list_identity_reply
from .imageaccess import ImageAccess
from .protocol import EnipProtocol
from .router import OBJECTS, MessageRouter
from .session import EncapSession
from .status import CIP_ERRORS, ENCAP_ERRORS, PCCC_ERRORS, READ_ONLY, TIMED_OUT
from .tags import SymbolObject, TagServices
from .templates import ProgramName, TemplateObject

# The longest encapsulation data taken: a Large_Forward_Open client may
# send up to 4002-byte messages (its connection size); a longer announced
# length is no client's, and closes the connection (a choice).
MAX_DATA = 4400
BUSY = st.RESOURCE_UNAVAILABLE  # CIP Volume 1, Appendix B: "resources needed ... were unavailable"
FAILURE = "failure"
COUNTER_OF_KIND = {"encap": ENCAP_ERRORS, "cip": CIP_ERRORS, "pccc": PCCC_ERRORS, "read-only": READ_ONLY,
                   "timeout": TIMED_OUT}


def served_objects(protocol: EnipProtocol) -> list:
    """The CIP objects this app serves: Identity, the Connection Manager,
    every object registered in router.OBJECTS (PCCC), the tag services on
    the app's symbols and files, the Symbol and Template objects, and the
    program name."""
    objects = [make() for make in OBJECTS if make not in (ConnectionManager,)]
    objects.append(ConnectionManager(protocol.config.max_cip_connections))
    logix = protocol.logix
    objects += [TagServices(protocol.symbols, logix=logix), SymbolObject(protocol.symbols, logix=logix),
                TemplateObject(logix), ProgramName(protocol.identity.app_name)]
    return objects


class EnipHandler(Handler):
    busy = BUSY
    failure = FAILURE

    def __init__(self, server, protocol: EnipProtocol) -> None:
        super().__init__(server)
        self.protocol = protocol
        self.identity = protocol.identity
        self.access = ImageAccess(server, protocol.slots, files_served=protocol.logix is None)
        self.router = MessageRouter(served_objects(protocol), identity=protocol.identity)
        self.router.count = self.count

    def count(self, kind: str, why: str) -> None:
        """A refusal inside a reply (a CIP or PCCC status), counted by its kind."""
        self.server.count(COUNTER_OF_KIND[kind], f"{PEER.get()}: {why}")

    def listener(self):
        return EnipListener(self.server, self.identity, self.protocol.config.list_identity_udp)

    # -- per connection ------------------------------------------------------------------------
    def opened(self, link) -> EncapSession:
        sockname = getattr(link, "sockname", lambda: None)() or (self.server.settings.host, 0)
        return EncapSession(self.router, self.access, self.identity, sockname[0], sockname[1])

    def closed(self, state: EncapSession) -> None:
        state.close()

    # -- frames ---------------------------------------------------------------------------------
    def frame_length(self, data: bytearray, at: int) -> int | None:
        if len(data) - at < encap.HEADER_SIZE:
            return None
        length = int.from_bytes(data[at + 2:at + 4], "little")
        if length > MAX_DATA:
            raise Malformed(f"an encapsulation header announcing {length} bytes of data (at most {MAX_DATA} "
                            "are taken)")
        whole = encap.HEADER_SIZE + length
        return whole if len(data) - at >= whole else None

    def header(self, frame: bytes, state: EncapSession):
        return frame, state

    def decode(self, frame: bytes, header):
        return _Request(header[1], EncapMessage.decode(frame))

    async def serve(self, request: "_Request") -> bytes:
        reply = await request.session.reply(request.message)
        if reply is None:
            return b""
        if reply.status != encap.SUCCESS:
            self.count("encap", f"command 0x{request.message.command:04X}: encapsulation status "
                                f"0x{reply.status:04X}")
        return reply.encode()

    # -- refusals --------------------------------------------------------------------------------
    def refusal_reply(self, code, header) -> bytes:
        frame, session = header
        return session.refusal(EncapMessage.decode(frame), BUSY).encode()

    def counter(self, code) -> int:
        return C.REFUSED_RATE

    def code_words(self, code) -> str:
        return "busy" if code == BUSY else str(code)


class _Request:
    __slots__ = ("session", "message")

    def __init__(self, session: EncapSession, message: EncapMessage) -> None:
        self.session, self.message = session, message

    def __str__(self) -> str:
        return f"command 0x{self.message.command:04X}, {len(self.message.data)} bytes"


class _ListIdentityOverUdp(asyncio.DatagramProtocol):
    """ListIdentity over UDP (CIP Volume 2, 2-4.2.1): answered to clients the
    allow-list admits, within the request rate; any other datagram is
    dropped unanswered (a choice: UDP carries no session to refuse)."""

    def __init__(self, server, identity: Identity, port: int) -> None:
        self.server, self.identity, self.port = server, identity, port
        self.transport = None

    def connection_made(self, transport) -> None:
        self.transport = transport

    def datagram_received(self, data: bytes, addr) -> None:
        if not admitted(str(addr[0]), self.server.settings.allow):
            self.server.count(C.REFUSED_NETWORK, f"{addr[0]}:{addr[1]}: UDP ListIdentity refused, not in the "
                                                 "allow-list")
            return
        reply = list_identity_reply(self.identity, data, self.server.settings.host, self.port)
        if reply is not None and self.server.rate_ok(str(addr[0])):
            self.transport.sendto(reply, addr)


class EnipListener(TcpListener):
    """TCP as the layer listens, and UDP ListIdentity on the same port."""

    def __init__(self, server, identity: Identity, udp: bool) -> None:
        super().__init__(server)
        self.identity, self.udp = identity, udp
        self._datagrams = None

    async def start(self) -> int:
        port = await super().start()
        if self.udp:
            loop = asyncio.get_running_loop()
            try:
                self._datagrams, _ = await loop.create_datagram_endpoint(
                    lambda: _ListIdentityOverUdp(self.server, self.identity, port),
                    local_addr=(self.server.settings.host, port))
            except OSError as e:  # TCP serves all the same: said, not fatal
                self.server.log(0, f"UDP {self.server.settings.host}:{port} not listened on ({e.strerror}): "
                                   "a browse will not find this PLC, clients that know its address connect")
        return port

    async def stop(self) -> None:
        if self._datagrams is not None:
            self._datagrams.close()
        await super().stop()
