"""A simulated Modbus RTU slave: the device behind ``sim://NAME?device=modbus``.

It answers Modbus RTU requests like a real RS-485 slave, with wire timing, so
that a PLC program's Modbus master can be tested without hardware. Its
behaviour follows the Modbus specification (Application Protocol V1.1b3 and
the Serial Line guide V1.02); a Siemens S7-200 Freeport Modbus slave (an STL
program answering functions 1-6, 15, 16 after a quiet-line timeout) served as
the example of a real device.

Options (``sim://NAME?device=modbus&id=2&registers=200``; any other option is
a ValueError):

- ``id``: the slave address, 1..247 (default 1).
- ``registers``: the size of each of the four tables, 1..65536 (default
  200): holding registers, input registers, coils and discrete inputs,
  addressed 0..registers-1 (the protocol address, as sent in the request).
- ``values``: how the tables start (default ``pattern``), see
  ``initial_value()``:

    table               pattern (the default)                        index   zero
    holding register k  (k * 257 + 1) & 0xFFFF: 0x0001, 0x0102,      k       0
                        0x0203, ... (0x0000 at k=255, 0x0101 at 256)
    input register k    holding register k ^ 0xFFFF: 0xFFFE, 0xFEFD  k       0
    coil k              on when k % 3 == 0                           k odd   off
    discrete input k    on when k % 4 == 1                           k odd   off

  ``pattern`` makes mistakes visible: a register never holds its own
  address, neighbouring registers differ in both bytes (an off-by-one
  shows), below k = 255 the two bytes of a register differ (byte order
  shows), the 65536 holding values are all different, an input register
  never equals the holding register at the same address (function 3 vs 4),
  and the bit patterns repeat every 3 and 4 bits, never every 8 (bit order
  shows).
- ``turnaround_ms``: extra time the slave takes before replying, after the
  3.5-character silence that ends the request (default 0; a number >= 0).

Framing: a frame is a run of bytes each arriving no later than 3.5 character
times (``simdevices.silence_ns``) after the one before; it ends once the
port's clock reaches its last byte's arrival + 3.5 character times, and the
reply starts then + ``turnaround_ms`` (the first reply byte arrives one
character time later). Frames are answered in order; a reply is queued
behind the one before it.

A frame is ignored, without reply (counted in ``ignored``), when it is
shorter than 4 bytes, longer than 256, has a bad CRC, or is for another
slave. Address 0 is a broadcast: it is executed (writes take effect) but
never answered. Every other frame is a request (counted in ``requests``) and
gets a reply: the normal one, or an exception ``id, function | 0x80, code,
CRC`` with the code checked in this order (as the specification's flow
charts):

- 01 illegal function: a function other than 1, 2, 3, 4, 5, 6, 15, 16;
- 03 illegal data value: a quantity out of range (1..2000 for functions 1
  and 2, 1..125 for 3 and 4, 1..1968 for 15, 1..123 for 16), a byte count
  that does not match the quantity or the bytes sent, a value other than
  0xFF00 / 0x0000 for function 5, or a request of the wrong length;
- 02 illegal data address: start + quantity past the end of the table.

Simplifications: the gap is measured between byte arrivals (the ends of the
characters), so a pause of more than 2.5 character times between two
characters splits a frame (the specification's 3.5 counts from the end of
one character to the start of the next; a master keeping the 1.5-character
limit within a frame is never split); there is no 1.5-character rule; and the
slave does not model half duplex (a request arriving while it is still
replying is answered in its turn).

The tables are lists a test may read and change: ``holding_registers`` and
``input_registers`` (ints 0..0xFFFF), ``coils`` and ``discrete_inputs``
(bools). ``respond(request, slave)`` is the whole protocol without a wire:
request ADU in, reply ADU (or None for silence) out. ``find_slave(name)``
gives the device of the open link ``name``.
"""

from __future__ import annotations

import struct

from ..tlm.comgenius.checksum import crc16_bytes  # TEMP: moves to the Modbus codec
from . import simdevices, wire
from .simdevices import SimDevice, check_options, float_option, silence_ns

KIND = "modbus"
OPTIONS = ("id", "registers", "values", "turnaround_ms")
VALUES = ("pattern", "index", "zero")
TABLES = ("holding", "input", "coil", "discrete")
MAX_ADU = 256

ILLEGAL_FUNCTION = 1
ILLEGAL_DATA_ADDRESS = 2
ILLEGAL_DATA_VALUE = 3

# function: (table attribute, largest quantity)
_READS = {1: ("coils", 2000), 2: ("discrete_inputs", 2000), 3: ("holding_registers", 125), 4: ("input_registers", 125)}


