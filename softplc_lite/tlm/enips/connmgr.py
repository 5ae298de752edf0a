"""The Connection Manager (class 0x06, CIP Volume 1, 3-5): Unconnected_Send
(0x52) carries a request to the module its route path names.

Our choice of what slots mean: the server is the controller in backplane
slot 0, so a route path of port 1 (backplane), link 0, or no route path, is
served here; any other hop is refused with connection failure (0x01),
extended status 0x0312 (link address not valid, Volume 1 Table 3-5.29)."""

from __future__ import annotations

import contextvars
import struct
import time

from ...cip import status
from ...cip.epath import PathError, ports
from ...cip.mr import MessageError, MessageRouterRequest
from .objects import CipObject, CipReply

CLASS_ID = 0x06
UNCONNECTED_SEND = 0x52
FORWARD_OPEN = 0x54
LARGE_FORWARD_OPEN = 0x5B
FORWARD_CLOSE = 0x4E
MAX_CONNECTIONS = 32  # a choice; more are refused with 0x01 / 0x0113 (out of connections)
OUT_OF_CONNECTIONS = 0x0113
CONNECTION_NOT_FOUND = 0x0107
LINK_ADDRESS_NOT_VALID = 0x0312
SERVED_ROUTES = ([], [(1, b"\x00")])

# Whose request is being served (an encapsulation session): a connection
# belongs to the session that opened it, is used by it alone, and closes
# with it (CIP Volume 2, 2-5: a connection over TCP lives within its
# encapsulation session).
OWNER: contextvars.ContextVar[object | None] = contextvars.ContextVar("cip_connection_owner", default=None)


class ConnectionManager(CipObject):
    class_id = CLASS_ID

    def __init__(self, max_connections: int = MAX_CONNECTIONS):
        self.router = None  # set by the Message Router that serves this object
        self.max_connections = max_connections
        # our O->T connection id -> (T->O id, connection serial, vendor, originator serial, timeout seconds)
        self.connections: dict[int, tuple[int, int, int, int, float]] = {}
        self._next_id = 0x10000001
        self.last_seen: dict[int, float] = {}
        self.owners: dict[int, object] = {}

    def alive(self, o_t_id: int, owner: object = None):
        """The connection ``o_t_id`` names, its timeout restarted; None if
        there is none, it is another session's, or it timed out (then it is
        closed)."""
        connection = self.connections.get(o_t_id)
        if connection is None or self.owners.get(o_t_id) is not owner:
            return None
        now = time.monotonic()
        if now - self.last_seen[o_t_id] > connection[4]:
            self._timed_out(o_t_id)
            return None
        self.last_seen[o_t_id] = now
        return connection

    def _close(self, o_t_id: int) -> None:
        del self.connections[o_t_id], self.last_seen[o_t_id]
        self.owners.pop(o_t_id, None)

    def _timed_out(self, o_t_id: int) -> None:
        self._close(o_t_id)
        if self.router is not None:
            self.router.count("timeout", f"CIP connection 0x{o_t_id:08X} closed: no message within its RPI "
                                         "times its multiplier")

    def sweep(self) -> None:
        """Close every connection past its timeout (before one is opened:
        a client that vanished must not keep the slots)."""
        now = time.monotonic()
        for o_t_id, connection in list(self.connections.items()):
            if now - self.last_seen[o_t_id] > connection[4]:
                self._timed_out(o_t_id)

    def close_owned(self, owner: object) -> int:
        """Close the connections ``owner`` opened (its TCP connection ended); how many."""
        mine = [k for k, o in self.owners.items() if o is owner]
        for o_t_id in mine:
            self._close(o_t_id)
        return len(mine)

    async def serve(self, request, access):
        if request.service == UNCONNECTED_SEND:
            return await self.unconnected_send(request, access)
        if request.service in (FORWARD_OPEN, LARGE_FORWARD_OPEN):
            return self.forward_open(request)
        if request.service == FORWARD_CLOSE:
            return self.forward_close(request)
        return CipReply.error(request, status.SERVICE_NOT_SUPPORTED)

    async def unconnected_send(self, request, access):
        data = request.data
        if len(data) < 4:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        size = struct.unpack_from("<H", data, 2)[0]
        end = 4 + size + (size & 1)
        if len(data) < end + 2:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        route = data[end + 2:end + 2 + 2 * data[end]]
        if len(route) != 2 * data[end]:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        try:
            hops = ports(route)
            embedded = MessageRouterRequest.decode(data[4:4 + size])
        except PathError:
            return CipReply.error(request, status.PATH_SEGMENT_ERROR)
        except MessageError:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        if hops not in SERVED_ROUTES:
            return CipReply.error(request, status.CONNECTION_FAILURE, LINK_ADDRESS_NOT_VALID)
        return await self.router.route(embedded, access)

    def forward_open(self, request):
        """Open a class-3 connection. Its timeout is the O->T RPI times the
        multiplier 4 << n (CIP Volume 1, 3-5.4.1.4)."""
        large = request.service == LARGE_FORWARD_OPEN
        fmt = "<BBIIHHIB3xIIIIB" if large else "<BBIIHHIB3xIHIHB"
        size = struct.calcsize(fmt)
        if len(request.data) < size + 1:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        (_, _, _, t_o_id, serial, vendor, orig_serial, multiplier,
         o_t_rpi, _, t_o_rpi, _, _) = struct.unpack_from(fmt, request.data)
        self.sweep()
        if len(self.connections) >= self.max_connections:
            return CipReply.error(request, status.CONNECTION_FAILURE, OUT_OF_CONNECTIONS)
        o_t_id, self._next_id = self._next_id, self._next_id + 1
        timeout = o_t_rpi / 1e6 * (4 << min(multiplier, 7))
        self.connections[o_t_id] = (t_o_id, serial, vendor, orig_serial, timeout)
        self.last_seen[o_t_id] = time.monotonic()
        self.owners[o_t_id] = OWNER.get()
        return CipReply.ok(request, struct.pack("<IIHHIIIBx", o_t_id, t_o_id, serial, vendor,
                                                orig_serial, o_t_rpi, t_o_rpi, 0))

    def forward_close(self, request):
        if len(request.data) < 10:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        serial, vendor, orig_serial = struct.unpack_from("<HHI", request.data, 2)
        for o_t_id, (_, s, v, o, _) in list(self.connections.items()):
            if (s, v, o) == (serial, vendor, orig_serial) and self.owners.get(o_t_id) is OWNER.get():
                self._close(o_t_id)
                return CipReply.ok(request, struct.pack("<HHIBx", serial, vendor, orig_serial, 0))
        return CipReply.error(request, status.CONNECTION_FAILURE, CONNECTION_NOT_FOUND)
