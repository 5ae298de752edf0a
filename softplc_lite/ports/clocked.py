"""``ClockedSerial``: the pyserial base shared by the ``sim://`` and ``replay://`` ports.

Both run on a clock they are given (``set_clock()``, the engine's, so a run
on simulated time is the same every time); reads block only with the
real-time default clock. ``read_timed()`` gives what has arrived with each
byte's arrival time, ``cts_state()`` CTS and when it last changed.
"""

from __future__ import annotations

import numbers
import time
from typing import Callable

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, to_bytes

Clock = Callable[[], int]


class ClockedSerial(SerialBase):
    """pyserial base of the simulated ports: a settable clock and polling reads.

    Subclasses implement ``_open_port()``, ``_close_port()``,
    ``_take(size, now)``, ``_available(now)``, ``_write(data, now)``,
    ``_pending(now)``, ``_reset_input(now)``, ``_reset_output(now)`` and
    ``_configure()``."""

    POLL_S = 0.001

    def __init__(self, *args, **kwargs) -> None:
        self._clock: Clock = time.monotonic_ns
        self._clock_set = False
        super().__init__(*args, **kwargs)

    def set_clock(self, fn: Clock) -> None:
        """Use ``fn()`` (int ns) as this port's time; reads stop blocking."""
        self._clock = fn
        self._clock_set = True

    def read_now(self) -> bytes:
        """Everything that has arrived by the clock's time, never blocking:
        ``read(in_waiting)`` (what a polling driver does), in one call."""
        self._check_open()
        n = self._available(self._clock())
        return self._take(n, self._clock()) if n else b""

    def read_at(self, now: int) -> bytes:
        """``read_now``, given the clock's reading ``now`` (the same clock)."""
        return self.read_now()

    # - - - open / close - - -

    def open(self) -> None:
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        self._open_port()
        try:
            self.is_open = True
            self._reconfigure_port()
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        if getattr(self, "is_open", False):
            self.is_open = False
            self._close_port()

    def __del__(self) -> None:
        # io.IOBase's finalizer calls close(), which takes the link registry's
        # lock; a finalizer can run inside any allocation, even one made while
        # that lock is held, and would wait for it forever: it releases lock-free.
        if getattr(self, "is_open", False):
            self.is_open = False
            self._close_from_finalizer()

    def _close_from_finalizer(self) -> None:
        """Release what the port holds without taking a lock."""
        self._close_port()

    def _reconfigure_port(self) -> None:
        if not isinstance(self._baudrate, numbers.Integral) or not 0 < self._baudrate < 2 ** 32:
            raise ValueError(f"invalid baudrate: {self._baudrate!r}")
        if self.is_open:
            self._configure()

    def _update_break_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        if self.is_open:
            self._set_rts(bool(self._rts_state), self._clock())

    def _set_rts(self, on: bool, now: int) -> None:
        pass

    def cts_state(self) -> tuple[bool, int]:
        """CTS now and the time (ns) it last changed."""
        self._check_open()
        return self._cts(self._clock())

    def _cts(self, now: int) -> tuple[bool, int]:
        return True, 0

    @property
    def cts(self) -> bool:
        return self.cts_state()[0]

    @property
    def dsr(self) -> bool:
        self._check_open()
        return True

    @property
    def ri(self) -> bool:
        self._check_open()
        return False

    @property
    def cd(self) -> bool:
        self._check_open()
        return True

    def _update_dtr_state(self) -> None:
        pass

    def _check_open(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()

    # - - - data - - -

    @property
    def in_waiting(self) -> int:
        self._check_open()
        return self._available(self._clock())

    @property
    def out_waiting(self) -> int:
        self._check_open()
        return self._pending(self._clock())

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes. Returns at once with what has arrived when a
        clock was set or ``timeout == 0``; otherwise waits (polling) for
        ``size`` bytes or the timeout, like a real port."""
        self._check_open()
        if size <= 0:
            return b""
        data = self._take(size, self._clock())
        if len(data) >= size or self._clock_set or self._timeout == 0:
            return data
        parts = [data]
        got = len(data)
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        while got < size and self.is_open:
            if deadline is not None and time.monotonic() >= deadline:
                break
            time.sleep(self.POLL_S)
            if not self.is_open:
                break
            more = self._take(size - got, self._clock())
            parts.append(more)
            got += len(more)
        return b"".join(parts)

    def read_timed(self) -> tuple[bytes, list[int]]:
        """Everything that has arrived by the clock's time, with each byte's
        arrival time in ns; never blocks."""
        self._check_open()
        return self._take_timed(self._clock())

    def _take_timed(self, now: int) -> tuple[bytes, list[int]]:
        data = self._take(1 << 30, now)
        return data, [now] * len(data)

    def write(self, data) -> int:
        """Queue ``data`` on the wire; never blocks."""
        self._check_open()
        data = to_bytes(data)
        self._write(data, self._clock())
        return len(data)

    def reset_input_buffer(self) -> None:
        self._check_open()
        self._reset_input(self._clock())

    def reset_output_buffer(self) -> None:
        self._check_open()
        self._reset_output(self._clock())

    def _settings(self) -> str:
        stop = {1: "1", 1.5: "1.5", 2: "2"}.get(self._stopbits, str(self._stopbits))
        return f"{self._baudrate} {self._bytesize}{self._parity}{stop}"
