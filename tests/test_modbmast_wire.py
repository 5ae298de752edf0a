"""MODBMAST on the simulated wire: deterministic timing and protocol.

Every time asserted here is computed from the line's settings, not read off
the code: a character is ``char(baud)`` ns, the simulated slave answers
3.5 character times after the request's last byte (``slave_silence``), the
master's timeout runs from the end of its request, its inter-character
limit is 1.5 characters (750 us above 19200 baud), and its next request
waits max(requestGap, 3.5 characters; 1.75 ms above 19200 baud) after a
reply."""

from __future__ import annotations

import re

import pytest

from softplc_lite.ladder.engine import Mode
from softplc_lite.modbus.framing import rtu_intervals_ns
from softplc_lite.ports.modbus_slave import find_slave, initial_value, with_crc
from softplc_lite.tlm.modbmast.status import BAD_CRC, BAD_REPLY, INCOMPLETE_REPLY, NO_CTS, NO_REPLY
from softplc_lite.watch.forces import Forces, parse_force

from helpers.modbmast_apps import Apps, char, driver, link, scans, serial_xml, slave_silence, status, traffic
from helpers.words import signed

MS = 1_000_000


@pytest.fixture
def apps(tmp_path):
    made = Apps(tmp_path)
    yield made
    made.close()


def read4(refnum: str = "40001", dest: str = "N7:0", count: int = 4, attrs: str = "") -> str:
    return (f'<ReadMultipleRegisters{attrs}><refNum>{refnum}</refNum>'
            f'<toBlock dest="{dest}" count="{count}" fmt="i2"/></ReadMultipleRegisters>')


def port_xml(name: str, body: str, baud: int = 38400, attrs: str = "", device: str = "id=2") -> str:
    url = f"sim://{name}?device=modbus&{device}".replace("&", "&amp;")
    return serial_xml(f'<Port num="1" baudrate="{baud}" device="{url}"{attrs}>{body}</Port>')


def units(frames) -> list[tuple[int, int]]:
    return [(frame[0], frame[1]) for _, frame in frames]


# -- timing -----------------------------------------------------------------------------------

@pytest.mark.parametrize("baud", [9600, 19200, 38400, 115200])
@pytest.mark.parametrize("gap_ms", [0, 3])
def test_back_to_back_transactions_take_exactly_the_wire_time(apps, baud, gap_ms):
    r = apps(port_xml(link(), f'<Slave id="2">{read4()}</Slave>', baud, f' requestGap="{gap_ms}"'))
    scans(r, 60)
    c = char(baud)
    t35 = rtu_intervals_ns(baud, c)[1]
    period = 8 * c + slave_silence(c) + 13 * c + max(gap_ms * MS, t35)
    times = [t for t, _ in traffic(r)]
    assert len(times) > 5
    assert {b - a for a, b in zip(times, times[1:])} == {period}
    assert r.table.read("N7:3") == initial_value(3)


def test_the_scan_list_goes_round_robin_in_file_order(apps):
    body = "".join(f'<Slave id="{sid}">{read4(count=1)}<ReadInputRegisters><refNum>30001</refNum>'
                   f'<toBlock dest="N9:{sid}" count="1" fmt="i2"/></ReadInputRegisters></Slave>' for sid in (1, 2, 3))
    r = apps(port_xml(link(), body, device="id=1,2,3"))
    scans(r, 30)
    sequence = units(traffic(r))
    assert sequence[:8] == [(1, 3), (1, 4), (2, 3), (2, 4), (3, 3), (3, 4), (1, 3), (1, 4)]
    assert sequence == (sequence[:6] * 20)[:len(sequence)]
    assert [r.table.read(f"N9:{sid}") for sid in (1, 2, 3)] == [
        initial_value(0, "input", unit=k) - 0x10000 for k in range(3)]