def crc16(data: bytes) -> int:
    """The Modbus CRC (init 0xFFFF, polynomial 0xA001); sent low byte first.

    >>> hex(crc16(bytes.fromhex("02 03 00 00 00 7D")))
    '0xd885'
    """
    return crc16_bytes(data, 0xFFFF)  # the table-driven CRC the formats' %#R uses


def with_crc(frame: bytes) -> bytes:
    """``frame`` followed by its CRC, low byte first.

    >>> with_crc(bytes.fromhex("02 03 00 00 00 7D")).hex(" ")
    '02 03 00 00 00 7d 85 d8'
    """
    return bytes(frame) + crc16(frame).to_bytes(2, "little")


def initial_value(k: int, table: str = "holding", values: str = "pattern") -> int | bool:
    """What entry ``k`` of ``table`` ("holding", "input", "coil" or "discrete")
    holds when a slave starts with option ``values`` (see the module docstring).

    >>> [hex(initial_value(k)) for k in range(3)], hex(initial_value(1, "input"))
    (['0x1', '0x102', '0x203'], '0xfefd')
    >>> [initial_value(k, "coil") for k in range(4)], [initial_value(k, "discrete") for k in range(4)]
    ([True, False, False, True], [False, True, False, False])
    """
    if table not in TABLES:
        raise ValueError(f"table must be one of {', '.join(TABLES)}, not {table!r}")
    if values == "pattern":
        if table == "holding":
            return (k * 257 + 1) & 0xFFFF
        if table == "input":
            return ((k * 257 + 1) & 0xFFFF) ^ 0xFFFF
        return k % 3 == 0 if table == "coil" else k % 4 == 1
    if values == "index":
        return k & 0xFFFF if table in ("holding", "input") else k % 2 == 1
    if values == "zero":
        return 0 if table in ("holding", "input") else False
    raise ValueError(f"values must be one of {', '.join(VALUES)}, not {values!r}")


class ModbusSlave(SimDevice):
    """A Modbus RTU slave on a simulated wire (see the module docstring)."""

    name = KIND

    def __init__(self, slave_id: int = 1, registers: int = 200, values: str = "pattern",
                 turnaround_ms: float = 0.0) -> None:
        if not 1 <= slave_id <= 247:
            raise ValueError(f"{KIND} device: id must be 1..247, not {slave_id}")
        if not 1 <= registers <= 65536:
            raise ValueError(f"{KIND} device: registers must be 1..65536, not {registers}")
        if values not in VALUES:
            raise ValueError(f"{KIND} device: values must be one of {', '.join(VALUES)}, not {values!r}")
        self.slave_id = slave_id
        self.size = registers
        self.values = values
        self.turnaround_ns = round(turnaround_ms * 1_000_000)
        self.holding_registers: list[int] = [initial_value(k, "holding", values) for k in range(registers)]
        self.input_registers: list[int] = [initial_value(k, "input", values) for k in range(registers)]
        self.coils: list[bool] = [initial_value(k, "coil", values) for k in range(registers)]
        self.discrete_inputs: list[bool] = [initial_value(k, "discrete", values) for k in range(registers)]
        self.requests = 0  # frames executed (answered, or broadcast)
        self.ignored = 0  # frames dropped: too short or long, bad CRC, another slave's
        self._frame = bytearray()
        self._last = 0  # arrival time of the frame's last byte

    def receive(self, data: bytes, times_ns: list[int]) -> None:
        gap = silence_ns(self.end.char_ns)
        frame = self._frame
        for byte, t in zip(data, times_ns):
            if frame and t - self._last > gap:
                self._finish(gap)
            if len(frame) <= MAX_ADU:  # one byte over marks the frame as too long
                frame.append(byte)
            self._last = t

    def poll(self, now_ns: int) -> None:
        gap = silence_ns(self.end.char_ns)
        if self._frame and now_ns >= self._last + gap:
            self._finish(gap)

    def _finish(self, gap: int) -> None:
        request = bytes(self._frame)
        self._frame.clear()
        reply = respond(request, self)
        if reply is not None:
            self.end.send(reply, self._last + gap + self.turnaround_ns)

    def __repr__(self) -> str:
        return (f"<ModbusSlave id={self.slave_id} registers={self.size} values={self.values}: "
                f"{self.requests} request(s), {self.ignored} ignored>")


def respond(request: bytes, slave: ModbusSlave) -> bytes | None:
    """Execute one request ADU (address, PDU, CRC) on ``slave``; the reply
    ADU, or None when the slave stays silent (ignored frame or broadcast).
    Counts the frame in ``slave.requests`` or ``slave.ignored``.

    >>> slave = ModbusSlave(slave_id=2)
    >>> respond(with_crc(bytes.fromhex("02 03 00 00 00 02")), slave).hex(" ")
    '02 03 04 00 01 01 02 18 a2'
    >>> respond(with_crc(bytes.fromhex("02 03 00 c7 00 02")), slave).hex(" ")
    '02 83 02 30 f1'
    >>> respond(with_crc(bytes.fromhex("03 03 00 00 00 02")), slave) is None
    True
    """
    if not 4 <= len(request) <= MAX_ADU or crc16(request[:-2]) != int.from_bytes(request[-2:], "little"):
        slave.ignored += 1
        return None
    address = request[0]
    if address != 0 and address != slave.slave_id:
        slave.ignored += 1
        return None
    slave.requests += 1
    pdu = _execute(slave, request[1:-2])
    return None if address == 0 else with_crc(bytes([address]) + pdu)


