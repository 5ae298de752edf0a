"""A bare asyncio EtherNet/IP TCP listener: frames messages by the
encapsulation header's length field and keeps one EncapSession per
connection. The ENIPS module serves the same sessions on the network-server
layer; this one serves a TableAccess in one process (tools, tests)."""

from __future__ import annotations

import asyncio

from ...cip import encap
from ...cip.encap import EncapHeader, EncapMessage
from .access import TableAccess
from .identity import Identity
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
