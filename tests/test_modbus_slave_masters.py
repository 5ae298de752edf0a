"""The Modbus RTU slave written in ladder (programs/modbus_slave) polled by
the project's own masters, each in a runtime of its own: two engines on
simulated time (SimulatedClock, 1 ms a scan), one ``sim://NAME`` link
between their ports, scanned in lockstep (master, slave, master, ...), so
every run is the same.

- The COMGENIUS master of the manual's example 5 (programs/modbus_master):
  slave 2, 125 holding registers from 0, 38400 baud.
- MODBMAST, at 19200 baud, with every function it has that the slave serves
  (1, 2, 3, 4, 5, 6, 15, 16), and with the two it has that the slave does not
  (22, 23: exception 01).
"""

from __future__ import annotations

import itertools
from collections import deque
from pathlib import Path

from softplc_lite.app import load_app
from softplc_lite.ladder.engine import Mode
from softplc_lite.runner import RunOptions, Runner

from helpers.modbmast_apps import serial_xml, status, write_app
from helpers.modbus_slave_app import MASTER_APP, SLAVE_APP, copy_app
from helpers.reference_checks import crc16_modbus_ref, rtu_frame as frame
from helpers.words import signed

_names = itertools.count()


def link_name() -> str:
    return f"mbs-masters-{next(_names)}"


def slave_counters(runner: Runner) -> dict[str, int]:
    t = runner.table
    return {name: t.read(f"C5:{k}.ACC") for k, name in
            enumerate(("served", "exceptions", "bad", "others", "broadcasts"))}


class Line:
    """A master runtime and the ladder slave's runtime on one simulated link,
    scanned in lockstep, one scan each in the order they were added. Closes both.

    The slave goes first: its first scan clears its receive buffer (file 50,
    "forget what arrived before the PLC went to RUN"), and MODBMAST sends its
    first request at time 0, so with the master scanned first the request's
    first byte is already in (and cleared from) the slave's buffer at that
    scan and the rest of it reads as a frame for unit 03."""

    def __init__(self) -> None:
        self.runners: list[Runner] = []

    def add(self, app: Path, sets: tuple[str, ...] = (), ports: tuple[str, ...] = ()) -> Runner:
        runner = Runner(load_app(app), RunOptions(fresh=True, scan_ms=1, sets=sets, ports=ports))
        self.runners.append(runner)
        return runner

    def run(self, scans: int) -> None:
        for runner in self.runners:
            if runner.engine.mode is not Mode.RUN:
                runner.engine.set_mode(Mode.RUN)
        for _ in range(scans):
            for runner in self.runners:
                runner.engine.scan()
        clocks = {runner.engine.clock.now_ms for runner in self.runners}
        assert len(clocks) == 1, clocks  # lockstep: one time for both
        for runner in self.runners:
            assert runner.engine.mode is Mode.RUN and runner.engine.fault is None, runner.engine.fault

    def close(self) -> None:
        for runner in self.runners:
            runner.engine.close()


def keep_traffic(runner: Runner) -> None:
    """Keep every frame of the runner's ports, not only the watch view's last ones."""
    for module in runner.engine.modules:
        for port in module.serial_ports():
            port.history = deque(maxlen=100_000)


def frames(runner: Runner, direction: str) -> list[bytes]:
    """What the runner's ports sent (one write a frame, so one frame each) or
    received (in the chunks each read found: join them, see replies())."""
    return [bytes(data) for module in runner.engine.modules for port in module.serial_ports()
            for _, d, data in port.history if d == direction]


def reply_length(request: bytes, function: int) -> int:
    if function & 0x80:
        return 5
    if function in (1, 2):
        return 5 + (int.from_bytes(request[4:6], "big") + 7) // 8
    if function in (3, 4):
        return 5 + 2 * int.from_bytes(request[4:6], "big")
    return 8  # 5, 6, 15, 16


def replies(sent: list[bytes], received: list[bytes]) -> list[bytes]:
    """The received bytes cut into one reply a request, in order, each
    checked: the request's address, its function (or + 80h), a good CRC, and
    nothing between replies. The last request's reply may be missing or cut
    short (still on the wire when the run stopped)."""
    stream = b"".join(received)
    out, pos = [], 0
    for index, request in enumerate(sent):
        if pos == len(stream):
            break
        assert stream[pos] == request[0] and stream[pos + 1] & 0x7F == request[1], (
            request.hex(" "), stream[pos:pos + 8].hex(" "))
        reply = stream[pos:pos + reply_length(request, stream[pos + 1])]
        pos += len(reply)
        if len(reply) < reply_length(request, reply[1]):
            assert index == len(sent) - 1, reply.hex(" ")  # only the last may be cut short
            break
        assert crc16_modbus_ref(reply, 0xFFFF) == 0, reply.hex(" ")
        out.append(reply)
    assert pos == len(stream), stream[pos:].hex(" ")  # nothing after the last reply
    assert len(out) >= len(sent) - 1
    return out


