"""MODBMAST.XML (or MODBUS.XML): the reader and checker of the MODBMAST
configuration, against the manual's chapter 4 (Table 7 reference numbers,
Table 8 elements and what they contain, the attribute table of 4.3) and the
softplc_lite decisions (extensions, block addresses, quantities, every problem
at once with its line and column, hostile or broken files).

Expected lines and columns are computed from the text each test writes
(``locate``), never copied from the checker's output."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from softplc_lite.datatable import parse_address
from softplc_lite.tlm.errors import ModuleError, ModuleErrors
from softplc_lite.tlm.modbmast.config import (
    Block,
    ModbmastConfig,
    PortConfig,
    Request,
    Slave,
    load_config,
    parse_config,
)
from softplc_lite.tlm.modbmast.requests import REQUEST_KINDS
from softplc_lite.tlm.xmlreader import MAX_BYTES

from helpers.located import locate, where

PATH = "MODBMAST.XML"

# The manual's Table 3 / Table 7 facts, written out here rather than taken from the code:
# request element -> (Modbus function, refNum region digit, reads, bit request).
KINDS = {
    "ReadCoils": (1, 0, True, True),
    "ReadInputDiscretes": (2, 1, True, True),
    "ReadMultipleRegisters": (3, 4, True, False),
    "ReadInputRegisters": (4, 3, True, False),
    "WriteCoil": (5, 0, False, True),
    "WriteSingleRegister": (6, 4, False, False),
    "ForceMultipleCoils": (15, 0, False, True),
    "WriteMultipleRegisters": (16, 4, False, False),
    "MaskWriteRegister": (22, 4, False, False),
    "ReadWriteRegisters": (23, 4, True, False),
}
# Modbus limits per function: (lowest, highest) quantity; 23 has (read, write).
LIMITS = {1: (1, 2000), 2: (1, 2000), 3: (1, 125), 4: (1, 125), 5: (1, 1), 6: (1, 1), 15: (1, 1968),
          16: (1, 123), 22: (1, 1), 23: (1, 125)}
RWR_WRITE_LIMIT = 121


# -- helpers ----------------------------------------------------------------------------------

def parse(xml: str | bytes, path: str = PATH) -> ModbmastConfig:
    return parse_config(xml.encode() if isinstance(xml, str) else xml, path)


def problems(xml: str | bytes, path: str = PATH) -> list[ModuleError]:
    with pytest.raises(ModuleErrors) as info:
        parse(xml, path)
    return info.value.problems


def only_problem(xml: str | bytes) -> ModuleError:
    found = problems(xml)
    assert len(found) == 1, ModuleErrors(found).report()
    return found[0]


def in_slave(inner: str, port: str = 'num="1" baudrate="19200"', slave: str = 'id="2"') -> str:
    return f"<ModbusSerial>\n<Port {port}>\n<Slave {slave}>\n{inner}\n</Slave>\n</Port>\n</ModbusSerial>\n"


def request(inner: str, **kw) -> Request:
    """The one request of slave 2 on port 1."""
    (req,) = parse(in_slave(inner, **kw)).ports[1].slaves[2].requests
    return req


def to(dest: str, count: int, fmt: str = "i2") -> str:
    return f'<toBlock dest="{dest}" count="{count}" fmt="{fmt}"/>'


def frm(source: str, count: int, fmt: str = "i2") -> str:
    return f'<fromBlock source="{source}" count="{count}" fmt="{fmt}"/>'


def const(count: int, values: str, fmt: str = "i2") -> str:
    return f'<fromBlock count="{count}" fmt="{fmt}"><const>{values}</const></fromBlock>'


def req(kind: str, *content: str, attrs: str = "") -> str:
    return f"<{kind}{' ' + attrs if attrs else ''}>{''.join(content)}</{kind}>"


def ref(number: str) -> str:
    return f"<refNum>{number}</refNum>"


# One valid request of each kind; {r} (and {r2}) are its refNums.
SAMPLES = {
    "ReadCoils": req("ReadCoils", "<refNum>{r}</refNum>", to("B3:0", 8, "bit")),
    "ReadInputDiscretes": req("ReadInputDiscretes", "<refNum>{r}</refNum>", to("I:0", 8, "bit")),
    "ReadMultipleRegisters": req("ReadMultipleRegisters", "<refNum>{r}</refNum>", to("N7:0", 2)),
    "ReadInputRegisters": req("ReadInputRegisters", "<refNum>{r}</refNum>", to("N7:0", 2)),
    "WriteCoil": req("WriteCoil", "<refNum>{r}</refNum>", frm("B3:0", 1, "bit")),
    "WriteSingleRegister": req("WriteSingleRegister", "<refNum>{r}</refNum>", frm("N7:0", 1)),
    "ForceMultipleCoils": req("ForceMultipleCoils", "<refNum>{r}</refNum>", frm("O:0", 8, "bit")),
    "WriteMultipleRegisters": req("WriteMultipleRegisters", "<refNum>{r}</refNum>", frm("N7:0", 2)),
    "MaskWriteRegister": req("MaskWriteRegister", "<refNum>{r}</refNum>", "<andMask>0xFFFE</andMask>",
                             frm("N7:0", 1)),
    "ReadWriteRegisters": req("ReadWriteRegisters", "<refNum>{r}</refNum>", to("N7:0", 2),
                              "<refNum>{r2}</refNum>", frm("N7:10", 3)),
}


def sample(kind: str, element: int = 1, region: int | None = None, region2: int | None = None) -> str:
    digit = KINDS[kind][1]
    r = f"{digit if region is None else region}{element:04d}"
    r2 = f"{digit if region2 is None else region2}0001"
    return SAMPLES[kind].replace("{r}", r).replace("{r2}", r2)


# -- 1. a full valid file: every element, every attribute --------------------------------------

FULL = """\
<?xml version="1.0" encoding="UTF-8"?>
<!-- every element and every attribute at least once -->
<ModbusSerial debug="2" portErrors="RETRY" retryMs="250">
  <Port num="0" framing="ascii" baudrate="0x2580" dataBits="7" parity="Even" stopBits="2"
        minPeriod="100" requestTimeout="200" attempts="3" requestGap="10"
        device="sim://bus0?device=modbus&amp;id=1" demoteAfter="4" demotePeriod="2000">
    <ModemControl waitDelayCTS="50"/>
    <Slave id="1" minPeriod="150" requestTimeout="250" attempts="2" demoteAfter="7" demotePeriod="3000">
      <ReadCoils when="start" minPeriod="1000" requestTimeout="500" attempts="5">
        <refNum>0438</refNum>
        <toBlock dest="B3/16" count="20" fmt="bit"/>
      </ReadCoils>
      <ReadInputDiscretes when="STOP">
        <refNum>120438</refNum>
        <toBlock dest="I:1" count="2" fmt="i2"/>
      </ReadInputDiscretes>
      <ReadMultipleRegisters when="run">
        <refNum>40438</refNum>
        <toBlock dest="N7:0" count="10" fmt="i2"/>
        <toBlock dest="O:2" count="5" fmt="I2"/>
      </ReadMultipleRegisters>
      <ReadInputRegisters>
        <refNum> 3023 </refNum>
        <toBlock dest="N7:10" count="0x4" fmt="i2"/>
      </ReadInputRegisters>
      <WriteCoil>
        <refNum>00001</refNum>
        <fromBlock source="B3/5" count="1" fmt="bit"/>
      </WriteCoil>
      <WriteSingleRegister>
        <refNum>40001</refNum>
        <fromBlock count="1" fmt="i2"><const>-1</const></fromBlock>
      </WriteSingleRegister>
    </Slave>
    <Slave id="247">
      <ForceMultipleCoils>
        <refNum>00017</refNum>
        <fromBlock source="O:0/3" count="10" fmt="bit"/>
      </ForceMultipleCoils>
      <WriteMultipleRegisters>
        <refNum>40100</refNum>
        <fromBlock source="S:0" count="2" fmt="i2"/>
        <fromBlock count="4" fmt="i2"><const>1, 0x10 65535,
          -32768</const></fromBlock>
      </WriteMultipleRegisters>
      <MaskWriteRegister>
        <refNum>40005</refNum>
        <andMask>0xFFF0</andMask>
        <fromBlock source="N7:20" count="1" fmt="i2"/>
      </MaskWriteRegister>
      <ReadWriteRegisters>
        <refNum>40200</refNum>
        <toBlock dest="N7:30" count="3" fmt="i2"/>
        <toBlock dest="B3:2" count="2" fmt="i2"/>
        <refNum>40300</refNum>
        <fromBlock source="N7:40" count="4" fmt="i2"/>
        <fromBlock count="2" fmt="i2"><const>0x1234 7</const></fromBlock>
      </ReadWriteRegisters>
    </Slave>
  </Port>
  <Port num="31" baudrate="300"/>