def _exception(function: int, code: int) -> bytes:
    return bytes([function | 0x80, code])


def _execute(slave: ModbusSlave, pdu: bytes) -> bytes:
    """The reply PDU to ``pdu`` (function code + data), after executing it."""
    function, data = pdu[0], pdu[1:]
    if function in _READS:
        attribute, most = _READS[function]
        if len(data) != 4:
            return _exception(function, ILLEGAL_DATA_VALUE)
        start, count = struct.unpack(">HH", data)
        if not 1 <= count <= most:
            return _exception(function, ILLEGAL_DATA_VALUE)
        table = getattr(slave, attribute)
        if start + count > len(table):
            return _exception(function, ILLEGAL_DATA_ADDRESS)
        if function <= 2:
            packed = pack_bits(table[start:start + count])
        else:
            packed = struct.pack(f">{count}H", *table[start:start + count])
        return bytes([function, len(packed)]) + packed
    if function in (5, 6):
        if len(data) != 4:
            return _exception(function, ILLEGAL_DATA_VALUE)
        address, value = struct.unpack(">HH", data)
        if function == 5 and value not in (0x0000, 0xFF00):
            return _exception(function, ILLEGAL_DATA_VALUE)
        if address >= slave.size:
            return _exception(function, ILLEGAL_DATA_ADDRESS)
        if function == 5:
            slave.coils[address] = value == 0xFF00
        else:
            slave.holding_registers[address] = value
        return pdu
    if function in (15, 16):
        if len(data) < 5:
            return _exception(function, ILLEGAL_DATA_VALUE)
        start, count, byte_count = struct.unpack(">HHB", data[:5])
        most, needed = (1968, (count + 7) // 8) if function == 15 else (123, 2 * count)
        if not 1 <= count <= most or byte_count != needed or len(data) != 5 + byte_count:
            return _exception(function, ILLEGAL_DATA_VALUE)
        if start + count > slave.size:
            return _exception(function, ILLEGAL_DATA_ADDRESS)
        if function == 15:
            slave.coils[start:start + count] = unpack_bits(data[5:], count)
        else:
            slave.holding_registers[start:start + count] = struct.unpack(f">{count}H", data[5:])
        return pdu[:5]
    return _exception(function, ILLEGAL_FUNCTION)


def pack_bits(bits) -> bytes:
    """Bits 8 a byte, the first in the lowest bit of the first byte; unused high bits 0.

    >>> pack_bits([True, False, False, True, False, False, True, False, False, True]).hex(" ")
    '49 02'
    """
    out = bytearray((len(bits) + 7) // 8)
    for i, bit in enumerate(bits):
        if bit:
            out[i >> 3] |= 1 << (i & 7)
    return bytes(out)


def unpack_bits(data: bytes, count: int) -> list[bool]:
    """The first ``count`` bits of ``data`` (lowest bit of the first byte first)."""
    return [bool(data[i >> 3] >> (i & 7) & 1) for i in range(count)]


def _int_option(options: dict[str, str], key: str, default: int, low: int, high: int) -> int:
    if key not in options:
        return default
    text = options[key]
    value = int(text) if text.isascii() and text.isdigit() else None
    if value is None or not low <= value <= high:
        raise ValueError(f"{KIND} device: {key} must be an integer {low}..{high}, not {text!r}")
    return value


def create(options: dict[str, str]) -> ModbusSlave:
    """The ``modbus`` device factory: ``options`` as given in the URL."""
    check_options(KIND, options, OPTIONS)
    return ModbusSlave(
        slave_id=_int_option(options, "id", 1, 1, 247),
        registers=_int_option(options, "registers", 200, 1, 65536),
        values=options.get("values", "pattern"),
        turnaround_ms=float_option(KIND, options, "turnaround_ms", 0.0),
    )


def find_slave(name: str) -> ModbusSlave:
    """The Modbus slave at the far end of the open ``sim://`` link ``name``
    (the newest, when several ports have opened one of that name);
    LookupError when there is none."""
    links = wire.device_links(name)
    device = links[-1].device if links else None
    if not isinstance(device, ModbusSlave):
        raise LookupError(f"no open sim:// link {name!r} to a {KIND} device")
    return device


simdevices.register_device(KIND, create)
