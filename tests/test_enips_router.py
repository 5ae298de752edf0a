import asyncio
import struct

from helpers.cip import route
from softplc_lite.cip import epath, status
from softplc_lite.cip.mr import MessageRouterRequest, MessageRouterResponse
from softplc_lite.tlm.enips.objects import CipObject, CipReply
from softplc_lite.tlm.enips.router import MessageRouter


class Echo(CipObject):
    class_id = 0x70

    async def serve(self, request, access):
        if request.service != 0x0E:
            return CipReply.error(request, status.SERVICE_NOT_SUPPORTED)
        return CipReply.ok(request, bytes(x or 0 for x in request.logical) + request.data)


class Symbols(CipObject):
    class_id = None

    async def serve(self, request, access):
        return CipReply.ok(request, request.path)


def test_dispatch_by_class_and_symbolic_path():
    router = MessageRouter([Echo(), Symbols()])
    reply = route(router, 0x0E, epath.encode_logical(0x70, 1, 3), b"x")
    assert (reply.service, reply.status, reply.data) == (0x8E, 0, b"\x70\x01\x03x")
    assert route(router, 0x4C, b"\x91\x02N7").data == b"\x91\x02N7"
    assert route(router, 0x0E, epath.encode_logical(0x99, 1)).status == status.PATH_DESTINATION_UNKNOWN
    assert route(router, 0x10, epath.encode_logical(0x70, 1)).status == status.SERVICE_NOT_SUPPORTED
    assert route(router, 0x0E, b"\x50\x00").status == status.PATH_SEGMENT_ERROR
    assert MessageRouterResponse.decode(asyncio.run(router.handle(b"\x0e\x05", None))).status == status.NOT_ENOUGH_DATA
    assert epath.logical(epath.encode_logical(0x300, 0x1234, 7)) == (0x300, 0x1234, 7)


def test_multiple_service_packet():
    router = MessageRouter([Echo()])
    inner = [MessageRouterRequest(0x0E, epath.encode_logical(0x70, 2, 1)).encode(),
             MessageRouterRequest(0x0E, epath.encode_logical(0x71, 1)).encode()]
    data = struct.pack("<HHH", 2, 6, 6 + len(inner[0])) + b"".join(inner)
    reply = route(router, 0x0A, epath.encode_logical(0x02, 1), data)
    assert reply.status == status.EMBEDDED_SERVICE_ERROR  # the second names no object
    count, first, second = struct.unpack_from("<HHH", reply.data)
    assert count == 2
    assert MessageRouterResponse.decode(reply.data[first:second]).data == b"\x70\x02\x01"
    assert MessageRouterResponse.decode(reply.data[second:]).status == status.PATH_DESTINATION_UNKNOWN


def test_route_path_ports():
    assert epath.ports(b"\x01\x00") == [(1, b"\x00")]
    assert epath.ports(b"\x12\x09127.0.0.1\x00\x01\x00") == [(2, b"127.0.0.1"), (1, b"\x00")]