</ModbusSerial>
"""


def block(needle: str, address: str | None, count: int, fmt: str, values: tuple[int, ...] | None = None,
          text: str = FULL) -> Block:
    line, column = locate(text, needle)
    return Block(None if address is None else parse_address(address), count, fmt, values, line, column)


def full_request(kind: str, needle: str, slave: int, when: str, timing: tuple[int, int, int], address: int,
                 count: int, tos=(), froms=(), write_address: int = 0, write_count: int = 0,
                 and_mask: int = 0xFFFF) -> Request:
    line, column = locate(FULL, needle)
    return Request(REQUEST_KINDS[kind], slave, when, *timing, address, count, tuple(tos), tuple(froms),
                   write_address, write_count, and_mask, line, column)


def test_full_example_top_and_ports():
    config = parse(FULL, "app/MODBMAST.XML")
    assert config.path == "app/MODBMAST.XML"
    assert (config.debug, config.port_errors, config.retry_ms, config.warnings) == (2, "retry", 250, [])
    assert sorted(config.ports) == [0, 31]
    p0 = config.ports[0]
    assert (p0.num, p0.framing, p0.baud, p0.data_bits, p0.parity, p0.stop_bits) == (0, "ASCII", 9600, 7, "E", 2)
    assert (p0.request_gap_ms, p0.wait_cts_ms, p0.device) == (10, 50, "sim://bus0?device=modbus&id=1")
    assert p0.line == locate(FULL, '<Port num="0"')[0]
    assert sorted(p0.slaves) == [1, 247]
    s1, s247 = p0.slaves[1], p0.slaves[247]
    assert (s1.id, s1.demote_after, s1.demote_period_ms, s1.line) == (1, 7, 3000, locate(FULL, '<Slave id="1"')[0])
    # Slave 247 sets nothing: the port's demote attributes.
    assert (s247.id, s247.demote_after, s247.demote_period_ms) == (247, 4, 2000)
    assert [r.name for r in s1.requests] == ["ReadCoils", "ReadInputDiscretes", "ReadMultipleRegisters",
                                             "ReadInputRegisters", "WriteCoil", "WriteSingleRegister"]
    assert [r.name for r in s247.requests] == ["ForceMultipleCoils", "WriteMultipleRegisters",
                                               "MaskWriteRegister", "ReadWriteRegisters"]
    # Port 31 sets only what is required: every default.
    assert config.ports[31] == PortConfig(31, "RTU", 300, 8, "N", 1, 3, None, {}, None,
                                          line=locate(FULL, '<Port num="31"')[0])


def test_full_example_requests_of_slave_1():
    s1 = parse(FULL).ports[0].slaves[1]
    slave_timing = (150, 250, 2)  # minPeriod, requestTimeout, attempts of <Slave id="1">
    expected = [
        full_request("ReadCoils", "<ReadCoils", 1, "start", (1000, 500, 5), 437, 20,
                     tos=[block('<toBlock dest="B3/16"', "B3:1/0", 20, "bit")]),
        full_request("ReadInputDiscretes", "<ReadInputDiscretes", 1, "stop", slave_timing, 20437, 32,
                     tos=[block('<toBlock dest="I:1"', "I:1", 2, "i2")]),
        full_request("ReadMultipleRegisters", "<ReadMultipleRegisters", 1, "run", slave_timing, 437, 15,
                     tos=[block('<toBlock dest="N7:0"', "N7:0", 10, "i2"),
                          block('<toBlock dest="O:2"', "O:2", 5, "i2")]),
        full_request("ReadInputRegisters", "<ReadInputRegisters", 1, "run", slave_timing, 22, 4,
                     tos=[block('<toBlock dest="N7:10"', "N7:10", 4, "i2")]),
        full_request("WriteCoil", "<WriteCoil", 1, "run", slave_timing, 0, 1,
                     froms=[block('<fromBlock source="B3/5"', "B3/5", 1, "bit")]),
        full_request("WriteSingleRegister", "<WriteSingleRegister", 1, "run", slave_timing, 0, 1,
                     froms=[block('<fromBlock count="1"', None, 1, "i2", (0xFFFF,))]),
    ]
    assert list(s1.requests) == expected
    assert [r.kind.function for r in s1.requests] == [1, 2, 3, 4, 5, 6]


def test_full_example_requests_of_slave_247():
    s247 = parse(FULL).ports[0].slaves[247]
    port_timing = (100, 200, 3)  # nothing on the slave or the requests: the port's
    expected = [
        full_request("ForceMultipleCoils", "<ForceMultipleCoils", 247, "run", port_timing, 16, 10,
                     froms=[block('<fromBlock source="O:0/3"', "O:0/3", 10, "bit")]),
        full_request("WriteMultipleRegisters", "<WriteMultipleRegisters", 247, "run", port_timing, 99, 6,
                     froms=[block('<fromBlock source="S:0"', "S:0", 2, "i2"),
                            block('<fromBlock count="4"', None, 4, "i2", (1, 0x10, 0xFFFF, 0x8000))]),
        full_request("MaskWriteRegister", "<MaskWriteRegister", 247, "run", port_timing, 4, 1,
                     froms=[block('<fromBlock source="N7:20"', "N7:20", 1, "i2")], and_mask=0xFFF0),
        full_request("ReadWriteRegisters", "<ReadWriteRegisters", 247, "run", port_timing, 199, 5,
                     tos=[block('<toBlock dest="N7:30"', "N7:30", 3, "i2"),
                          block('<toBlock dest="B3:2"', "B3:2", 2, "i2")],
                     froms=[block('<fromBlock source="N7:40"', "N7:40", 4, "i2"),
                            block('<fromBlock count="2"', None, 2, "i2", (0x1234, 7))],
                     write_address=299, write_count=6),
    ]
    assert list(s247.requests) == expected
    assert [r.kind.function for r in s247.requests] == [15, 16, 22, 23]


def test_block_bits_and_words():
    s1 = parse(FULL).ports[0].slaves[1]
    coils = s1.requests[0].to_blocks[0]  # B3/16, 20 bits
    assert (coils.bits, coils.words) == (20, 2)
    discretes = s1.requests[1].to_blocks[0]  # I:1, 2 words of i2
    assert (discretes.bits, discretes.words) == (32, 2)
    odd = request(req("ForceMultipleCoils", ref("00001"), frm("B3/14", 3, "bit"))).from_blocks[0]
    assert (odd.bits, odd.words) == (3, 2)  # bits 14, 15 and the next word's 0


# -- 2. defaults and inheritance ----------------------------------------------------------------

MINIMAL = in_slave(sample("ReadCoils"))


def test_defaults_when_attributes_are_omitted():
    config = parse(MINIMAL)
    assert (config.debug, config.port_errors, config.retry_ms) == (0, "stop", 1000)
    port = config.ports[1]
    assert (port.framing, port.baud, port.data_bits, port.parity, port.stop_bits) == ("RTU", 19200, 8, "N", 1)
    assert (port.request_gap_ms, port.wait_cts_ms, port.device) == (3, None, None)
    slave = port.slaves[2]
    assert (slave.demote_after, slave.demote_period_ms) == (0, 5000)
    (r,) = slave.requests
    assert (r.when, r.min_period_ms, r.timeout_ms, r.attempts) == ("run", 0, 30, 1)
    assert (r.write_address, r.write_count, r.and_mask) == (0, 0, 0xFFFF)


def test_modem_control_with_zero_wait_is_still_handshaking():
    port = parse('<ModbusSerial><Port num="1" baudrate="9600"><ModemControl waitDelayCTS="0"/></Port>'
                 '</ModbusSerial>').ports[1]
    assert port.wait_cts_ms == 0  # present (0 ms), not None (absent)


def test_empty_configuration_has_no_ports():
    assert parse("<ModbusSerial/>").ports == {}


P = 'minPeriod="10" requestTimeout="20" attempts="3"'
S = 'minPeriod="11" requestTimeout="21" attempts="4"'
R = 'minPeriod="12" requestTimeout="22" attempts="5"'


@pytest.mark.parametrize("port, slave, request_attrs, expected", [
    ("", "", "", (0, 30, 1)),
    (P, "", "", (10, 20, 3)),
    ("", S, "", (11, 21, 4)),
    ("", "", R, (12, 22, 5)),
    (P, S, "", (11, 21, 4)),
    (P, "", R, (12, 22, 5)),
    ("", S, R, (12, 22, 5)),
    (P, S, R, (12, 22, 5)),
    # each attribute from its own level
    ('requestTimeout="40"', 'attempts="7"', 'minPeriod="60"', (60, 40, 7)),
    ('minPeriod="0x10"', 'minPeriod="0"', "", (0, 30, 1)),  # a slave's 0 still overrides
], ids=["defaults", "port", "slave", "request", "port+slave", "port+request", "slave+request", "all",
        "mixed", "zero-overrides"])
def test_inheritance_request_slave_port_default(port, slave, request_attrs, expected):
    r = request(req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"), attrs=request_attrs),
                port=f'num="1" baudrate="19200" {port}', slave=f'id="2" {slave}')
    assert (r.min_period_ms, r.timeout_ms, r.attempts) == expected


def test_inheritance_is_per_request_and_per_slave():
    xml = ('<ModbusSerial><Port num="1" baudrate="9600" requestTimeout="100">'
           '<Slave id="1" requestTimeout="200">'
           + req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"), attrs='requestTimeout="300"')
           + req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"))
           + '</Slave><Slave id="2">' + req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"))
           + "</Slave></Port></ModbusSerial>")
    port = parse(xml).ports[1]
    assert [r.timeout_ms for r in port.slaves[1].requests] == [300, 200]
    assert [r.timeout_ms for r in port.slaves[2].requests] == [100]


@pytest.mark.parametrize("port, slave, expected", [
    ("", "", (0, 5000)),
    ('demoteAfter="3" demotePeriod="100"', "", (3, 100)),
    ("", 'demoteAfter="5" demotePeriod="200"', (5, 200)),
    ('demoteAfter="3" demotePeriod="100"', 'demoteAfter="5"', (5, 100)),
])
def test_demote_attributes_inherit_slave_port_default(port, slave, expected):
    s = parse(in_slave("", port=f'num="1" baudrate="19200" {port}', slave=f'id="2" {slave}')).ports[1].slaves[2]
    assert (s.demote_after, s.demote_period_ms) == expected


@pytest.mark.parametrize("when, expected", [("run", "run"), ("start", "start"), ("stop", "stop"),
                                            ("START", "start"), (" Stop ", "stop")])
def test_when_values(when, expected):
    assert request(req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"), attrs=f'when="{when}"')).when == expected


@pytest.mark.parametrize("attrs, field, expected", [
    ('framing="rtu"', "framing", "RTU"), ('framing="Ascii"', "framing", "ASCII"),
    ('parity="none"', "parity", "N"), ('parity="EVEN"', "parity", "E"), ('parity="odd"', "parity", "O"),
    ('parity="Mark"', "parity", "M"), ('stopBits="2"', "stop_bits", 2), ('dataBits="8"', "data_bits", 8),
    ('framing="ASCII" dataBits="7"', "data_bits", 7), ('baudrate="230400"', "baud", 230400),
    ('baudrate="300"', "baud", 300), ('baudrate="0x4B00"', "baud", 19200), ('baudrate=" 9600 "', "baud", 9600),
    ('requestGap="0"', "request_gap_ms", 0), ('requestGap="250"', "request_gap_ms", 250),
    ('device=" /dev/ttyUSB0 "', "device", "/dev/ttyUSB0"), ('device="COM3"', "device", "COM3"),
])
def test_port_attribute_values(attrs, field, expected):
    num_baud = 'num="5"' + ("" if "baudrate" in attrs else ' baudrate="9600"')
    port = parse(f"<ModbusSerial><Port {num_baud} {attrs}/></ModbusSerial>").ports[5]
    assert getattr(port, field) == expected


@pytest.mark.parametrize("num", [0, 31])
def test_port_num_range_ends(num):
    assert list(parse(f'<ModbusSerial><Port num="{num}" baudrate="9600"/></ModbusSerial>').ports) == [num]


@pytest.mark.parametrize("sid", [1, 247])
def test_slave_id_range_ends(sid):
    assert list(parse(in_slave("", slave=f'id="{sid}"')).ports[1].slaves) == [sid]


def test_same_slave_id_on_two_ports_is_fine():
    config = parse('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="5"/></Port>'
                   '<Port num="2" baudrate="9600"><Slave id="5"/></Port></ModbusSerial>')
    assert (list(config.ports[1].slaves), list(config.ports[2].slaves)) == ([5], [5])


@pytest.mark.parametrize("attrs, expected", [
    ('debug="0"', (0, "stop", 1000)), ('debug="1"', (1, "stop", 1000)),
    ('portErrors="stop" retryMs="10"', (0, "stop", 10)),
    ('portErrors="retry" retryMs="3600000"', (0, "retry", 3600000)),
])
def test_root_attribute_values(attrs, expected):
    config = parse(f"<ModbusSerial {attrs}/>")
    assert (config.debug, config.port_errors, config.retry_ms) == expected


@pytest.mark.parametrize("attrs, expected", [
    ('minPeriod="3600000" requestTimeout="1" attempts="100"', (3600000, 1, 100)),
    ('minPeriod="0" requestTimeout="60000" attempts="1"', (0, 60000, 1)),
])
def test_inherited_attribute_range_ends(attrs, expected):
    r = request(req("ReadCoils", ref("00001"), to("B3:0", 1, "bit"), attrs=attrs))
    assert (r.min_period_ms, r.timeout_ms, r.attempts) == expected


# -- 3. refNum (Table 7) -------------------------------------------------------------------------

@pytest.mark.parametrize("kind, refnum, address", [
    ("ReadInputDiscretes", "120438", 20437),  # Table 7's examples
    ("ReadInputRegisters", "3023", 22),
    ("ReadCoils", "0438", 437),
    ("ReadMultipleRegisters", "40438", 437),
    ("ReadMultipleRegisters", "40001", 0),  # element 1 is protocol address 0
    ("ReadMultipleRegisters", "4000001", 0),
    ("WriteSingleRegister", "465536", 65535),  # the last element
    ("WriteCoil", "01", 0),
    ("ReadCoils", "  00010\n ", 9),  # whitespace around it is fine
])
def test_refnum_table_7(kind, refnum, address):
    xml = SAMPLES[kind].replace("{r}", refnum)
    assert request(xml).address == address


@pytest.mark.parametrize("kind", list(KINDS))
def test_each_request_kind_function_and_region(kind):
    r = request(sample(kind, element=11))
    function, _, reads, bits = KINDS[kind]
    assert (r.kind.function, r.name, r.address) == (function, kind, 10)
    assert (r.kind.reads, r.kind.bits) == (reads, bits)
    assert (bool(r.to_blocks), bool(r.from_blocks)) == (reads, kind in ("ReadWriteRegisters",) or not reads)


REGION_NAMES = {0: "0xxxx (coils)", 1: "1xxxx (input discretes)", 3: "3xxxx (input registers)",
                4: "4xxxx (holding registers)"}


@pytest.mark.parametrize("kind, digit", [(k, d) for k in KINDS for d in range(10) if d != KINDS[k][1]])
def test_refnum_region_must_fit_the_request(kind, digit):
    xml = in_slave(sample(kind, region=digit))
    p = only_problem(xml)
    right = KINDS[kind][1]
    assert f"refNum {digit}0001 is in region {digit}xxxx" in p.message
    assert f"<{kind}> {'reads' if KINDS[kind][2] else 'writes'} {REGION_NAMES[right]}" in p.message
    assert where(p) == locate(xml, "<refNum>")


@pytest.mark.parametrize("digit", [0, 1, 3, 5])
def test_read_write_registers_second_refnum_region(digit):
    xml = in_slave(sample("ReadWriteRegisters", region2=digit))
    p = only_problem(xml)
    assert f"is in region {digit}xxxx; <ReadWriteRegisters> writes 4xxxx" in p.message
    assert where(p) == locate(xml, "<refNum>", 2)


@pytest.mark.parametrize("refnum, element", [("40000", 0), ("465537", 65537), ("00", 0), ("1999999", 999999)])
def test_refnum_element_outside_1_to_65536(refnum, element):
    kind = {"4": "ReadMultipleRegisters", "0": "ReadCoils", "1": "ReadInputDiscretes"}[refnum[0]]
    xml = in_slave(SAMPLES[kind].replace("{r}", refnum))
    p = only_problem(xml)
    assert f"element {element} is outside 1..65536" in p.message
    assert where(p) == locate(xml, "<refNum>")


@pytest.mark.parametrize("text", ["", "4", "abc", "4-1", "0x10", "40001x", "4 0001", "400000001", "+40001", "٤0001"])
def test_refnum_that_is_not_a_reference_number(text):
    xml = in_slave(SAMPLES["ReadMultipleRegisters"].replace("{r}", text))
    p = only_problem(xml)
    assert "expected a Modicon reference number such as 40001" in p.message
    assert where(p) == locate(xml, "<refNum>")


# -- 4. quantity limits per function -------------------------------------------------------------

def regs(n: int, make=to, file: str = "N7") -> list[str]:
    """Blocks of at most 100 words adding up to ``n``."""
    return [make(f"{file}:{i * 100}", min(100, n - i * 100)) for i in range((n + 99) // 100)]


# (kind, function, content at the limit, content one over, the over quantity, noun, the limit's words)
QUANTITIES = [
    ("ReadCoils", [to("B3:0", 2000, "bit")], [to("B3:0", 126)], 2000, 2016, "coils", "1..2000"),
    ("ReadCoils", [to("B3:0", 125)], [to("B3:0", 126)], 2000, 2016, "coils", "1..2000"),
    ("ReadInputDiscretes", [to("I:0", 2000, "bit")], [to("I:0", 126)], 2000, 2016, "discretes", "1..2000"),
    ("ReadMultipleRegisters", regs(125), regs(126), 125, 126, "registers", "1..125"),
    ("ReadInputRegisters", regs(125), regs(126), 125, 126, "registers", "1..125"),
    ("WriteCoil", [frm("B3:0", 1, "bit")], [frm("B3:0", 2, "bit")], 1, 2, "coils", "exactly 1"),
    ("WriteCoil", [frm("B3:0", 1, "bit")], [frm("B3:0", 1)], 1, 16, "coils", "exactly 1"),
    ("WriteSingleRegister", [frm("N7:0", 1)], [frm("N7:0", 2)], 1, 2, "registers", "exactly 1"),
    ("ForceMultipleCoils", [frm("B3:0", 1968, "bit")], [frm("B3:0", 1969, "bit")], 1968, 1969, "coils",
     "1..1968"),
    ("ForceMultipleCoils", [frm("B3:0", 123)], [frm("B3:0", 124)], 1968, 1984, "coils", "1..1968"),
    ("WriteMultipleRegisters", regs(123, frm), regs(124, frm), 123, 124, "registers", "1..123"),
    ("MaskWriteRegister", ["<andMask>1</andMask>", frm("N7:0", 1)], ["<andMask>1</andMask>", frm("N7:0", 2)],
     1, 2, "registers", "exactly 1"),
]


@pytest.mark.parametrize("kind, at_limit, over, limit, too_many, noun, words", QUANTITIES,
                         ids=[f"{q[0]}-{q[4]}" for q in QUANTITIES])
def test_quantity_limits(kind, at_limit, over, limit, too_many, noun, words):
    function = KINDS[kind][0]
    refnum = f"{KINDS[kind][1]}0001"
    assert request(req(kind, ref(refnum), *at_limit)).count == limit
    xml = in_slave(req(kind, ref(refnum), *over))
    p = only_problem(xml)
    verb = "reads" if KINDS[kind][2] else "writes"
    assert f"<{kind}> {verb} {too_many} {noun}" in p.message
    assert f"function {function} takes {words} {noun}" in p.message
    assert where(p) == locate(xml, f"<{kind}>")


def test_read_write_registers_limits():
    ok = request(req("ReadWriteRegisters", ref("40001"), *regs(125), ref("40001"), *regs(121, frm, "N9")))
    assert (ok.count, ok.write_count) == (125, 121)
    xml = in_slave(req("ReadWriteRegisters", ref("40001"), *regs(126), ref("40001"), *regs(122, frm, "N9")))
    found = problems(xml)
    assert len(found) == 2
    assert "reads 126 registers" in found[0].message and "function 23 takes 1..125 registers" in found[0].message
    assert "writes 122 registers" in found[1].message and "function 23 takes 1..121 registers" in found[1].message
    assert {where(p) for p in found} == {locate(xml, "<ReadWriteRegisters>")}


def test_bit_block_count_attribute_limit():
    """2001 bits cannot even be written as one block's count (1..2000)."""
    xml = in_slave(req("ReadCoils", ref("00001"), to("B3:0", 2001, "bit")))
    p = only_problem(xml)
    assert "count='2001': expected an integer 1..2000" in p.message
    assert where(p) == locate(xml, 'count="2001"')