def test_min_period_holds_a_request_back_and_the_others_fill_the_wire(apps):
    periodic = read4(count=1, attrs=' minPeriod="100"')
    body = f'<Slave id="2">{periodic}{read4("40011", "N7:10", 1)}</Slave>'
    r = apps(port_xml(link(), body))
    scans(r, 100)  # 1 s
    frames = traffic(r)
    slow = [t for t, f in frames if f[2:4] == b"\x00\x00"]
    fast = [t for t, f in frames if f[2:4] == b"\x00\x0a"]
    period = 8 * char(38400) + slave_silence(char(38400)) + 7 * char(38400) + 3 * MS
    gaps = [b - a for a, b in zip(slow, slow[1:])]
    assert len(slow) == 10 and all(100 * MS <= g < 100 * MS + period for g in gaps)
    assert len(fast) > 80  # the wire is never idle while the slow one waits
    assert len(slow) + len(fast) == len(frames)


def test_a_missing_slave_is_retried_at_once_then_the_list_goes_on(apps):
    body = (f'<Slave id="5" requestTimeout="20" attempts="3">{read4()}</Slave>'
            f'<Slave id="2">{read4("40001", "N7:10")}</Slave>')
    r = apps(port_xml(link(), body))
    scans(r, 9)
    c = char(38400)
    frames = traffic(r)
    t0 = frames[0][0]
    attempt = 8 * c + 20 * MS  # request out, then the whole requestTimeout
    assert units(frames)[:4] == [(5, 3), (5, 3), (5, 3), (2, 3)]
    assert [t - t0 for t, _ in frames[:4]] == [0, attempt, 2 * attempt, 3 * attempt]
    s = status(r, 1, 5)
    assert s.words() == (0, 3, 0, 3, NO_REPLY) and not s.present
    assert status(r, 1, 2).present


@pytest.mark.parametrize("pause_ms,code", [(0.5, 0), (2.0, INCOMPLETE_REPLY)])
def test_a_pause_inside_a_reply_beyond_the_inter_character_limit_is_an_incomplete_reply(apps, pause_ms, code):
    # requestGap 10 ms: the rest of an abandoned reply ends before the next request (a 3 ms gap would
    # let its last byte land in the next reply, as on a real line where the slave talks on)
    r = apps(port_xml(link(), f'<Slave id="2">{read4()}</Slave>', attrs=' requestGap="10"',
                      device=f"id=2&pause_after=5&pause_ms={pause_ms}"))
    scans(r, 10)
    c = char(38400)
    t1_5 = 750_000  # above 19200 baud
    s = status(r, 1, 2)
    frames = traffic(r)
    t0 = frames[0][0]
    fifth = t0 + 8 * c + slave_silence(c) + 5 * c  # the 5th reply byte arrives
    if code:
        detected = [t + (fifth - t0) + c + t1_5 for t, _ in frames]  # each transaction's end, by the timing above
        assert s.words()[2:] == (0, 3, INCOMPLETE_REPLY)
        assert s.no_replies == sum(1 for t in detected if t <= 100 * MS)  # ended within the 10 scans
        assert frames[1][0] == fifth + c + t1_5 + 10 * MS  # detected when a 6th byte is overdue, then the gap
    else:
        assert s.words()[1:] == (0, 0, 0, 0) and r.table.read("N7:3") == initial_value(3)
        assert frames[1][0] == fifth + round(pause_ms * MS) + 8 * c + 10 * MS
    assert len({b - a for (a, _), (b, _) in zip(frames, frames[1:])}) == 1  # every transaction alike


@pytest.mark.parametrize("fault,code", [
    ("cut=6", INCOMPLETE_REPLY),
    ("bad_crc=1", BAD_CRC),
    ("cut=0&garbage=" + with_crc(bytes.fromhex("03 03 02 00 01")).hex(), BAD_REPLY),  # another slave's reply
    ("cut=0&garbage=" + with_crc(bytes.fromhex("02 04 02 00 01")).hex(), BAD_REPLY),  # another function's
])
def test_replies_that_are_not_right(apps, fault, code):
    r = apps(port_xml(link(), f'<Slave id="2">{read4()}</Slave>', device=f"id=2&{fault}"))
    scans(r, 3)
    s = status(r, 1, 2)
    assert s.last_code == code and s.failed_function == 3
    assert s.present  # something answered
    assert r.table.read("N7:0") == 0  # nothing stored


