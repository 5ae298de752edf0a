"""The simulated wire: character timing, links between two ends, the clock.

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

Links: ``open_port_end(name)`` makes the calling port one end of the link
``name`` (process-wide registry, thread-safe); the second call makes the
other end, a third raises ``SerialException``. ``open_device_end(name,
device)`` makes a link whose other end is a simulated device (simdevices.py).
A link is forgotten when its ports are closed, so its name can be reused.

The device side is "pumped" whenever its port end is used (``read``,
``available``, ``write``, ``pending``): every byte that has arrived at the
device by the port's clock is handed to ``device.receive(data, times_ns)``,
then ``device.poll(now_ns)`` runs. A polling driver's read
(``PortEnd.read_arrived``) leaves out a pump that could do nothing: while
nothing is on its way to the device and its ``next_due`` is later, and while
the whole link is quiet (``Link.quiet_until``). A device answers with
``DeviceEnd.send(data, at_ns)``, timed from ``at_ns`` even when that is
already in the past of the port's clock (turnaround is exact, not rounded up
to when the port next looks).

Modem lines: each port end drives RTS (``set_rts(on, now)``, remembered with
the time it changed). Between two ports the link is a null-modem cable: one
end's CTS is the other end's RTS. A device decides the port's CTS
(``SimDevice.cts(now)``; by default it follows the port's RTS at once).

``ClockedSerial`` is the pyserial base shared by the ``sim://`` and
``replay://`` ports: ``set_clock()``, reads that block only with the
real-time default clock, ``read_timed()`` (what has arrived with each byte's
arrival time) and ``cts_state()`` (CTS and when it last changed).
"""

from __future__ import annotations

import numbers
import threading
import time
from collections import deque
from typing import TYPE_CHECKING, Callable

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, to_bytes

if TYPE_CHECKING:
    from .simdevices import SimDevice

NS_PER_S = 1_000_000_000

Clock = Callable[[], int]


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
        while a reply arrives, issue 17)."""
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


class Link:
    """Two wires between end 0 and end 1; ``wires[i]`` carries what end i sends."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.lock = threading.RLock()
        self.wires = (Wire(), Wire())
        self.ports: list[PortEnd | None] = [None, None]
        self.device: SimDevice | None = None
        self.rts: list[tuple[bool, int]] = [(False, 0), (False, 0)]  # per end: (on, when it changed)
        # Until this time (ns) a pump would do nothing and end 0 has nothing
        # to read: no byte arrives on either wire and the device's poll is
        # not due. Set by PortEnd.available and read_arrived when they find
        # nothing (end 0, the port of a device link); reset to 0
        # by whatever changes the link (a send, a reset, new settings).
        self.quiet_until = 0

    def quiet_from(self, now: int) -> int:
        """When the next thing can happen on a device link pumped at ``now``
        (0 when it may be now, or on a port-to-port link)."""
        device = self.device
        if device is None:
            return 0
        due = device.next_due(now)
        for wire in self.wires:
            t = wire.next_arrival()
            if t is not None and (due is None or t < due):
                due = t
        if due is None:
            return 1 << 62
        return due if due > now else 0

    def pump(self, now: int) -> None:
        """Hand the device what has reached it by ``now``, then let it poll."""
        device = self.device
        if device is None:
            return
        wire = self.wires[0]
        if wire.chunks:  # most pumps find the port's wire empty: no call for it
            data, times = wire.take_timed(now)
            if data:
                device.receive(data, times)
        device.poll(now)

    def __repr__(self) -> str:
        other = f"device {self.device.name!r}" if self.device else f"{sum(p is not None for p in self.ports)} port end(s)"
        return f"<Link {self.name!r}: {other}>"


_links: dict[str, Link] = {}  # port-to-port links, by name
# Device links, by name: each port that opens sim://NAME?device=... gets a
# link and a device of its own, so two runtimes (or a test's two executors)
# may run the same app side by side; the newest is last.
_device_links: dict[str, list[Link]] = {}
_registry_lock = threading.Lock()
# Port ends whose Serial object was garbage-collected while open. A finalizer
# may run inside any allocation, including one made while this thread holds
# _registry_lock, so it takes no lock: it queues the end here (a deque append
# is atomic) and the next registry operation, holding the lock, releases it.
_closing: deque["PortEnd"] = deque()


def _release_closing() -> None:
    """Release the ends finalizers queued; the caller holds _registry_lock."""
    while _closing:
        _closing.popleft()._release()


def open_port_end(name: str) -> "PortEnd":
    """Become one end of the port-to-port link ``name`` (created on first use)."""
    with _registry_lock:
        _release_closing()
        if _device_links.get(name):
            device = _device_links[name][-1].device
            raise SerialException(f"link {name} already has two ends (a port and a {device.name} device)")
        link = _links.get(name)
        if link is None:
            link = _links[name] = Link(name)
        if None not in link.ports:
            raise SerialException(f"link {name} already has two ends")
        index = link.ports.index(None)
        end = PortEnd(link, index)
        with link.lock:
            link.wires[1 - index].clear()  # what was sent while nobody listened is lost
            link.ports[index] = end
        return end


def open_device_end(name: str, device: "SimDevice") -> "PortEnd":
    """A new link ``name`` between the calling port (end 0) and ``device`` (end 1)."""
    with _registry_lock:
        _release_closing()
        if name in _links:
            raise SerialException(f"link {name} is in use between two ports; a device link needs another name")
        link = Link(name)
        _device_links.setdefault(name, []).append(link)
        end = PortEnd(link, 0)
        link.ports[0] = end
        link.device = device
    try:
        device.attach(DeviceEnd(link, end))
    except BaseException:
        end.close()
        raise
    return end