@pytest.mark.parametrize("kind, refnum, content, ok", [
    ("ReadMultipleRegisters", "465536", [to("N7:0", 1)], True),
    ("ReadMultipleRegisters", "465536", [to("N7:0", 2)], False),
    ("ReadMultipleRegisters", "465412", [to("N7:0", 125)], True),  # 65411 + 125 = 65536
    ("ReadMultipleRegisters", "465413", [to("N7:0", 125)], False),
    ("ReadCoils", "065530", [to("B3:0", 7, "bit")], True),
    ("ReadCoils", "065530", [to("B3:0", 8, "bit")], False),
    ("ForceMultipleCoils", "065521", [frm("B3:0", 1)], True),  # 16 coils: 65520..65535
    ("ForceMultipleCoils", "065522", [frm("B3:0", 1)], False),
])
def test_quantity_must_not_run_past_element_65536(kind, refnum, content, ok):
    xml = in_slave(req(kind, ref(refnum), *content))
    if ok:
        r = request(req(kind, ref(refnum), *content))
        assert r.address + r.count == 65536
    else:
        p = only_problem(xml)
        assert "run past element 65536" in p.message
        assert where(p) == locate(xml, f"<{kind}>")


def test_read_write_registers_write_part_must_not_run_past_65536():
    xml = in_slave(req("ReadWriteRegisters", ref("40001"), to("N7:0", 1), ref("465536"), frm("N7:0", 2)))
    p = only_problem(xml)
    assert "2 registers from refNum element 65536 run past element 65536" in p.message


# -- 5. block addresses -------------------------------------------------------------------------

