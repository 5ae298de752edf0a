"""``sim://`` and ``replay://``: softplc_lite's own pyserial URL handlers
(urlhandler/). Both run on a clock they are given, the engine's, so a run
on simulated time is the same every time; reads and writes never block.
"""

from __future__ import annotations

from typing import Callable

from .loop import LoopTransport


class SimulatedTransport(LoopTransport):
    """Read and written as loop:// is (exact ``in_waiting``, no write
    timeout), and on the engine's clock."""

    kind = "sim"

    def __init__(self, serial) -> None:
        super().__init__(serial)
        # read(in_waiting) in one call, nothing done while the wire is quiet;
        # bound here so that a port's read at every scan is one call less
        self.read = serial.read_now
        self.read_at = serial.read_at

    def set_clock(self, now_ns: Callable[[], int]) -> None:
        self.serial.set_clock(now_ns)

    def read(self) -> bytes:  # replaced by serial.read_now in __init__
        return self.serial.read_now()

    def read_at(self, now_ns: int) -> bytes:  # replaced by serial.read_at in __init__
        return self.serial.read_at(now_ns)

    def quiet_link(self):
        return getattr(self.serial, "sim_link", None)  # replay:// has none


TRANSPORT = SimulatedTransport
