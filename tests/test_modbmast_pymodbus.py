"""MODBMAST against a third-party slave line: pymodbus 3.16's serial server,
in a process of its own, RTU and ASCII framing, over a socat pty pair and
over ``socket://`` (pymodbus listening on TCP with serial framing).

The line has slaves 1 and 2 with four tables each, holding the pattern our
simulated slave holds; slave 3 is configured but missing. Writes are checked
by reading them back from pymodbus through MODBMAST itself (the read path is
checked against the known pattern first). Then the line goes away and comes
back. The runtime is real-time and free-running, as it would be on hardware.
"""

from __future__ import annotations

import time

import pytest

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.ports.modbus_slave import initial_value
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.tlm.modbmast.status import NO_REPLY

from helpers.modbmast_apps import serial_xml, status, write_app
from helpers.modbus_peer import PeerProcess, free_tcp_port
from helpers.ptypair import PtyPair, require_socat
from helpers.words import signed

LIMIT_S = 15.0  # per waiting step; a step normally takes well under a second

SLAVE_1 = """
<Slave id="1">
  <ReadCoils><refNum>00001</refNum><toBlock dest="B3:0" count="20" fmt="bit"/></ReadCoils>
  <ReadInputDiscretes><refNum>10005</refNum><toBlock dest="I:0" count="1" fmt="i2"/></ReadInputDiscretes>
  <ReadMultipleRegisters><refNum>40001</refNum>
    <toBlock dest="N7:0" count="3" fmt="i2"/><toBlock dest="N9:0" count="2" fmt="i2"/></ReadMultipleRegisters>
  <ReadInputRegisters><refNum>30011</refNum><toBlock dest="N7:10" count="4" fmt="i2"/></ReadInputRegisters>
  <WriteCoil><refNum>00101</refNum><fromBlock source="B3:5/2" count="1" fmt="bit"/></WriteCoil>
  <ForceMultipleCoils><refNum>00111</refNum><fromBlock source="O:0/14" count="9" fmt="bit"/></ForceMultipleCoils>
  <ReadCoils><refNum>00101</refNum><toBlock dest="B3:6" count="20" fmt="bit"/></ReadCoils>
  <WriteSingleRegister><refNum>40051</refNum><fromBlock source="N7:30" count="1" fmt="i2"/></WriteSingleRegister>
  <WriteMultipleRegisters><refNum>40061</refNum><fromBlock source="N7:40" count="2" fmt="i2"/>
    <fromBlock count="2" fmt="i2"><const>7 0xFFFF</const></fromBlock></WriteMultipleRegisters>
  <MaskWriteRegister><refNum>40071</refNum><andMask>0xFF00</andMask>
    <fromBlock source="N7:45" count="1" fmt="i2"/></MaskWriteRegister>
  <ReadWriteRegisters><refNum>40081</refNum><toBlock dest="N7:50" count="2" fmt="i2"/>
    <refNum>40091</refNum><fromBlock source="N7:55" count="2" fmt="i2"/></ReadWriteRegisters>
  <ReadMultipleRegisters><refNum>40051</refNum><toBlock dest="N9:50" count="50" fmt="i2"/></ReadMultipleRegisters>
  <ReadMultipleRegisters><refNum>40199</refNum><toBlock dest="N9:100" count="4" fmt="i2"/></ReadMultipleRegisters>
</Slave>
<Slave id="2"><ReadMultipleRegisters><refNum>40001</refNum><toBlock dest="N10:0" count="125" fmt="i2"/>
  </ReadMultipleRegisters></Slave>
<Slave id="3" requestTimeout="100"><ReadMultipleRegisters><refNum>40001</refNum>
  <toBlock dest="N10:200" count="2" fmt="i2"/></ReadMultipleRegisters></Slave>
"""

LADDER = """\
OTE B3:5/2
MOV 1234 N7:30
OTE O:0/14
OTE O:0/16
OTE O:1/3
MOV -2 N7:40
MOV 300 N7:41
MOV 0x00AB N7:45
MOV 11 N7:55
MOV 22 N7:56
MBR_GETFAULTMAP 1 #B13:0
MBR_GETSTATUS #N20:0 1 1 3
"""
LADDER = "\n".join(f"XIO B3/400 {line}" for line in LADDER.splitlines()) + "\n"