@pytest.mark.parametrize("address, to_ok, from_ok", [
    ("O:0", True, True), ("I:0", True, True), ("S:0", False, True), ("B3:0", True, True), ("N7:0", True, True),
    ("B10:5", True, True), ("N50:0", True, True),
    ("T4:0", False, False), ("C5:0", False, False), ("R6:0", False, False), ("F8:0", False, False),
    ("ST9:0", False, False), ("T4:0.ACC", False, False), ("C5:0.PRE", False, False),
])
def test_block_file_types(address, to_ok, from_ok):
    for is_to, ok in ((True, to_ok), (False, from_ok)):
        kind = "ReadMultipleRegisters" if is_to else "WriteMultipleRegisters"
        block_xml = to(address, 1) if is_to else frm(address, 1)
        xml = in_slave(req(kind, ref("40001"), block_xml))
        if ok:
            r = parse(xml).ports[1].slaves[2].requests[0]
            assert (r.to_blocks if is_to else r.from_blocks)[0].address == parse_address(address)
        else:
            p = only_problem(xml)
            attr = "dest" if is_to else "source"
            files = "an O, I, B or N file" if is_to else "an O, I, S, B or N file"
            assert p.message.startswith(f"{attr}={address!r}: ") and files in p.message
            assert where(p) == locate(xml, f'{attr}="')


@pytest.mark.parametrize("address", ["N7:[N7:1]", "#N7:0", "N[N7:0]:0", "B3/[N7:0]", "N7:[N7:1]/3"])
@pytest.mark.parametrize("is_to", [True, False])
def test_indirect_and_indexed_block_addresses_refused(address, is_to):
    kind = "ReadCoils" if is_to else "ForceMultipleCoils"
    block_xml = to(address, 1, "bit") if is_to else frm(address, 1, "bit")
    xml = in_slave(req(kind, ref("00001"), block_xml))
    p = only_problem(xml)
    assert "must be direct" in p.message
    assert where(p) == locate(xml, "dest=" if is_to else "source=")


@pytest.mark.parametrize("address, message", [
    ("Q7:0", "unknown file type 'Q'"), ("N7", "expected ':'"), ("", "is empty"), ("   ", "is empty"),
])
def test_unreadable_block_address(address, message):
    xml = in_slave(req("ReadMultipleRegisters", ref("40001"), to(address, 1)))
    p = only_problem(xml)
    assert message in p.message
    assert where(p) == locate(xml, "dest=")


@pytest.mark.parametrize("kind, block_xml", [
    ("ReadMultipleRegisters", to("B3/16", 1)), ("ReadMultipleRegisters", to("N7:0/0", 1)),
    ("ReadInputRegisters", to("B3:1/0", 1)), ("ReadWriteRegisters", None),
    ("WriteMultipleRegisters", frm("B3/0", 1)), ("WriteSingleRegister", frm("N7:3/4", 1)),
    ("MaskWriteRegister", frm("O:0/0", 1)),
])
def test_register_requests_need_word_addresses(kind, block_xml):
    if kind == "ReadWriteRegisters":
        content = [ref("40001"), to("N7:0", 1), ref("40001"), frm("B3/32", 1)]
        attr = "source"
    else:
        content = [ref(f"{KINDS[kind][1]}0001"), *(["<andMask>1</andMask>"] if kind == "MaskWriteRegister" else []),
                   block_xml]
        attr = "dest" if "toBlock" in block_xml else "source"
    xml = in_slave(req(kind, *content))
    p = only_problem(xml)
    assert f"<{kind}> moves registers: {attr} must be a word address" in p.message
    assert where(p) == locate(xml, f"{attr}=")


@pytest.mark.parametrize("kind, block_xml", [
    ("ReadMultipleRegisters", to("N7:0", 1, "bit")), ("WriteMultipleRegisters", frm("N7:0", 1, "bit")),
    ("WriteSingleRegister", frm("N7:0", 1, "BIT")),
])
def test_fmt_bit_refused_in_register_requests(kind, block_xml):
    xml = in_slave(req(kind, ref("40001"), block_xml))
    p = only_problem(xml)
    assert 'fmt="bit"' in p.message and 'use fmt="i2"' in p.message
    assert where(p) == locate(xml, "fmt=")


@pytest.mark.parametrize("kind, block_xml, ok", [
    # toBlocks of coils or discretes: a word, or a bit address whose bit is 0
    ("ReadCoils", to("B3/16", 8, "bit"), True),
    ("ReadCoils", to("B3:1/0", 8, "bit"), True),
    ("ReadCoils", to("N7:4", 8, "bit"), True),
    ("ReadInputDiscretes", to("I:1/0", 8, "bit"), True),
    ("ReadCoils", to("B3/32", 2), True),
    ("ReadCoils", to("B3/17", 8, "bit"), False),
    ("ReadInputDiscretes", to("I:1/7", 8, "bit"), False),
    ("ReadCoils", to("N7:0/15", 1, "bit"), False),
    # fromBlocks of coils: fmt="bit" may start at any bit, fmt="i2" at a word
    ("ForceMultipleCoils", frm("B3/21", 5, "bit"), True),
    ("ForceMultipleCoils", frm("O:0/17", 5, "bit"), True),
    ("WriteCoil", frm("N7:2/15", 1, "bit"), True),
    ("ForceMultipleCoils", frm("B3/16", 1), True),
    ("ForceMultipleCoils", frm("B3/21", 1), False),
    ("ForceMultipleCoils", frm("N7:0/1", 2), False),
])
def test_bit_address_rules_of_coil_and_discrete_blocks(kind, block_xml, ok):
    xml = in_slave(req(kind, ref(f"{KINDS[kind][1]}0001"), block_xml))
    address = re.search(r'(?:dest|source)="([^"]*)"', block_xml).group(1)
    if ok:
        r = parse(xml).ports[1].slaves[2].requests[0]
        assert (r.to_blocks or r.from_blocks)[0].address == parse_address(address)
    else:
        p = only_problem(xml)
        assert "bit 0" in p.message
        assert where(p) == locate(xml, "dest=" if "toBlock" in block_xml else "source=")


@pytest.mark.parametrize("block_xml, ok", [
    (to("N7:9999", 1), True), (to("N7:9999", 2), False), (to("N7:9900", 100), True), (to("N7:9901", 100), False),
    (frm("N7:9999", 1), True), (frm("N7:9999", 2), False),
])
def test_word_block_must_not_run_past_element_9999(block_xml, ok):
    kind = "ReadMultipleRegisters" if "toBlock" in block_xml else "WriteMultipleRegisters"
    xml = in_slave(req(kind, ref("40001"), block_xml))
    if ok:
        assert parse(xml).ports[1].slaves[2].requests[0].count >= 1
    else:
        p = only_problem(xml)
        assert "run past the end of a file (elements 0..9999)" in p.message
        assert where(p) == locate(xml, "dest=" if kind.startswith("Read") else "source=")


@pytest.mark.parametrize("block_xml, ok", [
    (to("B3:9999/0", 16, "bit"), True), (to("B3:9999/0", 17, "bit"), False),
    (to("B3:9998", 32, "bit"), True), (to("B3:9998", 33, "bit"), False),
    (frm("B3:9999/15", 1, "bit"), True), (frm("B3:9999/15", 2, "bit"), False),
    (frm("B3:9999/0", 1), True), (frm("B3:9999/0", 2), False),
])
def test_bit_block_must_not_run_past_element_9999(block_xml, ok):
    kind = "ReadCoils" if "toBlock" in block_xml else "ForceMultipleCoils"
    xml = in_slave(req(kind, ref("00001"), block_xml))
    if ok:
        assert parse(xml).ports[1].slaves[2].requests[0].count >= 1
    else:
        p = only_problem(xml)
        assert "run past the end of a file" in p.message


# -- 6. const -----------------------------------------------------------------------------------

@pytest.mark.parametrize("count, values, fmt, expected", [
    (4, "-32768, 65535 0x10\n7", "i2", (0x8000, 0xFFFF, 16, 7)),
    (3, " 1,2 ,3 ", "i2", (1, 2, 3)),
    (2, "-1 0xFFFF", "i2", (0xFFFF, 0xFFFF)),
    (1, "0X7fff", "i2", (0x7FFF,)),
    (5, "1 0 1,1,0", "bit", (1, 0, 1, 1, 0)),
])
def test_const_values(count, values, fmt, expected):
    kind = "ForceMultipleCoils" if fmt == "bit" else "WriteMultipleRegisters"
    r = request(req(kind, ref(f"{KINDS[kind][1]}0001"), const(count, values, fmt)))
    (b,) = r.from_blocks
    assert (b.const, b.address, b.count, b.fmt) == (expected, None, count, fmt)


def test_const_i2_in_a_coil_request_counts_16_bits_a_word():
    r = request(req("ForceMultipleCoils", ref("00001"), const(2, "0xFFFF 0x0001")))
    assert (r.count, r.from_blocks[0].const) == (32, (0xFFFF, 1))


def test_const_with_source_too_keeps_both():
    r = request(req("WriteSingleRegister", ref("40001"),
                    '<fromBlock source="N7:0" count="1" fmt="i2"><const>5</const></fromBlock>'))
    (b,) = r.from_blocks
    assert (b.address, b.const) == (parse_address("N7:0"), (5,))


@pytest.mark.parametrize("count, values, fmt, message", [
    (1, "-32769", "i2", "<const> value '-32769': expected an integer -32768..65535"),
    (1, "65536", "i2", "<const> value '65536': expected an integer -32768..65535"),
    (1, "0x10000", "i2", "expected an integer -32768..65535"),
    (1, "abc", "i2", "<const> value 'abc'"),
    (1, "1.5", "i2", "<const> value '1.5'"),
    (1, "2", "bit", "<const> value '2': expected 0 or 1"),
    (1, "-1", "bit", "expected 0 or 1"),
    (3, "1 2", "i2", "<const> has 2 values; its fromBlock's count is 3"),
    (1, "1 2", "i2", "<const> has 2 values; its fromBlock's count is 1"),
    (1, "", "i2", "<const> has 0 values; its fromBlock's count is 1"),
    (2, "1", "bit", "<const> has 1 value; its fromBlock's count is 2"),
])
def test_const_errors(count, values, fmt, message):
    kind = "ForceMultipleCoils" if fmt == "bit" else "WriteMultipleRegisters"
    xml = in_slave(req(kind, ref(f"{KINDS[kind][1]}0001"), const(count, values, fmt)))
    p = only_problem(xml)
    assert message in p.message
    assert where(p) == locate(xml, "<const>")


def test_from_block_needs_source_or_const():
    xml = in_slave(req("WriteMultipleRegisters", ref("40001"), '<fromBlock count="1" fmt="i2"/>'))
    p = only_problem(xml)
    assert "needs the attribute source" in p.message and "<const>" in p.message
    assert where(p) == locate(xml, "<fromBlock")