def link_names() -> list[str]:
    """Names of the links open now (for diagnostics and tests)."""
    with _registry_lock:
        _release_closing()
        return sorted(set(_links) | set(_device_links))


def device_links(name: str) -> list[Link]:
    """The open device links named ``name``, oldest first."""
    with _registry_lock:
        _release_closing()
        return list(_device_links.get(name, ()))


def find_device(name: str, cls: type, kind: str):
    """The device of class ``cls`` at the far end of the open ``sim://``
    link ``name`` (the newest, when several ports have opened one of that
    name); LookupError when there is none."""
    links = device_links(name)
    device = links[-1].device if links else None
    if not isinstance(device, cls):
        raise LookupError(f"no open sim:// link {name!r} to a {kind} device")
    return device


class PortEnd:
    """A port's end of a link; every method takes the port's clock reading."""

    def __init__(self, link: Link, index: int) -> None:
        self.link = link
        self.index = index
        self.char_ns = char_time_ns(9600)
        self._table: bytes | None = None
        self._out = link.wires[index]
        self._in = link.wires[1 - index]

    def configure(self, baudrate: int, bytesize: int, parity: str, stopbits: float, unlimited: bool) -> None:
        char_ns = char_time_ns(baudrate, bytesize, parity, stopbits)
        self.char_ns = 0 if unlimited else char_ns
        self._table = mask_table(bytesize)
        self.link.quiet_until = 0  # the device's silence interval follows the character time

    def mask(self, data: bytes) -> bytes:
        return data if self._table is None else data.translate(self._table)

    def write(self, data: bytes, now: int) -> None:
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            self._out.send(self.mask(data), now, self.char_ns)
            self.link.pump(now)

    def read(self, size: int, now: int) -> bytes:
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            return self._in.take(size, now)

    def read_timed(self, now: int) -> tuple[bytes, list[int]]:
        """Everything arrived by ``now``, with each byte's arrival time."""
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            return self._in.take_timed(now)

    def set_rts(self, on: bool, now: int) -> None:
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            if self.link.rts[self.index][0] != on:
                self.link.rts[self.index] = (on, now)

    def cts(self, now: int) -> tuple[bool, int]:
        """CTS at ``now`` and when it last changed: the other end's RTS
        (a null-modem cable), or what the device says."""
        with self.link.lock:
            self.link.pump(now)
            device = self.link.device
            if device is not None:
                return device.cts(now)
            return self.link.rts[1 - self.index]

    def available(self, now: int) -> int:
        link = self.link
        with link.lock:
            link.pump(now)
            n = self._in.available(now)
            if not n and self.index == 0:
                link.quiet_until = link.quiet_from(now)
            return n

    def read_arrived(self, now: int) -> bytes:
        """What ``available`` then ``read`` of that many bytes return, in one
        call: the pump, the take of every arrived byte, and (when there were
        bytes and the device's poll is due) the pump ``read`` would run. While
        the link is quiet (see Link.quiet_until) none of it would do
        anything, so nothing is done; nor is a pump that would hand the device
        nothing and find its poll not due (SimDevice.next_due), e.g. the
        Modbus slave's while its reply arrives."""
        link = self.link
        if now < link.quiet_until:
            return b""
        with link.lock:
            device = link.device
            if device is None:  # a port-to-port link: no pump, never quiet
                return self._in.take_arrived(now)
            due = device.next_due(now)
            if link.wires[0].chunks or (due is not None and due <= now):
                link.pump(now)
                due = device.next_due(now)  # the take below changes nothing the device sees
            data = self._in.take_arrived(now)
            if not data:
                if self.index == 0:
                    link.quiet_until = link.quiet_from(now)
                return b""
            link.quiet_until = 0
            if due is not None and due <= now:
                # a device that cannot tell, or is due: polled again as read()
                # would (read() pumps after the count and before the take;
                # what the device sends then queues behind the bytes counted,
                # so taking them first changes nothing)
                link.pump(now)
            return data

    def pending(self, now: int) -> int:
        with self.link.lock:
            self.link.pump(now)
            return self._out.pending(now)

    def reset_input(self, now: int) -> None:
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            self._in.discard_arrived(now)

    def reset_output(self, now: int) -> None:
        with self.link.lock:
            self.link.quiet_until = 0
            self.link.pump(now)
            self._out.abort(now)

    def close(self) -> None:
        with _registry_lock:
            _release_closing()
            self._release()

    def close_later(self) -> None:
        """Close from a finalizer: no lock is taken here (see _closing)."""
        _closing.append(self)

    def _release(self) -> None:
        """Leave the link; the caller holds _registry_lock."""
        link = self.link
        with link.lock:
            if link.ports[self.index] is self:
                link.ports[self.index] = None
        if link.ports == [None, None]:
            if _links.get(link.name) is link:
                del _links[link.name]
            same = _device_links.get(link.name, [])
            if link in same:
                same.remove(link)
                if not same:
                    del _device_links[link.name]


class DeviceEnd:
    """What a simulated device holds: its way to send toward the port."""

    def __init__(self, link: Link, port: PortEnd) -> None:
        self._link = link
        self._port = port

    @property
    def char_ns(self) -> int:
        """Character time in ns, from the settings of the port the device is attached to."""
        return self._port.char_ns

    def rts(self) -> tuple[bool, int]:
        """The port's RTS and when it last changed."""
        return self._link.rts[self._port.index]

    def send(self, data: bytes, at_ns: int) -> None:
        """Transmit ``data`` toward the port, timed like a port write at ``at_ns``
        (queued behind what the device sent before)."""
        with self._link.lock:
            self._link.quiet_until = 0
            self._link.wires[1].send(self._port.mask(bytes(data)), at_ns, self._port.char_ns)


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
        # that lock is held (a deadlock once seen), so it releases lock-free.
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
