"""A serial port as every module drives it: opened through pyserial's
``serial_for_url``, read and written without blocking the scan, taken down
when its device goes away and retried until it comes back.

``SerialPort`` moves bytes; what a module makes of them is the module's own
(COMGENIUS keeps character buffers, MODBMAST frames Modbus requests). A
port:

- opens ``url`` (a device path, a pyserial URL, ``sim://`` or ``replay://``)
  with its ``LineSettings`` applied; the transport for the URL's kind
  (transports/) makes reads and writes non-blocking;
- is *down* when it cannot be opened or when its device fails while running
  (``error`` says why); ``retry()`` opens it again every ``retry_ms`` of
  wall-clock time;
- keeps its last frames (``history``, for the watch view), byte counts, and
  hands every frame to ``record`` when a run records a trace;
- reads with arrival times (``read_timed``) where the port knows them (the
  simulated wire), and drives RTS / reads CTS where the port has modem lines.

Ports are named for traces and logs by ``label``: COMGENIUS's logical port
numbers ("0"), MODBMAST's "MODBMAST:1".
"""

from __future__ import annotations

import errno
import re
import time
from collections import deque
from dataclasses import dataclass
from typing import Callable

import serial

from ..errors import os_error_words
from .transports import Transport, transport_for
from .wire import char_time_ns

HISTORY = 16  # recent frames kept per port (for the watch view and debugging)

PARITIES = {"N": serial.PARITY_NONE, "E": serial.PARITY_EVEN, "O": serial.PARITY_ODD, "M": serial.PARITY_MARK}

# Errors that mean "this port does not work (any more)". termios.error is
# not a SerialException (testing notes: a pty refusing 7E1), so list it.
try:
    import termios

    PORT_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, OSError, ValueError, termios.error)
except ImportError:  # pragma: no cover - Windows
    PORT_ERRORS = (serial.SerialException, OSError, ValueError)

Log = Callable[[int, str], None]
Clock = Callable[[], int]  # int ns


@dataclass(frozen=True)
class LineSettings:
    """Baud rate and character framing of a serial line."""

    baud: int
    data_bits: int = 8
    parity: str = "N"  # N, E, O or M (mark)
    stop_bits: int = 1

    @property
    def char_ns(self) -> int:
        """One character on the wire, in ns (start bit, data, parity, stop bits)."""
        return char_time_ns(self.baud, self.data_bits, self.parity, self.stop_bits)

    def __str__(self) -> str:
        return f"{self.baud} {self.data_bits}{self.parity}{self.stop_bits}"


def hexdump(data: bytes, limit: int = 64) -> str:
    text = data[:limit].hex(" ").upper()
    return text + (f" ... ({len(data)} bytes)" if len(data) > limit else "")