def test_an_exception_reply_counts_and_a_success_clears_the_failed_function(apps):
    name = link()
    bad = read4("40199", "N7:0", 4, attrs=' minPeriod="1000"')  # 198..201 of 0..199, once a second
    r = apps(port_xml(name, f'<Slave id="2">{bad}{read4("40001", "N7:10", 1)}</Slave>'))
    r.engine.scan()  # the bad read, then the good one goes out
    s = status(r, 1, 2)
    assert s.words()[1:] == (0, 1, 3, 2) and s.present
    assert s.words()[0] > 0  # an exception is a reply: its response time counts
    scans(r, 1)
    assert s.words()[3:] == (0, 0)  # the next request succeeded: words 3 and 4 back to zero
    assert s.words()[2] == 1


# -- what each function moves ----------------------------------------------------------------

ALL_FUNCTIONS = """
<Slave id="2">
  <ReadCoils><refNum>00001</refNum><toBlock dest="B3:0" count="10" fmt="bit"/></ReadCoils>
  <ReadInputDiscretes><refNum>10001</refNum><toBlock dest="I:0" count="2" fmt="i2"/></ReadInputDiscretes>
  <ReadMultipleRegisters><refNum>40001</refNum>
    <toBlock dest="N7:0" count="3" fmt="i2"/><toBlock dest="N9:5" count="2" fmt="i2"/></ReadMultipleRegisters>
  <ReadInputRegisters><refNum>30001</refNum><toBlock dest="N7:20" count="2" fmt="i2"/></ReadInputRegisters>
  <WriteCoil><refNum>00101</refNum><fromBlock source="B3:1/3" count="1" fmt="bit"/></WriteCoil>
  <WriteSingleRegister><refNum>40051</refNum><fromBlock source="N7:30" count="1" fmt="i2"/></WriteSingleRegister>
  <ForceMultipleCoils><refNum>00111</refNum><fromBlock source="O:0/14" count="5" fmt="bit"/></ForceMultipleCoils>
  <WriteMultipleRegisters><refNum>40061</refNum>
    <fromBlock source="N7:40" count="2" fmt="i2"/>
    <fromBlock count="2" fmt="i2"><const>7, 0xFFFF</const></fromBlock></WriteMultipleRegisters>
  <MaskWriteRegister><refNum>40071</refNum><andMask>0xFF00</andMask>
    <fromBlock source="N7:45" count="1" fmt="i2"/></MaskWriteRegister>
  <ReadWriteRegisters><refNum>40081</refNum><toBlock dest="N7:50" count="2" fmt="i2"/>
    <refNum>40091</refNum><fromBlock source="N7:55" count="2" fmt="i2"/></ReadWriteRegisters>
</Slave>
"""

ALL_LADDER = """\
OTE B3:1/3
MOV 1234 N7:30
OTE O:0/14
OTE O:0/16
OTE O:1/0
MOV -2 N7:40
MOV 300 N7:41
MOV 0x00AB N7:45
MOV 11 N7:55
MOV 22 N7:56
"""


