"""MODBTCPS against pymodbus's TCP client (a third-party peer): every read
and write function against every kind of region (bits across words, words,
floats in both word orders, strings), refusals and their status words,
forces, modes, and a client never seeing half a scan.

The runtime scans in a thread of this process; its server is a process of
its own, as in every run."""

from __future__ import annotations

import socket
import struct
import threading
import time

import pytest
from pymodbus.client import ModbusTcpClient
from pymodbus.pdu import ExceptionResponse

from softplc_lite.ladder.engine import Mode
from softplc_lite.tlm.modbtcps import status as S
from softplc_lite.watch.forces import Forces, parse_force

from helpers.modbtcps_apps import LIMIT_S, raw_request, server_xml

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def plc(tcp_plc):
    return tcp_plc


@pytest.fixture
def client(tcp_client):
    return tcp_client


def exception_code(response) -> int | None:
    return response.exception_code if isinstance(response, ExceptionResponse) else None


def f32_registers(value: float, high_first: bool = True) -> list[int]:
    high, low = struct.unpack(">HH", struct.pack(">f", value))
    return [high, low] if high_first else [low, high]


# -- reads ------------------------------------------------------------------------------


def test_read_coils_runs_on_across_words(plc, client):
    plc.engine.table.write("B3:1", 0b101)  # B3/16 and B3/18
    plc.engine.table.write("B3/3", 1)
    plc.wait_for(lambda: client.read_coils(0, count=40, device_id=1).bits[16], "a published scan")
    bits = client.read_coils(0, count=40, device_id=1).bits
    assert [k for k, b in enumerate(bits[:40]) if b] == [3, 16, 18]


def test_read_discrete_inputs_start_inside_a_word(plc, client):
    plc.engine.table.write("I:0", 0b110000)  # I:0/4 and I:0/5: discrete inputs 0 and 1
    plc.engine.table.write("I:1/3", 1)  # I:0/4 + 15 = I:1/3: input 15
    plc.wait_for(lambda: client.read_discrete_inputs(0, count=20, device_id=1).bits[15], "the inputs")
    bits = client.read_discrete_inputs(0, count=20, device_id=1).bits
    assert [k for k, b in enumerate(bits[:20]) if b] == [0, 1, 15]


def test_read_holding_words_are_the_16_bits_as_they_are(plc, client):
    plc.engine.table.write("N7:3", -2)
    plc.engine.table.write("N7:4", 1234)
    plc.wait_for(lambda: client.read_holding_registers(3, count=2, device_id=1).registers == [0xFFFE, 1234],
                 "N7:3..4")


def test_read_floats_in_both_word_orders(plc, client):
    plc.engine.table.write("F8:1", 3.25)
    plc.engine.table.write("F8:10", -1.5)
    plc.wait_for(lambda: client.read_holding_registers(102, count=2, device_id=1).registers
                 == f32_registers(3.25), "F8:1, high half first")
    assert client.read_holding_registers(110, count=2, device_id=1).registers == f32_registers(-1.5, False)
    # pymodbus's own conversion reads the default order
    regs = client.read_holding_registers(102, count=2, device_id=1).registers
    assert client.convert_from_registers(regs, client.DATATYPE.FLOAT32) == 3.25
    # half a float is one register of it
    assert client.read_holding_registers(103, count=1, device_id=1).registers == f32_registers(3.25)[1:]


def test_read_input_registers_words_and_a_float(plc, client):
    plc.engine.table.write("F8:20", 0.1)
    counted = plc.read("N11:0")  # a scan that counts past the next has published the write
    plc.wait_for(lambda: client.read_input_registers(0, count=1, device_id=1).registers[0] >= counted + 2,
                 "scans counted")
    regs = client.read_input_registers(20, count=2, device_id=1).registers
    assert client.convert_from_registers(regs, client.DATATYPE.FLOAT32) == pytest.approx(0.1, rel=1e-7)


