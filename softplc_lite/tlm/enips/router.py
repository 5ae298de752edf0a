"""The Message Router (CIP Volume 1, 5A-3): hands each request to the object
its path names, by class id; a path starting with an ANSI extended symbolic
segment goes to the object with class id None (tag services). It serves
Multiple Service Packet (0x0A) itself, on its own class (0x02, instance 1).

``OBJECTS`` lists the object classes served; each entry is a zero-argument
factory so the router builds its own instances (objects may keep state)."""

from __future__ import annotations

import struct
from typing import Callable

from ...cip import status
from ...cip.epath import SYMBOLIC, PathError, logical
from ...cip.mr import MessageError, MessageRouterRequest, MessageRouterResponse
from .access import TableAccess
from .connmgr import ConnectionManager
from .identity import IdentityObject
from .objects import REPLY, CipObject, CipReply, CipRequest
from .pccc_object import PcccObject

MESSAGE_ROUTER_CLASS = 0x02
MULTIPLE_SERVICE_PACKET = 0x0A

# The served object classes that need nothing of the app, one factory
# each (the tag services, built on the app's symbols, are added by the
# server: tlm/enips/handler.py).
OBJECTS: list[Callable[[], CipObject]] = [IdentityObject, ConnectionManager, PcccObject]


# Replies that are no refusal: success; a fragment with more to come; a
# Multiple Service Packet whose failed services are counted one by one.
UNCOUNTED = (status.SUCCESS, status.PARTIAL_TRANSFER, status.EMBEDDED_SERVICE_ERROR)


def _uncounted(kind: str, why: str) -> None:
    pass


def _service_words(request: MessageRouterRequest) -> str:
    return f"service 0x{request.service:02X} to path {request.path.hex(' ') or 'none'}"


class MessageRouter:
    def __init__(self, objects: list[CipObject] | None = None, identity=None):
        """``identity`` (an ``identity.Identity``) names this server in place
        of the Identity object's default."""
        built = objects if objects is not None else [make() for make in OBJECTS]
        if identity is not None:
            built = [obj for obj in built if obj.class_id != IdentityObject.class_id]
            built.append(IdentityObject(identity))
        self.count: Callable[[str, str], None] = _uncounted  # a refusal's kind and why (the server counts them)
        self.objects: dict[int | None, CipObject] = {}
        for obj in built:
            self.objects[obj.class_id] = obj
            if hasattr(obj, "router"):
                obj.router = self

    async def handle(self, raw: bytes, access: TableAccess) -> bytes:
        """The encoded response to one encoded Message Router request."""
        try:
            request = MessageRouterRequest.decode(raw)
        except MessageError:
            service = raw[0] | REPLY if raw else REPLY
            self.count("cip", f"a request of {len(raw)} bytes that is not a Message Router request: CIP status "
                              f"{status.describe(status.NOT_ENOUGH_DATA)}")
            return MessageRouterResponse(service, status.NOT_ENOUGH_DATA).encode()
        reply = await self.route(request, access)
        if reply.status not in UNCOUNTED:
            self.count("read-only" if reply.status == status.PRIVILEGE_VIOLATION else "cip",
                       f"{_service_words(request)}: CIP status {status.describe(reply.status)}"
                       + "".join(f" 0x{word:04X}" for word in reply.extended))
        return MessageRouterResponse(reply.service, reply.status, reply.extended, reply.data).encode()

    async def route(self, request: MessageRouterRequest, access: TableAccess) -> CipReply:
        service = request.service & ~REPLY & 0xFF
        if request.path[:1] == bytes((SYMBOLIC,)):
            cip = CipRequest(service, request.path, (None, None, None), request.data)
            target = self.objects.get(None)
            if target is None:
                return CipReply.error(cip, status.PATH_DESTINATION_UNKNOWN)
            return await target.serve(cip, access)
        try:
            path = logical(request.path)
        except PathError:
            return CipReply(service | REPLY, status.PATH_SEGMENT_ERROR)
        cip = CipRequest(service, request.path, path, request.data)
        if path[0] == MESSAGE_ROUTER_CLASS:
            if service != MULTIPLE_SERVICE_PACKET:
                return CipReply.error(cip, status.SERVICE_NOT_SUPPORTED)
            return await self.multiple(cip, access)
        target = self.objects.get(path[0]) if path[0] is not None else None
        if target is None:
            return CipReply.error(cip, status.PATH_DESTINATION_UNKNOWN)
        return await target.serve(cip, access)

    async def multiple(self, request: CipRequest, access: TableAccess) -> CipReply:
        """Multiple Service Packet: a count, offsets from the count, the
        requests; the reply has the same shape, general status 0x1E when
        any embedded service failed (CIP Volume 1, A-4.10)."""
        data = request.data
        if len(data) < 2:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        count = struct.unpack_from("<H", data)[0]
        if len(data) < 2 + 2 * count:
            return CipReply.error(request, status.NOT_ENOUGH_DATA)
        offsets = list(struct.unpack_from(f"<{count}H", data, 2)) + [len(data)]
        replies = []
        for start, end in zip(offsets, offsets[1:]):
            if not 2 + 2 * count <= start <= end <= len(data):
                return CipReply.error(request, status.INVALID_PARAMETER)
            replies.append(await self.handle(data[start:end], access))
        out = struct.pack("<H", count)
        offset = 2 + 2 * count
        for reply in replies:
            out += struct.pack("<H", offset)
            offset += len(reply)
        failed = any(reply[2] != status.SUCCESS for reply in replies)
        return CipReply(request.service | REPLY, status.EMBEDDED_SERVICE_ERROR if failed else 0, (),
                        out + b"".join(replies))
