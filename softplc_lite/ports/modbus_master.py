"""A simulated Modbus RTU master: the device behind ``sim://NAME?device=modbus_master``.

It polls one slave on a simulated wire with a fixed round of requests that
uses every function a basic slave serves, checks each reply, and keeps
score, so that a slave (``programs/modbus_slave``, the ladder port of the
S7-200 slave) can run and be checked on any machine. The protocol is the
project's one Modbus codec; the timing is the wire's.

Options (``sim://NAME?device=modbus_master&id=1&period_ms=20``; any other
option is a ValueError):

- ``id``: the slave polled, 1..247 (default 1).
- ``period_ms``: time from the start of one request to the start of the
  next, at least (default 20; a number >= 0). A reply that takes longer
  pushes the next request back: the master never has two out.
- ``timeout_ms``: how long after its request's last byte the master waits
  for a reply's first byte (default 100).
- ``start_ms``: when the first request goes (default 10), so the slave has
  scanned once and built its tables.
- ``requests``: PDUs in hex (function code and data, no address, no CRC),
  separated by commas, spaces ignored (``requests=05 0064 FF00,06 0000 0001``):
  sent in turn, over and over, in place of the round below, to put a slave
  through requests the round never makes (an address past its tables, a bad
  value; up to 300 bytes, past the 253 a PDU may have, so that a frame too
  long is sent as it is). Any well-formed reply of the slave polled counts: a normal one in
  ``replies``, an exception in ``exceptions``, its code in ``last_exception``.
  With ``requests``, ``id=0`` broadcasts them: the master waits for no
  reply, and any byte a slave sends back counts in ``bad``.

The round (``ROUND``), one request a period, ``n`` counting rounds from 0:

1. 06 write holding register 0 := n
2. 16 write holding registers 1..4 := n+1 .. n+4
3. 03 read holding registers 0..7 (0..4 must read back what was written)
4. 05 write coil n MOD 16 on in even rounds, off in odd ones
5. 15 write coils 16..25 with the pattern 1010110011 shifted by n
6. 01 read coils 0..31 (16..25 must read back what was written)
7. 02 read discrete inputs 0..15
8. 04 read input registers 0..3
9. 03 read holding register 1000: past 1,000 registers, exception 02 expected

A reply is complete 3.5 character times after its last byte (as a slave
sees a request end). Scores (attributes, also in ``repr``): ``sent``,
``replies`` (good normal replies), ``exceptions`` (exception replies that
were expected), ``timeouts``, ``bad`` (a reply with a bad CRC, from another
id, of the wrong function or shape, an unexpected exception, or data that
does not read back what was written). ``log`` keeps the last 50
(request, reply or None) frame pairs. ``find_master(name)`` gives the
device of the open link ``name``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from . import simdevices, simlink
from .simdevices import SimDevice, check_options, float_option, silence_ns
from ..modbus.framing import FrameError, RtuFramer, rtu_adu
from ..modbus.pdu import (ILLEGAL_DATA_ADDRESS, ExceptionResponse, ModbusDecodeError, ReadCoilsRequest,
                          ReadDiscreteInputsRequest, ReadHoldingRegistersRequest, ReadInputRegistersRequest,
                          WriteMultipleCoilsRequest, WriteMultipleRegistersRequest, WriteSingleCoilRequest,
                          WriteSingleRegisterRequest, decode_response)

KIND = "modbus_master"
OPTIONS = ("id", "period_ms", "timeout_ms", "start_ms", "requests")
PATTERN = (1, 0, 1, 0, 1, 1, 0, 0, 1, 1)


class _Model:
    """What the master wrote, to check what it reads back."""

    def __init__(self) -> None:
        self.registers: dict[int, int] = {}
        self.coils: dict[int, bool] = {}


def _round(n: int, model: _Model) -> list[tuple[object, Callable[[object], bool]]]:
    """The requests of round ``n``, each with a check of its decoded reply
    (True: as expected). A write's check also records what it wrote."""
    v = n & 0xFFFF
    regs = tuple((v + k) & 0xFFFF for k in range(1, 5))
    coil = n % 16
    on = n % 2 == 0
    bits = tuple(bool(PATTERN[(k + n) % len(PATTERN)]) for k in range(len(PATTERN)))

    def wrote(table: dict, start: int, values: tuple):
        def check(reply) -> bool:
            if isinstance(reply, ExceptionResponse):
                return False
            table.update({start + k: x for k, x in enumerate(values)})
            return True
        return check

    def read_registers(start: int):
        def check(reply) -> bool:
            values = getattr(reply, "values", None)
            return values is not None and all(values[a - start] == x for a, x in model.registers.items()
                                              if start <= a < start + len(values))
        return check

    def read_coils(start: int, count: int):
        def check(reply) -> bool:
            values = getattr(reply, "bits", None)
            return values is not None and len(values) >= count and all(
                values[a - start] == x for a, x in model.coils.items() if start <= a < start + count)
        return check

    def answered(reply) -> bool:
        return not isinstance(reply, ExceptionResponse)

    def refused(reply) -> bool:
        return isinstance(reply, ExceptionResponse) and reply.exception_code == ILLEGAL_DATA_ADDRESS

    return [
        (WriteSingleRegisterRequest(0, v), wrote(model.registers, 0, (v,))),
        (WriteMultipleRegistersRequest(1, regs), wrote(model.registers, 1, regs)),
        (ReadHoldingRegistersRequest(0, 8), read_registers(0)),
        (WriteSingleCoilRequest(coil, on), wrote(model.coils, coil, (on,))),
        (WriteMultipleCoilsRequest(16, bits), wrote(model.coils, 16, bits)),
        (ReadCoilsRequest(0, 32), read_coils(0, 32)),
        (ReadDiscreteInputsRequest(0, 16), answered),
        (ReadInputRegistersRequest(0, 4), answered),
        (ReadHoldingRegistersRequest(1000, 1), refused),
    ]


