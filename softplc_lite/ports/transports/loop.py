"""``loop://``: what is written is read back (pyserial's test port).

Its ``in_waiting`` counts bytes exactly, so a read takes just those. A
write timeout of 0 makes pyserial's loop port raise a write timeout for
any data, so it writes with none: its queue has no limit and never blocks.
"""

from __future__ import annotations

from . import Transport


class LoopTransport(Transport):
    kind = "loop"
    write_timeout = None

    def read(self) -> bytes:
        n = self.serial.in_waiting
        return self.serial.read(n) if n else b""


TRANSPORT = LoopTransport