def test_every_function_moves_its_data_where_the_xml_says(apps):
    name = link()
    ladder = ALL_LADDER.replace("OTE B3:1/3", "XIO B3/100 OTE B3:1/3").replace("OTE O:", "XIO B3/100 OTE O:")
    r = apps(port_xml(name, ALL_FUNCTIONS), ladder=ladder)
    slave = find_slave(name)
    before_70 = slave.holding_registers[70]
    scans(r, 20)
    # reads: scatter
    assert [r.table.read(f"B3/{k}") for k in range(11)] == [int(k % 3 == 0) for k in range(10)] + [0]
    assert r.table.read_word("I:0") == signed(0x2222) and r.table.read_word("I:1") == signed(0x2222)
    assert [r.table.read(f"N7:{k}") for k in range(3)] == [initial_value(k) for k in range(3)]
    assert [r.table.read(f"N9:{k}") for k in (5, 6)] == [initial_value(k) for k in (3, 4)]
    assert [r.table.read(f"N7:{k}") for k in (20, 21)] == [signed(initial_value(k, "input")) for k in (0, 1)]
    # writes: gather
    assert slave.coils[100] is True
    assert slave.holding_registers[50] == 1234
    assert slave.coils[110:115] == [True, False, True, False, True]  # O:0/14 .. O:0/17, O:1/0 (octal)
    assert slave.holding_registers[60:64] == [0xFFFE, 300, 7, 0xFFFF]
    assert slave.holding_registers[70] == (before_70 & 0xFF00) | 0x00AB
    assert slave.holding_registers[90:92] == [11, 22]
    assert [r.table.read(f"N7:{k}") for k in (50, 51)] == [initial_value(k) for k in (80, 81)]
    assert status(r, 1, 2).words()[1:] == (0, 0, 0, 0)


def test_outside_run_write_requests_send_idle_data_and_reads_go_on(apps):
    """Table 4: PROGRAM, TEST and FAULTED hold the outputs idle; the slave
    only sees that as zeros. Inputs keep being read in every mode."""
    name = link()
    body = ('<Slave id="2"><WriteMultipleRegisters><refNum>40011</refNum>'
            '<fromBlock source="N7:10" count="2" fmt="i2"/></WriteMultipleRegisters>'
            '<ForceMultipleCoils><refNum>00001</refNum><fromBlock source="O:0" count="4" fmt="bit"/>'
            f'</ForceMultipleCoils>{read4("40021", "N7:0", 1)}</Slave>')
    r = apps(port_xml(name, body), ladder="MOV 5 N7:10\nMOV 6 N7:11\nOTE O:0/1\n")
    slave = find_slave(name)
    scans(r, 5)
    assert slave.holding_registers[10:12] == [5, 6] and slave.coils[:4] == [False, True, False, False]
    for mode in (Mode.TEST, Mode.PROGRAM, Mode.RUN, Mode.PROGRAM):
        r.engine.set_mode(mode)
        slave.holding_registers[20] = 1000 + mode.value
        scans(r, 5)
        if mode is Mode.RUN:
            assert slave.holding_registers[10:12] == [5, 6] and slave.coils[1]
        else:
            assert slave.holding_registers[10:12] == [0, 0] and not any(slave.coils[:4])
        assert r.table.read("N7:0") == 1000 + mode.value


def test_start_requests_go_once_on_each_entry_to_run_and_stop_requests_on_leaving_it(apps):
    name = link()
    body = ('<Slave id="2">'
            '<WriteSingleRegister when="start"><refNum>40101</refNum>'
            '<fromBlock count="1" fmt="i2"><const>111</const></fromBlock></WriteSingleRegister>'
            '<WriteSingleRegister when="stop"><refNum>40102</refNum>'
            '<fromBlock count="1" fmt="i2"><const>222</const></fromBlock></WriteSingleRegister>'
            f'{read4("40001", "N7:0", 1)}</Slave>')
    r = apps(port_xml(name, body), run=False)

    def sent(register: int) -> int:
        return sum(1 for _, f in traffic(r) if f[1] == 6 and f[2:4] == register.to_bytes(2, "big"))

    scans(r, 5)  # PROGRAM: the read goes, no one-shot
    assert (sent(100), sent(101)) == (0, 0) and units(traffic(r))[0] == (2, 3)
    steps = [(Mode.RUN, (1, 0)), (Mode.PROGRAM, (1, 1)), (Mode.RUN, (2, 1)), (Mode.TEST, (2, 1)),
             (Mode.RUN, (3, 1)), (Mode.TEST, (3, 1)), (Mode.PROGRAM, (3, 1)), (Mode.RUN, (4, 1))]
    for mode, expected in steps:  # Table 6: TEST -> RUN starts; RUN -> TEST and TEST -> PROGRAM do not stop
        r.engine.set_mode(mode)
        scans(r, 5)
        assert (sent(100), sent(101)) == expected, mode
    r.engine.module_fault(203, "test")  # RUN -> FAULTED sends the stop requests too
    scans(r, 5)
    assert (sent(100), sent(101)) == (4, 2)
    assert find_slave(name).holding_registers[100:102] == [111, 222]


