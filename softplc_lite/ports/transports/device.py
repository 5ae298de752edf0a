"""Device paths (``/dev/ttyUSB0``, a pty, ``COM3``) and ``spy://`` around them.

pyserial's POSIX port is opened non-blocking; with ``timeout=0`` a read
returns what is there (and raises when the device is gone: a pty whose
other side closed reports readable and returns nothing). Its write with
``write_timeout=0`` returns after one ``os.write``, but loops while the OS
buffer is full, so we ask select() first and skip the write when the port
cannot take a byte.
"""

from __future__ import annotations

import select

from . import READ_CHUNK, Transport


class DeviceTransport(Transport):
    kind = "device"

    def _fd(self):
        fd = getattr(self.serial, "fd", None)
        return fd if isinstance(fd, int) else None

    def write(self, data: bytes) -> int:
        fd = self._fd()
        if fd is not None:
            _, writable, _ = select.select([], [fd], [], 0)
            if not writable:
                return 0
        return self.serial.write(data) or 0

    def read(self) -> bytes:
        return self.serial.read(READ_CHUNK)


TRANSPORT = DeviceTransport