# -- the COMGENIUS master of example 5 --------------------------------------------------------------

def test_the_comgenius_master_polls_the_ladder_slave(tmp_path):
    """Example 5's master (slave 2, function 3, 125 registers from 0, 38400
    baud) against the ladder slave set to address 2 at 38400: every reply is
    good, its registers reach the master's N11, a change at the slave
    follows, and both sides count the same transactions."""
    name = link_name()
    line = Line()
    try:
        slave = line.add(copy_app(SLAVE_APP, tmp_path / "slave", baud=38400), sets=("N9:4=2", "N9:5=1"),
                         ports=(f"0=sim://{name}",))
        master = line.add(copy_app(MASTER_APP, tmp_path / "master"), ports=(f"0=sim://{name}",))
        keep_traffic(master)
        values = [k * 3 - 500 for k in range(125)]
        for k, v in enumerate(values):
            slave.table.write(f"N10:{k}", v)

        line.run(3000)
        m = master.table
        assert [m.read(f"N11:{k}") for k in range(125)] == values
        good = m.read("C5:1.ACC")
        assert good > 20  # about one every 125 ms: the 50 ms poll timer, the 66.4 ms reply, scans and gaps
        assert [m.read(f"C5:{k}.ACC") for k in (2, 3, 4)] == [0, 0, 0]  # exceptions, timeouts, garbage
        counters = slave_counters(slave)
        assert abs(counters["served"] - good) <= 1, (counters, good)
        assert counters == {**counters, "exceptions": 0, "bad": 0, "others": 0, "broadcasts": 0}
        # what went over the wire: the query of the testing notes, every time
        sent = frames(master, "TX")
        assert set(sent) == {bytes.fromhex("02 03 00 00 00 7D 85 D8")}
        assert abs(len(sent) - good) <= 1 and m.read("C5:0.ACC") == len(sent)

        # the slave's data changes (an engineer, its own ladder): the master follows
        changed = [signed(v * 37 + 0x8000) for v in range(125)]
        for k, v in enumerate(changed):
            slave.table.write(f"N10:{k}", v)
        line.run(1000)
        assert [m.read(f"N11:{k}") for k in range(125)] == changed
        assert m.read("C5:1.ACC") > good and [m.read(f"C5:{k}.ACC") for k in (2, 3, 4)] == [0, 0, 0]
        assert abs(slave_counters(slave)["served"] - m.read("C5:1.ACC")) <= 1
        assert slave_counters(slave)["bad"] == 0
    finally:
        line.close()


# -- MODBMAST ------------------------------------------------------------------------------------------

# Slave 1's requests: every function MODBMAST has that the ladder slave serves. Reads of the slave's
# coils 0..31 and 3..23 (O), discrete inputs 5..54 (I), holding registers 0..99 (N10, scattered into
# two blocks, N24 and N25), input registers 1..15 (N11; register 0 is the slave's scan counter); writes of coil 40,
# coils 45..57, register 200 and registers 210..231 (20 from the table and two constants); a read of
# coils 32..63, where the writes land.
EVERY_FUNCTION = """
<Slave id="1">
  <ReadCoils><refNum>00001</refNum><toBlock dest="B20:0" count="32" fmt="bit"/></ReadCoils>
  <ReadCoils><refNum>00004</refNum><toBlock dest="B21:0" count="21" fmt="bit"/></ReadCoils>
  <ReadInputDiscretes><refNum>10006</refNum><toBlock dest="B22:0" count="50" fmt="bit"/></ReadInputDiscretes>
  <ReadMultipleRegisters><refNum>40001</refNum>
    <toBlock dest="N24:0" count="60" fmt="i2"/><toBlock dest="N25:0" count="40" fmt="i2"/></ReadMultipleRegisters>
  <ReadInputRegisters><refNum>30002</refNum><toBlock dest="N26:0" count="15" fmt="i2"/></ReadInputRegisters>
  <WriteCoil><refNum>00041</refNum><fromBlock source="B30:0/0" count="1" fmt="bit"/></WriteCoil>
  <ForceMultipleCoils><refNum>00046</refNum><fromBlock source="B30:1/0" count="13" fmt="bit"/></ForceMultipleCoils>
  <WriteSingleRegister><refNum>40201</refNum><fromBlock source="N31:0" count="1" fmt="i2"/></WriteSingleRegister>
  <WriteMultipleRegisters><refNum>40211</refNum><fromBlock source="N31:10" count="20" fmt="i2"/>
    <fromBlock count="2" fmt="i2"><const>7 0xFFFF</const></fromBlock></WriteMultipleRegisters>
  <ReadCoils><refNum>00033</refNum><toBlock dest="B23:0" count="32" fmt="bit"/></ReadCoils>
</Slave>
"""