def test_a_one_shot_goes_before_the_run_list_and_is_not_repeated_when_it_fails(apps):
    body = ('<Slave id="9" requestTimeout="5"><WriteSingleRegister when="start"><refNum>40101</refNum>'
            '<fromBlock count="1" fmt="i2"><const>1</const></fromBlock></WriteSingleRegister></Slave>'
            f'<Slave id="2">{read4()}</Slave>')
    r = apps(port_xml(link(), body), run=False)
    r.engine.set_mode(Mode.RUN)
    scans(r, 10)
    assert units(traffic(r))[:2] == [(9, 6), (2, 3)]
    assert sum(1 for u in units(traffic(r)) if u[0] == 9) == 1
    assert status(r, 1, 9).last_code == NO_REPLY


# -- ASCII, modem lines, forces -----------------------------------------------------------------

def test_ascii_framing_at_7_data_bits_even_parity(apps):
    name = link()
    r = apps(serial_xml(f'<Port num="3" framing="ASCII" baudrate="9600" dataBits="7" parity="even" '
                        f'device="sim://{name}?device=modbus&amp;id=2&amp;framing=ascii">'
                        f'<Slave id="2">{read4()}</Slave></Port>'))
    scans(r, 20)
    frames = traffic(r, 3)
    assert frames[0][1] == b":020300000004F7\r\n"
    assert [r.table.read(f"N7:{k}") for k in range(4)] == [initial_value(k) for k in range(4)]
    c = char(9600, 7, "E")
    reply = 1 + 2 * (3 + 8 + 1) + 2  # ':', unit function count 8-data-bytes LRC as hex, CR LF
    assert frames[1][0] - frames[0][0] == 17 * c + reply * c + 3 * MS  # no RTU silence in ASCII; LF ends the frame
    assert status(r, 3, 2).words()[1:] == (0, 0, 0, 0)


def test_rts_is_raised_to_send_and_cts_awaited(apps):
    r = apps(port_xml(link(), f'<ModemControl waitDelayCTS="10"/><Slave id="2">{read4()}</Slave>',
                      device="id=2&cts_delay_ms=4"))
    scans(r, 10)
    c = char(38400)
    times = [t for t, _ in traffic(r)]
    period = 4 * MS + 8 * c + slave_silence(c) + 13 * c + 3 * MS  # CTS comes 4 ms after RTS
    assert {b - a for a, b in zip(times, times[1:])} == {period}
    assert status(r, 1, 2).present and r.table.read("N7:1") == initial_value(1)


def test_no_cts_within_wait_delay_is_code_minus_4(apps):
    r = apps(port_xml(link(), f'<ModemControl waitDelayCTS="10"/><Slave id="2">{read4()}</Slave>',
                      device="id=2&cts=off"))
    scans(r, 5)
    s = status(r, 1, 2)
    assert s.last_code == NO_CTS and not s.present and traffic(r) == []
    assert s.words()[1] == 0  # word 1 counts replies that did not come, not requests that could not go


def test_input_and_output_forces_win_over_the_slave_and_the_ladder(apps):
    name = link()
    body = ('<Slave id="2"><ReadInputDiscretes><refNum>10001</refNum><toBlock dest="I:0" count="16" fmt="bit"/>'
            '</ReadInputDiscretes><ForceMultipleCoils><refNum>00001</refNum>'
            '<fromBlock source="O:0" count="4" fmt="bit"/></ForceMultipleCoils></Slave>')
    r = apps(port_xml(name, body), ladder="XIC I:0/1 OTE O:0/2\nXIC B3/0 OTE O:0/0\n")
    forces = Forces(r.engine)
    forces.set(parse_force("I:0/1=0"))
    forces.set(parse_force("O:0/0=1"))
    scans(r, 10)
    slave = find_slave(name)
    assert r.table.read("I:0/5") == 1  # discrete 5 is on in the pattern: reads go on
    assert r.table.read("I:0/1") == 0  # discrete 1 is on, but I:0/1 is forced off
    assert slave.coils[:4] == [True, False, False, False]  # O:0/0 forced on; O:0/2 follows the forced input


