"""The scan engine's time: each scan asks its clock how many milliseconds
passed since the previous one.

SimulatedClock advances a fixed number of ms per scan (deterministic, the
default: runs repeat exactly); RealClock reads the wall clock.
"""

from __future__ import annotations

import time


class SimulatedClock:
    """Each scan advances exactly ``scan_ms`` milliseconds."""

    realtime = False

    def __init__(self, scan_ms: int = 10) -> None:
        self.scan_ms = scan_ms
        self.now_ms = 0

    def advance(self) -> int:
        self.now_ms += self.scan_ms
        return self.scan_ms


class RealClock:
    """Milliseconds of wall-clock time since the previous scan."""

    realtime = True

    def __init__(self) -> None:
        self._last_ns = time.monotonic_ns()
        self._carry_ns = 0
        self.now_ms = 0

    def advance(self) -> int:
        now = time.monotonic_ns()
        elapsed = now - self._last_ns + self._carry_ns
        self._last_ns = now
        ms, self._carry_ns = divmod(elapsed, 1_000_000)
        self.now_ms += ms
        return ms