STATUS_LADDER = "MBR_GETFAULTMAP 1 #B13:0\nMBR_GETSTATUS #N40:0 1 1 1\n"


def modbmast_app(directory: Path, name: str, slave_xml: str) -> Path:
    xml = serial_xml(f'<Port num="1" baudrate="19200" device="sim://{name}">{slave_xml}</Port>')
    return write_app(directory, xml, STATUS_LADDER)


def bit(table, file: str, k: int) -> int:
    """Bit k of a bit-addressed file (B20/k; O and I words numbered in octal)."""
    word = f"{file}:{k // 16:o}" if file in ("O", "I") else f"{file}:{k // 16}"
    return table.read_word(word) >> (k % 16) & 1


def test_modbmast_polls_the_ladder_slave_with_every_function_it_serves(tmp_path):
    name = link_name()
    line = Line()
    try:
        slave = line.add(copy_app(SLAVE_APP, tmp_path / "slave"), ports=(f"0=sim://{name}",))
        master = line.add(modbmast_app(tmp_path / "master", name, EVERY_FUNCTION))
        keep_traffic(master)
        m, s = master.table, slave.table

        def give(o_words, i_words, holding, inputs, coil, coils, register, registers) -> None:
            for w, v in enumerate(o_words):
                s.write_word(f"O:{w:o}", v)
            for w, v in enumerate(i_words):
                s.write_word(f"I:{w:o}", v)
            for k, v in enumerate(holding):
                s.write(f"N10:{k}", v)
            for k, v in enumerate(inputs, start=1):
                s.write(f"N11:{k}", v)
            m.write("B30:0/0", coil)
            m.write_word("B30:1", coils)
            m.write("N31:0", register)
            for k, v in enumerate(registers, start=10):
                m.write(f"N31:{k}", v)

        def check(o_words, i_words, holding, inputs, coil, coils, register, registers) -> None:
            # the slave's data reached the master ...
            assert [bit(m, "B20", k) for k in range(32)] == [bit(s, "O", k) for k in range(32)]
            assert [m.read_word(f"B20:{w}") & 0xFFFF for w in (0, 1)] == [w & 0xFFFF for w in o_words[:2]]
            assert [bit(m, "B21", k) for k in range(21)] == [bit(s, "O", 3 + k) for k in range(21)]
            assert [bit(m, "B22", k) for k in range(50)] == [bit(s, "I", 5 + k) for k in range(50)]
            assert [m.read(f"N24:{k}") for k in range(60)] + [m.read(f"N25:{k}") for k in range(40)] == holding
            assert [m.read(f"N26:{k}") for k in range(15)] == inputs
            # ... and the master's data reached the slave
            assert s.read("O:2/10") == coil  # coil 40
            assert [bit(s, "O", 45 + k) for k in range(13)] == [coils >> k & 1 for k in range(13)]
            assert bit(s, "O", 44) == 0 and bit(s, "O", 58) == 0  # either side of the 13
            assert s.read("N10:200") == register
            assert [s.read(f"N10:{k}") for k in range(210, 232)] == registers + [7, -1]
            assert s.read("N10:232") == 0 and s.read("N10:209") == 0
            # ... and read back from it: coils 32..63 as the slave holds them
            assert [bit(m, "B23", k) for k in range(32)] == [bit(s, "O", 32 + k) for k in range(32)]
            assert bit(m, "B23", 8) == coil and [bit(m, "B23", 13 + k) for k in range(13)] == [
                coils >> k & 1 for k in range(13)]

        first = ([0x5A3C, 0x8001, 0, 0x4000],  # O: coils 0..63 (O:3/16 = coil 62, never written)
                 [0x1234, 0xF00F, 0x0F0F, 0x7777],  # I: discrete inputs 0..63
                 [k * 7 - 300 for k in range(100)], [1000 + k for k in range(1, 16)],
                 1, 0b1_0110_1100_1011, -1234, [k * 111 - 1000 for k in range(20)])
        give(*first)
        line.run(1500)
        check(*first)

        # everything changes on both sides; the next passes carry it over
        second = ([0x0F0F, 0x7FFE, 0, 0x4000], [0xEDCB, 0x0FF0, 0xF0F0, 0x8888],
                  [signed(0xFFFF - k * 13) for k in range(100)], [-k for k in range(1, 16)],
                  0, 0b0_1001_0011_0100, 32767, [signed(k * 3001) for k in range(20)])
        give(*second)
        line.run(1500)
        check(*second)

        # no error anywhere: MODBMAST's status of slave 1, its fault map, the slave's counters
        st = status(master, 1, 1)
        assert st.present and (st.no_replies, st.exceptions, st.failed_function, st.last_code) == (0, 0, 0, 0)
        assert st.average_ms is not None and st.average_ms > 0
        assert [m.read(f"N40:{k}") for k in range(1, 5)] == [0, 0, 0, 0] and m.read("N40:0") > 0
        assert m.read("B13/1") == 0
        sent, received = frames(master, "TX"), frames(master, "RX")
        functions = {f[1] for f in sent}
        assert functions == {1, 2, 3, 4, 5, 6, 15, 16}
        assert len(sent) >= 4 * 10  # at least four passes of the ten requests
        answers = replies(sent, received)
        assert all(r[1] < 0x80 for r in answers)  # never an exception
        counters = slave_counters(slave)
        assert counters == {**counters, "exceptions": 0, "bad": 0, "others": 0, "broadcasts": 0}
        assert len(sent) - 1 <= counters["served"] <= len(sent)  # the last may still be on the wire
    finally:
        line.close()