@pytest.mark.parametrize("content, message, needle", [
    ('<toBlock dest="N7:0" count="1" fmt="i2"><const>1</const></toBlock>', "<const> is not allowed here",
     "<const>"),
    ('<fromBlock count="1" fmt="i2"><const>1</const><const>1</const></fromBlock>',
     "<const> is not allowed here", "<const>1</const></fromBlock>"),
    ('<fromBlock count="1" fmt="i2"><const base="16">1</const></fromBlock>', "<const> has no attribute 'base'",
     "base="),
    ('<fromBlock count="1" fmt="i2"><const>1<x/></const></fromBlock>', "unknown element <x>", "<x/>"),
])
def test_const_in_wrong_places(content, message, needle):
    kind = "ReadMultipleRegisters" if content.startswith("<toBlock") else "WriteMultipleRegisters"
    xml = in_slave(req(kind, ref("40001"), content))
    p = only_problem(xml)
    assert message in p.message
    assert where(p) == locate(xml, needle)


# -- 7. structure (Table 8) ---------------------------------------------------------------------

T1 = to("N7:0", 1)
F1 = frm("N7:0", 1)


@pytest.mark.parametrize("kind, content, expected", [
    # (message fragment, needle of where it is reported)
    ("ReadMultipleRegisters", [T1], [("needs <refNum> here", "<toBlock")]),
    ("ReadMultipleRegisters", [], [("needs <refNum> here", "<ReadMultipleRegisters>"),
                                   ("needs <toBlock> here", "<ReadMultipleRegisters>")]),
    ("ReadMultipleRegisters", [ref("40001")], [("needs <toBlock> here", "<ReadMultipleRegisters>")]),
    ("ReadMultipleRegisters", [T1, ref("40001")], [("needs <refNum> here", "<toBlock"),
                                                   ("<refNum> is not allowed here", "<refNum>")]),
    ("ReadMultipleRegisters", [ref("40001"), ref("40002"), T1], [("<refNum> is not allowed here", "<refNum>40002")]),
    ("ReadMultipleRegisters", [ref("40001"), T1, ref("40002")], [("<refNum> is not allowed here", "<refNum>40002")]),
    ("ReadCoils", [ref("00001"), to("B3:0", 1, "bit"), to("B3:1", 1, "bit")],
     [("<toBlock> is not allowed here", '<toBlock dest="B3:1"')]),
    ("ReadInputDiscretes", [ref("10001"), to("B3:0", 1, "bit"), to("B3:1", 1, "bit")],
     [("<toBlock> is not allowed here", '<toBlock dest="B3:1"')]),
    ("WriteCoil", [ref("00001"), frm("B3:0", 1, "bit"), frm("B3:1", 1, "bit")],
     [("<fromBlock> is not allowed here", '<fromBlock source="B3:1"')]),
    ("ForceMultipleCoils", [ref("00001"), frm("B3:0", 1, "bit"), frm("B3:1", 1, "bit")],
     [("<fromBlock> is not allowed here", '<fromBlock source="B3:1"')]),
    ("WriteSingleRegister", [ref("40001"), F1, frm("N7:1", 1)],
     [("<fromBlock> is not allowed here", '<fromBlock source="N7:1"')]),
    ("WriteMultipleRegisters", [ref("40001"), T1], [("needs <fromBlock> here", "<WriteMultipleRegisters>"),
                                                    ("<toBlock> is not allowed here", "<toBlock")]),
    ("ReadMultipleRegisters", [ref("40001"), F1], [("needs <toBlock> here", "<ReadMultipleRegisters>"),
                                                   ("<fromBlock> is not allowed here", "<fromBlock")]),
    ("ReadWriteRegisters", [ref("40001"), T1, F1], [("needs <refNum> here", "<fromBlock")]),
    ("ReadWriteRegisters", [ref("40001"), ref("40002"), F1], [("needs <toBlock> here", "<refNum>40002")]),
    ("ReadWriteRegisters", [ref("40001"), T1, ref("40002"), F1, ref("40003")],
     [("<refNum> is not allowed here", "<refNum>40003")]),
    ("ReadWriteRegisters", [ref("40001"), T1, ref("40002"), T1, F1], [("<toBlock> is not allowed here", "<toBlock", 2)]),
    ("MaskWriteRegister", [ref("40001"), F1], [("needs <andMask> here", "<fromBlock")]),
    ("MaskWriteRegister", [ref("40001"), F1, "<andMask>1</andMask>"],
     [("needs <andMask> here", "<fromBlock"), ("<andMask> is not allowed here", "<andMask>")]),
    ("MaskWriteRegister", [ref("40001"), "<andMask>1</andMask>", "<andMask>2</andMask>", F1],
     [("<andMask> is not allowed here", "<andMask>2")]),
    ("WriteMultipleRegisters", [ref("40001"), "<fromBlok/>"],
     [("needs <fromBlock> here", "<WriteMultipleRegisters>"),
      (("unknown element <fromBlok> (<WriteMultipleRegisters> contains <refNum>, <fromBlock>+); "
       "did you mean <fromBlock>?"), "<fromBlok")]),
    ("WriteMultipleRegisters", ["<refnum>40001</refnum>", F1],
     [("unknown element <refnum>", "<refnum>"), ("needs <refNum> here", "<fromBlock")]),
    ("ReadCoils", [ref("00001"), "<Slave/>", to("B3:0", 1, "bit")], [("<Slave> is not allowed here", "<Slave/>")]),
])
def test_request_content_order_and_counts(kind, content, expected):
    xml = in_slave(req(kind, *content))
    found = problems(xml)
    want = sorted((locate(xml, e[1], *e[2:]), e[0]) for e in expected)
    assert [where(p) for p in found] == [w for w, _ in want], ModuleErrors(found).report()
    for p, (_, fragment) in zip(found, want):
        assert fragment in p.message


def test_a_misplaced_element_does_not_hide_what_follows():
    """An element that fits nowhere is reported, and the elements after it are
    still matched and checked (the valid ones are not called misplaced)."""
    xml = ('<ModbusSerial>\n<port num="1"/>\n<Port num="1" baudrate="9600">\n<Slvae/>\n<Slave id="300"/>\n'
           '</Port>\n</ModbusSerial>\n')
    found = problems(xml)
    assert [where(p) for p in found] == [locate(xml, "<port"), locate(xml, "<Slvae"), locate(xml, 'id="300"')]
    assert "unknown element <port>" in found[0].message and "did you mean <Port>?" in found[0].message
    assert "unknown element <Slvae>" in found[1].message and "did you mean <Slave>?" in found[1].message
    assert "id='300': expected an integer 1..247" in found[2].message


@pytest.mark.parametrize("xml, fragment, needle", [
    ('<ModbusSerial><Slave id="1"/></ModbusSerial>', "<Slave> is not allowed here (<ModbusSerial> contains <Port>*)",
     "<Slave"),
    ('<ModbusSerial><ModbusSerial/></ModbusSerial>', "<ModbusSerial> is not allowed here", "<ModbusSerial/>"),
    ('<ModbusSerial><Port num="1" baudrate="9600"><Port num="2" baudrate="9600"/></Port></ModbusSerial>',
     "<Port> is not allowed here (<Port> contains <ModemControl>?, <Slave>*)", '<Port num="2"'),
    (('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"/><ModemControl waitDelayCTS="1"/></Port>'
     '</ModbusSerial>'), "<ModemControl> is not allowed here", "<ModemControl"),
    (('<ModbusSerial><Port num="1" baudrate="9600"><ModemControl waitDelayCTS="1"/><ModemControl waitDelayCTS="2"/>'
     '</Port></ModbusSerial>'), "<ModemControl> is not allowed here", '<ModemControl waitDelayCTS="2"'),
    (('<ModbusSerial><Port num="1" baudrate="9600"><ModemControl waitDelayCTS="1"><Slave id="1"/></ModemControl>'
     '</Port></ModbusSerial>'), "<Slave> is not allowed here (<ModemControl> contains no elements)", "<Slave"),
    (('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><ModemControl waitDelayCTS="1"/></Slave></Port>'
     '</ModbusSerial>'), "<ModemControl> is not allowed here (<Slave> contains requests: ReadCoils,", "<ModemControl"),
    ('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><refNum>1</refNum></Slave></Port></ModbusSerial>',
     "<refNum> is not allowed here", "<refNum>"),
    ('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><ReadCoil/></Slave></Port></ModbusSerial>',
     "<ReadCoil> is not a request", "<ReadCoil/>"),
    ('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><readcoils/></Slave></Port></ModbusSerial>',
     "did you mean <ReadCoils>?", "<readcoils/>"),
    ('<ModbusSerial><port num="1" baudrate="9600"/></ModbusSerial>', "unknown element <port>", "<port"),
    (('<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><ReadCoils><refNum>00001</refNum>'
     '<toBlock dest="B3:0" count="1" fmt="bit"><refNum>1</refNum></toBlock></ReadCoils></Slave></Port>'
     '</ModbusSerial>'), "<refNum> is not allowed here (<toBlock> contains no elements)", "<refNum>1"),
])
def test_elements_in_the_wrong_place(xml, fragment, needle):
    p = only_problem(xml)
    assert fragment in p.message
    assert where(p) == locate(xml, needle)


def test_unknown_element_hint_only_when_close():
    xml = in_slave("<Frobnicate/>")
    p = only_problem(xml)
    assert "<Frobnicate> is not a request" in p.message and "did you mean" not in p.message


@pytest.mark.parametrize("xml", [
    "<ModbusSerial/>", "<Modbus/>", "<modbusserial/>", "<ModbusSerialX/>",
])
def test_top_element(xml):
    if xml == "<ModbusSerial/>":
        assert parse(xml).ports == {}
    else:
        p = only_problem(xml)
        name = xml[1:-2]
        assert p.message.startswith(f"the top element is <{name}>; expected <ModbusSerial>")
        assert where(p) == (1, 1)


def test_text_comments_cdata_and_processing_instructions_are_fine():
    """Text where no text is expected is ignored; comments, CDATA and
    processing instructions anywhere are allowed."""
    xml = ("<?xml version='1.0'?>\n<!-- head -->\n<ModbusSerial>some text<?editor x?>\n"
           " <Port num='1' baudrate='9600'>port text<!-- c -->\n"
           "  <Slave id='2'>slave text\n"
           "   <ReadCoils>request text<refNum><![CDATA[00042]]></refNum>between"
           "<toBlock dest='B3:0' count='4' fmt='bit'>block text</toBlock>after</ReadCoils>\n"
           "   <WriteCoil><refNum>000<!-- a comment inside -->07</refNum>"
           "<fromBlock count='1' fmt='bit'><const><![CDATA[1]]></const></fromBlock></WriteCoil>\n"
           "  </Slave>\n </Port>\n</ModbusSerial>\n<!-- tail -->\n")
    reqs = parse(xml).ports[1].slaves[2].requests
    assert [(r.name, r.address, r.count) for r in reqs] == [("ReadCoils", 41, 4), ("WriteCoil", 6, 1)]
    assert reqs[1].from_blocks[0].const == (1,)


