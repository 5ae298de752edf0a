"""COMGENIUS ports: one per ``[PORTS]`` line, each with its buffers.

A Port owns the pyserial port of its line (opened with
``serial.serial_for_url``), a receive buffer of 16-bit characters (what
COMSCAN matches; its size is COMRCVSTS's PRE) and a transmit buffer of
bytes (what COMPRINT fills). The driver moves bytes at the engine's input
and output points, never blocking the scan:

- input: read what has arrived, decode it with the port's encoding and
  append it to the receive buffer; characters that do not fit are dropped
  and the overflow flag (COMRCVSTS OV) is set;
- output: hand as much of the transmit buffer to the port as it takes now.

A port that cannot be opened, or whose device goes away while running (a
USB adapter pulled, a pty whose other side closed), is *down*: the
instructions on it set ER, the engine keeps scanning, and the port is
tried again every ``RETRY_MS`` of wall-clock time until it comes back.

The physical field of a ``[PORTS]`` line (see :func:`physical_url`):
``COMn`` (a bare number ``n`` is ``COM(n+1)``) maps to a device through
``[DRIVER] COMn=...`` or the platform default; anything else is a device
path or a pyserial URL. ``softplc run --port N=DEVICE`` replaces it for
logical port N.
"""

from __future__ import annotations

import sys
import time
from collections import deque
from typing import Callable

import serial

from ..errors import ModuleError
from .config import COM_NAME, ComGeniusConfig, PortConfig
from .encodings import encoding
from .transports import Transport, transport_for

RX_BUFFER_CHARS = 4096  # characters; COMRCVSTS sets PRE to this
TX_BUFFER_BYTES = 4096  # bytes; a COMPRINT waits until its whole output fits
HISTORY = 16  # recent frames kept per port (for the watch view and debugging)

_PARITY = {"N": serial.PARITY_NONE, "E": serial.PARITY_EVEN, "O": serial.PARITY_ODD}

# Errors that mean "this port does not work (any more)". termios.error is
# not a SerialException (testing notes: a pty refusing 7E1), so list it.
try:
    import termios

    PORT_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, OSError, ValueError, termios.error)
except ImportError:  # pragma: no cover - Windows
    PORT_ERRORS = (serial.SerialException, OSError, ValueError)


def default_com_device(n: int, platform: str = sys.platform) -> str:
    """The device of COMn when COMGENIUS.LST does not say: ``COMn`` on
    Windows, the n-th on-board UART ``/dev/ttyS{n-1}`` elsewhere."""
    return f"COM{n}" if platform.startswith("win") else f"/dev/ttyS{n - 1}"


def physical_url(physical: str, com_devices: dict[int, str] | None = None, platform: str = sys.platform) -> str:
    """What to give ``serial_for_url`` for a ``[PORTS]`` physical field."""
    text = physical.strip()
    if text.isdigit():  # the manual's sample: physical port 0 is COM1
        text = f"COM{int(text) + 1}"
    m = COM_NAME.fullmatch(text)
    if m:
        n = int(m.group(1))
        return (com_devices or {}).get(n) or default_com_device(n, platform)
    return text


def hexdump(data: bytes, limit: int = 64) -> str:
    text = data[:limit].hex(" ").upper()
    return text + (f" ... ({len(data)} bytes)" if len(data) > limit else "")


