"""Simulated Modbus slaves: the device behind ``sim://NAME?device=modbus``.

They answer Modbus RTU (or ASCII) requests like real RS-485 slaves, with wire
timing, so that a Modbus master (a ladder program's, MODBMAST) can be tested
without hardware. The protocol is the one Modbus codec (softplc_lite.modbus:
PDUs and framers); behaviour follows the Modbus specification (Application
Protocol V1.1b3 and the Serial Line guide V1.02).

Options (``sim://NAME?device=modbus&id=2&registers=200``; any other option is
a ValueError):

- ``id``: the slave address, 1..247 (default 1), or several on one line
  (``id=1,2,5``): one slave each, each with its own tables; the line is
  silent for any other id.
- ``registers``: the size of each of the four tables of each slave,
  1..65536 (default 200): holding registers, input registers, coils and
  discrete inputs, addressed 0..registers-1 (the protocol address).
- ``values``: how the tables start (default ``pattern``), see
  ``initial_value()``; the k-th id of a list (k from 0) has the pattern
  XOR (k * 0x1111 & 0xFFFF) in its registers and its bit patterns shifted by
  k, so neighbouring slaves never look alike.
- ``framing``: ``rtu`` (default) or ``ascii``.
- ``turnaround_ms``: extra time before replying (default 0; a number >= 0).
- ``cts_delay_ms``: CTS follows the port's RTS after this delay (default 0,
  at once); ``cts=off``: CTS never rises (a modem that does not answer).

Framing and timing: an RTU frame is a run of bytes each arriving no later
than 3.5 character times (``simdevices.silence_ns``) after the one before;
it ends once the port's clock reaches its last byte's arrival + 3.5
character times, and the reply starts then + ``turnaround_ms``. An ASCII
frame runs from ':' to CR LF; the reply starts when the LF has arrived +
``turnaround_ms``. Frames are answered in order, each reply queued behind
the one before.

A frame is ignored, without reply (counted in ``ignored``), when it is too
short or too long, has a bad CRC or LRC, or is for an id the line does not
have. Address 0 is a broadcast: every slave executes it, none answers.
Every other frame is a request (counted in ``requests``) and gets a reply:
the normal one, or an exception with the code checked in the
specification's order: 01 illegal function (other than 1-6, 15, 16, 22,
23), 03 illegal data value (a quantity out of range, a byte count that does
not match, a coil value other than 0xFF00/0x0000, a wrong length), 02
illegal data address (past the end of the table).

Faults, for testing a master (``device.fault``, a ``ReplyFault``; URL
options of the same names set it at start): ``cut=N`` sends only the first N
bytes of each reply; ``pause_after=N&pause_ms=X`` pauses X ms after the
first N bytes; ``garbage=HEX`` sends those bytes just before each reply;
``bad_crc=1`` corrupts the check; ``silent=1`` answers nothing (a slave that
is present again once it is cleared). A unit's ``online`` flag does the
same for one id.

Simplifications: the gap is measured between byte arrivals (the ends of the
characters); there is no 1.5-character rule on the slave side; and no
half-duplex model (a request arriving while the slave is still replying is
answered in its turn).

The tables are lists a test may read and change, per id: ``unit(id)``'s
``holding_registers``, ``input_registers`` (ints 0..0xFFFF), ``coils`` and
``discrete_inputs`` (bools); the device's own attributes of those names are
its first id's. ``respond(request, slave)`` is the whole protocol without a
wire: request frame in, reply frame (or None for silence) out.
``find_slave(name)`` gives the device of the open link ``name``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..modbus.crc import crc16
from ..modbus.framing import AsciiFramer, FrameError, RtuFramer
from ..modbus.packing import pack_bits, unpack_bits
from ..modbus.pdu import (ILLEGAL_DATA_ADDRESS, ExceptionResponse, MaskWriteRegisterRequest,
                          MaskWriteRegisterResponse, ModbusDecodeError, ReadCoilsRequest, ReadCoilsResponse,
                          ReadDiscreteInputsRequest, ReadDiscreteInputsResponse, ReadHoldingRegistersRequest,
                          ReadHoldingRegistersResponse, ReadInputRegistersRequest, ReadInputRegistersResponse,
                          ReadWriteMultipleRegistersRequest, ReadWriteMultipleRegistersResponse,
                          WriteMultipleCoilsRequest, WriteMultipleCoilsResponse, WriteMultipleRegistersRequest,
                          WriteMultipleRegistersResponse, WriteSingleCoilRequest, WriteSingleCoilResponse,
                          WriteSingleRegisterRequest, WriteSingleRegisterResponse, decode_request)
from . import simdevices, simlink
from .simdevices import SimDevice, check_options, float_option, silence_ns

KIND = "modbus"
OPTIONS = ("id", "registers", "values", "framing", "turnaround_ms", "cts_delay_ms", "cts", "cut", "pause_after",
           "pause_ms", "garbage", "bad_crc", "silent")
VALUES = ("pattern", "index", "zero")
TABLES = ("holding", "input", "coil", "discrete")
MAX_ADU = 256

__all__ = ["ModbusSlave", "ModbusUnit", "ReplyFault", "crc16", "find_slave", "initial_value", "pack_bits", "respond",
           "unpack_bits", "with_crc"]


def with_crc(frame: bytes) -> bytes:
    """``frame`` followed by its CRC, low byte first.

    >>> with_crc(bytes.fromhex("02 03 00 00 00 7D")).hex(" ")
    '02 03 00 00 00 7d 85 d8'
    """
    return bytes(frame) + crc16(frame).to_bytes(2, "little")


def initial_value(k: int, table: str = "holding", values: str = "pattern", unit: int = 0) -> int | bool:
    """What entry ``k`` of ``table`` ("holding", "input", "coil" or "discrete")
    holds when a slave starts with option ``values``; ``unit`` is the
    slave's place in the ``id`` list (0 for the first).

    >>> [hex(initial_value(k)) for k in range(3)], hex(initial_value(1, "input"))
    (['0x1', '0x102', '0x203'], '0xfefd')
    >>> [initial_value(k, "coil") for k in range(4)], [initial_value(k, "discrete") for k in range(4)]
    ([True, False, False, True], [False, True, False, False])
    >>> hex(initial_value(0, unit=1)), [initial_value(k, "coil", unit=1) for k in range(4)]
    ('0x1110', [False, False, True, False])
    """
    if table not in TABLES:
        raise ValueError(f"table must be one of {', '.join(TABLES)}, not {table!r}")
    if values == "pattern":
        shift = (unit * 0x1111) & 0xFFFF  # registers stay 16-bit whatever the place in a long id list
        if table == "holding":
            return ((k * 257 + 1) & 0xFFFF) ^ shift
        if table == "input":
            return ((k * 257 + 1) & 0xFFFF) ^ 0xFFFF ^ shift
        return (k + unit) % 3 == 0 if table == "coil" else (k + unit) % 4 == 1
    if values == "index":
        return k & 0xFFFF if table in ("holding", "input") else k % 2 == 1
    if values == "zero":
        return 0 if table in ("holding", "input") else False
    raise ValueError(f"values must be one of {', '.join(VALUES)}, not {values!r}")


@dataclass
class ReplyFault:
    """What goes wrong with every reply (for testing masters)."""

    cut: int | None = None  # send only the first N bytes
    pause_after: int | None = None  # pause after the first N bytes ...
    pause_ms: float = 0.0  # ... for this long
    garbage: bytes = b""  # sent just before the reply
    bad_crc: bool = False  # the CRC (or LRC) of the reply is wrong
    silent: bool = False  # no reply at all


class ModbusUnit:
    """One slave id's four tables."""

    def __init__(self, slave_id: int, size: int, values: str, position: int = 0) -> None:
        self.slave_id = slave_id
        self.online = True  # False: this id answers nothing (a slave switched off)
        self.holding_registers: list[int] = [initial_value(k, "holding", values, position) for k in range(size)]
        self.input_registers: list[int] = [initial_value(k, "input", values, position) for k in range(size)]
        self.coils: list[bool] = [initial_value(k, "coil", values, position) for k in range(size)]
        self.discrete_inputs: list[bool] = [initial_value(k, "discrete", values, position) for k in range(size)]
        self.last_read: tuple[bytes, tuple, bytes] | None = None  # (request PDU, values, reply PDU)

    def __repr__(self) -> str:
        return f"<ModbusUnit id={self.slave_id}{'' if self.online else ' offline'}>"


