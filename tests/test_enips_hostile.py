"""ENIPS against clients that misbehave, over real sockets to the module's
server process: bytes that are not EtherNet/IP, headers that announce too
much or stop half way, a session never registered, a connection never
closed, clients the allow-list refuses, the connection and request-rate
limits, and UDP ListIdentity; each refusal with the status the
specification gives and counted in the status words."""

from __future__ import annotations

import socket
import struct
import time

import pytest
from pycomm3.custom_types import ListIdentityObject

from softplc_lite.cip import encap
from softplc_lite.cip import status as st
from softplc_lite.cip.encap import EncapMessage
from softplc_lite.tlm.enips import status as S

from helpers.enips_apps import (LIMIT_S, WRITABLE, connect, connected, enips_xml, exchange, forward_open, register,
                                unconnected)

pytestmark = pytest.mark.timeout(120)
OTHER_LOOPBACK = "127.0.0.2"  # Linux routes all of 127.0.0.0/8 to lo: a second client address
IDENTITY = bytes.fromhex("20012401")  # class 1 instance 1


def closed_by_server(sock: socket.socket) -> bool:
    try:
        return sock.recv(4096) == b""
    except ConnectionResetError:
        return True


def test_bytes_that_are_not_ethernet_ip_close_their_connection(enips_apps):
    plc = enips_apps.start()
    with connect(plc.port) as sock:
        sock.sendall(b"GET / HTTP/1.1\r\nHost: plc\r\n\r\n" + bytes(100))  # its "length" is 0x2F20
        assert closed_by_server(sock)
    with connect(plc.port) as sock:  # a header announcing 65535 data bytes
        sock.sendall(struct.pack("<HHII8sI", encap.SEND_RR_DATA, 0xFFFF, 0, 0, bytes(8), 0))
        assert closed_by_server(sock)
    plc.wait_for(lambda: plc.status(S.W_MALFORMED) == 2, "both malformed connections counted")
    with connect(plc.port) as sock:  # the server goes on
        assert register(sock)


def test_a_header_that_stops_half_way_is_closed_at_the_idle_timeout(enips_apps):
    plc = enips_apps.start(enips_xml(idleTimeout=300))
    with connect(plc.port) as sock:
        sock.sendall(EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 1, 0)).encode()[:10])
        started = time.monotonic()
        assert closed_by_server(sock)
        assert time.monotonic() - started < LIMIT_S
    plc.wait_for(lambda: plc.status(S.W_IDLE) == 1, "the idle close counted")


def test_a_session_never_registered_gets_invalid_session_handle(enips_apps):
    plc = enips_apps.start()
    with connect(plc.port) as sock:
        reply, response = unconnected(sock, 0, 0x0E, IDENTITY + b"\x30\x07")
        assert reply.status == encap.INVALID_SESSION and response is None
        session = register(sock)
        reply, _ = unconnected(sock, session + 1, 0x0E, IDENTITY + b"\x30\x07")  # another session's handle
        assert reply.status == encap.INVALID_SESSION
        assert exchange(sock, EncapMessage(0x0001)).status == encap.INVALID_COMMAND
        assert exchange(sock, EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 1, 0))).status == \
            encap.INCORRECT_DATA  # one session per connection
        _, response = unconnected(sock, session, 0x0E, IDENTITY + b"\x30\x07")
        assert response.status == st.SUCCESS and response.data[1:] == b"softplc_lite app1"
    plc.wait_for(lambda: plc.status(S.W_ENCAP_ERRORS) == 4, "four encapsulation refusals counted")


def test_cip_refusals_carry_the_specifications_status(enips_apps):
    plc = enips_apps.start()
    with connect(plc.port) as sock:
        session = register(sock)
        assert unconnected(sock, session, 0x0E, bytes.fromhex("20992401"))[1].status == st.PATH_DESTINATION_UNKNOWN
        assert unconnected(sock, session, 0x33, IDENTITY)[1].status == st.SERVICE_NOT_SUPPORTED
        assert unconnected(sock, session, 0x4D, bytes.fromhex("91024e372800"),
                           bytes.fromhex("c3000100"))[1].status == st.NOT_ENOUGH_DATA  # a write with no value
    plc.wait_for(lambda: plc.status(S.W_CIP_ERRORS) == 3, "three CIP refusals counted")