def test_read_a_string_is_its_len_and_ucs2_units(plc, client):
    plc.engine.table.write("ST9:1", "Hé€")
    plc.wait_for(lambda: client.read_holding_registers(283, count=1, device_id=1).registers == [3], "ST9:1.LEN")
    regs = client.read_holding_registers(283, count=5, device_id=1).registers
    assert regs == [3, ord("H"), ord("é"), ord("€"), 0]


# -- writes ------------------------------------------------------------------------------


def test_write_single_and_multiple_coils(plc, client):
    assert not client.write_coil(17, True, device_id=1).isError()
    assert plc.read("B3:1/1") == 1  # answered once applied: no wait needed
    assert not client.write_coils(30, [True, False, True], device_id=1).isError()
    assert [plc.read(f"B3/{k}") for k in (30, 31, 32)] == [1, 0, 1]
    assert not client.write_coil(17, False, device_id=1).isError()
    assert plc.read("B3/17") == 0


def test_write_registers_words_floats_and_strings(plc, client):
    assert not client.write_register(0, 0xFFFF, device_id=1).isError()
    assert plc.read("N7:0") == -1
    assert not client.write_registers(1, [1, 2, 3], device_id=1).isError()
    assert [plc.read(f"N7:{k}") for k in (1, 2, 3)] == [1, 2, 3]
    assert not client.write_registers(100, f32_registers(2.5) + f32_registers(-7.0), device_id=1).isError()
    assert plc.read("F8:0") == 2.5 and plc.read("F8:1") == -7.0
    assert not client.write_registers(110, f32_registers(1e6, False), device_id=1).isError()
    assert plc.read("F8:10") == 1e6
    text = [ord(c) for c in "PUMP"]
    assert not client.write_registers(200, [len(text), *text], device_id=1).isError()
    assert plc.read("ST9:0") == "PUMP"


def test_packed_strings_are_two_characters_a_register_as_hmis_read_them(plc, client):
    plc.engine.table.write("ST9:2", "Tank 1")
    plc.engine.table.write("ST9:3", "Ω!")  # a code unit over 255 reads as ?
    plc.wait_for(lambda: client.read_holding_registers(400, count=1, device_id=1).registers == [0x5461], "'Ta'")
    regs = client.read_holding_registers(400, count=41, device_id=1).registers
    assert client.convert_from_registers(regs, client.DATATYPE.STRING) == "Tank 1"  # pymodbus's own decoding
    assert regs[3:] == [0] * 38  # NULs after the text
    assert client.read_holding_registers(441, count=1, device_id=1).registers == [(ord("?") << 8) | ord("!")]
    # written the way an HMI writes one: the string ends at the first NUL, LEN follows
    regs = client.convert_to_registers("PUMP 7", client.DATATYPE.STRING)
    assert not client.write_registers(441, regs, device_id=1).isError()
    assert plc.read("ST9:3") == "PUMP 7"
    assert not client.write_register(400, 0x4F00, device_id=1).isError()  # "O", then NUL: the string ends
    assert plc.read("ST9:2") == "O"


def test_write_half_a_float_keeps_the_other_half(plc, client):
    plc.engine.table.write("F8:2", 1.0)
    high, low = f32_registers(1.0)
    new_high, _ = f32_registers(-1.0)
    assert not client.write_register(104, new_high, device_id=1).isError()
    assert plc.read("F8:2") == -1.0 and low == 0


def test_mask_write_and_read_write_multiple(plc, client):
    plc.engine.table.write("N7:5", 0x12)
    assert not client.mask_write_register(address=5, and_mask=0xF2, or_mask=0x25, device_id=1).isError()
    assert plc.read("N7:5") == (0x12 & 0xF2) | (0x25 & ~0xF2 & 0xFFFF)  # Modbus spec 6.16: 0x17
    r = client.readwrite_registers(read_address=6, read_count=2, write_address=6, values=[77, 88], device_id=1)
    assert r.registers == [77, 88]  # the write is applied before the read (spec 6.17)
    assert plc.read("N7:6") == 77


