"""The Connection Manager (class 0x06, CIP Volume 1, 3-5): Unconnected_Send
(0x52) carries a request to the module its route path names.

Our choice of what slots mean: the server is the controller in backplane
slot 0, so a route path of port 1 (backplane), link 0, or no route path, is
served here; any other hop is refused with connection failure (0x01),
extended status 0x0312 (link address not valid, Volume 1 Table 3-5.29)."""

from __future__ import annotations

import struct

from ...cip import status
from ...cip.epath import PathError, ports
from ...cip.mr import MessageError, MessageRouterRequest
from .objects import CipObject, CipReply

CLASS_ID = 0x06
UNCONNECTED_SEND = 0x52
LINK_ADDRESS_NOT_VALID = 0x0312
SERVED_ROUTES = ([], [(1, b"\x00")])


class ConnectionManager(CipObject):
    class_id = CLASS_ID

    def __init__(self):
        self.router = None  # set by the Message Router that serves this object

    async def serve(self, request, access):
        if request.service == UNCONNECTED_SEND:
            return await self.unconnected_send(request, access)
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