class SerialPort:
    """One open (or down) port: its pyserial object, transport and traffic."""

    def __init__(self, label: str, url: str, settings: LineSettings, log: Log, now_ns: Clock,
                 retry_ms: int = 1000, log_frames: bool = False) -> None:
        self.label = label
        self.url = url
        self.settings = settings
        self.log = log
        self.log_frames = log_frames  # DEBUG=2: every frame in hex (formatted only then)
        self.now_ns = now_ns
        self.retry_s = retry_ms / 1000
        self.serial = None
        self.transport: Transport | None = None
        self.error: str | None = "not opened"  # why the port is down; None when up
        self.next_try = 0.0
        self.rx_bytes = self.tx_bytes = 0  # totals since start
        self.history: deque[tuple[float, str, bytes]] = deque(maxlen=HISTORY)
        self.record: Callable[..., None] | None = None  # record(label, direction, data, at_ns=None)
        self.clocked = False  # a simulated port on the clock it was given (exact arrival times)
        # A simulated link's quiet time (simlink.Link.quiet_until): a driver
        # polling at every scan reads nothing before it (see read_at).
        self.quiet = None

    def __repr__(self) -> str:
        state = "up" if self.up else f"down ({self.error})"
        return f"<{type(self).__name__} {self.label} {self.url} {state}>"

    @property
    def up(self) -> bool:
        return self.error is None

    # -- open and close ------------------------------------------------------------------
    def open(self) -> None:
        """Open the device; on failure the port is down and the reason
        raised as a SerialException."""
        c = self.settings
        s = None
        try:
            s = serial.serial_for_url(self.url, do_not_open=True)
            s.baudrate = c.baud
            s.bytesize = c.data_bits
            s.parity = PARITIES[c.parity]
            s.stopbits = c.stop_bits
            s.timeout = 0
            transport = transport_for(self.url, s)
            s.write_timeout = transport.write_timeout
            s.open()
            transport.set_clock(self.now_ns)
        except PORT_ERRORS as e:
            if s is not None:
                quiet_close(s)
            self._down(reason(e))
            raise serial.SerialException(self.error) from None
        self.serial, self.transport = s, transport
        self.clocked = transport.kind == "sim"
        self.quiet = transport.quiet_link()
        self.error = None
        self.opened()
        self.log(1, f"port {self.label}: opened {self.url} ({c})")

    def opened(self) -> None:
        """Subclasses reset their decoding state here."""

    def _down(self, why: str) -> None:
        if self.serial is not None:
            quiet_close(self.serial)
        self.serial = self.transport = self.quiet = None
        was_up = self.error is None
        self.error = why
        self.next_try = time.monotonic() + self.retry_s
        if was_up:
            self.log(1, f"port {self.label}: down: {why}; retrying every {self.retry_s * 1000:g} ms")

    def retry(self) -> bool:
        """Try a down port again once its retry time has come; True when it is up."""
        if self.up:
            return True
        if self.error == "closed" or time.monotonic() < self.next_try:
            return False
        try:
            self.open()
        except serial.SerialException:
            self.next_try = time.monotonic() + self.retry_s
            return False
        self.log(1, f"port {self.label}: back up")
        return True

    def replay_report(self) -> str | None:
        """What a ``replay://`` port says of the run (did the program's output
        match the recording); None for any other port."""
        s = self.serial
        return s.report() if s is not None and hasattr(s, "mismatches") else None

    def close(self) -> None:
        if self.serial is not None:
            quiet_close(self.serial)
        self.serial = self.transport = self.quiet = None
        self.error = "closed"

    # -- bytes ---------------------------------------------------------------------------
    def read(self) -> bytes:
        """What has arrived (b"" when nothing, or when the port just went down)."""
        if self.transport is None:
            return b""
        try:
            data = self.transport.read()
        except PORT_ERRORS as e:
            self._down(reason(e))
            return b""
        if data:
            self.rx_bytes += len(data)
            self._traffic("RX", data)
        return data

    def read_at(self, now: int) -> bytes:
        """``read()`` on a clocked port, given its clock's reading ``now``
        (ns): a driver polling at every scan reads the clock once, tests
        ``quiet`` with it and reads. Elsewhere, ``read()``."""
        transport = self.transport
        if transport is None:
            return b""
        if not self.clocked:
            return self.read()
        try:
            data = transport.read_at(now)
        except PORT_ERRORS as e:
            self._down(reason(e))
            return b""
        if data:  # what read() does, with _traffic inline and stamped now (the clock's reading)
            self.rx_bytes += len(data)
            self.history.append((now / 1e6, "RX", data))
            if self.record is not None:
                self.record(self.label, "RX", data, now)
            if self.log_frames:
                self.log(2, f"port {self.label} RX {len(data):4d} bytes: {hexdump(data)}")
        return data

    def read_timed(self) -> tuple[bytes, list[int] | None]:
        """What has arrived and, on a clocked simulated port, each byte's
        arrival time in ns (None elsewhere: the bytes arrived by now)."""
        if not self.clocked or self.transport is None:
            return self.read(), None
        try:
            data, times = self.serial.read_timed()
        except PORT_ERRORS as e:
            self._down(reason(e))
            return b"", None
        if data:
            self.rx_bytes += len(data)
            self._traffic("RX", data, times[-1])  # when it arrived, not when the driver looked
        return data, times

    def write(self, data: bytes) -> int:
        """Hand ``data`` to the port; returns how many bytes it took now."""
        if self.transport is None or not data:
            return 0
        try:
            n = self.transport.write(data)
        except serial.SerialTimeoutException:
            n = 0
        except PORT_ERRORS as e:
            self._down(reason(e))
            return 0
        if n:
            self.tx_bytes += n
            self._traffic("TX", data[:n] if n < len(data) else data)
        return n

    def out_waiting(self) -> int:
        """Bytes handed to the port that have not left it yet (0 where the
        port cannot tell)."""
        if self.serial is None:
            return 0
        try:
            return self.serial.out_waiting
        except (AttributeError, NotImplementedError, *PORT_ERRORS):
            return 0

    def reset_input(self) -> None:
        if self.serial is not None:
            try:
                self.serial.reset_input_buffer()
            except PORT_ERRORS:
                pass

    def reset_output(self) -> None:
        if self.serial is not None:
            try:
                self.serial.reset_output_buffer()
            except PORT_ERRORS:
                pass

    # -- modem lines -----------------------------------------------------------------------
    def set_rts(self, on: bool) -> bool:
        """Drive RTS; False when the port has no modem lines (a pty)."""
        if self.serial is None:
            return False
        try:
            self.serial.rts = on
            return True
        except PORT_ERRORS:
            return False

    def cts(self) -> tuple[bool, int | None]:
        """CTS now and, on a clocked simulated port, when it last changed
        (None elsewhere). (False, None) when it cannot be read."""
        if self.serial is None:
            return False, None
        try:
            if self.clocked:
                return self.serial.cts_state()
            return bool(self.serial.cts), None
        except PORT_ERRORS:
            return False, None

    def _traffic(self, direction: str, data: bytes, at_ns: int | None = None) -> None:
        t_ms = (self.now_ns() if at_ns is None else at_ns) / 1e6
        self.history.append((t_ms, direction, data))
        if self.record is not None:
            self.record(self.label, direction, data, at_ns)
        if self.log_frames:
            self.log(2, f"port {self.label} {direction} {len(data):4d} bytes: {hexdump(data)}")