class Port:
    """One logical port: its pyserial port, receive and transmit buffers."""

    def __init__(self, config: PortConfig, url: str, log: Callable[[int, str], None],
                 now_ns: Callable[[], int], retry_ms: int = 1000, log_frames: bool = False) -> None:
        self.config = config
        self.number = config.logical
        self.url = url
        self.encoding = encoding(config.encoding)
        self.decoder = self.encoding.decoder()
        self.log = log
        self.log_frames = log_frames  # DEBUG=2: every frame in hex (formatted only then)
        self.now_ns = now_ns
        self.retry_s = retry_ms / 1000
        self.rx = ""  # received characters COMSCAN has not taken
        self.rx_size = RX_BUFFER_CHARS
        self.overflow = False
        self.tx = bytearray()
        self.tx_size = TX_BUFFER_BYTES
        self.serial = None
        self.transport: Transport | None = None
        self.error: str | None = "not opened"  # why the port is down; None when up
        self.next_try = 0.0
        self.rx_bytes = self.tx_bytes = 0  # totals since start
        self.dropped = 0  # characters lost to overflows
        self.history: deque[tuple[float, str, bytes]] = deque(maxlen=HISTORY)
        self.record: Callable[[int, str, bytes], None] | None = None

    def __repr__(self) -> str:
        state = "up" if self.up else f"down ({self.error})"
        return f"<Port {self.number} {self.url} {state}>"

    @property
    def up(self) -> bool:
        return self.error is None

    # -- open and close ------------------------------------------------------------------
    def open(self) -> None:
        """Open the device; on failure the port is down and the reason
        raised as a SerialException."""
        c = self.config
        s = None
        try:
            s = serial.serial_for_url(self.url, do_not_open=True)
            s.baudrate = c.baud
            s.bytesize = c.data_bits
            s.parity = _PARITY[c.parity]
            s.stopbits = c.stop_bits
            s.timeout = 0
            transport = transport_for(self.url, s)
            s.write_timeout = transport.write_timeout
            s.open()
            transport.set_clock(self.now_ns)
        except PORT_ERRORS as e:
            if s is not None:
                _quiet_close(s)
            self._down(_reason(e))
            raise serial.SerialException(self.error) from None
        self.serial, self.transport = s, transport
        self.decoder.reset()
        self.error = None
        self.log(1, f"port {self.number}: opened {self.url} ({c.baud} {c.data_bits}{c.parity}{c.stop_bits})")

    def _down(self, reason: str) -> None:
        if self.serial is not None:
            _quiet_close(self.serial)
        self.serial = self.transport = None
        was_up = self.error is None
        self.error = reason
        self.next_try = time.monotonic() + self.retry_s
        if was_up:
            self.log(1, f"port {self.number}: down: {reason}; retrying every {self.retry_s * 1000:g} ms")

    def retry(self) -> None:
        """Try a down port again once its retry time has come."""
        if self.up or time.monotonic() < self.next_try:
            return
        try:
            self.open()
        except serial.SerialException:
            self.next_try = time.monotonic() + self.retry_s
            return
        self.log(1, f"port {self.number}: back up")

    def close(self) -> None:
        if self.serial is not None:
            _quiet_close(self.serial)
        self.serial = self.transport = None
        self.error = "closed"

    # -- the driver's two points ---------------------------------------------------------
    def poll_input(self) -> None:
        if self.transport is None:
            return
        try:
            data = self.transport.read()
        except PORT_ERRORS as e:
            self._down(_reason(e))
            return
        if not data:
            return
        self.rx_bytes += len(data)
        self._traffic("RX", data)
        text = self.decoder.decode(data)
        room = self.rx_size - len(self.rx)
        if len(text) > room:
            self.dropped += len(text) - room
            text = text[:room]
            if not self.overflow:
                self.log(1, f"port {self.number}: receive buffer overflow ({self.rx_size} characters); "
                            "characters dropped until a COMSCAN makes room")
            self.overflow = True
        if text:
            self.rx += text

    def flush_output(self) -> None:
        if self.transport is None or not self.tx:
            return
        try:
            n = self.transport.write(bytes(self.tx))
        except serial.SerialTimeoutException:
            n = 0
        except PORT_ERRORS as e:
            self._down(_reason(e))
            return
        if n:
            sent = bytes(self.tx[:n])
            del self.tx[:n]
            self.tx_bytes += n
            self._traffic("TX", sent)

    def _traffic(self, direction: str, data: bytes) -> None:
        t_ms = self.now_ns() / 1e6
        self.history.append((t_ms, direction, data))
        if self.record is not None:
            self.record(self.number, direction, data)
        if self.log_frames:
            self.log(2, f"port {self.number} {direction} {len(data):4d} bytes: {hexdump(data)}")

    # -- what the instructions do ----------------------------------------------------------
    def queue(self, data: bytes) -> bool:
        """All or nothing into the transmit buffer (COMPRINT)."""
        if len(self.tx) + len(data) > self.tx_size:
            return False
        self.tx += data
        return True

    def take(self, n: int) -> None:
        """COMSCAN matched the first ``n`` characters: remove them. That
        also ends an overflow once the buffer has room again."""
        if n:
            self.rx = self.rx[n:]
        if self.overflow and len(self.rx) < self.rx_size:
            self.overflow = False

    def clear_rx(self) -> None:
        self.rx = ""
        self.decoder.reset()
        if self.serial is not None:
            try:
                self.serial.reset_input_buffer()
            except PORT_ERRORS:
                pass

    def clear_tx(self) -> None:
        self.tx.clear()
        if self.serial is not None:
            try:
                self.serial.reset_output_buffer()
            except PORT_ERRORS:
                pass


