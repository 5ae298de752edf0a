"""The simulated Modbus RTU slave (``sim://NAME?device=modbus``).

Replies are compared byte for byte with a real pymodbus 3.16 server: a
``ModbusSerialServer`` with RTU framing listening on
``socket://127.0.0.1:PORT`` (TCP, no socat), its datastore holding the same
values (``SimDevice`` with four separate tables, 0-based: what the request
says is what it reads). Every request goes to both our ``respond()`` (on one
module-wide slave, the twin of the pymodbus device) and pymodbus, over a new
TCP connection each time, so the two stay in step whatever the order of the
tests. Where pymodbus departs from the Modbus specification, the test
states both what the specification wants (what we send) and what pymodbus
3.16.1 sends (see ``DISAGREEMENTS``).

Then the wire: timing of the reply on a fake clock at 38400 8N1, frames
split on 3.5 characters of silence, back-to-back queries.
"""

from __future__ import annotations

import asyncio
import doctest
import itertools
import re
import socket
import subprocess
import sys
import threading
import time

import pytest
import serial

import softplc_lite.ports.urlhandler  # noqa: F401  (registers sim://)
from softplc_lite.ports import modbus_slave, simdevices, simlink
from softplc_lite.ports.modbus_slave import (
    ModbusSlave,
    find_slave,
    initial_value,
    pack_bits,
    respond,
    unpack_bits,
    with_crc,
)

# The pymodbus comparison writes to one module-wide peer and twin, and later
# tests read what earlier ones wrote: with xdist, the module keeps to one
# worker, in order (--dist loadgroup in pyproject.toml).
pytestmark = pytest.mark.xdist_group("modbus_slave")

CHAR = 260_417  # one character at 38400 8N1, ns
GAP = 911_460  # 3.5 characters
SLAVE = 2
SIZE = 200
QUERY = bytes.fromhex("02 03 00 00 00 7D 85 D8")

_names = itertools.count()


def fresh() -> str:
    return f"mb_{next(_names)}"


def adu(text: str) -> bytes:
    """The request ``text`` (hex, without CRC) with its CRC."""
    return with_crc(bytes.fromhex(text))


def exception(function: int, code: int, slave: int = SLAVE) -> bytes:
    return with_crc(bytes([slave, function | 0x80, code]))


# - - - a real pymodbus server - - -


class PymodbusPeer:
    """A pymodbus ModbusSerialServer on socket://127.0.0.1:PORT (RTU framing),
    run by an asyncio loop in a background thread."""

    SILENCE_S = 0.3  # how long a request must stay unanswered to count as silence

    def __init__(self) -> None:
        pytest.importorskip("pymodbus", minversion="3.16.1")
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, name="pymodbus-peer", daemon=True)
        self.thread.start()
        try:
            self.server, self.port = self._call(self._start())
        except BaseException:
            self._stop_loop()
            raise

    def _call(self, coroutine, timeout: float = 5):
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result(timeout)

    async def _start(self):
        from pymodbus.framer import FramerType
        from pymodbus.server import ModbusSerialServer
        from pymodbus.simulator import DataType, SimData, SimDevice

        def table(name: str, datatype):
            values = [initial_value(k, name) for k in range(SIZE)]
            return [SimData(0, values=values, datatype=datatype)]

        device = SimDevice(SLAVE, simdata=(
            table("coil", DataType.BITS), table("discrete", DataType.BITS),
            table("holding", DataType.REGISTERS), table("input", DataType.REGISTERS),
        ))

        def drop_other_ids(sending, pdu):
            # an RS-485 slave is silent to other addresses (pymodbus would send exception 04)
            return pdu if sending or pdu.dev_id in (0, SLAVE) else None

        server = ModbusSerialServer(device, framer=FramerType.RTU, port="socket://127.0.0.1:0",
                                    broadcast_enable=True, trace_pdu=drop_other_ids)
        await server.serve_forever(background=True)
        return server, server.transport.sockets[0].getsockname()[1]

    def ask(self, request: bytes, expect: int) -> bytes:
        """pymodbus's raw reply to ``request``: read until ``expect`` bytes
        (then a moment more, to catch extra bytes), or for SILENCE_S when
        ``expect`` is 0."""
        with socket.create_connection(("127.0.0.1", self.port), timeout=2) as sock:
            sock.sendall(request)
            reply = b""
            deadline = time.monotonic() + (2.0 if expect else self.SILENCE_S)
            while time.monotonic() < deadline:
                wait = 0.01 if expect and len(reply) >= expect else deadline - time.monotonic()
                sock.settimeout(max(wait, 0.001))
                try:
                    data = sock.recv(4096)
                except socket.timeout:
                    if expect and len(reply) >= expect:
                        break
                    continue
                if not data:
                    break
                reply += data
            return reply

    def close(self) -> None:
        try:
            self._call(self._shutdown())
        finally:
            self._stop_loop()

    async def _shutdown(self) -> None:
        await self.server.shutdown()
        tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    def _stop_loop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)
        assert not self.thread.is_alive(), "the pymodbus loop thread did not stop"
        self.loop.close()