ROUND = len(_round(0, _Model()))


MAX_RAW_PDU = 300  # more than a PDU's 253 bytes: a slave's refusal of a frame too long is tested too


class RawRequest:
    """A request given as its PDU (the ``requests`` option)."""

    def __init__(self, pdu: bytes) -> None:
        if not 1 <= len(pdu) <= MAX_RAW_PDU:
            raise ValueError(f"{KIND} device: a request has 1..{MAX_RAW_PDU} bytes (a function code, data), "
                             f"not {len(pdu)}")
        self.pdu = bytes(pdu)
        self.function_code = pdu[0]

    def encode(self) -> bytes:
        return self.pdu


def _any_reply(reply) -> bool:
    return True


def parse_requests(text: str) -> list[RawRequest]:
    """The ``requests`` option: hex PDUs separated by commas."""
    out = []
    for item in text.split(","):
        try:
            out.append(RawRequest(bytes.fromhex(item.replace(" ", ""))))
        except ValueError:
            raise ValueError(f"{KIND} device: requests must be hex PDUs separated by commas "
                             f"(05 0064 FF00,06 0000 0001), not {item.strip()!r}") from None
    return out


class ModbusMaster(SimDevice):
    """A Modbus RTU master polling one slave (see the module docstring)."""

    name = KIND

    def __init__(self, slave_id: int = 1, period_ms: float = 20.0, timeout_ms: float = 100.0,
                 start_ms: float = 10.0, requests: list[RawRequest] | None = None) -> None:
        if not (1 if not requests else 0) <= slave_id <= 247:
            raise ValueError(f"{KIND} device: id must be 1..247 (0, a broadcast, with requests), not {slave_id}")
        self.slave_id = slave_id
        self.period_ns = round(period_ms * 1_000_000)
        self.timeout_ns = round(timeout_ms * 1_000_000)
        self.model = _Model()
        self.requests = list(requests or [])
        self.last_exception = 0  # the code of the last exception reply
        self.sent = self.replies = self.exceptions = self.timeouts = self.bad = 0
        self.log: deque[tuple[bytes, bytes | None]] = deque(maxlen=50)
        self._queue: list[tuple[object, Callable[[object], bool]]] = []
        self._rounds = 0
        self._next_at = round(start_ms * 1_000_000)
        self._pending: tuple[bytes, Callable[[object], bool], object] | None = None
        self._sent_end = 0
        self._reply = bytearray()
        self._last = 0

    def receive(self, data: bytes, times_ns: list[int]) -> None:
        if self.slave_id == 0 and data:
            self.bad += 1  # no slave answers a broadcast
            return
        if self._pending is None:
            return  # nothing asked: noise on the line, ignored
        gap = silence_ns(self.end.char_ns)
        for byte, t in zip(data, times_ns):
            if self._reply and t - self._last > gap:
                self._finish(self._last + gap)
                if self._pending is None:
                    return
            self._reply.append(byte)
            self._last = t

    def poll(self, now_ns: int) -> None:
        gap = silence_ns(self.end.char_ns)
        if self._pending is not None:
            if self._reply and now_ns >= self._last + gap:
                self._finish(self._last + gap)
            elif not self._reply and now_ns >= self._sent_end + self.timeout_ns:
                self.timeouts += 1
                self.log.append((self._pending[0], None))
                self._pending = None
                self._next_at = max(self._next_at, self._sent_end + self.timeout_ns)
        if self._pending is None and now_ns >= self._next_at:
            self._send(self._next_at)

    def _send(self, at: int) -> None:
        if not self._queue:
            self._queue = [(r, _any_reply) for r in self.requests] or _round(self._rounds, self.model)
            self._rounds += 1
        request, check = self._queue.pop(0)
        pdu = request.encode()
        frame = rtu_adu(self.slave_id, pdu)  # RtuFramer.encode refuses the over-long PDUs requests= may give
        self.end.send(frame, at)
        self.sent += 1
        self._pending = (frame, check, request) if self.slave_id else None  # a broadcast waits for nothing
        if self._pending is None:
            self.log.append((frame, None))
        self._sent_end = at + len(frame) * self.end.char_ns
        self._next_at = at + self.period_ns
        self._reply.clear()

    def _finish(self, ended_at: int) -> None:
        frame, check, request = self._pending
        reply = bytes(self._reply)
        self._reply.clear()
        self._pending = None
        self.log.append((frame, reply))
        self._next_at = max(self._next_at, ended_at)
        try:
            unit, pdu = RtuFramer.decode(reply)
            decoded = decode_response(pdu)
        except (FrameError, ModbusDecodeError):
            self.bad += 1
            return
        if unit != self.slave_id or decoded.function_code != request.function_code or not check(decoded):
            self.bad += 1
        elif isinstance(decoded, ExceptionResponse):
            self.exceptions += 1
            self.last_exception = decoded.exception_code
        else:
            self.replies += 1

    def __repr__(self) -> str:
        return (f"<ModbusMaster id={self.slave_id}: {self.sent} sent, {self.replies} replies, "
                f"{self.exceptions} expected exceptions, {self.timeouts} timeouts, {self.bad} bad>")


def create(options: dict[str, str]) -> ModbusMaster:
    """The ``modbus_master`` device factory: ``options`` as given in the URL."""
    check_options(KIND, options, OPTIONS)
    text = options.get("id", "1")
    slave_id = int(text) if text.isascii() and text.isdigit() and len(text) < 4 else -1
    if not (0 if "requests" in options else 1) <= slave_id <= 247:
        raise ValueError(f"{KIND} device: id must be an integer 1..247 (0, a broadcast, with requests), "
                         f"not {text!r}")
    return ModbusMaster(slave_id, float_option(KIND, options, "period_ms", 20.0),
                        float_option(KIND, options, "timeout_ms", 100.0),
                        float_option(KIND, options, "start_ms", 10.0),
                        parse_requests(options["requests"]) if "requests" in options else None)


def find_master(name: str) -> ModbusMaster:
    """The master at the far end of the open ``sim://`` link ``name``
    (the newest, when several ports have opened one of that name);
    LookupError when there is none."""
    return simlink.find_device(name, ModbusMaster, KIND)


simdevices.register_device(KIND, create)