def test_requests_in_a_slave_in_any_order_and_number():
    content = [sample("WriteCoil"), sample("ReadWriteRegisters"), sample("ReadCoils"), sample("WriteCoil", 9),
               sample("ReadInputRegisters"), sample("ReadCoils", 3)]
    reqs = parse(in_slave("\n".join(content))).ports[1].slaves[2].requests
    assert [(r.name, r.address) for r in reqs] == [("WriteCoil", 0), ("ReadWriteRegisters", 0), ("ReadCoils", 0),
                                                    ("WriteCoil", 8), ("ReadInputRegisters", 0), ("ReadCoils", 2)]


# - attributes -

BASE = {
    "root": {},
    "port": {"num": "1", "baudrate": "19200"},
    "modem": {"waitDelayCTS": "5"},
    "slave": {"id": "2"},
    "request": {},
    "to": {"dest": "B3:0", "count": "8", "fmt": "bit"},
    "from": {"source": "N7:0", "count": "2", "fmt": "i2"},
}


def render(changes: dict[str, dict[str, str | None]]) -> str:
    """A valid file, with attributes changed (None: removed) per element."""
    a = {k: {**v, **changes.get(k, {})} for k, v in BASE.items()}

    def attrs(k: str) -> str:
        return "".join(f' {n}="{v}"' for n, v in a[k].items() if v is not None)

    return (f"<ModbusSerial{attrs('root')}>\n"
            f"  <Port{attrs('port')}>\n"
            f"    <ModemControl{attrs('modem')}/>\n"
            f"    <Slave{attrs('slave')}>\n"
            f"      <ReadCoils{attrs('request')}>\n"
            f"        <refNum>00001</refNum>\n"
            f"        <toBlock{attrs('to')}/>\n"
            f"      </ReadCoils>\n"
            f"      <WriteMultipleRegisters>\n"
            f"        <refNum>40001</refNum>\n"
            f"        <fromBlock{attrs('from')}/>\n"
            f"      </WriteMultipleRegisters>\n"
            f"    </Slave>\n"
            f"  </Port>\n"
            f"</ModbusSerial>\n")


def test_render_base_is_valid():
    config = parse(render({}))
    assert [r.name for r in config.ports[1].slaves[2].requests] == ["ReadCoils", "WriteMultipleRegisters"]
    assert config.ports[1].wait_cts_ms == 5


BAD_VALUES = [
    ("root", "debug", "3"), ("root", "debug", "-1"), ("root", "debug", "one"), ("root", "portErrors", "ignore"),
    ("root", "retryMs", "9"), ("root", "retryMs", "3600001"),
    ("port", "num", "32"), ("port", "num", "-1"), ("port", "num", "0x"), ("port", "num", "1 2"),
    ("port", "framing", "RTU8"), ("port", "baudrate", "299"), ("port", "baudrate", "230401"),
    ("port", "baudrate", "19200.0"), ("port", "baudrate", "1e4"), ("port", "dataBits", "6"),
    ("port", "dataBits", "9"), ("port", "parity", "space"), ("port", "stopBits", "0"), ("port", "stopBits", "3"),
    ("port", "minPeriod", "-1"), ("port", "minPeriod", "3600001"), ("port", "requestTimeout", "0"),
    ("port", "requestTimeout", "60001"), ("port", "attempts", "0"), ("port", "attempts", "101"),
    ("port", "requestGap", "251"), ("port", "requestGap", "-1"), ("port", "demoteAfter", "1001"),
    ("port", "demotePeriod", "9"),
    ("modem", "waitDelayCTS", "60001"), ("modem", "waitDelayCTS", "-1"), ("modem", "waitDelayCTS", ""),
    ("slave", "id", "0"), ("slave", "id", "248"), ("slave", "id", "x"), ("slave", "minPeriod", "3600001"),
    ("slave", "requestTimeout", "0"), ("slave", "attempts", "101"), ("slave", "demoteAfter", "-1"),
    ("slave", "demotePeriod", "3600001"),
    ("request", "when", "always"), ("request", "when", ""), ("request", "minPeriod", "3600001"),
    ("request", "requestTimeout", "60001"), ("request", "attempts", "0"),
    ("to", "count", "0"), ("to", "count", "2001"), ("to", "count", "-8"), ("to", "fmt", "i4"), ("to", "fmt", ""),
    ("from", "count", "0"), ("from", "fmt", "bits"),
]


@pytest.mark.parametrize("element, attr, value", BAD_VALUES, ids=[f"{e}-{a}={v}" for e, a, v in BAD_VALUES])
def test_bad_attribute_values(element, attr, value):
    xml = render({element: {attr: value}})
    p = only_problem(xml)
    assert p.message.startswith(f"{attr}={value!r}: expected "), p.message
    assert where(p) == locate(xml, f'{attr}="{value}"')


@pytest.mark.parametrize("element, attr", [("port", "device"), ("to", "dest"), ("from", "source")])
@pytest.mark.parametrize("value", ["", "  "])
def test_empty_text_attributes(element, attr, value):
    xml = render({element: {attr: value}})
    p = only_problem(xml)
    assert p.message.startswith(f"{attr} is empty; expected ")
    assert where(p) == locate(xml, f'{attr}="')


@pytest.mark.parametrize("element, attr, element_needle", [
    ("port", "num", "<Port"), ("port", "baudrate", "<Port"), ("modem", "waitDelayCTS", "<ModemControl"),
    ("slave", "id", "<Slave"), ("to", "dest", "<toBlock"), ("to", "count", "<toBlock"), ("to", "fmt", "<toBlock"),
    ("from", "count", "<fromBlock"), ("from", "fmt", "<fromBlock"),
])
def test_missing_required_attributes(element, attr, element_needle):
    xml = render({element: {attr: None}})
    p = only_problem(xml)
    assert f"needs the attribute {attr}" in p.message
    assert where(p) == locate(xml, element_needle)


@pytest.mark.parametrize("element, attr, hint", [
    ("port", "baudRate", "baudrate"), ("port", "stopbits", "stopBits"), ("slave", "ids", "id"),
    ("to", "dst", "dest"), ("from", "sourc", "source"), ("request", "When", "when"), ("root", "Debug", "debug"),
    ("modem", "waitDelayCts", "waitDelayCTS"), ("port", "colour", None), ("slave", "xmlns", None),
])
def test_unknown_attributes(element, attr, hint):
    xml = render({element: {attr: "1"}})
    p = only_problem(xml)
    assert f"has no attribute {attr!r}" in p.message
    if hint:
        assert p.message.endswith(f"; did you mean {hint}?")
    else:
        assert "did you mean" not in p.message
    assert where(p) == locate(xml, f'{attr}="1"')


def test_unknown_attribute_on_elements_without_attributes():
    xml = in_slave(req("ReadMultipleRegisters", '<refNum base="10">40001</refNum>', T1))
    p = only_problem(xml)
    assert "<refNum> has no attribute 'base' (its attributes: none)" in p.message
    assert where(p) == locate(xml, "base=")


def test_data_bits_7_needs_ascii():
    xml = render({"port": {"dataBits": "7"}})
    p = only_problem(xml)
    assert "dataBits=7 needs framing=\"ASCII\"" in p.message
    assert where(p) == locate(xml, 'dataBits="7"')
    assert only_problem(render({"port": {"dataBits": "7", "framing": "RTU"}})).message == p.message
    assert parse(render({"port": {"dataBits": "7", "framing": "ascii"}})).ports[1].data_bits == 7


def test_bad_framing_with_7_data_bits_is_one_problem():
    """A wrong framing is reported; dataBits=7 is not blamed on RTU it never asked for."""
    xml = render({"port": {"dataBits": "7", "framing": "ASCI"}})
    p = only_problem(xml)
    assert p.message.startswith("framing='ASCI': expected 'RTU' or 'ASCII'")


def test_element_and_attribute_names_are_case_sensitive_values_are_not():
    assert parse(render({"port": {"parity": "ODD", "framing": "aScIi"}})).ports[1].parity == "O"
    p = only_problem(render({"port": {"Parity": "odd"}}))
    assert "has no attribute 'Parity'" in p.message and "did you mean parity?" in p.message


def test_duplicate_port_num():
    xml = ('<ModbusSerial>\n  <Port num="3" baudrate="9600"/>\n  <Port num="0x3" baudrate="19200"/>\n'
           '</ModbusSerial>\n')
    p = only_problem(xml)
    assert "port num 3 is used twice (first on line 2)" in p.message
    assert where(p) == locate(xml, 'num="0x3"')


def test_duplicate_slave_id_within_a_port():
    xml = in_slave("", slave='id="9"').replace("</Slave>", '</Slave>\n<Slave id="09"/>')
    p = only_problem(xml)
    assert "slave id 9 is used twice on port 1 (first on line 3)" in p.message
    assert where(p) == locate(xml, 'id="09"')


@pytest.mark.parametrize("text, expected", [
    ("0xFFFE", 0xFFFE), ("65534", 65534), ("0", 0), ("0xffff", 0xFFFF), (" 0x00FF ", 0xFF),
])
def test_and_mask_values(text, expected):
    r = request(req("MaskWriteRegister", ref("40001"), f"<andMask>{text}</andMask>", F1))
    assert r.and_mask == expected


@pytest.mark.parametrize("text", ["0x10000", "65536", "-1", "", "mask", "0xFFFE 1"])
def test_and_mask_errors(text):
    xml = in_slave(req("MaskWriteRegister", ref("40001"), f"<andMask>{text}</andMask>", F1))
    p = only_problem(xml)
    assert "expected an integer 0..0xFFFF" in p.message
    assert where(p) == locate(xml, "<andMask>")


# -- 8. every problem at once -------------------------------------------------------------------

MANY_PROBLEMS = """\
<?xml version="1.0"?>
<ModbusSerial debug="5">
  <Port num="1" baudrate="19200" parity="space">
    <ModemControl/>
    <Slave id="2" atempts="3">
      <ReadCoil><refNum>00001</refNum></ReadCoil>
      <ReadCoils>
        <refNum>40001</refNum>
        <toBlock dest="B3:0" count="8" fmt="bit"/>
      </ReadCoils>
      <ReadMultipleRegisters>
        <refNum>40001</refNum>
        <toBlock dest="F8:0" count="2" fmt="i2"/>
        <toBlock dest="N7:0" count="2" fmt="bit"/>
      </ReadMultipleRegisters>
      <WriteMultipleRegisters>
        <refNum>40001</refNum>
        <fromBlock count="3" fmt="i2"><const>1 2</const></fromBlock>
      </WriteMultipleRegisters>
      <ReadWriteRegisters>
        <refNum>40001</refNum>
        <toBlock dest="N7:0" count="126" fmt="i2"/>
        <refNum>40001</refNum>
        <fromBlock source="N7:0" count="1" fmt="i2"/>
      </ReadWriteRegisters>
    </Slave>
    <Slave id="2"/>
  </Port>
  <Port num="1" baudrate="19200" dataBits="7"/>
  <Slave id="3"/>
</ModbusSerial>
"""