def quiet_close(s) -> None:
    try:
        s.close()
    except Exception:  # closing a port that is already gone must not fail the run
        pass


# errno -> why a port is down, in words (a device, not a file: ENOENT is "no such device").
_DEVICE_WORDS = {
    errno.ENOENT: "no such device", errno.ENXIO: "no such device", errno.ENODEV: "no such device",
    errno.EACCES: "permission denied", errno.EPERM: "permission denied",
    errno.EISDIR: "it is a directory, not a device", errno.ENOTTY: "not a serial device",
    errno.EBUSY: "the device is busy", errno.EIO: "input/output error on the device",
    errno.ECONNREFUSED: "connection refused", errno.ETIMEDOUT: "timed out", errno.EHOSTUNREACH: "host unreachable",
    errno.ENETUNREACH: "network unreachable", errno.ECONNRESET: "connection reset",
}
# pyserial puts the OS's error inside its own text: "could not open port X: [Errno 2] No such file ...",
# "Could not configure port: (25, 'Inappropriate ioctl for device')".
_ERRNO_IN_TEXT = re.compile(r"\[Errno (\d+)\]|\((\d+), '")


def reason(e: BaseException) -> str:
    """Why a port is down, in words: "no such device", "permission denied";
    never Python's "[Errno 2] ..." text or an exception's class name."""
    text = str(e)
    number = e.errno if isinstance(e, OSError) and isinstance(e.errno, int) else None
    if number is None and isinstance(e.args, tuple) and len(e.args) == 2 and isinstance(e.args[0], int):
        number = e.args[0]  # termios.error: (errno, message)
    if number is None:
        found = _ERRNO_IN_TEXT.search(text)
        if found:
            number = int(found.group(1) or found.group(2))
    if number is not None:
        if number in _DEVICE_WORDS:
            return _DEVICE_WORDS[number]
        return os_error_words(OSError(number, ""))  # the common words, never the C library's text
    return text or "the device refused it"