def test_writes_land_in_arrival_order_and_none_is_lost(plc, client):
    for k in range(200):
        assert not client.write_register(9, k, device_id=1).isError()
    assert plc.read("N7:9") == 199
    assert plc.status(S.W_WRITES_APPLIED) >= 200


def test_a_write_to_a_forced_bit_follows_the_force(plc, client):
    forces = Forces(plc.engine)
    plc.runner.between_scans.append(lambda runner: None)  # forces hook themselves into the scan
    forces.set(parse_force("B3/12=1"))
    assert not client.write_coil(12, False, device_id=1).isError()
    assert plc.read("B3/12") == 1
    assert client.read_coils(12, count=1, device_id=1).bits[0] is True
    forces.clear()


# -- refusals ----------------------------------------------------------------------------


def test_outside_the_map_is_exception_02_and_counted(plc, client):
    assert exception_code(client.read_holding_registers(20, count=1, device_id=1)) == 2
    assert exception_code(client.read_holding_registers(18, count=3, device_id=1)) == 2  # runs off the end
    assert exception_code(client.read_coils(40, count=1, device_id=1)) == 2
    assert exception_code(client.write_register(999, 1, device_id=1)) == 2
    plc.wait_for(lambda: plc.status(S.W_EXCEPTION_02) == 4, "exception 02 counted")
    assert plc.status(S.W_REFUSALS) == 4


def test_read_only_regions_refuse_writes(plc, client):
    # HoldingRegisters 50..54 (N7:50) and Coils 100.. (O:0) are not writable: exception 02
    assert exception_code(client.write_register(50, 1, device_id=1)) == 2
    assert exception_code(client.write_coil(100, True, device_id=1)) == 2
    assert exception_code(client.write_registers(19, [1, 2], device_id=1)) == 2  # half in a read-only gap
    assert plc.read("N7:50") == 0 and plc.read("O:0/0") == 0 and plc.read("N7:19") == 0


def test_a_unit_with_no_writable_region_refuses_the_function(tcp_apps):
    units = '<Unit id="3"><HoldingRegisters start="0" count="4" address="N7:0"/></Unit>\n'
    plc = tcp_apps.start(server_xml(units))
    with ModbusTcpClient("127.0.0.1", port=plc.port, timeout=LIMIT_S, retries=0) as c:
        assert exception_code(c.write_register(0, 1, device_id=3)) == 1
        assert c.read_holding_registers(0, count=4, device_id=3).registers == [0, 0, 0, 0]
    plc.wait_for(lambda: plc.status(S.W_EXCEPTION_01) == 1, "exception 01 counted")


def test_bad_counts_and_string_lengths_are_exception_03(plc, client):
    assert raw_request(plc.port, struct.pack(">BHH", 3, 0, 126)) == bytes([0x83, 3])
    assert exception_code(client.write_register(200, 83, device_id=1)) == 3  # ST9:0.LEN over 82
    assert plc.read("ST9:0") == ""
    plc.wait_for(lambda: plc.status(S.W_EXCEPTION_03) == 2, "exception 03 counted")


def test_an_unknown_unit_is_exception_0b(plc, client):
    assert exception_code(client.read_holding_registers(0, count=1, device_id=7)) == 0x0B
    plc.wait_for(lambda: plc.status(S.W_EXCEPTION_0B) == 1, "exception 0B counted")


def test_a_function_not_served_is_exception_01(plc, client):
    assert exception_code(client.diag_read_bus_message_count(device_id=1)) == 1
    plc.wait_for(lambda: plc.status(S.W_EXCEPTION_01) == 1, "exception 01 counted")


# -- the scan's view ---------------------------------------------------------------------


