"""How a port's bytes move without blocking the scan: one small module per
kind of port, chosen by the URL scheme, as pyserial chooses its URL
handlers.

Every port opens through ``serial.serial_for_url``; what differs between
kinds is how to read what has arrived and write what fits *now*:

==========  ================================  =============================================
kind        chosen for                        module
==========  ================================  =============================================
device      a device path (``/dev/ttyUSB0``,  ``device.py``: select() before each call, so a
            ``COM3``) and ``spy://``          full OS buffer never spins pyserial's write loop
loop        ``loop://``                       ``loop.py``: reads what ``in_waiting`` counts;
                                              writes with no write timeout (pyserial's
                                              loop:// refuses a zero one)
socket      ``socket://``, ``rfc2217://``     ``tcp.py``: ``in_waiting`` is only 0 or 1
                                              there, so read a chunk, non-blocking
sim         ``sim://``, ``replay://``         ``simulated.py``: softplc_lite's own handlers;
                                              they run on the engine's clock
==========  ================================  =============================================

A transport raises ``serial.SerialException`` or ``OSError`` when the port
has gone (the port then goes down and is retried, see ports.py).
"""

from __future__ import annotations

import importlib
from typing import Callable

READ_CHUNK = 4096  # bytes per read call


class Transport:
    """The non-blocking operations of one open port."""

    kind = "url"
    write_timeout: float | None = 0  # pyserial's "non-blocking" write

    def __init__(self, serial) -> None:
        self.serial = serial

    def read(self) -> bytes:
        """What has arrived, at most READ_CHUNK bytes; b"" when nothing."""
        return self.serial.read(READ_CHUNK)

    def read_at(self, now_ns: int) -> bytes:
        """``read()`` on a port on the engine's clock, which reads ``now_ns``."""
        return self.read()

    def quiet_link(self):
        """An object whose ``quiet_until`` (ns on the port's clock) says until
        when a read surely finds nothing (a simulated link), or None."""
        return None

    def write(self, data: bytes) -> int:
        """Write what the port takes now; return how many bytes."""
        return self.serial.write(data) or 0

    def set_clock(self, now_ns: Callable[[], int]) -> None:
        """Ports on the engine's clock (simulated kinds) take it here."""


_KINDS = {
    "loop": "loop", "socket": "tcp", "rfc2217": "tcp",
    "sim": "simulated", "replay": "simulated", "spy": "device", "": "device",
}


def scheme(url: str) -> str:
    return url.split("://", 1)[0].lower() if "://" in url else ""


def transport_for(url: str, serial) -> Transport:
    """The Transport for an open pyserial port made from ``url``."""
    module = importlib.import_module(f"{__name__}.{_KINDS.get(scheme(url), 'device')}")
    return module.TRANSPORT(serial)
