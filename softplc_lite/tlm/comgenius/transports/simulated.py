"""``sim://`` and ``replay://``: softplc_lite's own pyserial URL handlers
(urlhandler/). Both run on a clock they are given, the engine's, so a run
on simulated time is the same every time; reads and writes never block.
"""

from __future__ import annotations

from typing import Callable

from . import Transport


class SimulatedTransport(Transport):
    kind = "sim"
    write_timeout = None

    def read(self) -> bytes:
        n = self.serial.in_waiting
        return self.serial.read(n) if n else b""

    def set_clock(self, now_ns: Callable[[], int]) -> None:
        self.serial.set_clock(now_ns)


TRANSPORT = SimulatedTransport
