import asyncio
import threading

from pycomm3 import CIPDriver

from softplc_lite.tlm.enips.identity import Identity
from softplc_lite.tlm.enips.tcp import serve


class Served:
    """The listener on an ephemeral port in a thread of its own, so a
    blocking client (pycomm3) can talk to it."""

    def __enter__(self):
        self.loop = asyncio.new_event_loop()
        self.server = self.loop.run_until_complete(serve(None, Identity("PUMPS")))
        self.port = self.server.sockets[0].getsockname()[1]
        self.thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)
        self.server.close()
        self.loop.run_until_complete(self.server.wait_closed())
        self.loop.close()


def test_pycomm3_reads_the_identity_unconnected():
    with Served() as served:
        driver = CIPDriver(f"127.0.0.1:{served.port}")
        assert driver.open()
        try:
            name = driver.generic_message(service=0x0E, class_code=1, instance=1, attribute=7,
                                          connected=False)
            assert name.error is None, name.error
            assert name.value[1:] == b"softplc_lite PUMPS"
            info = driver.get_module_info(0)
            assert info["product_name"] == "softplc_lite PUMPS"
            assert info["vendor"] == "Rockwell Automation/Allen-Bradley"
        finally:
            driver.close()


def test_raw_socket_refusals():
    import socket
    import struct

    from softplc_lite.cip import encap
    from softplc_lite.cip.encap import EncapMessage

    with Served() as served:
        with socket.create_connection(("127.0.0.1", served.port), timeout=5) as sock:
            sock.sendall(EncapMessage(encap.SEND_RR_DATA, bytes(8), session=77).encode())
            reply = EncapMessage.decode(sock.recv(4096))
            assert (reply.status, reply.session) == (encap.INVALID_SESSION, 77)
            sock.sendall(EncapMessage(0x01).encode())
            assert EncapMessage.decode(sock.recv(4096)).status == encap.INVALID_COMMAND
            # A header announcing more data than the server takes closes the connection.
            sock.sendall(struct.pack("<HHII8sI", encap.SEND_RR_DATA, 0xFFFF, 0, 0, bytes(8), 0))
            assert sock.recv(4096) == b""


def test_udp_list_identity():
    import socket

    from pycomm3.custom_types import ListIdentityObject

    from softplc_lite.cip import encap
    from softplc_lite.cip.encap import EncapMessage
    from softplc_lite.tlm.enips.tcp import serve_udp

    loop = asyncio.new_event_loop()
    transport = loop.run_until_complete(serve_udp(Identity("PUMPS"), tcp_port=4242))
    port = transport.get_extra_info("sockname")[1]
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.setblocking(False)  # received on the server's loop, which must run to answer
            sock.sendto(b"garbage", ("127.0.0.1", port))  # dropped, no reply
            sock.sendto(EncapMessage(encap.LIST_IDENTITY, context=b"discover").encode(), ("127.0.0.1", port))
            raw = loop.run_until_complete(asyncio.wait_for(loop.sock_recv(sock, 4096), 5))
            reply = EncapMessage.decode(raw)
        assert reply.context == b"discover"
        seen = ListIdentityObject.decode(reply.data[2:])
        assert seen["product_name"] == "softplc_lite PUMPS"
        assert reply.data[10:12] == (4242).to_bytes(2, "big")
    finally:
        transport.close()
        loop.close()


def test_pycomm3_connected_messaging():
    with Served() as served:
        with CIPDriver(f"127.0.0.1:{served.port}") as driver:
            assert driver._forward_open()
            name = driver.generic_message(service=0x0E, class_code=1, instance=1, attribute=7,
                                          connected=True)
            assert name.error is None, name.error
            assert name.value[1:] == b"softplc_lite PUMPS"
            assert driver._forward_close()