def _quiet_close(s) -> None:
    try:
        s.close()
    except Exception:  # closing a port that is already gone must not fail the run
        pass


def _reason(e: BaseException) -> str:
    text = str(e) or type(e).__name__
    if isinstance(e, OSError) and e.strerror:
        text = f"{e.strerror}" + (f": {e.filename}" if e.filename else "")
    return text


class PortSet:
    """The ports of one COMGENIUS instance, opened from its config."""

    def __init__(self, config: ComGeniusConfig, log: Callable[[int, str], None], now_ns: Callable[[], int],
                 overrides: dict[int, str] | None = None) -> None:
        from .urlhandler import register  # sim:// and replay:// join pyserial's URL schemes

        register()
        self.config = config
        self.log = log
        self.ports: dict[int, Port] = {}
        for number, pc in sorted(config.ports.items()):
            physical = (overrides or {}).get(number, pc.physical)
            url = physical_url(physical, config.com_devices)
            self.ports[number] = Port(pc, url, log, now_ns, config.retry_ms, log_frames=config.debug >= 2)

    def open_all(self, keep_going: bool | None = None) -> list[str]:
        """Open every port. A port that cannot be opened raises ModuleError
        naming its [PORTS] line, unless the app runs on (``PORT_ERRORS=RETRY``
        or ``keep_going``): then it is returned as a warning and retried."""
        if keep_going is None:
            keep_going = self.config.port_errors == "RETRY"
        warnings = []
        for port in self.ports.values():
            try:
                port.open()
            except serial.SerialException:
                message = f"port {port.number}: cannot open {port.url}: {port.error}"
                if not keep_going:
                    self.close()
                    raise ModuleError(f"[PORTS]: {message} (set PORT_ERRORS=RETRY in [DRIVER] to run on "
                                      "without it)", self.config.path, port.config.line) from None
                warnings.append(f"{self.config.path}:{port.config.line}: [PORTS]: {message}; running on, "
                                f"its instructions set ER and it is retried every {self.config.retry_ms} ms")
        return warnings

    def poll_input(self) -> None:
        for port in self.ports.values():
            if port.error is None:
                port.poll_input()
            elif port.error != "closed":
                port.retry()

    def flush_output(self) -> None:
        for port in self.ports.values():
            if port.tx:
                port.flush_output()

    def close(self) -> None:
        for port in self.ports.values():
            port.close()

    def lookup(self, number: int) -> tuple[Port | None, str | None]:
        """The port for an instruction, or why there is none."""
        port = self.ports.get(number)
        if port is None:
            if not 0 <= number <= 35:
                return None, f"port {number} is out of range (0..35)"
            have = ", ".join(str(n) for n in self.ports) or "none"
            return None, f"port {number} is not configured in [PORTS] (configured: {have})"
        if port.error is not None:
            return None, f"port {number} is down: {port.error}"
        return port, None