@pytest.fixture(params=["pty", "socket"])
def line(request, tmp_path):
    """(device for MODBMAST, start a pymodbus line with the given framer)."""
    if request.param == "pty":
        require_socat()
        pair = PtyPair(tmp_path)
        device, listen = pair.a, pair.b
    else:
        pair = None
        port = free_tcp_port()
        device = listen = f"socket://127.0.0.1:{port}"
    peers: list[PeerProcess] = []

    def start(framer: str) -> PeerProcess:
        peer = PeerProcess(listen, ids=[1, 2], size=200, framer=framer)
        peers.append(peer)
        return peer

    yield device, start
    for peer in peers:
        peer.stop()
    if pair is not None:
        pair.close()
        assert pair.leftovers() == []


def run_until(runner: Runner, condition, limit_s: float = LIMIT_S) -> bool:
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        for _ in range(50):
            runner.engine.scan()
        if condition():
            return True
    return False


@pytest.mark.parametrize("framer", ["rtu", "ascii"])
def test_every_function_against_pymodbus_and_a_slave_that_comes_back(tmp_path, line, framer):
    device, start = line
    peer = start(framer)
    xml = serial_xml(f'<Port num="1" baudrate="38400" framing="{framer.upper()}" device="{device}">'
                     f'{SLAVE_1}</Port>')
    app = load_app(write_app(tmp_path / "app", xml, LADDER))
    runner = Runner(app, RunOptions(fresh=True, realtime=True, scan_ms=0))
    t = runner.table
    try:
        runner.engine.set_mode(Mode.RUN)
        assert run_until(runner, lambda: t.read("N9:62") == 7 and t.read("N10:124") != 0 and
                         status(runner, 1, 3).last_code == NO_REPLY)
        # reads, scattered
        assert [t.read(f"B3/{k}") for k in range(20)] == [int(initial_value(k, "coil")) for k in range(20)]
        assert t.read_word("I:0") == signed(sum(1 << k for k in range(16) if initial_value(4 + k, "discrete")))
        assert [t.read(f"N7:{k}") for k in range(3)] + [t.read(f"N9:{k}") for k in range(2)] == [
            signed(initial_value(k)) for k in range(5)]
        assert [t.read(f"N7:{k}") for k in range(10, 14)] == [signed(initial_value(k, "input")) for k in range(10, 14)]
        assert [t.read(f"N10:{k}") for k in range(125)] == [signed(initial_value(k, unit=1)) for k in range(125)]
        # writes, gathered, read back from pymodbus
        assert t.read("B3:6/0") == 1  # coil 100 (WriteCoil from B3:5/2)
        # coils 110..118 from O:0/14 (octal: bit 12) across into O:1: O:0/14, O:0/16 and O:1/3 on
        assert [t.read(f"B3/{16 * 6 + 10 + k}") for k in range(9)] == [1, 0, 1, 0, 0, 0, 0, 1, 0]
        assert t.read("N9:50") == 1234  # register 50
        assert [t.read(f"N9:{k}") for k in range(60, 64)] == [-2, 300, 7, -1]
        assert t.read("N9:70") == signed((initial_value(70) & 0xFF00) | 0x00AB)
        assert [t.read(f"N9:{k}") for k in (90, 91)] == [11, 22]
        assert [t.read(f"N7:{k}") for k in (50, 51)] in ([signed(initial_value(k)) for k in (80, 81)],)
        # an exception, a missing slave, the fault map, the status blocks
        runner.engine.scan()  # slave 3 may have gone Not Present after this scan's ladder copied the map
        s1, s3 = status(runner, 1, 1), status(runner, 1, 3)
        assert s1.exceptions >= 1 and s1.present  # 198..201 of 0..199: exception 02, a reply all the same
        assert s3.words()[3:] == (3, NO_REPLY) and not s3.present
        assert [t.read(f"B13/{k}") for k in range(5)] == [0, 0, 0, 1, 0]
        assert t.read("N20:0") >= 0 and t.read("N20:2") >= 1  # slave 1: a response time, exceptions counted
        assert t.read("N20:13") == 3 and t.read("N20:14") == NO_REPLY
        # the line goes away: every slave Not Present; it comes back: they answer again
        peer.stop()
        assert run_until(runner, lambda: not status(runner, 1, 1).present and not status(runner, 1, 2).present)
        runner.engine.scan()  # a slave may have gone Not Present after this scan's ladder copied the map
        assert t.read("B13/1") == 1 and t.read("B13/2") == 1
        t.write("N10:0", 0)
        start(framer)
        assert run_until(runner, lambda: status(runner, 1, 1).present and status(runner, 1, 2).present and
                         t.read("N10:0") == signed(initial_value(0, unit=1)))
        runner.engine.scan()  # a slave may have answered after this scan's ladder copied the map
        assert t.read("B13/1") == 0 and t.read("B13/2") == 0 and t.read("B13/3") == 1
    finally:
        runner.engine.close()