class ModbusSlave(SimDevice):
    """Modbus slaves on a simulated wire (see the module docstring)."""

    name = KIND

    def __init__(self, slave_id: int | list[int] = 1, registers: int = 200, values: str = "pattern",
                 turnaround_ms: float = 0.0, framing: str = "rtu", cts_delay_ms: float = 0.0, cts: bool = True,
                 fault: ReplyFault | None = None) -> None:
        ids = [slave_id] if isinstance(slave_id, int) else list(slave_id)
        for i in ids:
            if not 1 <= i <= 247:
                raise ValueError(f"{KIND} device: id must be 1..247, not {i}")
        if len(set(ids)) != len(ids) or not ids:
            raise ValueError(f"{KIND} device: ids must be different, not {ids}")
        if not 1 <= registers <= 65536:
            raise ValueError(f"{KIND} device: registers must be 1..65536, not {registers}")
        if values not in VALUES:
            raise ValueError(f"{KIND} device: values must be one of {', '.join(VALUES)}, not {values!r}")
        if framing not in ("rtu", "ascii"):
            raise ValueError(f"{KIND} device: framing must be rtu or ascii, not {framing!r}")
        self.units = {i: ModbusUnit(i, registers, values, k) for k, i in enumerate(ids)}
        self.slave_id = ids[0]
        self.size = registers
        self.values = values
        self.framing = framing
        self.framer = RtuFramer if framing == "rtu" else AsciiFramer
        self.turnaround_ns = round(turnaround_ms * 1_000_000)
        self.cts_delay_ns = round(cts_delay_ms * 1_000_000)
        self.cts_enabled = cts
        self.fault = fault or ReplyFault()
        self.requests = 0  # frames executed (answered, or broadcast)
        self.ignored = 0  # frames dropped: too short or long, bad CRC, another slave's
        self._frame = bytearray()
        self._last = 0  # arrival time of the frame's last byte
        self._last_reply: tuple | None = None  # (address, reply PDU, framer, frame) of the last reply

    # the first id's tables, as the device's own
    holding_registers = property(lambda self: self.units[self.slave_id].holding_registers)
    input_registers = property(lambda self: self.units[self.slave_id].input_registers)
    coils = property(lambda self: self.units[self.slave_id].coils)
    discrete_inputs = property(lambda self: self.units[self.slave_id].discrete_inputs)

    def unit(self, slave_id: int) -> ModbusUnit:
        return self.units[slave_id]

    # -- the wire --------------------------------------------------------------------------------
    def receive(self, data: bytes, times_ns: list[int]) -> None:
        if self.framing == "ascii":
            self._receive_ascii(data, times_ns)
            return
        gap = silence_ns(self.end.char_ns)
        frame = self._frame
        for byte, t in zip(data, times_ns):
            if frame and t - self._last > gap:
                self._finish(self._last + gap)
            if len(frame) <= MAX_ADU:  # one byte over marks the frame as too long
                frame.append(byte)
            self._last = t

    def _receive_ascii(self, data: bytes, times_ns: list[int]) -> None:
        frame = self._frame
        for byte, t in zip(data, times_ns):
            if byte == 0x3A:  # ':' starts a frame, whatever came before
                frame.clear()
            if frame or byte == 0x3A:
                if len(frame) <= AsciiFramer.MAX_FRAME_LENGTH:
                    frame.append(byte)
                if byte == 0x0A and frame[-2:] == b"\r\n":
                    self._last = t
                    self._finish(t)

    def poll(self, now_ns: int) -> None:
        if self._frame and self.framing == "rtu":  # idle (no frame) at most polls: nothing computed
            gap = silence_ns(self.end.char_ns)
            if now_ns >= self._last + gap:
                self._finish(self._last + gap)

    def next_due(self, now_ns: int) -> int | None:
        """When ``poll`` ends the frame being received (RTU, once the line
        has been silent 3.5 characters); None with no frame, or in ASCII
        (a frame ends on its own bytes there, in ``receive``)."""
        if self.framing == "rtu" and self._frame:
            return self._last + silence_ns(self.end.char_ns)
        return None

    def cts(self, now_ns: int) -> tuple[bool, int]:
        on, since = self.end.rts()
        if not self.cts_enabled:
            return False, 0
        if not on:
            return False, since
        rises = since + self.cts_delay_ns
        return (True, rises) if now_ns >= rises else (False, since)

    def _finish(self, ended_at: int) -> None:
        request = bytes(self._frame)
        self._frame.clear()
        reply = respond(request, self)
        fault = self.fault
        if reply is None or fault.silent:
            return
        if fault.bad_crc:
            reply = reply[:-3] + bytes([reply[-3] ^ 0x01]) + reply[-2:] if self.framing == "ascii" else \
                reply[:-1] + bytes([reply[-1] ^ 0xFF])
        if fault.cut is not None:
            reply = reply[:fault.cut]
        at = ended_at + self.turnaround_ns
        if fault.garbage:
            self.end.send(fault.garbage, at)
            at += len(fault.garbage) * self.end.char_ns
        if fault.pause_after is not None and fault.pause_after < len(reply):
            first, rest = reply[:fault.pause_after], reply[fault.pause_after:]
            self.end.send(first, at)
            at += len(first) * self.end.char_ns + round(fault.pause_ms * 1_000_000)
            reply = rest
        self.end.send(reply, at)

    def __repr__(self) -> str:
        ids = ",".join(map(str, self.units))
        return (f"<ModbusSlave id={ids} registers={self.size} values={self.values} {self.framing}: "
                f"{self.requests} request(s), {self.ignored} ignored>")