@pytest.fixture(scope="module")
def peer():
    peer = PymodbusPeer()
    yield peer
    peer.close()


@pytest.fixture(scope="module")
def twin() -> ModbusSlave:
    """Our slave holding what the pymodbus device holds (same requests, same order)."""
    return ModbusSlave(slave_id=SLAVE, registers=SIZE)


def both(peer: PymodbusPeer, twin: ModbusSlave, request: bytes, expect: int | None = None) -> tuple[bytes | None, bytes]:
    """Our reply and pymodbus's; pymodbus is read until it sent ``expect``
    bytes (by default as many as we send; 0: waits to see silence)."""
    ours = respond(request, twin)
    if expect is None:
        expect = len(ours) if ours else 0
    return ours, peer.ask(request, expect)


def regs(values) -> str:
    return " ".join(f"{v:04X}" for v in values)


# - - - initial values - - -


def test_initial_values_are_the_documented_ones():
    slave = ModbusSlave()
    assert slave.slave_id == 1 and slave.size == 200
    assert slave.holding_registers[:4] == [0x0001, 0x0102, 0x0203, 0x0304]
    assert slave.holding_registers[199] == 199 * 257 + 1
    assert slave.input_registers[:2] == [0xFFFE, 0xFEFD]
    assert slave.coils[:7] == [True, False, False, True, False, False, True]
    assert slave.discrete_inputs[:6] == [False, True, False, False, False, True]
    assert [initial_value(k) for k in (255, 256, 65535)] == [0x0000, 0x0101, 0xFF00]
    index = ModbusSlave(values="index", registers=70000 // 2)
    assert index.holding_registers[34999] == 34999 and index.input_registers[3] == 3
    assert index.coils[:3] == [False, True, False] == index.discrete_inputs[:3]
    zero = ModbusSlave(values="zero", registers=3)
    assert zero.holding_registers == [0, 0, 0] and zero.coils == [False] * 3
    with pytest.raises(ValueError, match="table must be one of"):
        initial_value(0, "holdings")


def test_pymodbus_reads_the_same_values_at_the_same_addresses(peer):
    """No address offset: pymodbus's SimData is 0-based like the protocol (the
    deprecated ModbusSequentialDataBlock is not: it subtracts 1)."""
    reply = peer.ask(adu("02 03 00 00 00 03"), 11)
    assert reply == adu("02 03 06 0001 0102 0203")
    reply = peer.ask(adu("02 04 00 C5 00 02"), 9)
    assert reply[3:7] == bytes.fromhex(regs([initial_value(197, "input"), initial_value(198, "input")]))
    reply = peer.ask(adu("02 01 00 00 00 C8"), 30)
    assert unpack_bits(reply[3:-2], SIZE) == [initial_value(k, "coil") for k in range(SIZE)]
    reply = peer.ask(adu("02 02 00 00 00 C8"), 30)
    assert unpack_bits(reply[3:-2], SIZE) == [initial_value(k, "discrete") for k in range(SIZE)]


# - - - byte for byte against pymodbus - - -

SAME_AS_PYMODBUS = [
    # reads
    ("read 125 holding registers", "02 03 00 00 00 7D"),
    ("read 1 holding register at the end", "02 03 00 C7 00 01"),
    ("read 3 input registers", "02 04 00 0A 00 03"),
    ("read 125 input registers at the end", "02 04 00 4B 00 7D"),
    ("read 1 coil", "02 01 00 00 00 01"),
    ("read 10 coils", "02 01 00 00 00 0A"),
    ("read 19 coils from 5", "02 01 00 05 00 13"),
    ("read all 200 coils", "02 01 00 00 00 C8"),
    ("read 16 discrete inputs", "02 02 00 00 00 10"),
    ("read 37 discrete inputs from 163", "02 02 00 A3 00 25"),
    # writes
    ("write coil 1 on", "02 05 00 01 FF 00"),
    ("write coil 0 off", "02 05 00 00 00 00"),
    ("write coil 199 on", "02 05 00 C7 FF 00"),
    ("write register 7", "02 06 00 07 BE EF"),
    ("write register 199", "02 06 00 C7 12 34"),
    ("write 10 coils from 3", "02 0F 00 03 00 0A 02 CD 01"),
    ("write 16 coils from 184", "02 0F 00 B8 00 10 02 5A A5"),
    ("write 3 registers from 20", "02 10 00 14 00 03 06 1111 2222 3333"),
    ("write 123 registers from 77", "02 10 00 4D 00 7B F6 " + " ".join(f"{0xA000 + i:04X}" for i in range(123))),
    # illegal data address (02)
    ("read registers past the end", "02 03 00 C6 00 03"),
    ("read registers from the end", "02 03 00 C8 00 01"),
    ("read input registers past the end", "02 04 00 4C 00 7D"),
    ("read coils well past the end", "02 01 00 C8 00 09"),
    ("read discrete inputs at 65535", "02 02 FF FF 00 01"),
    ("write coil past the end", "02 05 00 D0 FF 00"),
    ("write register past the end", "02 06 00 C8 00 01"),
    ("write coils past the end", "02 0F 00 C8 00 10 02 FF FF"),
    ("write registers past the end", "02 10 00 C7 00 02 04 0001 0002"),
    # illegal data value (03)
    ("write 0 registers", "02 10 00 00 00 00 00"),
    ("write registers, byte count not 2 x quantity", "02 10 00 00 00 02 02 00 01"),
    ("write coils, byte count not (quantity + 7) / 8", "02 0F 00 00 00 08 02 FF 00"),
]


@pytest.mark.parametrize("request_hex", [pytest.param(h, id=name) for name, h in SAME_AS_PYMODBUS])
def test_same_reply_as_pymodbus(peer, twin, request_hex):
    request = adu(request_hex)
    ours, theirs = both(peer, twin, request)
    assert ours is not None
    assert ours.hex(" ") == theirs.hex(" ")


def test_the_exception_cases_above_are_what_the_spec_says(twin):
    """The table above covers exceptions 02 and 03 for every function."""
    codes = {}
    for name, text in SAME_AS_PYMODBUS:
        probe = ModbusSlave(slave_id=SLAVE, registers=SIZE)
        reply = respond(adu(text), probe)
        if reply[1] & 0x80:
            codes.setdefault(reply[2], set()).add(reply[1] & 0x7F)
    assert codes == {2: {1, 2, 3, 4, 5, 6, 15, 16}, 3: {15, 16}}


def test_tables_still_agree_after_the_writes(peer, twin):
    for start in (0, 125):
        count = min(125, SIZE - start)
        request = adu(f"02 03 {start:04X} {count:04X}")
        ours, theirs = both(peer, twin, request)
        assert ours == theirs
    ours, theirs = both(peer, twin, adu(f"02 01 0000 {SIZE:04X}"))
    assert ours == theirs
    assert twin.holding_registers[7] == 0xBEEF and twin.holding_registers[77:80] == [0xA000, 0xA001, 0xA002]
    assert twin.coils[:5] == [False, True, False, True, False]  # 0 off, 1 on, 3.. from CD = 1100 1101


# Where pymodbus 3.16.1 departs from the Modbus specification (Application
# Protocol V1.1b3, section 6 and the flow charts): (request, what the
# specification wants, what pymodbus sends; None = silence).
DISAGREEMENTS = [
    pytest.param("02 03 00 00 00 00", exception(3, 3), exception(0, 1),
                 id="quantity 0 for function 3: pymodbus fails to decode and answers function 0x80, code 01"),
    pytest.param("02 04 00 00 00 7E", exception(4, 3), exception(0, 1),
                 id="126 input registers: same"),
    pytest.param("02 01 00 00 07 D1", exception(1, 3), exception(0, 1),
                 id="2001 coils: same"),
    pytest.param("02 0F 00 00 07 B1 F7" + " 00" * 247, exception(15, 3), exception(15, 2),
                 id="1969 coils for function 15: pymodbus accepts up to 2000 (limit 1968), then finds the address bad"),
    pytest.param("02 05 00 00 12 34", exception(5, 3), adu("02 05 00 00 FF 00"),
                 id="function 5 value 0x1234: pymodbus takes any non-zero value as ON"),
    pytest.param("02 01 00 C7 00 02", exception(1, 2), adu("02 01 01 01"),
                 id="coils 199-200 of 200: pymodbus pads bit tables to a multiple of 16 and reads coil 200"),
    pytest.param("02 10 00 00 00 7C F8" + " 00" * 248, None, exception(16, 3),
                 id="124 registers for function 16: a 257-byte frame, over the RTU maximum of 256; we ignore it"),
    pytest.param("02 41 00 00", exception(0x41, 1), None,
                 id="function 0x41: pymodbus does not know it and stays silent (no exception 01)"),
    pytest.param("02 07", exception(7, 1), adu("02 07 00"),
                 id="function 7 (read exception status): pymodbus answers it; our slave has only 1-6, 15, 16"),
]


@pytest.mark.parametrize("request_hex,spec,pymodbus_reply", DISAGREEMENTS)
def test_where_pymodbus_disagrees_we_follow_the_spec(peer, twin, request_hex, spec, pymodbus_reply):
    # none of these changes the tables on either side (function 5 above sets coil 0,
    # already on in pymodbus), so the twin stays in step
    ours, theirs = both(peer, twin, adu(request_hex), expect=len(pymodbus_reply or b""))
    assert (ours or b"").hex(" ") == (spec or b"").hex(" ")
    assert theirs.hex(" ") == (pymodbus_reply or b"").hex(" ")


@pytest.mark.parametrize("request_hex,code", [
    ("02 03 00 00 00 01 00", 3),  # one byte too many for function 3
    ("02 06 00 01 00", 3),  # one byte short
    ("02 05", 3),
    ("02 10 00 00 00 02 04 00 01", 3),  # byte count 4, 2 bytes sent
    ("02 10 00 00 00 01 02 00 01 00", 3),  # one byte too many
    ("02 0F 00 00 00 08", 3),  # no byte count
    ("02 0F 00 00 07 B0 F6" + " 00" * 246, 2),  # 1968 coils: quantity fine, address not
    ("02 01 00 00 07 D0", 2),  # 2000 coils: quantity fine, address not
    ("02 10 00 C8 00 00 00", 3),  # the value check comes before the address check
    ("02 2B 0E 01 00", 1),
    ("02 00", 1),
])
def test_spec_only_exceptions(request_hex, code):
    """Requests pymodbus cannot frame (its RTU framer trusts the byte count
    and the function's length): compared with the specification only."""
    slave = ModbusSlave(slave_id=SLAVE)
    before = (list(slave.holding_registers), list(slave.coils))
    request = adu(request_hex)
    assert respond(request, slave) == exception(request[1], code)
    assert (slave.holding_registers, slave.coils) == before
    assert (slave.requests, slave.ignored) == (1, 0)


# - - - silence - - -


@pytest.mark.parametrize("frame", [
    pytest.param(adu("02 03 00 00 00 01")[:-1] + b"\x00", id="bad CRC"),
    pytest.param(adu("03 03 00 00 00 01"), id="another slave id"),
    pytest.param(adu("F8 06 00 00 00 01"), id="id 248"),
])
def test_silence_like_pymodbus(peer, twin, frame):
    ignored = twin.ignored
    ours, theirs = both(peer, twin, frame)
    assert ours is None and theirs == b""
    assert twin.ignored == ignored + 1


def test_broadcast_write_executes_without_reply_like_pymodbus(peer, twin):
    ours, theirs = both(peer, twin, adu("00 06 00 0B 5A 5A"))
    assert ours is None and theirs == b""
    assert twin.holding_registers[11] == 0x5A5A
    ours, theirs = both(peer, twin, adu("02 03 00 0B 00 01"))
    assert ours == theirs == adu("02 03 02 5A 5A")


def test_broadcast_of_every_write_function_and_a_read():
    slave = ModbusSlave(slave_id=9, registers=10)
    for text in ("00 05 00 01 00 00", "00 06 00 02 00 63", "00 0F 00 04 00 03 01 05",
                 "00 10 00 08 00 02 04 0102 0304", "00 03 00 00 00 01", "00 03 00 00 00 00"):
        assert respond(adu(text), slave) is None
    assert slave.coils[:7] == [True, False, False, True, True, False, True]
    assert slave.holding_registers[2] == 0x63 and slave.holding_registers[8:] == [0x0102, 0x0304]
    assert (slave.requests, slave.ignored) == (6, 0)


@pytest.mark.parametrize("frame", [b"", b"\x02", b"\x02\x03", adu("02")[:3], b"\x02" * 257])
def test_short_and_overlong_frames_are_ignored(frame):
    slave = ModbusSlave(slave_id=SLAVE)
    assert respond(frame, slave) is None
    assert (slave.requests, slave.ignored) == (0, 1)


def test_a_four_byte_frame_is_a_request():
    assert respond(adu("02 03"), ModbusSlave(slave_id=SLAVE)) == exception(3, 3)


def test_bit_packing():
    bits = [k % 3 == 0 for k in range(19)]
    assert pack_bits(bits) == bytes([0x49, 0x92, 0x04])
    assert unpack_bits(pack_bits(bits), 19) == bits
    assert pack_bits([]) == b""


# - - - over the wire - - -


@pytest.fixture(autouse=True)
def no_links_left():
    """Every link a test opened is gone once its ports are closed."""
    yield
    assert not any(name.startswith("mb_") for name in simlink.link_names())


def test_reply_timing_over_the_wire(opened, clock):
    name = fresh()
    port = opened(f"sim://{name}?device=modbus&id=2&registers=200", clock, baudrate=38400)
    assert (port.bytesize, port.parity, port.stopbits) == (8, "N", 1)
    slave = find_slave(name)
    port.write(QUERY)
    query_done = 8 * CHAR
    assert query_done == 2_083_336
    done = query_done + GAP + 255 * CHAR
    assert done == 2_083_336 + 911_460 + 66_406_335
    clock.now = query_done + GAP + CHAR - 1
    assert port.in_waiting == 0
    clock.now += 1  # the first reply byte
    assert port.in_waiting == 1
    clock.now = done - 1
    assert port.in_waiting == 254
    clock.now = done
    reply = port.read(300)
    expected = [initial_value(k) for k in range(125)]
    assert reply == with_crc(bytes.fromhex("02 03 FA " + regs(expected)))
    assert len(reply) == 255
    assert reply == respond(QUERY, ModbusSlave(slave_id=2))
    assert (slave.requests, slave.ignored) == (1, 0)


def test_looking_late_does_not_delay_the_reply(opened, clock):
    port = opened(f"sim://{fresh()}?device=modbus&id=2", clock, baudrate=38400)
    port.write(QUERY)
    clock.now = 100_000_000  # first look long after: the reply was timed from the frame's end
    assert port.out_waiting == 0
    assert len(port.read(300)) == 255


def test_no_reply_while_the_query_is_still_arriving(opened, clock):
    name = fresh()
    port = opened(f"sim://{name}?device=modbus&id=2", clock, baudrate=38400)
    slave = find_slave(name)
    # the master pauses 1 character after byte 4 (allowed: under 1.5 characters)
    port.write(QUERY[:4])
    clock.now = 5 * CHAR
    port.write(QUERY[4:])
    last = 9 * CHAR
    for t in range(0, last + GAP, CHAR // 4):
        clock.now = t
        assert port.in_waiting == 0
        assert (slave.requests, slave.ignored) == (0, 0), t
    clock.now = last + GAP
    assert port.in_waiting == 0 and slave.requests == 1  # the frame ends; the reply starts
    clock.now = last + GAP + 255 * CHAR
    assert len(port.read(300)) == 255


def test_a_frame_ends_after_3_5_characters_between_arrivals(opened, clock):
    name = fresh()
    port = opened(f"sim://{name}?device=modbus&id=2", clock, baudrate=38400)
    slave = find_slave(name)
    # each byte arrives exactly 3.5 characters after the one before: still one frame
    for i, byte in enumerate(QUERY):
        clock.now = i * GAP
        port.write(bytes([byte]))
    clock.now = 7 * GAP + CHAR + GAP + 255 * CHAR
    assert len(port.read(300)) == 255
    # 1 ns more: every byte is a frame of its own, each ignored, no reply
    start = clock.now
    for i, byte in enumerate(QUERY):
        clock.now = start + i * (GAP + 1)
        port.write(bytes([byte]))
    clock.now += 1_000_000_000
    assert port.in_waiting == 0
    assert (slave.requests, slave.ignored) == (1, 8)


def test_two_queries_back_to_back_are_each_answered(opened, clock):
    name = fresh()
    port = opened(f"sim://{name}?device=modbus&id=2", clock, baudrate=38400)
    second = adu("02 04 00 0A 00 02")
    second_reply = adu("02 04 04 " + regs([initial_value(10, "input"), initial_value(11, "input")]))
    # the second query follows the first after exactly 3.5 characters of silence
    port.write(QUERY)
    clock.now = 8 * CHAR + GAP
    port.write(second)
    end1 = 8 * CHAR + GAP + 255 * CHAR
    end2 = end1 + len(second_reply) * CHAR  # queued behind the first reply
    clock.now = end1
    assert port.read(300) == respond(QUERY, ModbusSlave(slave_id=2))
    clock.now = end2 - 1
    assert port.in_waiting == len(second_reply) - 1
    clock.now = end2
    assert port.read(300) == second_reply
    # a master that sends the next query as soon as the reply is in
    port.write(second)
    clock.now = end2 + 8 * CHAR + GAP + len(second_reply) * CHAR
    assert port.read(300) == second_reply
    assert find_slave(name).requests == 3


def test_turnaround_delays_the_reply(opened, clock):
    port = opened(f"sim://{fresh()}?device=modbus&id=2&turnaround_ms=2.5", clock, baudrate=38400)
    port.write(QUERY)
    first = 8 * CHAR + GAP + 2_500_000 + CHAR
    clock.now = first - 1
    assert port.in_waiting == 0
    clock.now = first
    assert port.in_waiting == 1


def test_writes_over_the_wire_change_the_slave_and_exceptions_come_back(opened, clock):
    name = fresh()
    port = opened(f"sim://{name}?device=modbus&id=17&registers=10&values=zero", clock, baudrate=19200)
    slave = find_slave(name)
    assert slave.slave_id == 17 and len(slave.holding_registers) == 10
    port.write(adu("11 10 00 08 00 02 04 CAFE F00D"))
    clock.now = 50_000_000
    assert port.read(100) == adu("11 10 00 08 00 02")
    assert slave.holding_registers[8:] == [0xCAFE, 0xF00D]
    slave.holding_registers[0] = 0x0102  # a test may change the tables
    port.write(adu("11 03 00 00 00 0B"))
    clock.now = 100_000_000
    assert port.read(100) == exception(3, 2, slave=17)
    port.write(adu("11 03 00 00 00 01"))
    clock.now = 150_000_000
    assert port.read(100) == adu("11 03 02 0102")
    port.write(adu("00 05 00 09 FF 00"))  # broadcast: done, no reply
    clock.now = 200_000_000
    assert port.in_waiting == 0 and slave.coils[9] is True


def test_rate_unlimited_answers_at_once(opened, clock):
    port = opened(f"sim://{fresh()}?device=modbus&id=2&rate=unlimited", clock)
    port.write(adu("02 06 00 00 12 34"))
    assert port.read(100) == adu("02 06 00 00 12 34")


# - - - options, registration, names - - -


@pytest.mark.parametrize("options,message", [
    ("id=0", "id must be an integer 1..247, not '0'"),
    ("id=248", "id must be an integer 1..247"),
    ("id=two", "id must be an integer"),
    ("registers=0", "registers must be an integer 1..65536"),
    ("registers=65537", "registers must be an integer 1..65536"),
    ("values=random", "values must be one of pattern, index, zero"),
    ("turnaround_ms=-1", "turnaround_ms must be a number >= 0"),
    ("delay_ms=5", r"unknown option 'delay_ms' \(known: id, registers, values, framing, turnaround_ms, "
                   r"cts_delay_ms, cts, cut, pause_after, pause_ms, garbage, bad_crc, silent\)"),
    ("framing=binary", "framing must be rtu or ascii, not 'binary'"),
    ("garbage=zz", "garbage must be hex bytes"),
    ("id=2,300", r"id must be an integer 1..247, not '300' \(several: id=1,2,5\)"),
])
def test_bad_options(options, message):
    name = fresh()
    with pytest.raises(serial.SerialException) as info:
        serial.serial_for_url(f"sim://{name}?device=modbus&{options}")
    assert re.search("modbus device: " + message, str(info.value)), str(info.value)
    assert name not in simlink.link_names()
    with pytest.raises(ValueError, match=message):
        simdevices.create_device("modbus", dict([options.split("=")]))


def test_unknown_kind_lists_modbus():
    with pytest.raises(ValueError, match=r"unknown device kind 'nope' \(known: echo, modbus, modbus_master, scripted\)"):
        simdevices.create_device("nope", {})


def test_create_device_imports_the_modbus_module_itself():
    code = (
        "import sys\n"
        "from softplc_lite.ports import simdevices\n"
        "assert 'softplc_lite.ports.modbus_slave' not in sys.modules\n"
        "device = simdevices.create_device('modbus', {'id': '5'})\n"
        "print(type(device).__name__, device.slave_id, sorted(simdevices.DEVICES))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["ModbusSlave", "5", "['echo',", "'modbus']"]


def test_registration_is_the_same_factory_either_way():
    assert simdevices.DEVICES["modbus"] is modbus_slave.create
    assert simdevices.BUILTIN_DEVICES["modbus"] == "softplc_lite.ports.modbus_slave:create"
    simdevices.register_device("modbus", modbus_slave.create)  # harmless


def test_find_slave_gives_the_newest_open_device_of_a_name(clock):
    name = fresh()
    port = serial.serial_for_url(f"sim://{name}?device=modbus", baudrate=38400)
    try:
        first = find_slave(name)
        assert isinstance(first, ModbusSlave)
        second_port = serial.serial_for_url(f"sim://{name}?device=modbus&id=5")  # another runtime's slave
        assert find_slave(name).slave_id == 5 and find_slave(name) is not first
        second_port.close()
        assert find_slave(name) is first
        assert repr(port).endswith(f"of link '{name}' to modbus device>")
    finally:
        port.close()
    with pytest.raises(LookupError, match=f"no open sim:// link '{name}'"):
        find_slave(name)
    again = serial.serial_for_url(f"sim://{name}?device=modbus&id=3")
    try:
        assert find_slave(name).slave_id == 3  # a new device: fresh tables
    finally:
        again.close()
    with pytest.raises(LookupError):
        find_slave("mb_never_opened")


def test_module_doctests():
    result = doctest.testmod(modbus_slave)
    assert result.attempted > 0 and result.failed == 0
