"""``socket://host:port`` and ``rfc2217://``: a TCP peer with serial framing.

``in_waiting`` there is only ever 0 or 1 (testing notes), so sizing reads by
it would take one byte a scan: read a chunk with ``timeout=0`` instead,
which returns what the socket holds. The socket is non-blocking; ask
select() before writing so a full send buffer skips the write instead of
spinning.
"""

from __future__ import annotations

import select

from . import READ_CHUNK, Transport


class SocketTransport(Transport):
    kind = "socket"

    def read(self) -> bytes:
        return self.serial.read(READ_CHUNK)

    def write(self, data: bytes) -> int:
        sock = getattr(self.serial, "_socket", None)
        if sock is not None:
            _, writable, _ = select.select([], [sock], [], 0)
            if not writable:
                return 0
        return self.serial.write(data) or 0


TRANSPORT = SocketTransport