# (needle, which occurrence, message fragment), in file order
MANY_EXPECTED = [
    ('debug="5"', 1, "debug='5': expected an integer 0..2"),
    ('parity="space"', 1, "parity='space': expected 'none' or 'even' or 'odd' or 'mark'"),
    ("<ModemControl/>", 1, "<ModemControl> needs the attribute waitDelayCTS"),
    ('atempts="3"', 1, "<Slave> has no attribute 'atempts'"),
    ("<ReadCoil>", 1, "<ReadCoil> is not a request"),
    ("<refNum>40001", 1, "refNum 40001 is in region 4xxxx; <ReadCoils> reads 0xxxx (coils)"),
    ('dest="F8:0"', 1, "dest='F8:0': reply data goes"),
    ('fmt="bit"/>\n      </ReadMultipleRegisters>', 1, 'fmt="bit" in <ReadMultipleRegisters>'),
    ("<const>", 1, "<const> has 2 values; its fromBlock's count is 3"),
    ("<ReadWriteRegisters>", 1, "<ReadWriteRegisters> reads 126 registers"),
    ('id="2"/>', 1, "slave id 2 is used twice on port 1 (first on line 5)"),
    ('num="1"', 2, "port num 1 is used twice (first on line 3)"),
    ('dataBits="7"', 1, 'dataBits=7 needs framing="ASCII"'),
    ('<Slave id="3"/>', 1, "<Slave> is not allowed here (<ModbusSerial> contains <Port>*)"),
]


def test_every_problem_at_once_sorted_with_line_and_column():
    found = problems(MANY_PROBLEMS, "app/MODBMAST.XML")
    expected = [(locate(MANY_PROBLEMS, needle, nth), fragment) for needle, nth, fragment in MANY_EXPECTED]
    assert len({line for (line, _), _ in expected}) >= 8
    assert [where(p) for p in found] == [w for w, _ in expected], ModuleErrors(found).report()
    for p, (_, fragment) in zip(found, expected):
        assert fragment in p.message
        assert p.path == "app/MODBMAST.XML"
    # the fmt="bit" problem points at the attribute itself, not at its element
    assert expected[7][0] != locate(MANY_PROBLEMS, '<toBlock dest="N7:0" count="2" fmt="bit"')


def test_every_problem_report_format():
    with pytest.raises(ModuleErrors) as info:
        parse(MANY_PROBLEMS, "app/MODBMAST.XML")
    lines = info.value.report().splitlines()
    assert len(lines) == len(MANY_EXPECTED)
    for line, (needle, nth, fragment) in zip(lines, MANY_EXPECTED):
        row, column = locate(MANY_PROBLEMS, needle, nth)
        assert line.startswith(f"app/MODBMAST.XML:{row}:{column}: ")
        assert fragment in line
    # the exception itself is the first problem
    assert (info.value.line, info.value.column) == locate(MANY_PROBLEMS, 'debug="5"')


def test_problems_in_walk_order_are_sorted_by_line_then_column():
    xml = '<ModbusSerial>\n<Port num="40" baudrate="1" parity="x"><Slave id="0"/></Port>\n</ModbusSerial>'
    found = problems(xml)
    assert [where(p) for p in found] == sorted(where(p) for p in found)
    assert [where(p) for p in found] == [locate(xml, 'num="40"'), locate(xml, 'baudrate="1"'),
                                         locate(xml, 'parity="x"'), locate(xml, 'id="0"')]


@pytest.mark.parametrize("prefix, separator", [
    ("", " "),
    ("<!-- Pumpstation Süd – Zähler ✓ -->", " "),  # non-ASCII before on the same line: columns in characters
    ("", "\n   "),
    ("", "\r\n   "),
    ("", "\r   "),  # a lone CR is a line break to XML too
    ("", " \t "),
])
def test_attribute_positions_in_characters_and_lines(prefix, separator):
    xml = f'<ModbusSerial>{prefix}<Port num="1"{separator}baudrate="x" parity="y"/></ModbusSerial>'
    normal = xml.replace("\r\n", "\n").replace("\r", "\n")  # how XML counts lines
    found = problems(xml)
    assert [where(p) for p in found] == [locate(normal, 'baudrate="x"'), locate(normal, 'parity="y"')]


def test_attribute_name_inside_another_value_is_not_taken_for_it():
    xml = ('<ModbusSerial><Port num="1" device="sim://bus?baudrate=1&amp;parity=x>y" baudrate="x"'
           ' parity=\'bad\'/></ModbusSerial>')
    found = problems(xml)
    assert [where(p) for p in found] == [locate(xml, 'baudrate="x"'), locate(xml, "parity='bad'")]


# -- 9. robustness ------------------------------------------------------------------------------

def check_problems(error: ModuleErrors, data: bytes) -> None:
    assert error.problems
    lines = len(re.split(rb"\r\n?|\n", data))
    for p in error.problems:
        assert isinstance(p, ModuleError) and p.path == PATH and p.message
        assert 1 <= p.line <= lines and p.column >= 1, p.report()
    assert error.report().count("\n") == len(error.problems) - 1


def check_valid(config: ModbmastConfig) -> None:
    """What a configuration that passed must hold, whatever it was."""
    assert isinstance(config, ModbmastConfig)
    assert 0 <= config.debug <= 2
    for num, port in config.ports.items():
        assert isinstance(port, PortConfig) and port.num == num and 0 <= num <= 31
        assert port.framing in ("RTU", "ASCII") and 300 <= port.baud <= 230400
        assert port.data_bits == 8 or (port.data_bits == 7 and port.framing == "ASCII")
        for sid, slave in port.slaves.items():
            assert isinstance(slave, Slave) and slave.id == sid and 1 <= sid <= 247
            for r in slave.requests:
                function = r.kind.function
                low, high = LIMITS[function]
                assert low <= r.count <= high and 0 <= r.address and r.address + r.count <= 65536
                if function == 23:
                    assert 1 <= r.write_count <= RWR_WRITE_LIMIT and r.write_address + r.write_count <= 65536
                for b in r.to_blocks:
                    assert b.address.type_letter in "OIBN" and b.address.is_direct
                for b in r.from_blocks:
                    assert b.const is not None or b.address.type_letter in ("O", "I", "S", "B", "N")
                    assert b.const is None or len(b.const) == b.count


def parse_anything(data: bytes) -> None:
    try:
        config = parse_config(data, PATH)
    except ModuleErrors as e:
        check_problems(e, data)
    else:
        check_valid(config)


FAST = settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(st.binary(max_size=400))
def test_random_bytes_only_raise_module_errors(data):
    parse_anything(data)


@FAST
@given(st.binary(max_size=200))
def test_random_bytes_inside_a_valid_frame(data):
    parse_anything(b'<ModbusSerial><Port num="1" baudrate="9600">' + data + b"</Port></ModbusSerial>")


PIECES = [b"<", b">", b"/", b"=", b'"', b"'", b"&", b";", b"#", b"x", b"0", b"9", b"1", b" ", b"\n", b"\r",
          b"\t", b"\x00", b"\xff", b"\xe9", b"\xc3\xa9", b"\xef\xbb\xbf", b"]]>", b"<!--", b"-->", b"<![CDATA[",
          b"&amp;", b"&#0;", b"&#x41;", b"&lt;", b"<!DOCTYPE x>", b"<?pi?>", b"<a>", b"</a>", b"N7:", b"/17",
          b"bit", b"i2", b"0x"]

VALUES = [b"", b" ", b"0", b"1", b"-1", b"7", b"16", b"65535", b"65536", b"0x", b"0xFFFF", b"99999999999",
          b"N7:9999", b"B3/17", b"S:0", b"T4:0", b"#N7:0", b"bit", b"i2", b"RTU", b"ASCII", b"run", b"x",
          b"\xd9\xa3", b"40001", b"00001", b"465536", b"1 2 3"]

mutation = st.one_of(
    st.tuples(st.sampled_from(["delete", "duplicate", "replace", "insert", "digit"]),
              st.integers(0, 10**6), st.integers(1, 8), st.sampled_from(PIECES)),
    # a new attribute value or element text: mostly well-formed files with wrong contents
    st.tuples(st.just("value"), st.integers(0, 10**6), st.integers(1, 8), st.sampled_from(VALUES)),
)


def mutate(data: bytes, ops) -> bytes:
    for op, at, size, piece in ops:
        at %= len(data) + 1
        if op == "delete":
            data = data[:at] + data[at + size:]
        elif op == "duplicate":
            data = data[:at + size] + data[at:]
        elif op == "replace":
            data = data[:at] + piece + data[at + 1:]
        elif op == "insert":
            data = data[:at] + piece + data[at:]
        elif op == "value":
            spans = [m.span(1) for m in re.finditer(rb'"([^"<]*)"|>([^<>]*)<', data) if m.start(1) >= 0]
            if spans:
                start, end = spans[at % len(spans)]
                data = data[:start] + piece + data[end:]
        else:  # change a digit into another: often still a valid file
            digits = [m.start() for m in re.finditer(rb"[0-9]", data)]
            if digits:
                i = digits[at % len(digits)]
                data = data[:i] + str(size).encode() + data[i + 1:]
    return data


@FAST
@given(st.lists(mutation, min_size=1, max_size=4))
def test_mutations_of_the_full_example(ops):
    parse_anything(mutate(FULL.encode(), ops))


@FAST
@given(st.lists(mutation, min_size=1, max_size=3))
def test_mutations_of_the_many_problems_file(ops):
    parse_anything(mutate(MANY_PROBLEMS.encode(), ops))


def test_digit_changes_can_leave_a_valid_file():
    """The mutation test does see valid files: a harmless change is still valid."""
    data = FULL.replace('minPeriod="1000"', 'minPeriod="1001"').encode()
    config = parse_config(data)
    check_valid(config)
    assert config.ports[0].slaves[1].requests[0].min_period_ms == 1001


