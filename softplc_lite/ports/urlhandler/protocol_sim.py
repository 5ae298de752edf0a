# URL format:    sim://NAME[?device=KIND[&KEY=VALUE...]][&rate=unlimited]
# NAME: letters, digits, "_", "-", "."
# options:
# - "device=KIND" the other end is a new simulated device of that kind
#   (simdevices.DEVICES, e.g. "echo"); the options this handler does not
#   know are the device's (e.g. "delay_ms=5" for echo)
# - "rate=unlimited" what this port (and its device) sends takes no time
#   ("rate=wire", the default, times it from the port's settings)
"""``sim://``: one end of a simulated serial link with wire timing.

Two ports opening ``sim://NAME`` are the two ends of link NAME; with
``device=KIND`` the other end is a new simulated device. The timing model and
the links in simlink.py, the devices in simdevices.py, the port's clock in
clocked.py; the user's page is docs/simulated-wire.md.
"""

from __future__ import annotations

import re
from urllib.parse import parse_qsl

from serial.serialutil import PortNotOpenError, SerialException

from .. import simdevices, simlink
from ..clocked import ClockedSerial

FORM = "sim://NAME[?device=KIND[&KEY=VALUE...]][&rate=unlimited]"
_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")
RATES = ("wire", "unlimited")


def parse_url(url: str) -> tuple[str, str | None, dict[str, str], bool]:
    """``(name, device kind or None, device options, unlimited)``; ValueError when bad."""
    scheme, sep, rest = url.partition("://")
    if not sep or scheme.lower() != "sim":
        raise ValueError(f"not starting with sim:// ({url!r})")
    name, _, query = rest.partition("?")
    if not _NAME.match(name):
        raise ValueError(f"bad link name {name!r}")
    options: dict[str, str] = {}
    if query:
        for key, value in parse_qsl(query, keep_blank_values=True, strict_parsing=True):
            if key in options:
                raise ValueError(f"option {key!r} given twice")
            options[key] = value
    rate = options.pop("rate", "wire")
    if rate not in RATES:
        raise ValueError(f"rate must be unlimited or wire, not {rate!r}")
    kind = options.pop("device", None)
    if kind is None and options:
        raise ValueError(f"unknown option {next(iter(options))!r} (a device's options need device=KIND)")
    if kind == "":
        raise ValueError("device= needs a device kind")
    return name, kind, options, rate == "unlimited"


def url_problem(url: str) -> str | None:
    """Why opening ``url`` (a sim:// URL) would fail, without opening it: a
    bad form, an unknown device kind or a bad device option; None when it
    would open. ``softplc check`` asks, so that it refuses what run would."""
    try:
        _, kind, options, _ = parse_url(url)
        if kind is not None:
            simdevices.create_device(kind, options)
    except (ValueError, SerialException) as e:
        return f'{e} (expected "{FORM}")'
    return None


class Serial(ClockedSerial):
    """A port on a simulated link (see the module docstring)."""

    def __init__(self, *args, **kwargs) -> None:
        self._end: simlink.PortEnd | None = None
        self._unlimited = False
        self._device_kind: str | None = None
        super().__init__(*args, **kwargs)

    def _open_port(self) -> None:
        try:
            name, kind, options, self._unlimited = parse_url(self._port)
            device = simdevices.create_device(kind, options) if kind is not None else None
        except ValueError as e:
            raise SerialException(f'expected a string in the form "{FORM}": {e}') from None
        self._device_kind = kind
        self._end = simlink.open_device_end(name, device) if device else simlink.open_port_end(name)

    def _close_port(self) -> None:
        if self._end is not None:
            self._end.close()
            self._end = None

    def _close_from_finalizer(self) -> None:
        if self._end is not None:
            self._end.close_later()  # released by the next registry operation
            self._end = None

    def _configure(self) -> None:
        self._end.set_rts(bool(self._rts_state), self._clock())  # pyserial raises RTS on open
        self._end.configure(self._baudrate, self._bytesize, self._parity, self._stopbits, self._unlimited)

    def _take(self, size: int, now: int) -> bytes:
        end = self._end
        return end.read(size, now) if end is not None else b""

    def _take_timed(self, now: int) -> tuple[bytes, list[int]]:
        end = self._end
        return end.read_timed(now) if end is not None else (b"", [])

    def _set_rts(self, on: bool, now: int) -> None:
        self._end.set_rts(on, now)

    def _cts(self, now: int) -> tuple[bool, int]:
        return self._end.cts(now)

    def read_now(self) -> bytes:
        return self.read_at(self._clock())

    def read_at(self, now: int) -> bytes:
        """``read_now`` at ``now``, the clock read by the caller (a driver
        polling at every scan reads it once for the quiet test and the read)."""
        if not self.is_open:
            raise PortNotOpenError()
        return self._end.read_arrived(now)

    @property
    def sim_link(self) -> simlink.Link | None:
        """The link this port is an end of (its ``quiet_until`` says until when
        a read finds nothing); None when closed."""
        return self._end.link if self._end is not None else None

    def _available(self, now: int) -> int:
        return self._end.available(now)

    def _write(self, data: bytes, now: int) -> None:
        self._end.write(data, now)

    def _pending(self, now: int) -> int:
        return self._end.pending(now)

    def _reset_input(self, now: int) -> None:
        self._end.reset_input(now)

    def _reset_output(self, now: int) -> None:
        self._end.reset_output(now)

    def __repr__(self) -> str:
        if not self.is_open or self._end is None:
            return f"<sim port {self._port!r} closed>"
        other = f"{self._device_kind} device" if self._device_kind else f"end {1 - self._end.index}"
        rate = ", unlimited rate" if self._unlimited else ""
        return (f"<sim port {self._port!r} {self._settings()}{rate}: end {self._end.index} "
                f"of link {self._end.link.name!r} to {other}>")
