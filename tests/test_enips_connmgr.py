import struct

from helpers.cip import route
from softplc_lite.cip import epath, status
from softplc_lite.cip.mr import MessageRouterRequest
from softplc_lite.tlm.enips.router import MessageRouter


def unconnected_send(route_path):
    inner = MessageRouterRequest(0x0E, epath.encode_logical(1, 1, 1)).encode()
    data = bytes((0x0A, 0x05)) + struct.pack("<H", len(inner)) + inner + b"\x00" * (len(inner) & 1)
    data += bytes((len(route_path) // 2, 0)) + route_path
    return route(MessageRouter(), 0x52, epath.encode_logical(6, 1), data)


def test_backplane_slot_zero_is_served():
    for route_path in (b"", b"\x01\x00"):
        reply = unconnected_send(route_path)
        assert (reply.service, reply.status, reply.data) == (0x8E, 0, b"\x01\x00")


def test_other_slots_are_refused():
    reply = unconnected_send(b"\x01\x03")
    assert (reply.service, reply.status, reply.extended) == (0xD2, status.CONNECTION_FAILURE, (0x0312,))
    assert unconnected_send(b"\x50\x00").status == status.PATH_SEGMENT_ERROR


def test_a_connection_never_used_times_out():
    from softplc_lite.tlm.enips.connmgr import ConnectionManager

    manager = ConnectionManager()
    router = MessageRouter([manager])

    def forward_open(rpi_us):
        data = struct.pack("<BBIIHHIB3xIHIHB", 0x0A, 0x05, 0, 0x77, 1, 1, 9, 0, rpi_us, 0x43F4, rpi_us, 0x43F4, 0xA3)
        data += bytes((2,)) + epath.encode_logical(2, 1)
        reply = route(router, 0x54, epath.encode_logical(6, 1), data)
        return struct.unpack_from("<I", reply.data)[0]

    lasting = forward_open(10_000_000)  # 10 s x 4
    assert manager.alive(lasting)[0] == 0x77
    fleeting = forward_open(0)  # a timeout of zero: over by the next request
    import time
    while time.monotonic() == manager.last_seen[fleeting]:
        pass
    assert manager.alive(fleeting) is None
    assert fleeting not in manager.connections and lasting in manager.connections
