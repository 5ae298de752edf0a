"""The simulated wire: character timing and the bytes in flight on one direction.

Timing model (docs/simulated-wire.md explains it for users):

- A character takes ``1 start bit + data bits + (1 if parity) + stop bits``
  bit times: ``char_time_ns()`` gives it in whole nanoseconds, rounded to the
  nearest (10 bits at 38400 baud: 260417 ns). The SENDER's settings decide
  it; the receiver's settings do not matter (bytes arrive unchanged).
- Each direction of a link is a ``Wire``: a queue of chunks, one per write
  (``start_ns``, ``char_ns``, bytes, how many were taken). Bytes written at
  ``t`` start at ``max(t, wire free)``; byte ``j`` (0-based) of the write
  arrives at ``start + (j + 1) * char_ns``, and the wire is free again after
  the last one. A receiver sees a byte once its clock reads at least the
  byte's arrival time. Availability is computed from the chunk, never with
  one Python object per byte.
- ``char_ns == 0`` is the unlimited rate: a write arrives whole at once.

The links that join two wires between two ends are in simlink.py; the
pyserial port on a settable clock is in clocked.py.
"""

from __future__ import annotations

import numbers
from collections import deque

NS_PER_S = 1_000_000_000


def char_time_ns(baudrate: int, bytesize: int = 8, parity: str = "N", stopbits: float = 1) -> int:
    """Time of one character on the wire in whole ns (rounded half up).

    >>> char_time_ns(38400), char_time_ns(38400, 7, "E", 1), char_time_ns(38400, 8, "N", 2)
    (260417, 260417, 286458)
    """
    if not isinstance(baudrate, numbers.Integral) or baudrate <= 0:
        raise ValueError(f"invalid baudrate: {baudrate!r}")
    half_bits = 2 * (1 + bytesize + (parity != "N")) + round(2 * stopbits)
    return (half_bits * NS_PER_S + baudrate) // (2 * baudrate)


def mask_table(bytesize: int) -> bytes | None:
    """A ``bytes.translate`` table keeping the low ``bytesize`` bits, or None for 8."""
    if bytesize >= 8:
        return None
    keep = (1 << bytesize) - 1
    return bytes(b & keep for b in range(256))


class _Chunk:
    """One write on a wire: ``data`` starts at ``start``, one byte every ``char_ns``."""

    __slots__ = ("start", "char_ns", "data", "taken")

    def __init__(self, start: int, char_ns: int, data: bytes) -> None:
        self.start = start
        self.char_ns = char_ns
        self.data = data
        self.taken = 0

    def arrived(self, now: int) -> int:
        """How many of the chunk's bytes have arrived by ``now`` (taken or not)."""
        if self.char_ns == 0:
            return len(self.data) if now >= self.start else 0
        n = (now - self.start) // self.char_ns
        if n <= 0:
            return 0
        return n if n < len(self.data) else len(self.data)

    def end(self) -> int:
        return self.start + len(self.data) * self.char_ns


class Wire:
    """One direction of a link: bytes in flight and arrived, not yet taken."""

    def __init__(self) -> None:
        self.chunks: deque[_Chunk] = deque()
        self.free_at = 0  # when the last byte sent so far has arrived

    def send(self, data: bytes, at_ns: int, char_ns: int) -> None:
        if not data:
            return
        start = at_ns if at_ns > self.free_at else self.free_at
        self.chunks.append(_Chunk(start, char_ns, data))
        self.free_at = start + len(data) * char_ns

    def available(self, now: int) -> int:
        """Bytes arrived by ``now`` and not yet taken."""
        total = 0
        for chunk in self.chunks:
            n = chunk.arrived(now)
            total += n - chunk.taken
            if n < len(chunk.data):
                break
        return total

    def take(self, size: int, now: int) -> bytes:
        """Up to ``size`` arrived bytes, removed from the wire."""
        parts = []
        chunks = self.chunks
        while size > 0 and chunks:
            chunk = chunks[0]
            n = chunk.arrived(now)
            k = min(n - chunk.taken, size)
            if k <= 0:
                break
            parts.append(chunk.data[chunk.taken:chunk.taken + k])
            chunk.taken += k
            size -= k
            if chunk.taken == len(chunk.data):
                chunks.popleft()
            else:
                break
        return parts[0] if len(parts) == 1 else b"".join(parts)

    def take_arrived(self, now: int) -> bytes:
        """Every byte arrived by ``now``, removed: ``take(available(now), now)``
        in one pass over the chunks (the read of a polling port at every scan
        while a reply arrives)."""
        chunks = self.chunks
        if not chunks:
            return b""
        chunk = chunks[0]
        if chunk.char_ns:  # the usual read while a reply arrives: more of one chunk, not all of it
            n = (now - chunk.start) // chunk.char_ns
            taken = chunk.taken
            if n < len(chunk.data):
                if n <= taken:
                    return b""
                chunk.taken = n
                return chunk.data[taken:n]
        parts = None
        got = b""
        while chunks:
            chunk = chunks[0]
            data = chunk.data
            size = len(data)
            c = chunk.char_ns
            if c:
                n = (now - chunk.start) // c
                if n > size:
                    n = size
            else:
                n = size if now >= chunk.start else 0
            taken = chunk.taken
            if n <= taken:
                break
            part = data if taken == 0 and n == size else data[taken:n]
            chunk.taken = n
            if not got:
                got = part
            else:
                if parts is None:
                    parts = [got]
                parts.append(part)
            if n < size:
                break
            chunks.popleft()
        return got if parts is None else b"".join(parts)

    def take_timed(self, now: int) -> tuple[bytes, list[int]]:
        """All arrived bytes, removed, with each byte's arrival time."""
        chunks = self.chunks
        if not chunks or chunks[0].arrived(now) <= chunks[0].taken:
            return b"", []  # the usual case while a driver waits: nothing new
        parts, times = [], []
        while chunks:
            chunk = chunks[0]
            n = chunk.arrived(now)
            if n > chunk.taken:
                parts.append(chunk.data[chunk.taken:n])
                if chunk.char_ns:
                    c = chunk.char_ns
                    times.extend(range(chunk.start + (chunk.taken + 1) * c, chunk.start + (n + 1) * c, c))
                else:
                    times.extend([chunk.start] * (n - chunk.taken))
                chunk.taken = n
            if n < len(chunk.data):
                break
            chunks.popleft()
        return b"".join(parts), times

    def next_arrival(self) -> int | None:
        """When the first byte not yet taken arrives (it may have by now);
        None when the wire is empty."""
        chunks = self.chunks
        if not chunks:
            return None
        chunk = chunks[0]
        return chunk.start + (chunk.taken + 1) * chunk.char_ns if chunk.char_ns else chunk.start

    def pending(self, now: int) -> int:
        """Bytes sent but not yet arrived by ``now``."""
        total = 0
        for chunk in reversed(self.chunks):
            n = chunk.arrived(now)
            total += len(chunk.data) - n
            if n:
                break
        return total

    def discard_arrived(self, now: int) -> None:
        while self.take(1 << 30, now):
            pass

    def abort(self, now: int) -> None:
        """Drop every byte that has not arrived by ``now``; the wire is free at once."""
        kept: deque[_Chunk] = deque()
        for chunk in self.chunks:
            n = chunk.arrived(now)
            if n > chunk.taken:
                chunk.data = chunk.data[:n]
                kept.append(chunk)
        self.chunks = kept
        self.free_at = min(self.free_at, now)

    def clear(self) -> None:
        self.chunks.clear()