def respond(request: bytes, slave: ModbusSlave) -> bytes | None:
    """Execute one request frame (RTU, or ASCII on an ASCII slave) on
    ``slave``; the reply frame, or None when the line stays silent (ignored
    frame, an id it does not have, or a broadcast). Counts the frame in
    ``slave.requests`` or ``slave.ignored``.

    >>> slave = ModbusSlave(slave_id=2)
    >>> respond(with_crc(bytes.fromhex("02 03 00 00 00 02")), slave).hex(" ")
    '02 03 04 00 01 01 02 18 a2'
    >>> respond(with_crc(bytes.fromhex("02 03 00 c7 00 02")), slave).hex(" ")
    '02 83 02 30 f1'
    >>> respond(with_crc(bytes.fromhex("03 03 00 00 00 02")), slave) is None
    True
    """
    framer = slave.framer
    if len(request) > (MAX_ADU if framer is RtuFramer else AsciiFramer.MAX_FRAME_LENGTH):
        slave.ignored += 1
        return None
    try:
        address, pdu = framer.decode(request)
    except FrameError:
        slave.ignored += 1
        return None
    if address == 0:
        units = [u for u in slave.units.values() if u.online]
    else:
        unit = slave.units.get(address)
        units = [unit] if unit is not None and unit.online else []
    if not units or not pdu:
        slave.ignored += 1
        return None
    slave.requests += 1
    replies = [_execute(unit, pdu, slave.size) for unit in units]
    if address == 0:
        return None
    # A master polling the same registers gets the same reply frame while the
    # values stay the same: framed (and its CRC computed) once.
    last = slave._last_reply
    if last is not None and last[0] == address and last[1] == replies[0] and last[2] is framer:
        return last[3]
    frame = framer.encode(address, replies[0])
    slave._last_reply = (address, replies[0], framer, frame)
    return frame