FUNCTIONS_22_23 = """
<Slave id="1">
  <ReadMultipleRegisters><refNum>40001</refNum><toBlock dest="N20:0" count="4" fmt="i2"/></ReadMultipleRegisters>
  <MaskWriteRegister><refNum>40002</refNum><andMask>0xFF00</andMask>
    <fromBlock source="N30:0" count="1" fmt="i2"/></MaskWriteRegister>
  <ReadWriteRegisters><refNum>40001</refNum><toBlock dest="N21:0" count="2" fmt="i2"/>
    <refNum>40003</refNum><fromBlock source="N30:1" count="2" fmt="i2"/></ReadWriteRegisters>
</Slave>
"""


def test_modbmast_functions_22_and_23_get_exception_01_from_the_ladder_slave(tmp_path):
    """MaskWriteRegister (22) and ReadWriteRegisters (23): the ladder slave
    answers exception 01 and changes nothing; MODBMAST counts each as an
    exception, keeps the slave Present, and the read between them works."""
    name = link_name()
    line = Line()
    try:
        slave = line.add(copy_app(SLAVE_APP, tmp_path / "slave"), ports=(f"0=sim://{name}",))
        master = line.add(modbmast_app(tmp_path / "master", name, FUNCTIONS_22_23))
        keep_traffic(master)
        m, s = master.table, slave.table
        for k, v in enumerate((11, 0x1234, 33, 44)):
            s.write(f"N10:{k}", v)
        for k, v in enumerate((0x00AB, 555, 666)):
            m.write(f"N30:{k}", v)
        st = status(master, 1, 1)
        seen = set()
        line.run(1)
        for _ in range(600):
            line.run(1)
            seen.add((st.failed_function, st.last_code))
        assert [m.read(f"N20:{k}") for k in range(4)] == [11, 0x1234, 33, 44]
        assert [s.read(f"N10:{k}") for k in range(6)] == [11, 0x1234, 33, 44, 0, 0]  # neither 22 nor 23 wrote
        assert [m.read(f"N21:{k}") for k in range(2)] == [0, 0]  # 23's read half never came

        sent, received = frames(master, "TX"), frames(master, "RX")
        assert sent[:3] == [frame("01 03 00 00 00 04"), frame("01 16 00 01 ff 00 00 ab"),
                            frame("01 17 00 00 00 02 00 02 00 02 04 02 2b 02 9a")]
        rejected = [f for f in sent if f[1] in (22, 23)]
        assert len(rejected) >= 10
        exceptions = [r for r in replies(sent, received) if r[1] & 0x80]
        assert set(exceptions) == {frame("01 96 01"), frame("01 97 01")}
        assert len(rejected) - 1 <= len(exceptions) <= len(rejected)
        # MODBMAST: a reply all the same (Present, no timeouts), each one an exception, 01 seen for both
        assert st.present and st.no_replies == 0 and st.exceptions == len(exceptions)
        assert {(22, 1), (23, 1)} <= seen <= {(0, 0), (22, 1), (23, 1)}
        # the ladder's copy (MBR_GETSTATUS): an exception handled after this scan's ladder is not in it yet
        assert m.read("N40:1") == 0 and m.read("N40:2") in (st.exceptions - 1, st.exceptions)
        assert m.read("B13/1") == 0
        counters = slave_counters(slave)
        assert counters["exceptions"] == len(exceptions) and counters["bad"] == 0 and counters["others"] == 0
        assert counters["served"] in (len(sent) - len(rejected) - 1, len(sent) - len(rejected))
    finally:
        line.close()
