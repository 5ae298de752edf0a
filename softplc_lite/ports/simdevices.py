"""Simulated devices: what sits at the far end of ``sim://NAME?device=KIND``.

A device kind is registered with ``register_device(kind, factory)``; the
factory gets the URL's remaining query options as ``dict[str, str]`` and
returns a ``SimDevice``, or raises ``ValueError`` for an unknown or bad
option (``check_options`` helps). The ``sim://`` handler turns that into a
``SerialException``. Register a kind at import of the module that defines
it, before a port opens a URL naming it. The built-in kinds that live in
other modules (``BUILTIN_DEVICES``: kind -> "module:factory", e.g. ``modbus``
in modbus_slave.py) are imported and registered on first use. A kind whose
name starts with ``_`` is private to the code that registers it (the testing
API's devices given as objects): it is not listed among the known kinds.

The device API (all times are int ns on the clock of the port the device
is attached to):

- ``attach(end)``: called once, before any other call. ``end.send(data,
  at_ns)`` transmits toward the port, timed like a port write at ``at_ns``
  (behind whatever the device sent before); ``end.char_ns`` is the character
  time of the port's current settings (0 at ``rate=unlimited``).
- ``receive(data, times_ns)``: bytes that have arrived from the port, with
  each byte's arrival time (non-decreasing). One call may hold several
  bursts: compare the times to find gaps.
- ``cts(now_ns)``: the port's CTS line and the time it last changed (by
  default the port's RTS, as ``end.rts()`` gives it: always ready).
- ``poll(now_ns)``: called every time the port is used (read, in_waiting,
  write, out_waiting), after ``receive`` has been given everything that
  arrived by ``now_ns``. Decide time-based things here (a frame ends after
  silence) and answer with ``end.send(reply, at_ns)``: an ``at_ns`` in the
  past of ``now_ns`` is honoured, so the reply is timed from the moment the
  device would really have answered, not from when the port looked.

The ``echo`` device sends every received burst back. A burst is a run of
bytes each arriving no later than 3.5 character times after the one before;
it is complete once the port's clock reaches (last byte's arrival + 3.5
character times), and the echo starts at (last byte's arrival +
max(delay_ms, 3.5 character times)). Option: ``delay_ms`` (default 0).
"""

from __future__ import annotations

import importlib
import math
import threading
from typing import TYPE_CHECKING, Callable, Iterable

if TYPE_CHECKING:
    from .simlink import DeviceEnd


class SimDevice:
    """Base class of simulated devices; the default methods do nothing."""

    name = "device"

    def attach(self, end: "DeviceEnd") -> None:
        self.end = end

    def receive(self, data: bytes, times_ns: list[int]) -> None:
        pass

    def poll(self, now_ns: int) -> None:
        pass

    def next_due(self, now_ns: int) -> int | None:
        """The earliest time at which ``poll`` could do anything, given
        nothing new is received before it (None: never). The link skips its
        per-read work until then; a device that cannot tell returns
        ``now_ns`` (polled at every read, the default)."""
        return now_ns

    def cts(self, now_ns: int) -> tuple[bool, int]:
        """The port's CTS and when it last changed: by default it follows
        the port's RTS at once (a device that is always ready)."""
        return self.end.rts()


DeviceFactory = Callable[[dict[str, str]], SimDevice]
# The device kinds of the process (one, as the sim:// links are: see
# simlink.py), changed only under _kinds_lock: ports open from any thread.
DEVICES: dict[str, DeviceFactory] = {}
_kinds_lock = threading.Lock()
# Built-in kinds defined in other modules: imported when first created.
BUILTIN_DEVICES: dict[str, str] = {"modbus": "softplc_lite.ports.modbus_slave:create",
                                   "modbus_master": "softplc_lite.ports.modbus_master:create",
                                   "scripted": "softplc_lite.ports.scripted:create"}


def register_device(kind: str, factory: DeviceFactory) -> None:
    """Make ``sim://NAME?device=kind`` create its device with ``factory(options)``.
    Registering the same factory again is harmless; another one for a taken
    kind is a ValueError."""
    if not kind or not kind.replace("_", "").isalnum():
        raise ValueError(f"device kind {kind!r} must be letters, digits and _")
    with _kinds_lock:
        known = DEVICES.get(kind)
        if known is not None and known is not factory:
            raise ValueError(f"device kind {kind!r} is already registered")
        DEVICES[kind] = factory


def create_device(kind: str, options: dict[str, str]) -> SimDevice:
    """A new device of ``kind``; ValueError for an unknown kind or a bad option."""
    factory = DEVICES.get(kind)
    if factory is None and kind in BUILTIN_DEVICES:
        module, _, name = BUILTIN_DEVICES[kind].partition(":")
        factory = getattr(importlib.import_module(module), name)
        register_device(kind, factory)
    if factory is None:
        known = ", ".join(sorted(k for k in {*DEVICES, *BUILTIN_DEVICES} if not k.startswith("_")))
        raise ValueError(f"unknown device kind {kind!r} (known: {known})")
    return factory(dict(options))


def check_options(kind: str, options: dict[str, str], known: Iterable[str]) -> None:
    """ValueError naming the first option not in ``known``."""
    known = list(known)
    for key in options:
        if key not in known:
            allowed = ", ".join(known) if known else "none"
            raise ValueError(f"{kind} device: unknown option {key!r} (known: {allowed})")


def float_option(kind: str, options: dict[str, str], key: str, default: float, minimum: float = 0.0) -> float:
    """``options[key]`` as a finite float >= ``minimum`` (``default`` when absent)."""
    if key not in options:
        return default
    try:
        value = float(options[key])
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < minimum:
        raise ValueError(f"{kind} device: {key} must be a number >= {minimum:g}, not {options[key]!r}")
    return value


def silence_ns(char_ns: int) -> int:
    """3.5 character times in ns, rounded half up (911460 at 38400 8N1)."""
    return (7 * char_ns + 1) // 2


class EchoDevice(SimDevice):
    """Sends each received burst back (see the module docstring for the timing)."""

    name = "echo"

    def __init__(self, delay_ms: float = 0.0) -> None:
        self.delay_ns = round(delay_ms * 1_000_000)
        self._burst = bytearray()
        self._last = 0

    def receive(self, data: bytes, times_ns: list[int]) -> None:
        gap = silence_ns(self.end.char_ns)
        start = 0
        previous = self._last if self._burst else None
        for i, t in enumerate(times_ns):
            if previous is not None and t - previous > gap:
                self._burst += data[start:i]
                self._last = previous
                self._flush(gap)
                start = i
            previous = t
        self._burst += data[start:]
        self._last = times_ns[-1]

    def poll(self, now_ns: int) -> None:
        gap = silence_ns(self.end.char_ns)
        if self._burst and now_ns >= self._last + gap:
            self._flush(gap)

    def _flush(self, gap: int) -> None:
        self.end.send(bytes(self._burst), self._last + max(self.delay_ns, gap))
        self._burst.clear()


def _echo(options: dict[str, str]) -> EchoDevice:
    check_options("echo", options, ["delay_ms"])
    return EchoDevice(float_option("echo", options, "delay_ms", 0.0))


register_device("echo", _echo)
