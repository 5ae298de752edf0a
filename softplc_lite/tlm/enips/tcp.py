"""A bare asyncio EtherNet/IP TCP listener: frames messages by the
encapsulation header's length field and keeps one EncapSession per
connection. The ENIPS module serves the same sessions on the network-server
layer; this one serves a TableAccess in one process (tools, tests)."""

from __future__ import annotations

import asyncio

from ...cip import encap
from ...cip.encap import EncapHeader, EncapMessage
from .access import TableAccess
from .identity import Identity, list_identity_reply
from .router import MessageRouter
from .session import EncapSession

MAX_DATA = 4096  # a longer announced length closes the connection (a choice)


async def serve(access: TableAccess, identity: Identity, host: str = "127.0.0.1",
                port: int = 0) -> asyncio.AbstractServer:
    router = MessageRouter(identity=identity)

    async def connection(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        bound = writer.get_extra_info("sockname")
        session = EncapSession(router, access, identity, bound[0], bound[1])
        try:
            while True:
                raw = await reader.readexactly(encap.HEADER_SIZE)
                header = EncapHeader.decode(raw)
                if header.length > MAX_DATA:
                    break
                message = EncapMessage.decode(raw + await reader.readexactly(header.length))
                reply = await session.reply(message)
                if reply is not None:
                    writer.write(reply.encode())
                    await writer.drain()
        except (asyncio.IncompleteReadError, ConnectionError):
            pass
        finally:
            writer.close()

    return await asyncio.start_server(connection, host, port)


class _ListIdentityProtocol(asyncio.DatagramProtocol):
    """Answers ListIdentity (and nothing else: other commands over UDP are
    dropped, a choice) with the identity item; the sockaddr names the TCP
    listener's address and port."""

    def __init__(self, identity: Identity, host: str, tcp_port: int):
        self.identity, self.host, self.tcp_port = identity, host, tcp_port

    def connection_made(self, transport):
        self.transport = transport

    def datagram_received(self, data, addr):
        reply = list_identity_reply(self.identity, data, self.host, self.tcp_port)
        if reply is not None:
            self.transport.sendto(reply, addr)


async def serve_udp(identity: Identity, host: str = "127.0.0.1", port: int = 0,
                    tcp_port: int = 44818) -> asyncio.DatagramTransport:
    loop = asyncio.get_running_loop()
    transport, _ = await loop.create_datagram_endpoint(
        lambda: _ListIdentityProtocol(identity, host, tcp_port), local_addr=(host, port))
    return transport