def _execute(unit: ModbusUnit, pdu: bytes, size: int) -> bytes:
    """The reply PDU to ``pdu`` (function code + data), after executing it."""
    try:
        request = decode_request(pdu)
    except ModbusDecodeError as e:
        if not 1 <= pdu[0] <= 0x7F:  # no function has that code: the exception says so as sent
            return bytes([pdu[0] | 0x80, e.exception_code])
        return ExceptionResponse(pdu[0], e.exception_code).encode()
    f = pdu[0]
    if any(address + count > size for address, count in _spans(request)):
        return ExceptionResponse(f, ILLEGAL_DATA_ADDRESS).encode()
    if isinstance(request, (ReadCoilsRequest, ReadDiscreteInputsRequest)):
        table = unit.coils if f == 1 else unit.discrete_inputs
        bits = tuple(table[request.address:request.address + request.count])
        return (ReadCoilsResponse if f == 1 else ReadDiscreteInputsResponse)(bits).encode()
    if isinstance(request, (ReadHoldingRegistersRequest, ReadInputRegistersRequest)):
        table = unit.holding_registers if f == 3 else unit.input_registers
        values = tuple(table[request.address:request.address + request.count])
        # the same request on the same values: the reply PDU built (and its
        # values checked) before: a master polls the same block
        last = unit.last_read
        if last is not None and last[0] == pdu and last[1] == values:
            return last[2]
        reply = (ReadHoldingRegistersResponse if f == 3 else ReadInputRegistersResponse)(values).encode()
        unit.last_read = (pdu, values, reply)
        return reply
    if isinstance(request, WriteSingleCoilRequest):
        unit.coils[request.address] = request.value
        return WriteSingleCoilResponse(request.address, request.value).encode()
    if isinstance(request, WriteSingleRegisterRequest):
        unit.holding_registers[request.address] = request.value
        return WriteSingleRegisterResponse(request.address, request.value).encode()
    if isinstance(request, WriteMultipleCoilsRequest):
        unit.coils[request.address:request.address + request.count] = list(request.values)
        return WriteMultipleCoilsResponse(request.address, request.count).encode()
    if isinstance(request, WriteMultipleRegistersRequest):
        unit.holding_registers[request.address:request.address + request.count] = list(request.values)
        return WriteMultipleRegistersResponse(request.address, request.count).encode()
    if isinstance(request, MaskWriteRegisterRequest):  # 6.16: (current AND and) OR (or AND NOT and)
        current = unit.holding_registers[request.address]
        unit.holding_registers[request.address] = (current & request.and_mask) | (request.or_mask & ~request.and_mask
                                                                                 & 0xFFFF)
        return MaskWriteRegisterResponse(request.address, request.and_mask, request.or_mask).encode()
    # 23 (6.17): the write goes first, then the read
    unit.holding_registers[request.write_address:request.write_address + request.write_count] = list(request.values)
    values = tuple(unit.holding_registers[request.read_address:request.read_address + request.read_count])
    return ReadWriteMultipleRegistersResponse(values).encode()


