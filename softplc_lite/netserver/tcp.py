"""The plain TCP listener: asyncio's server, for a protocol whose replies
are bytes the handler builds itself. (A protocol library that frames its
replies brings its own listener: MODBTCPS's is pymodbus's server.)"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .connection import Connection
    from .server import Server


class TcpLink(asyncio.Protocol):
    """One client connection: asyncio's calls go to the layer's Connection."""

    def __init__(self, server: Server, links: set) -> None:
        self.server = server
        self.links = links  # the listener's open links
        self.transport: asyncio.Transport | None = None
        self.connection: Connection = server.connect(self)
        self._ended = False

    # asyncio -> the connection
    def connection_made(self, transport) -> None:
        self.transport = transport
        self.links.add(self)
        self.connection.connected()

    def data_received(self, data: bytes) -> None:
        if self.transport is not None:
            self.connection.received(data)

    def pause_writing(self) -> None:
        self.connection.pause_writing()

    def resume_writing(self) -> None:
        self.connection.resume_writing()

    def connection_lost(self, exc) -> None:
        self.transport = None
        self._end()

    # the connection -> asyncio
    @property
    def is_open(self) -> bool:
        return self.transport is not None

    def peername(self):
        return self.transport.get_extra_info("peername") if self.transport is not None else None

    def sockname(self):
        """The address the client reached (ours): what an EtherNet/IP
        ListIdentity reply names."""
        return self.transport.get_extra_info("sockname") if self.transport is not None else None

    def reply(self, response: bytes) -> None:
        if self.transport is not None:
            self.transport.write(response)

    def pause_reading(self) -> None:
        if self.transport is not None:
            self.transport.pause_reading()

    def resume_reading(self) -> None:
        if self.transport is not None:
            self.transport.resume_reading()

    def abort(self) -> None:
        """Close now, dropping the replies not yet sent (a client that stops
        reading must not keep its socket and their memory)."""
        transport, self.transport = self.transport, None
        if transport is not None:
            transport.abort()
        self._end()

    def _end(self) -> None:
        self.links.discard(self)
        if not self._ended:
            self._ended = True
            self.connection.ended()


class TcpListener:
    def __init__(self, server: Server) -> None:
        self.server = server
        self._listening: asyncio.Server | None = None
        self._links: set[TcpLink] = set()

    async def start(self) -> int:
        """Listen; the port bound."""
        settings = self.server.settings
        self._listening = await asyncio.get_running_loop().create_server(
            lambda: TcpLink(self.server, self._links), settings.host, settings.port, reuse_address=True)
        return self._listening.sockets[0].getsockname()[1]

    async def stop(self) -> None:
        """Stop listening and close every connection."""
        if self._listening is not None:
            self._listening.close()
            for link in list(self._links):
                link.abort()
            await self._listening.wait_closed()
