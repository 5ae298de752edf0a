import asyncio
import struct

from softplc_lite.cip import epath, status
from softplc_lite.cip.mr import MessageRouterRequest, MessageRouterResponse
from softplc_lite.tlm.enips.router import MessageRouter


def unconnected_send(route):
    inner = MessageRouterRequest(0x0E, epath.encode_logical(1, 1, 1)).encode()
    data = bytes((0x0A, 0x05)) + struct.pack("<H", len(inner)) + inner + b"\x00" * (len(inner) & 1)
    data += bytes((len(route) // 2, 0)) + route
    raw = MessageRouterRequest(0x52, epath.encode_logical(6, 1), data).encode()
    return MessageRouterResponse.decode(asyncio.run(MessageRouter().handle(raw, None)))


def test_backplane_slot_zero_is_served():
    for route in (b"", b"\x01\x00"):
        reply = unconnected_send(route)
        assert (reply.service, reply.status, reply.data) == (0x8E, 0, b"\x01\x00")


def test_other_slots_are_refused():
    reply = unconnected_send(b"\x01\x03")
    assert (reply.service, reply.status, reply.extended) == (0xD2, status.CONNECTION_FAILURE, (0x0312,))
    assert unconnected_send(b"\x50\x00").status == status.PATH_SEGMENT_ERROR