def _spans(request) -> list[tuple[int, int]]:
    """(address, count) of each table range a request touches."""
    if isinstance(request, ReadWriteMultipleRegistersRequest):
        return [(request.read_address, request.read_count), (request.write_address, request.write_count)]
    return [(request.address, getattr(request, "count", 1))]


def _int_option(options: dict[str, str], key: str, default: int, low: int, high: int) -> int:
    if key not in options:
        return default
    text = options[key]
    value = int(text) if text.isascii() and text.isdigit() and len(text) < 8 else None
    if value is None or not low <= value <= high:
        raise ValueError(f"{KIND} device: {key} must be an integer {low}..{high}, not {text!r}")
    return value


def _ids(options: dict[str, str]) -> list[int]:
    text = options.get("id", "1")
    out = []
    for item in text.split(","):
        value = int(item) if item.isascii() and item.isdigit() and len(item) < 4 else None
        if value is None or not 1 <= value <= 247:
            raise ValueError(f"{KIND} device: id must be an integer 1..247, not {item!r} (several: id=1,2,5)")
        out.append(value)
    return out


def _choice(options: dict[str, str], key: str, choices: tuple[str, ...]) -> str:
    value = options.get(key, choices[0])
    if value not in choices:
        raise ValueError(f"{KIND} device: {key} must be {' or '.join(choices)}, not {value!r}")
    return value


def create(options: dict[str, str]) -> ModbusSlave:
    """The ``modbus`` device factory: ``options`` as given in the URL."""
    check_options(KIND, options, OPTIONS)
    garbage = options.get("garbage", "")
    try:
        garbage_bytes = bytes.fromhex(garbage)
    except ValueError:
        raise ValueError(f"{KIND} device: garbage must be hex bytes such as 00FF, not {garbage!r}") from None
    cut = _int_option(options, "cut", -1, 0, MAX_ADU * 3)
    pause_after = _int_option(options, "pause_after", -1, 0, MAX_ADU * 3)
    fault = ReplyFault(cut=None if cut < 0 else cut, pause_after=None if pause_after < 0 else pause_after,
                       pause_ms=float_option(KIND, options, "pause_ms", 0.0), garbage=garbage_bytes,
                       bad_crc=_choice(options, "bad_crc", ("0", "1")) == "1",
                       silent=_choice(options, "silent", ("0", "1")) == "1")
    return ModbusSlave(
        slave_id=_ids(options),
        registers=_int_option(options, "registers", 200, 1, 65536),
        values=options.get("values", "pattern"),
        turnaround_ms=float_option(KIND, options, "turnaround_ms", 0.0),
        framing=_choice(options, "framing", ("rtu", "ascii")),
        cts_delay_ms=float_option(KIND, options, "cts_delay_ms", 0.0),
        cts=_choice(options, "cts", ("on", "off")) == "on",
        fault=fault,
    )


def find_slave(name: str) -> ModbusSlave:
    """The Modbus slaves at the far end of the open ``sim://`` link ``name``
    (the newest, when several ports have opened one of that name);
    LookupError when there is none."""
    return simlink.find_device(name, ModbusSlave, KIND)


simdevices.register_device(KIND, create)
