"""COMGENIUS ports: one per ``[PORTS]`` line, each with its buffers.

A ComPort is a ``SerialPort`` (softplc_lite.ports: opening through
``serial_for_url``, non-blocking reads and writes, down and retried when its
device fails) with what COMGENIUS adds: a receive buffer of 16-bit
characters (what COMSCAN matches; its size is COMRCVSTS's PRE) and a
transmit buffer of bytes (what COMPRINT fills). The driver moves bytes at
the engine's input and output points, never blocking the scan:

- input: read what has arrived, decode it with the port's encoding and
  append it to the receive buffer; characters that do not fit are dropped
  and the overflow flag (COMRCVSTS OV) is set;
- output: hand as much of the transmit buffer to the port as it takes now.

A port that is down makes the instructions on it set ER; the engine keeps
scanning, and the port is tried again every ``RETRY_MS`` until it comes back.

The physical field of a ``[PORTS]`` line (see :func:`port_url`): ``COMn``
(a bare number ``n`` is ``COM(n+1)``) maps to a device through
``[DRIVER] COMn=...`` or the platform default; anything else is a device
path or a pyserial URL. ``softplc run --port N=DEVICE`` replaces it for
logical port N.
"""

from __future__ import annotations

import sys
from typing import Callable

import serial

from ...ports import LineSettings, PortClaim, SerialPort, physical_url
from ..errors import ModuleError
from .config import MAX_PORT, ComGeniusConfig, PortConfig
from .encodings import encoding

RX_BUFFER_CHARS = 4096  # characters; COMRCVSTS sets PRE to this
TX_BUFFER_BYTES = 4096  # bytes; a COMPRINT waits until its whole output fits


def port_url(physical: str, com_devices: dict[int, str] | None = None, platform: str = sys.platform) -> str:
    """What to give ``serial_for_url`` for a ``[PORTS]`` physical field."""
    text = physical.strip()
    if text.isdigit():  # the manual's sample: physical port 0 is COM1
        text = f"COM{int(text) + 1}"
    return physical_url(text, com_devices, platform)


class ComPort(SerialPort):
    """One logical port: a SerialPort with receive and transmit buffers."""

    def __init__(self, config: PortConfig, url: str, log: Callable[[int, str], None],
                 now_ns: Callable[[], int], retry_ms: int = 1000, log_frames: bool = False) -> None:
        settings = LineSettings(config.baud, config.data_bits, config.parity, config.stop_bits)
        super().__init__(str(config.logical), url, settings, log, now_ns, retry_ms, log_frames)
        self.config = config
        self.number = config.logical
        self.encoding = encoding(config.encoding)
        self.decoder = self.encoding.decoder()
        self.rx = ""  # received characters COMSCAN has not taken
        self.rx_size = RX_BUFFER_CHARS
        self.overflow = False
        self.tx = bytearray()
        self.tx_size = TX_BUFFER_BYTES
        self.dropped = 0  # characters lost to overflows

    @property
    def waiting(self) -> int:
        """Characters received and not yet taken (the watch view shows it)."""
        return len(self.rx)

    def opened(self) -> None:
        self.decoder.reset()

    # -- the driver's two points ---------------------------------------------------------
    def poll_input(self) -> None:
        if self.clocked:  # the clock read once; a quiet simulated link is not read at all
            now = self.now_ns()
            quiet = self.quiet
            if quiet is not None and now < quiet.quiet_until:
                return
            data = self.read_at(now)
        else:
            data = self.read()
        if not data:
            return
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
        if self.tx:
            n = self.write(bytes(self.tx))
            if n:
                del self.tx[:n]

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
        self.reset_input()

    def clear_tx(self) -> None:
        self.tx.clear()
        self.reset_output()


class PortSet:
    """The ports of one COMGENIUS instance, opened from its config."""

    def __init__(self, config: ComGeniusConfig, log: Callable[[int, str], None], now_ns: Callable[[], int],
                 overrides: dict[int, str] | None = None, given: set[int] = frozenset()) -> None:
        # ``given``: the ports whose device a ``--port`` option names (their errors name the option)
        from ...ports.urlhandler import register  # sim:// and replay:// join pyserial's URL schemes

        register()
        self.config = config
        self.log = log
        self.ports: dict[int, ComPort] = {}
        self.given = {number: (overrides or {})[number] for number in given if number in (overrides or {})}
        for number, pc in sorted(config.ports.items()):
            physical = (overrides or {}).get(number, pc.physical)
            url = port_url(physical, config.com_devices)
            self.ports[number] = ComPort(pc, url, log, now_ns, config.retry_ms, log_frames=config.debug >= 2)
        # the driver's input and output points (ComGenius.on_input, on_output) walk it at every scan
        self.port_list = list(self.ports.values())

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
                    why = port.error
                    self.close()
                    retry = "(set PORT_ERRORS=RETRY in [DRIVER] to run on without it)"
                    if port.number in self.given:  # the device is the option's, not the [PORTS] line's
                        raise ModuleError(f"--port {port.number}={self.given[port.number]}: cannot open {port.url}: "
                                          f"{why} {retry}") from None
                    raise ModuleError(f"[PORTS]: {message} {retry}", self.config.path, port.config.line) from None
                warnings.append(f"{self.config.path}:{port.config.line}: [PORTS]: {message}; running on, "
                                f"its instructions set ER and it is retried every {self.config.retry_ms} ms")
        return warnings

    def close(self) -> None:
        for port in self.ports.values():
            port.close()

    def claims(self, module: str) -> list[PortClaim]:
        """The devices these ports open (for the one-owner check)."""
        return [PortClaim(module, n, p.url, f"{self.config.path}:{p.config.line}") for n, p in self.ports.items()]

    def lookup(self, number: int) -> tuple[ComPort | None, str | None]:
        """The port for an instruction, or why there is none."""
        port = self.ports.get(number)
        if port is None:
            if not 0 <= number <= MAX_PORT:
                return None, f"port {number} is out of range (0..{MAX_PORT})"
            have = ", ".join(str(n) for n in self.ports) or "none"
            return None, f"port {number} is not configured in [PORTS] (configured: {have})"
        if port.error is not None:
            return None, f"port {number} is down: {port.error}"
        return port, None