@pytest.mark.parametrize("data, fragment", [
    (b"", "no element found"),
    (b"   \n\n", "no element found"),
    (b"\x00\x01\x02\x03", None),
    (b"\xff\xfe\x00", None),  # a UTF-16 BOM and half a character
    (b"\xfe\xff\xd8\x00\x00<", None),  # UTF-16 with a lone surrogate
    (b"PK\x03\x04\x14\x00\x00\x00\x08\x00", None),  # a zip file
    (b"<ModbusSerial>", "no element found"),
    (b"<ModbusSerial></Port>", "mismatched tag"),
    (b"<ModbusSerial/><ModbusSerial/>", "junk after document element"),
    (b'<ModbusSerial debug="1" debug="2"/>', "duplicate attribute"),
    (b"<ModbusSerial>&undefined;</ModbusSerial>", "undefined entity"),
    (b'<?xml version="1.0" encoding="no-such-codec"?><ModbusSerial/>', "cannot read the file's characters"),
    (b'<?xml version="1.0" encoding="UTF-32"?><ModbusSerial/>', "cannot read the file's characters"),
])
def test_broken_files_give_module_errors(data, fragment):
    with pytest.raises(ModuleErrors) as info:
        parse_config(data)
    check_problems(info.value, data)
    if fragment:
        assert fragment in info.value.problems[0].message


def test_malformed_xml_reported_at_expat_position():
    xml = '<ModbusSerial>\n  <Port num="1" baudrate="9600">\n    <Slave id="1"\n  </Port>\n</ModbusSerial>\n'
    p = only_problem(xml)
    assert p.message.startswith("not well-formed XML: ")
    assert where(p) == locate(xml, "<", 4)  # the "<" of "</Port>" cannot be inside a start tag


BILLION_LAUGHS = """\
<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
 <!ENTITY lol5 "&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;">
 <!ENTITY lol6 "&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;">
 <!ENTITY lol7 "&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;">
 <!ENTITY lol8 "&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;">
 <!ENTITY lol9 "&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;">
]>
<ModbusSerial><Port num="1" baudrate="9600" device="&lol9;"/></ModbusSerial>
"""


@pytest.mark.parametrize("xml", [
    BILLION_LAUGHS,
    '<!DOCTYPE ModbusSerial>\n<ModbusSerial/>',
    '<?xml version="1.0"?>\n\n<!DOCTYPE ModbusSerial SYSTEM "http://example.com/modbus.dtd">\n<ModbusSerial/>',
    '<!DOCTYPE x [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>\n<ModbusSerial debug="&xxe;"/>',
    '<!DOCTYPE x [\n<!ENTITY e "1">\n]>\n<ModbusSerial debug="&e;"/>',
], ids=["billion-laughs", "doctype", "external-dtd", "external-entity", "internal-entity"])
def test_doctype_and_entity_declarations_refused(xml):
    p = only_problem(xml)
    assert "document type declaration (<!DOCTYPE ...>) is not allowed" in p.message
    assert p.line == locate(xml, "<!DOCTYPE")[0]


DEPTH = 20_000  # twenty times Python's recursion limit: a recursive walk of any part would fail


@pytest.mark.parametrize("data", [
    b"<ModbusSerial>" + b"<Port>" * DEPTH + b"</Port>" * DEPTH + b"</ModbusSerial>",
    b"<a>" * DEPTH + b"</a>" * DEPTH,
    b"<ModbusSerial>" + b"<a>" * DEPTH,  # never closed
    (b'<ModbusSerial><Port num="1" baudrate="9600"><Slave id="1"><WriteCoil><refNum>01</refNum>'
     b'<fromBlock count="1" fmt="bit"><const>' + b"<const>" * DEPTH + b"</const>" * DEPTH
     + b"1</const></fromBlock></WriteCoil></Slave></Port></ModbusSerial>"),
], ids=["ports", "unknown-root", "unclosed", "consts"])
def test_deep_nesting_is_an_error_not_a_recursion_error(data):
    assert DEPTH > sys.getrecursionlimit()
    with pytest.raises(ModuleErrors) as info:
        parse_config(data)
    assert len(info.value.problems) <= 3  # what is nested inside a misplaced element is not walked
    check_problems(info.value, data)


def test_size_limit():
    head, tail = b"<ModbusSerial><!--", b"--></ModbusSerial>"
    at_limit = head + b" " * (MAX_BYTES - len(head) - len(tail)) + tail
    assert len(at_limit) == MAX_BYTES
    assert parse_config(at_limit).ports == {}
    over = at_limit + b"\n"
    p = only_problem(over)
    assert f"{MAX_BYTES + 1:,} bytes" in p.message and f"at most {MAX_BYTES:,}" in p.message
    assert where(p) == (1, 1)


def test_many_text_lines_in_one_element_are_fast():
    """Text pieces are joined once (expat hands text over line by line)."""
    data = b"<ModbusSerial>" + b"x\n" * 400_000 + b"</ModbusSerial>"
    assert parse_config(data).ports == {}


SMALL = ('<?xml version="1.0" encoding="{enc}"?>\n<!-- Zähler -->\n<ModbusSerial debug="1">\n'
         '  <Port num="1" baudrate="9600" device="/dev/ttyé">\n    <Slave id="2">\n'
         '      <ReadCoils><refNum>00005</refNum><toBlock dest="B3:0" count="8" fmt="bit"/></ReadCoils>\n'
         '    </Slave>\n  </Port>\n</ModbusSerial>\n')


@pytest.mark.parametrize("encoding, codec, bom", [
    ("UTF-16", "utf-16", b""),  # Python's utf-16 writes a BOM
    ("UTF-16", "utf-16-le", b"\xff\xfe"),
    ("UTF-16", "utf-16-be", b"\xfe\xff"),
    ("UTF-16", "utf-16-le", b""),  # no BOM: recognised by "<\0?\0"
    ("UTF-8", "utf-8", b"\xef\xbb\xbf"),
    ("UTF-8", "utf-8", b""),
    ("ISO-8859-1", "latin-1", b""),
])
def test_encodings_accepted(encoding, codec, bom):
    text = SMALL.replace("{enc}", encoding)
    config = parse_config(bom + text.encode(codec))
    assert config.debug == 1
    assert config.ports[1].device == "/dev/ttyé"
    assert config.ports[1].slaves[2].requests[0].address == 4
    assert config == parse_config(SMALL.replace("{enc}", "UTF-8").encode())


@pytest.mark.parametrize("codec, bom", [("utf-16", b""), ("utf-16-be", b"\xfe\xff"), ("utf-8", b"")])
def test_positions_in_utf16_files_are_those_of_the_text(codec, bom):
    text = SMALL.replace("{enc}", "UTF-16" if codec.startswith("utf-16") else "UTF-8")
    text = text.replace('baudrate="9600"', 'baudrate="96OO"').replace("00005", "40005")
    found = problems(bom + text.encode(codec))
    assert [where(p) for p in found] == [locate(text, 'baudrate="96OO"'), locate(text, "<refNum>")]


def test_latin1_bytes_without_declaration_give_a_located_error():
    text = '<ModbusSerial>\n  <Port num="1" baudrate="9600" device="/dev/ttyé"/>\n</ModbusSerial>\n'
    p = only_problem(text.encode("latin-1"))
    assert where(p) == locate(text, "é")
    assert "0xE9 is not UTF-8" in p.message and "encoding" in p.message


def test_latin1_bytes_after_non_ascii_utf8_located_in_characters():
    text = '<ModbusSerial>\n<!-- ü -->é\n</ModbusSerial>\n'
    data = text.encode("utf-8").replace("é".encode(), b"\xe9")
    p = only_problem(data)
    assert where(p) == locate(text, "é")


# -- 10. finding the file -----------------------------------------------------------------------

def write(directory: Path, name: str, debug: int) -> Path:
    path = directory / name
    path.write_text(f'<ModbusSerial debug="{debug}"/>\n')
    return path


@pytest.mark.parametrize("name", ["MODBMAST.XML", "modbmast.xml", "Modbmast.Xml", "MODBUS.XML", "modbus.xml",
                                  "ModBus.xml"])
def test_load_config_finds_either_name_in_any_case(tmp_path, name):
    path = write(tmp_path, name, 1)
    config = load_config(tmp_path)
    assert config.debug == 1
    assert config.path == str(path)
    assert config.warnings == []


@pytest.mark.parametrize("main, alias", [("MODBMAST.XML", "MODBUS.XML"), ("modbmast.xml", "modbus.xml"),
                                         ("MODBMAST.XML", "Modbus.Xml")])
def test_load_config_both_names_modbmast_wins(tmp_path, main, alias):
    main_path = write(tmp_path, main, 1)
    alias_path = write(tmp_path, alias, 2)
    config = load_config(tmp_path)
    assert (config.debug, config.path) == (1, str(main_path))
    (warning,) = config.warnings
    assert str(alias_path) in warning and "ignored" in warning and main_path.name in warning


def test_load_config_neither(tmp_path):
    (tmp_path / "MODULES.LST").write_text("MODBMAST\n")
    (tmp_path / "MODBMAST.XML.bak").write_text("<ModbusSerial/>")
    (tmp_path / "MODBUS.XML").mkdir()  # a directory is not the file
    with pytest.raises(ModuleError) as info:
        load_config(tmp_path)
    assert not isinstance(info.value, ModuleErrors)
    message = info.value.message
    assert str(tmp_path / "MODBMAST.XML") in message and "MODBUS.XML" in message
    assert "does not exist" in message


def test_load_config_problems_name_the_file(tmp_path):
    path = tmp_path / "modbus.xml"
    path.write_text('<ModbusSerial>\n<Port num="99" baudrate="9600"/>\n</ModbusSerial>\n')
    with pytest.raises(ModuleErrors) as info:
        load_config(tmp_path)
    (p,) = info.value.problems
    assert (p.path, p.line, p.column) == (str(path), 2, 7)
    assert info.value.report() == f"{path}:2:7: num='99': expected an integer 0..31"


def test_a_repeated_num_is_reported_even_when_a_copy_has_other_problems():
    text = '<ModbusSerial>\n<Port num="4" baudrate="9"/>\n<Port num="4" baudrate="9600"/>\n</ModbusSerial>'
    with pytest.raises(ModuleErrors) as info:
        parse_config(text.encode())
    messages = [(p.line, p.message) for p in info.value.problems]
    assert messages == [(2, "baudrate='9': expected an integer 300..230400"),
                        (3, "port num 4 is used twice (first on line 2); num is unique among ports")]


def test_a_file_full_of_mistakes_lists_the_first_200_and_counts_the_rest():
    text = "<ModbusSerial>\n" + "<Prot/>\n" * 1000 + "</ModbusSerial>"
    with pytest.raises(ModuleErrors) as info:
        parse_config(text.encode())
    problems = info.value.problems
    assert len(problems) == 201 and problems[199].line == 201
    assert problems[-1].message == "... and 800 more problems (the first 200 are listed)"