def test_a_connection_never_closed_is_closed_with_its_tcp_connection(enips_apps):
    plc = enips_apps.start(enips_xml(maxCipConnections=1))
    first = connect(plc.port)
    session = register(first)
    opened = forward_open(first, session, serial=1)
    assert opened.status == st.SUCCESS
    o_t_id = struct.unpack_from("<I", opened.data)[0]
    with connect(plc.port) as other:  # the one place is taken; and the connection is not another's to use
        other_session = register(other)
        refused = forward_open(other, other_session, serial=2)
        assert (refused.status, refused.extended) == (st.CONNECTION_FAILURE, (0x0113,))
        assert connected(other, other_session, o_t_id, 0x0E, IDENTITY + b"\x30\x07").status == encap.INCORRECT_DATA
    assert connected(first, session, o_t_id, 0x0E, IDENTITY + b"\x30\x07").status == encap.SUCCESS
    first.close()  # no Forward_Close: the TCP connection's end closes it
    plc.wait_for(lambda: plc.status(S.W_CONNECTED) == 0, "the first client gone")
    with connect(plc.port) as later:
        assert forward_open(later, register(later), serial=3).status == st.SUCCESS


def test_a_connection_past_its_rpi_timeout_is_closed_and_counted(enips_apps):
    plc = enips_apps.start()
    with connect(plc.port) as sock:
        session = register(sock)
        opened = forward_open(sock, session, serial=4, rpi_us=10_000, multiplier=0)  # 40 ms
        o_t_id = struct.unpack_from("<I", opened.data)[0]
        time.sleep(0.2)
        assert connected(sock, session, o_t_id, 0x0E, IDENTITY + b"\x30\x07").status == encap.INCORRECT_DATA
    plc.wait_for(lambda: plc.status(S.W_TIMED_OUT) == 1, "the timed-out connection counted")


def test_the_allow_list_admits_its_networks_only(enips_apps):
    plc = enips_apps.start(enips_xml(f'  <Allow network="{OTHER_LOOPBACK}/32"/>\n' + WRITABLE))
    with connect(plc.port) as refused:
        assert closed_by_server(refused)
    with connect(plc.port, source=OTHER_LOOPBACK) as admitted:
        assert register(admitted)
    plc.wait_for(lambda: plc.status(S.W_REFUSED_NETWORK) == 1, "the refused client counted")


def test_connections_past_the_limit_are_refused(enips_apps):
    plc = enips_apps.start(enips_xml(maxConnections=2))
    kept = [connect(plc.port) for _ in range(2)]
    try:
        for sock in kept:
            assert register(sock)
        with connect(plc.port) as third:
            assert closed_by_server(third)
        plc.wait_for(lambda: plc.status(S.W_REFUSED_LIMIT) == 1, "the refused connection counted")
    finally:
        for sock in kept:
            sock.close()


def test_requests_over_the_rate_are_answered_busy(enips_apps):
    plc = enips_apps.start(enips_xml(maxRequestsPerSecond=5))
    with connect(plc.port) as sock:
        session = register(sock)
        answers = [unconnected(sock, session, 0x0E, IDENTITY + b"\x30\x07") for _ in range(12)]
        busy = [r for _, r in answers if r is not None and r.status == st.RESOURCE_UNAVAILABLE]
        assert busy and len(busy) + sum(r is not None and r.status == 0 for _, r in answers) == 12
        services = [exchange(sock, EncapMessage(encap.LIST_SERVICES)) for _ in range(6)]
        assert encap.INSUFFICIENT_MEMORY in {m.status for m in services}  # no CIP request to answer busy
    plc.wait_for(lambda: plc.status(S.W_REFUSED_RATE) >= len(busy) + 1, "the busy answers counted")


def test_udp_list_identity_finds_the_plc(enips_apps):
    plc = enips_apps.start(enips_xml(f'  <Allow network="127.0.0.1/32"/>\n' + WRITABLE))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
        udp.settimeout(LIMIT_S)
        udp.sendto(b"garbage", ("127.0.0.1", plc.port))  # dropped
        udp.sendto(EncapMessage(encap.LIST_IDENTITY, context=b"browse!!").encode(), ("127.0.0.1", plc.port))
        raw, _ = udp.recvfrom(4096)
    reply = EncapMessage.decode(raw)
    assert reply.context == b"browse!!"
    seen = ListIdentityObject.decode(reply.data[2:])
    assert seen["product_name"] == "softplc_lite app1" and seen["product_type"] == "Programmable Logic Controller"
    assert reply.data[10:12] == plc.port.to_bytes(2, "big")  # the socket address names the TCP listener
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as stranger:
        stranger.bind((OTHER_LOOPBACK, 0))
        stranger.settimeout(0.5)
        stranger.sendto(EncapMessage(encap.LIST_IDENTITY).encode(), ("127.0.0.1", plc.port))
        with pytest.raises(socket.timeout):
            stranger.recvfrom(4096)
    plc.wait_for(lambda: plc.status(S.W_REFUSED_NETWORK) == 1, "the stranger's datagram counted")


def test_udp_can_be_left_off(enips_apps):
    plc = enips_apps.start(enips_xml(udpListIdentity="no"))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
        udp.settimeout(0.5)
        udp.sendto(EncapMessage(encap.LIST_IDENTITY).encode(), ("127.0.0.1", plc.port))
        with pytest.raises((socket.timeout, ConnectionRefusedError)):
            udp.recvfrom(4096)
