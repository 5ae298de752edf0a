"""The Modbus RTU slave written in ladder (programs/modbus_slave) on the
simulated wire: every function against the project's reference slave (the
simulated slave of softplc_lite.ports.modbus_slave, itself checked against
pymodbus), every function at its limits, exceptions, silence and recovery,
timing, both executors. pymodbus as the master is in
test_modbus_slave_pymodbus.py; two runtimes on one wire in
test_modbus_slave_masters.py."""

from __future__ import annotations

import struct

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from softplc_lite.datatable.table import to_signed
from softplc_lite.ladder.engine import Mode
from softplc_lite.modbus.packing import pack_bits
from softplc_lite.ports.modbus_master import find_master
from softplc_lite.ports.modbus_slave import ModbusSlave, respond, with_crc

from helpers.modbus_slave_app import WireSlave, slave_runner

SIZE = 200  # every table of the reference slave; the ladder's limits are set to match


def req(text: str) -> bytes:
    return with_crc(bytes.fromhex(text))


def load_reference_tables(slave: WireSlave, ref: ModbusSlave, size: int) -> None:
    """Give the ladder slave the reference slave's tables and limits."""
    t = slave.table
    t.reference(f"N11:{size - 1}")
    for k in range(size):
        t.write(f"N10:{k}", to_signed(ref.holding_registers[k]))
        t.write(f"N11:{k}", to_signed(ref.input_registers[k]))
    for w in range((size + 15) // 16):
        coils = sum(1 << b for b in range(16) if w * 16 + b < size and ref.coils[w * 16 + b])
        inputs = sum(1 << b for b in range(16) if w * 16 + b < size and ref.discrete_inputs[w * 16 + b])
        t.write_word(f"O:{w:o}", coils)
        t.write_word(f"I:{w:o}", inputs)
    for addr, value in (("N9:0", size), ("N9:1", size), ("N9:2", size)):
        t.write(addr, value)


@pytest.fixture
def slave(tmp_path):
    s = WireSlave(tmp_path)
    yield s
    s.close()


# -- requests, as a master may send them --------------------------------------------------------

address = st.one_of(st.integers(0, SIZE + 10), st.sampled_from([0xFFFF, 0x8000, 0x7FFF]))


@st.composite
def requests(draw) -> bytes:
    unit = draw(st.sampled_from([1] * 12 + [0, 2]))  # mostly ours; broadcasts and another slave's
    function = draw(st.sampled_from([1, 2, 3, 4, 5, 6, 15, 16] * 3 + [0, 7, 8, 17, 43, 0x81]))
    start = draw(address)
    if function == 4 and start == 0:
        start = 1  # input register 0 is the example program's scan counter
    if function in (1, 2):
        body = struct.pack(">HH", start, draw(st.one_of(st.integers(0, 40), st.integers(1990, 2010))))
    elif function in (3, 4):
        body = struct.pack(">HH", start, draw(st.one_of(st.integers(0, 20), st.integers(120, 130))))
    elif function == 5:
        body = struct.pack(">HH", start, draw(st.sampled_from([0xFF00, 0x0000, 0x0001, 0xFFFF, 0x00FF])))
    elif function == 6:
        body = struct.pack(">HH", start, draw(st.integers(0, 0xFFFF)))
    elif function == 15:
        count = draw(st.one_of(st.integers(0, 40), st.integers(1960, 1975)))
        nbytes = (count + 7) // 8
        nbytes = draw(st.sampled_from([nbytes] * 4 + [max(0, nbytes - 1), nbytes + 1]))
        data = bytes(draw(st.lists(st.integers(0, 255), min_size=min(nbytes, 246), max_size=min(nbytes, 246))))
        body = struct.pack(">HHB", start, count, len(data)) + data
    elif function == 16:
        count = draw(st.one_of(st.integers(0, 12), st.integers(120, 125)))
        nbytes = draw(st.sampled_from([2 * count] * 4 + [2 * count + 2, max(0, 2 * count - 2)]))
        data = bytes(draw(st.lists(st.integers(0, 255), min_size=min(nbytes, 246), max_size=min(nbytes, 246))))
        body = struct.pack(">HHB", start, count, len(data)) + data
    else:
        body = bytes(draw(st.lists(st.integers(0, 255), max_size=4)))
    return with_crc(bytes([unit, function]) + body)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(frames=st.lists(requests(), min_size=1, max_size=6))
def test_every_request_gets_the_reference_slaves_reply(slave, frames):
    """The ladder answers every request byte for byte as the reference slave
    does (or stays silent when it does), and both end with the same tables."""
    if not hasattr(slave, "reference"):
        slave.reference = ModbusSlave(slave_id=1, registers=SIZE)
        load_reference_tables(slave, slave.reference, SIZE)
    ref = slave.reference
    for frame in frames:
        expected = respond(frame, ref)
        assert slave.transact(frame) == expected, frame.hex(" ")
    t = slave.table
    assert [t.read(f"N10:{k}") for k in range(SIZE)] == [to_signed(v) for v in ref.holding_registers]
    coils = [t.read_word(f"O:{w:o}") & 0xFFFF for w in range(SIZE // 16)]
    assert coils == [sum(1 << b for b in range(16) if ref.coils[w * 16 + b]) for w in range(SIZE // 16)]
    assert slave.engine.mode is Mode.RUN and slave.engine.fault is None


def test_every_function_at_its_limits(tmp_path):
    s = WireSlave(tmp_path, sets=("N9:0=2048", "N9:2=125"))
    t = s.table
    t.reference("N11:124")
    try:
        for k in range(1000):
            t.write(f"N10:{k}", to_signed((k * 31 + 7) & 0xFFFF))
        for k in range(125):
            t.write(f"N11:{k}", to_signed(0xFFFF - k))
        for w in range(128):
            t.write_word(f"O:{w:o}", (w * 0x1357) & 0xFFFF)
            t.write_word(f"I:{w:o}", (w * 0x2468 + 1) & 0xFFFF)

        def bit(file: str, k: int) -> bool:
            return bool(t.read_word(f"{file}:{k // 16:o}") >> (k % 16) & 1)

        # 01 / 02: 2000 bits from an odd start
        for function, file in ((1, "O"), (2, "I")):
            reply = s.transact(req(f"01 {function:02x} 00 25 07 d0"))
            assert reply == with_crc(bytes([1, function, 250]) + pack_bits([bit(file, 37 + k) for k in range(2000)]))
        # 03 / 04: 125 registers, the last ones of the table
        reply = s.transact(req("01 03 03 6b 00 7d"))  # 875..999
        assert reply == with_crc(bytes([1, 3, 250]) + struct.pack(">125H", *[(k * 31 + 7) & 0xFFFF for k in range(875, 1000)]))
        reply = s.transact(req("01 04 00 00 00 7d"))  # input register 0 is the example's scan counter
        scans = struct.unpack(">H", reply[3:5])[0]  # what it was when the request was served
        assert 0 < scans < s.engine.scans
        assert reply == with_crc(bytes([1, 4, 250]) + struct.pack(">125H", scans, *[0xFFFF - k for k in range(1, 125)]))
        # one past the end: exception 02
        assert s.transact(req("01 03 03 6c 00 7d")) == req("01 83 02")
        assert s.transact(req("01 01 00 31 07 d0")) == req("01 81 02")  # 49 + 2000 > 2048
        # 16: 123 registers, to the last one
        values = [(k * 977) & 0xFFFF for k in range(123)]
        frame = req("01 10 03 6d 00 7b f6" + struct.pack(">123H", *values).hex())
        assert len(frame) == 255  # 123 registers: the longest function 16 frame
        assert s.transact(frame) == req("01 10 03 6d 00 7b")
        assert [t.read(f"N10:{k}") & 0xFFFF for k in range(877, 1000)] == values
        # 15: 1968 coils from bit 45 (not a byte boundary), an odd pattern
        bits = [(k * 7) % 5 < 2 for k in range(1968)]
        before = [bit("O", k) for k in range(2048)]
        assert s.transact(req("01 0f 00 2d 07 b0 f6" + pack_bits(bits).hex())) == req("01 0f 00 2d 07 b0")
        assert [bit("O", k) for k in range(2048)] == before[:45] + bits + before[45 + 1968:]
        assert s.counters() == {"served": 6, "exceptions": 2, "bad": 0, "others": 0, "broadcasts": 0}
    finally:
        s.close()


def test_single_writes_and_a_broadcast(slave):
    t = slave.table
    assert slave.transact(req("01 05 00 3f ff 00")) == req("01 05 00 3f ff 00")  # coil 63 = O:3/17
    assert t.read("O:3/17") == 1
    assert slave.transact(req("01 05 00 3f 00 00")) == req("01 05 00 3f 00 00")
    assert t.read("O:3/17") == 0
    assert slave.transact(req("01 05 00 40 ff 00")) == req("01 85 02")  # coil 64: past the 64 I/O bits
    assert slave.transact(req("01 05 00 01 12 34")) == req("01 85 03")  # neither FF00 nor 0000
    assert slave.transact(req("01 06 03 e7 80 01")) == req("01 06 03 e7 80 01")  # register 999
    assert t.read("N10:999") == -32767
    assert slave.transact(req("01 06 03 e8 00 01")) == req("01 86 02")  # register 1000
    # a broadcast write is executed, and nobody answers; a broadcast read does nothing
    assert slave.transact(req("00 06 00 02 00 2a")) is None
    assert slave.transact(req("00 03 00 00 00 01")) is None
    assert t.read("N10:2") == 42
    assert slave.counters() == {"served": 3, "exceptions": 3, "bad": 0, "others": 0, "broadcasts": 2}


def test_unknown_functions_get_exception_01(slave):
    for function in (0x07, 0x16, 0x17, 0x2B, 0x64):
        assert slave.transact(req(f"01 {function:02x} 00 00 00 01")) == req(f"01 {function | 0x80:02x} 01")


@pytest.mark.parametrize("frame", [
    req("01 03 00 00 00 01")[:-1] + b"\x00",  # a bad CRC
    req("02 03 00 00 00 01"),  # another slave
    req("01 03 00 00 00 01")[:5],  # truncated
    req("01 03 00 00 00 01 00"),  # a good CRC on a 9-byte read: not a read request
    req("01 10 00 00 00 01 02 00"),  # function 16 whose byte count promises more than came
    req("01 0f 00 00 00 08 01"),  # function 15 without its data
    req("01"),  # a CRC-valid 3-byte frame
    bytes(range(256)) + bytes(range(44)),  # 300 bytes: longer than any frame
], ids=["bad-crc", "other-slave", "truncated", "long-read", "short-16", "short-15", "three-bytes", "300-bytes"])
def test_no_reply_to_a_bad_frame_and_ready_for_the_next(slave, frame):
    assert slave.transact(frame) is None
    assert slave.transact(req("01 03 00 00 00 01")) == req("01 03 02 00 00")
    counters = slave.counters()
    assert counters["served"] == 1 and counters["exceptions"] == 0
    assert counters["bad"] + counters["others"] == 1


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(garbage=st.binary(min_size=1, max_size=400))
def test_garbage_never_stops_the_slave(slave, garbage):
    """Whatever arrives, the scan goes on, and after a quiet line the next
    request is answered."""
    slave.transact(garbage)  # usually silence; an accidental good frame may be answered
    slave.table.write("N10:5", 1234)
    assert slave.transact(req("01 03 00 05 00 01")) == req("01 03 02 04 d2")
    assert slave.engine.mode is Mode.RUN


def test_the_address_and_the_limits_are_data(slave):
    t = slave.table
    t.write("N9:4", 17)  # SlaveAddress, online
    assert slave.transact(req("01 03 00 00 00 01")) is None
    assert slave.transact(req("11 03 00 00 00 01")) == req("11 03 02 00 00")
    t.write("N9:1", 10)  # HoldingRegisters
    assert slave.transact(req("11 03 00 09 00 01")) == req("11 03 02 00 00")
    assert slave.transact(req("11 03 00 0a 00 01")) == req("11 83 02")
    t.write("N9:3", 10)  # InputRegisterFile: function 4 now reads N10
    t.write("N10:1", 77)
    assert slave.transact(req("11 04 00 01 00 01")) == req("11 04 02 00 4d")


@pytest.mark.parametrize("baud", [9600, 19200, 38400])
def test_the_reply_waits_for_the_quiet_line_and_no_longer_than_a_scan_or_two(tmp_path, baud):
    quiet_ms = {9600: 4, 19200: 2, 38400: 1}[baud]  # 3.5 characters, rounded up to whole ms
    s = WireSlave(tmp_path, baud=baud, sets=(f"N9:5={quiet_ms}",))
    try:
        for frame in (req("01 03 00 00 00 01"), req("01 03 00 00 00 7d")):
            reply, gap_ns = s.transact_timed(frame)
            assert reply is not None and reply[:2] == b"\x01\x03"
            assert gap_ns >= 3.5 * s.char_ns  # never before the request has ended
            assert gap_ns <= (quiet_ms + 3) * 1_000_000  # the quiet time, plus at most 3 scans
    finally:
        s.close()


def test_both_executors_serve_the_simulated_master_alike(tmp_path):
    tables = []
    for executor in ("compiled", "reference"):
        link = f"exec-{executor}"
        r = slave_runner(tmp_path / executor, executor=executor,
                         ports=(f"0=sim://{link}?device=modbus_master&period_ms=5",))
        try:
            r.engine.run(1500)
            master = find_master(link)
            assert master.sent > 80 and master.bad == 0 and master.timeouts == 0, master
            assert master.replies + master.exceptions >= master.sent - 1  # the last may be on the wire
            assert master.exceptions in (master.sent // 9, master.sent // 9 - 1)  # one a round
            tables.append(r.engine.table)
        finally:
            r.engine.close()
    assert tables[0] == tables[1]


def test_the_app_out_of_the_box(tmp_path):
    """softplc run programs/modbus_slave: a simulated master polls it; every
    reply is right."""
    r = slave_runner(tmp_path / "app")
    try:
        r.engine.run(3000)
        master = find_master("modbus-slave")
        assert master.sent == 150 and master.bad == 0 and master.timeouts == 0
        served, exceptions = r.table.read("C5:0.ACC"), r.table.read("C5:1.ACC")
        assert served + exceptions == master.sent  # every request answered by the ladder
        assert master.replies + master.exceptions >= master.sent - 1  # the last reply may be on the wire
        assert served - master.replies in (0, 1) and exceptions == master.exceptions
    finally:
        r.engine.close()


def test_a_request_that_arrives_whole_between_two_scans_is_served(tmp_path):
    """On a fast line (a pty, a TCP serial server) the next request can be
    complete before the slave's next scan. Same length as the last one, the
    receive count looks unchanged: the slave must still see a new frame."""
    import serial

    link = "instant-line"
    r = slave_runner(tmp_path / "app", ports=(f"0=sim://{link}?rate=unlimited",))
    master = serial.serial_for_url(f"sim://{link}?rate=unlimited", baudrate=19200)
    master.set_clock(lambda: r.engine.clock.now_ms * 1_000_000)
    try:
        r.engine.scan()
        for k in range(5):
            r.table.write("N10:0", 100 + k)
            master.write(req("01 03 00 00 00 01"))
            reply = b""
            for _ in range(20):
                r.engine.scan()
                reply += master.read(100)
                if reply:
                    break  # the next request goes at once, before the slave's next scan
            assert reply == with_crc(bytes([1, 3, 2, 0, 100 + k])), k
        assert r.table.read("C5:0.ACC") == 5 and r.table.read("C5:2.ACC") == 0
    finally:
        master.close()
        r.engine.close()
