"""A clock for the simulated ports that a test moves by hand."""

from __future__ import annotations


class Clock:
    """A fake clock in int ns, advanced by the test (``clock.now += ...``)."""

    def __init__(self, now: int = 0) -> None:
        self.now = now

    def __call__(self) -> int:
        return self.now