def test_a_port_that_takes_no_more_bytes_fails_requests_with_no_xmit_room(tmp_path):
    """A TCP serial server that accepts and never reads: once the kernel's
    buffers are full the port takes nothing, and each request fails with
    -5 NO XMIT ROOM after its requestTimeout; the scan goes on."""
    import socket

    from softplc_lite.tlm.modbmast.status import NO_XMIT_ROOM

    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    body = ('<Slave id="1" requestTimeout="5"><WriteMultipleRegisters><refNum>40001</refNum>'
            '<fromBlock source="N7:0" count="123" fmt="i2"/></WriteMultipleRegisters></Slave>')
    xml = serial_xml(f'<Port num="1" baudrate="115200" device="socket://127.0.0.1:{server.getsockname()[1]}">'
                     f'{body}</Port>')
    runner = Runner(load_app(write_app(tmp_path / "app", xml)), RunOptions(fresh=True, realtime=True, scan_ms=0))
    conn = None
    try:
        conn, _ = server.accept()
        from helpers.modbmast_apps import driver

        driver(runner, 1).port.serial._socket.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        runner.engine.set_mode(Mode.RUN)
        s = status(runner, 1, 1)
        assert run_until(runner, lambda: s.last_code == NO_XMIT_ROOM, limit_s=20)
        assert not s.present and s.no_replies > 5  # the requests before the buffers filled: no reply
        scans_before = runner.engine.scans
        runner.engine.scan()
        assert runner.engine.scans == scans_before + 1 and runner.engine.mode is Mode.RUN
    finally:
        runner.engine.close()
        if conn is not None:
            conn.close()
        server.close()


def test_a_reply_is_stored_at_the_input_point_only(tmp_path, line):
    """On a real port a reply can complete at the output point (wall time
    passed during the ladder); its data waits for the next input point, so
    the table changes only there and an input force holds between scans."""
    from softplc_lite.watch.forces import Forces, parse_force

    device, start = line
    start("rtu")
    xml = serial_xml(f'<Port num="1" baudrate="38400" device="{device}"><Slave id="1"><ReadCoils><refNum>00001'
                     f'</refNum><toBlock dest="I:0" count="16" fmt="bit"/></ReadCoils></Slave></Port>')
    runner = Runner(load_app(write_app(tmp_path / "app", xml)), RunOptions(fresh=True, realtime=True, scan_ms=0))
    Forces(runner.engine).set(parse_force("I:0/0=0"))  # coil 0 is on at the slave
    driver = runner.engine.modules[0].drivers[0]
    seen_at_output = []
    runner.engine.output_hooks.append(lambda e, enabled: seen_at_output.append(
        (len(driver.pending), e.table.read("I:0/0"), e.table.read("I:0/3"))))
    try:
        runner.engine.set_mode(Mode.RUN)
        assert run_until(runner, lambda: runner.table.read("I:0/3") == 1 and any(p for p, _, _ in seen_at_output))
        assert all(forced == 0 for _, forced, _ in seen_at_output)  # never the slave's 1, at any point
    finally:
        runner.engine.close()