def test_demoting_a_dead_slave_stops_it_costing_a_timeout_on_every_pass(apps):
    body = (f'<Slave id="5" requestTimeout="50">{read4()}{read4("40011", "N7:10")}</Slave>'
            f'<Slave id="2">{read4("40001", "N7:20")}</Slave>')
    plain = apps(port_xml(link(), body))
    demoting = apps(port_xml(link(), body, attrs=' demoteAfter="2" demotePeriod="1000"'))
    scans(plain, 300)
    scans(demoting, 300)
    dead = [sum(1 for u in units(traffic(r)) if u[0] == 5) for r in (plain, demoting)]
    alive = [sum(1 for u in units(traffic(r)) if u[0] == 2) for r in (plain, demoting)]
    assert dead[0] > 40  # two timeouts on every pass
    assert dead[1] == 4 + 2  # two passes, then one probe a second
    assert alive[1] > 5 * alive[0]
    assert status(demoting, 1, 5).demoted and not status(demoting, 1, 5).present


def test_a_request_still_in_the_ports_queue_at_the_timeout_is_wait_xmitted(apps):
    """Table 14's -6: the port's transmit queue does not empty (here 1000
    bytes already queued on the port ahead of the request: 260 ms of wire
    at 38400 baud), so when requestTimeout expires the request has not even
    left the port."""
    from softplc_lite.tlm.modbmast.status import WAIT_XMITTED

    r = apps(port_xml(link(), f'<Slave id="2">{read4()}</Slave>'), run=False)
    driver(r).port.serial.write(b"\x00" * 1000)  # the backlog, through the same pyserial port
    r.engine.set_mode(Mode.RUN)
    scans(r, 4)  # the request went at 0 ms; 2 ms of it, then 30 ms of requestTimeout
    s = status(r, 1, 2)
    assert s.last_code == WAIT_XMITTED and not s.present and s.words()[1] == 0
    scans(r, 40)  # the backlog drains; the slave answers again
    assert s.present and s.last_code == 0 and r.table.read("N7:1") == initial_value(1)


@pytest.mark.parametrize("level", [0, 1, 2])
def test_debug_levels(apps, capsys, level):
    """Manual 6.2: 0 minimal (nothing), 1 more (port events, failures,
    slaves going Not Present), 2 adds each transaction with its timing."""
    body = f'<Slave id="2">{read4()}</Slave><Slave id="5" requestTimeout="5">{read4()}</Slave>'
    xml = port_xml(link(), body).replace("<ModbusSerial>", f'<ModbusSerial debug="{level}">')
    r = apps(xml)
    scans(r, 3)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("MODBMAST: ")]
    failed = [line for line in lines if "slave 5: ReadMultipleRegisters failed: -3 NO REPLY" in line]
    ok = [line for line in lines if "slave 2: ReadMultipleRegisters ok in" in line]
    if level == 0:
        assert lines == []
    else:
        assert failed and any("port MODBMAST:1: opened sim://" in line for line in lines)
        assert any("slave 5: Not Present" in line for line in lines)
        assert bool(ok) is (level == 2)
        assert any(" TX    8 bytes: 02 03 00 00 00 04 44 3A" in line for line in lines) is (level == 2)
        # stamped with the wall clock, the engine's time, and the event's own time on the port
        assert re.match(r"MODBMAST: \d\d:\d\d:\d\d\.\d{3} t=\d+ms port 1 @\d+\.\d{3}ms slave 5", failed[0])