def test_a_client_never_sees_half_a_scan(tcp_apps):
    """Each scan writes one value into ten words; reads of all ten, while the
    PLC scans as fast as it can, always find them equal."""
    ladder = "ADD N11:0 1 N11:0\nFLL N11:0 #N11:1 9\n"
    plc = tcp_apps.start(server_xml(maxRequestsPerSecond=100000), ladder=ladder, realtime=False)
    with ModbusTcpClient("127.0.0.1", port=plc.port, timeout=LIMIT_S, retries=0) as c:
        seen = set()
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            regs = c.read_input_registers(0, count=10, device_id=1).registers
            assert len(set(regs)) == 1, regs
            seen.add(regs[0])
    assert len(seen) > 20  # the scan moved on between reads: the reads did overlap scans


def test_status_words_show_the_server(plc, client):
    client.read_holding_registers(0, count=1, device_id=1)
    plc.wait_for(lambda: plc.status(S.W_CONNECTED) == 1, "the connection counted")
    assert plc.status(S.W_BITS) & S.BIT_LISTENING and plc.status(S.W_BITS) & S.BIT_CLIENT
    plc.wait_for(lambda: plc.status(S.W_REQUESTS) >= 1, "the request counted")
    client.close()
    plc.wait_for(lambda: plc.status(S.W_CONNECTED) == 0, "the disconnection counted")


@pytest.mark.parametrize("mode", [Mode.PROGRAM, Mode.TEST])
def test_writes_land_in_program_and_test_mode(tcp_apps, mode):
    """HMI setpoints are kept whatever the mode; the ladder runs in TEST mode only."""
    plc = tcp_apps.start(ladder="XIC B3/0 OTE B3/1\n")
    plc.runner.request_stop()
    plc.thread.join(LIMIT_S)
    engine = plc.engine
    engine.set_mode(Mode.PROGRAM)
    engine.set_mode(mode)
    stop = threading.Event()

    def scan() -> None:
        while not stop.is_set():
            engine.scan()

    t = threading.Thread(target=scan, daemon=True)
    t.start()
    try:
        with ModbusTcpClient("127.0.0.1", port=plc.port, timeout=LIMIT_S, retries=0) as c:
            assert not c.write_coil(0, True, device_id=1).isError()
            assert not c.write_register(0, 555, device_id=1).isError()
            assert c.read_coils(0, count=2, device_id=1).bits[:2] == [True, mode is Mode.TEST]
        assert plc.read("B3/0") == 1 and plc.read("N7:0") == 555
        assert plc.read("B3/1") == (1 if mode is Mode.TEST else 0)  # the ladder ran on the write, or not
    finally:
        stop.set()
        t.join(LIMIT_S)


# -- the server process ------------------------------------------------------------------


def test_an_address_in_use_fails_the_server_saying_why_and_the_scan_goes_on(tcp_apps, capfd):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        plc = tcp_apps.start(server_xml(port=port))
        plc.wait_for(lambda: plc.status(S.W_BITS) & S.BIT_FAILED, "the failed bit")
        assert not plc.status(S.W_BITS) & S.BIT_LISTENING
        scans = plc.engine.scans
        plc.wait_for(lambda: plc.engine.scans > scans + 5, "scans after the server failed")
    status = plc.module.server_status()
    assert not status.up and status.listening == f"cannot listen on 127.0.0.1:{port}: the address is in use " \
                                                 "(another program listens there)"
    assert f"MODBTCPS: cannot listen on 127.0.0.1:{port}: the address is in use (another program listens there) " \
           "(MODBTCPS.XML address and port; docs/modbtcps.md); clients are not served (the scan goes on)" \
           in capfd.readouterr().err


def test_a_server_process_that_dies_sets_the_failed_bit_and_the_scan_goes_on(plc):
    plc.wait_for(lambda: plc.status(S.W_BITS) & S.BIT_LISTENING, "listening")
    plc.module.process.kill()
    plc.wait_for(lambda: plc.status(S.W_BITS) & S.BIT_FAILED, "the failed bit")
    assert not plc.status(S.W_BITS) & S.BIT_LISTENING
    scans = plc.engine.scans
    plc.wait_for(lambda: plc.engine.scans > scans + 5, "scans after the server died")
    assert plc.module.server_status().up is False
