"""The simulated line: links between two ends, and the registry that finds them by name.

Links: ``open_port_end(name)`` makes the calling port one end of the link
``name``; the second call makes the other end, a third raises
``SerialException``. ``open_device_end(name, device)`` makes a link whose
other end is a simulated device (simdevices.py). A link is forgotten when
its ports are closed, so its name can be reused. Each direction of a link
is a ``wire.Wire``, which times its bytes.

The registry is one per process (``REGISTRY``, a ``LinkRegistry``): a
``sim://NAME`` URL is all pyserial hands the URL handler, and two ports of
one process (two runtimes side by side, a test's two executors) meet by that
name. Its maps are changed only under its lock, so ports open and close
from any thread; a link's own state is guarded by the link's lock (taken
after the registry's, never before it). A ``LinkRegistry`` of one's own
keeps its links apart from the process's (``open_port_end`` and
``open_device_end`` are its methods too).

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
"""

from __future__ import annotations

import threading
from collections import deque
from typing import TYPE_CHECKING

from serial.serialutil import SerialException

from .wire import Wire, char_time_ns, mask_table

if TYPE_CHECKING:
    from .simdevices import SimDevice

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


class LinkRegistry:
    """The open links by name: port-to-port links (two port ends) and
    device links (one port end and its own device)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self._links: dict[str, Link] = {}  # port-to-port links, by name
        # Device links, by name: each port that opens sim://NAME?device=...
        # gets a link and a device of its own, so two runtimes (or a test's
        # two executors) may run the same app side by side; the newest is last.
        self._device_links: dict[str, list[Link]] = {}
        # Port ends whose Serial object was garbage-collected while open. A
        # finalizer may run inside any allocation, including one made while
        # this thread holds the lock, so it takes no lock: it queues the end
        # here (a deque append is atomic) and the next registry operation,
        # holding the lock, releases it.
        self._closing: deque[PortEnd] = deque()

    def _release_closing(self) -> None:
        """Release the ends finalizers queued; the caller holds the lock."""
        while self._closing:
            self._release(self._closing.popleft())

    def open_port_end(self, name: str) -> "PortEnd":
        """Become one end of the port-to-port link ``name`` (created on first use)."""
        with self.lock:
            self._release_closing()
            if self._device_links.get(name):
                device = self._device_links[name][-1].device
                raise SerialException(f"link {name} already has two ends (a port and a {device.name} device)")
            link = self._links.get(name)
            if link is None:
                link = self._links[name] = Link(name)
            if None not in link.ports:
                raise SerialException(f"link {name} already has two ends")
            index = link.ports.index(None)
            end = PortEnd(link, index, self)
            with link.lock:
                link.wires[1 - index].clear()  # what was sent while nobody listened is lost
                link.ports[index] = end
            return end

    def open_device_end(self, name: str, device: "SimDevice") -> "PortEnd":
        """A new link ``name`` between the calling port (end 0) and ``device`` (end 1)."""
        with self.lock:
            self._release_closing()
            if name in self._links:
                raise SerialException(f"link {name} is in use between two ports; a device link needs another name")
            link = Link(name)
            self._device_links.setdefault(name, []).append(link)
            end = PortEnd(link, 0, self)
            link.ports[0] = end
            link.device = device
        try:
            device.attach(DeviceEnd(link, end))
        except BaseException:
            end.close()
            raise
        return end

    def link_names(self) -> list[str]:
        """Names of the links open now (for diagnostics and tests)."""
        with self.lock:
            self._release_closing()
            return sorted(set(self._links) | set(self._device_links))

    def device_links(self, name: str) -> list[Link]:
        """The open device links named ``name``, oldest first."""
        with self.lock:
            self._release_closing()
            return list(self._device_links.get(name, ()))

    def close(self, end: "PortEnd") -> None:
        with self.lock:
            self._release_closing()
            self._release(end)

    def close_later(self, end: "PortEnd") -> None:
        """Close from a finalizer: no lock is taken here (see _closing)."""
        self._closing.append(end)

    def _release(self, end: "PortEnd") -> None:
        """``end`` leaves its link; the caller holds the lock."""
        link = end.link
        with link.lock:
            if link.ports[end.index] is end:
                link.ports[end.index] = None
        if link.ports == [None, None]:
            if self._links.get(link.name) is link:
                del self._links[link.name]
            same = self._device_links.get(link.name, [])
            if link in same:
                same.remove(link)
                if not same:
                    del self._device_links[link.name]


REGISTRY = LinkRegistry()  # the process's links (see the module docstring)


def open_port_end(name: str) -> "PortEnd":
    """Become one end of the process's port-to-port link ``name``."""
    return REGISTRY.open_port_end(name)


def open_device_end(name: str, device: "SimDevice") -> "PortEnd":
    """A new link ``name`` of the process between the calling port and ``device``."""
    return REGISTRY.open_device_end(name, device)


def link_names() -> list[str]:
    """Names of the process's links open now (for diagnostics and tests)."""
    return REGISTRY.link_names()


def device_links(name: str) -> list[Link]:
    """The process's open device links named ``name``, oldest first."""
    return REGISTRY.device_links(name)


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

    def __init__(self, link: Link, index: int, registry: LinkRegistry) -> None:
        self.link = link
        self.index = index
        self.registry = registry
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
        self.registry.close(self)

    def close_later(self) -> None:
        """Close from a finalizer: no lock is taken (see LinkRegistry._closing)."""
        self.registry.close_later(self)


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
