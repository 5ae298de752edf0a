"""The PCCC object (Execute PCCC, class 0x67) on a real data table: the
PLC-5 commands, which no Python client sends, as 1770-6.5.16 lays them out
through the Message Router; then pycomm3's SLCDriver, the client the field
uses, against the ENIPS module over a real socket: every file type read and
written, bits, sub-elements, strings, and the refusals it reports."""

from __future__ import annotations

import struct

import pytest
from pycomm3 import SLCDriver

from softplc_lite.cip import epath
from softplc_lite.cip import pccc as P
from softplc_lite.cip import status as cip_status
from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips import status as S
from softplc_lite.tlm.enips.access import TableAccessOnTable
from softplc_lite.tlm.enips.pccc_object import PcccObject
from softplc_lite.tlm.enips.router import MessageRouter

from helpers.cip import route
from helpers.enips_apps import enips_xml

pytestmark = pytest.mark.timeout(120)
REQUESTOR = bytes.fromhex("07 0100 78563412")
PCCC_PATH = epath.encode_logical(0x67, 1)


def table() -> DataTable:
    t = DataTable()
    for address in ("N7:9", "F8:3", "T4:1", "ST9:1", "L12:1", "B3:3", "D14:1", "C5:1"):
        t.reference(address)
    return t


class Pccc:
    """Commands to a PCCC object through a Message Router, as a client's bytes go."""

    def __init__(self, t: DataTable, writable=frozenset({"N7", "F8", "T4", "ST9", "B3"})) -> None:
        self.router = MessageRouter([PcccObject()])
        self.counted: list[tuple[str, str]] = []
        self.router.count = lambda kind, why: self.counted.append((kind, why))
        self.access = TableAccessOnTable(t, writable)
        self.tns = 0

    def __call__(self, cmd: int, fnc: int, body: bytes) -> P.PcccReply:
        self.tns += 1
        raw = REQUESTOR + struct.pack("<BBHB", cmd, 0, self.tns, fnc) + body
        response = route(self.router, P.EXECUTE_PCCC, PCCC_PATH, raw, self.access)
        assert response.status == 0
        reply = P.PcccReply.decode(response.data)
        assert (reply.requestor, reply.cmd, reply.tns) == (REQUESTOR, cmd, self.tns)
        return reply

    def command(self, command, cmd: int = 0x0F) -> P.PcccReply:
        fnc = next(f for (c, f), kind in P.COMMANDS.items() if kind is type(command) and c == cmd
                   and (kind is not P.SlcTypedRead or (f == 0xA2) == command.three_fields)
                   and (kind is not P.SlcTypedWrite or f == (0xAB if command.mask is not None else
                                                             0xAA if command.three_fields else 0xA9)))
        return self(cmd, fnc, command.encode())


def refused(reply: P.PcccReply) -> tuple[int, int | None]:
    return reply.sts, reply.ext


# -- PLC-5 commands -----------------------------------------------------------------------------

def test_word_range_read_and_write():
    t = table()
    t.write("N7:2", -7)
    t.write("F8:1", 1.5)
    pccc = Pccc(t)
    reply = pccc.command(P.WordRangeRead(2, 4, P.Plc5Address(7, 0), 4))  # words 2 and 3 of a 4-word transaction
    assert reply.sts == 0 and struct.unpack("<hh", reply.data) == (-7, 0)
    assert struct.unpack("<f", pccc.command(P.WordRangeRead(0, 2, P.Plc5Address(8, 1), 4)).data)[0] == 1.5
    assert pccc.command(P.WordRangeWrite(1, 3, P.Plc5Address(7, 4), struct.pack("<hh", 11, 12))).sts == 0
    assert (t.read("N7:5"), t.read("N7:6")) == (11, 12)  # packet offset 1 from N7:4


def test_sub_elements_address_a_timers_words():
    t = table()
    t.write("T4:1.ACC", 33)
    pccc = Pccc(t)
    reply = pccc.command(P.WordRangeRead(0, 1, P.Plc5Address(4, 1, 2), 2))  # T4:1.ACC
    assert struct.unpack("<h", reply.data) == (33,)
    assert pccc.command(P.WordRangeWrite(0, 1, P.Plc5Address(4, 1, 1), struct.pack("<h", 250))).sts == 0
    assert t.read("T4:1.PRE") == 250
    assert refused(pccc.command(P.WordRangeRead(0, 1, P.Plc5Address(4, 1, 3), 2))) == (P.STS_EXTENDED,
                                                                                       P.EXT_NOT_USABLE)


def test_read_modify_write_sets_and_clears_bits_the_scan_left_alone():
    t = table()
    t.write("B3:1", 0b1010)
    pccc = Pccc(t)
    sets = ((P.Plc5Address(3, 1), 0xFFFF, 0x0100), (P.Plc5Address(3, 1), 0xFFFD, 0x0000))  # set bit 8, clear bit 1
    assert pccc.command(P.ReadModifyWrite(sets)).sts == 0
    assert t.read("B3:1") == 0b100001000


def test_typed_read_and_write_carry_their_data_types():
    t = table()
    for k in range(4):
        t.write(f"F8:{k}", k + 0.5)
    t.write("T4:0.PRE", 100)
    pccc = Pccc(t)
    reply = pccc.command(P.TypedRead(1, 3, P.Plc5Address(8, 0), 3))  # elements 1..3
    r = P.Reader(reply.data)
    assert P.read_type_param(r) == (P.DT_ARRAY, 1 + 1 + 12)
    assert P.read_type_param(r) == (P.DT_FLOAT, 4)
    assert struct.unpack("<3f", r.rest()) == (1.5, 2.5, 3.5)
    timer = P.Reader(pccc.command(P.TypedRead(0, 1, P.Plc5Address(4, 0), 1)).data)
    P.read_type_param(timer)
    assert P.read_type_param(timer) == (P.DT_TIMER, 6) and struct.unpack("<3h", timer.rest())[1] == 100
    assert pccc.command(P.TypedWrite(0, 2, P.Plc5Address(7, 0), P.DT_INTEGER, 2, struct.pack("<hh", 5, 6))).sts == 0
    assert (t.read("N7:0"), t.read("N7:1")) == (5, 6)
    mismatch = pccc.command(P.TypedWrite(0, 1, P.Plc5Address(7, 0), P.DT_FLOAT, 4, struct.pack("<f", 1)))
    assert refused(mismatch) == (P.STS_EXTENDED, P.EXT_DATA_TYPE)


def test_refusals_each_with_its_status_and_counted():
    t = table()
    pccc = Pccc(t)
    cases = [
        (P.WordRangeRead(0, 1, P.Plc5Address(99, 0), 2), (P.STS_EXTENDED, P.EXT_NOT_USABLE)),  # no file 99
        (P.WordRangeRead(0, 1, P.Plc5Address(7, 50), 2), (P.STS_EXTENDED, P.EXT_NOT_USABLE)),  # N7 has 10 elements
        (P.WordRangeRead(0, 4, P.Plc5Address(7, 8), 8), (P.STS_EXTENDED, P.EXT_TOO_LARGE)),  # runs past N7:9
        (P.WordRangeRead(0, 200, P.Plc5Address(7, 0), 250), (P.STS_ILLEGAL, None)),  # more than one reply holds
        (P.WordRangeWrite(0, 1, P.Plc5Address(12, 0), bytes(4)), (P.STS_EXTENDED, P.EXT_ACCESS_DENIED)),  # L12
        (P.WordRangeWrite(0, 1, P.Plc5Address(8, 0), bytes(2)), (P.STS_EXTENDED, P.EXT_WRONG_SIZE)),  # half a float
        (P.ReadModifyWrite(((P.Plc5Address(8, 0), 0, 1),)), (P.STS_EXTENDED, P.EXT_DATA_TYPE)),  # a float's bits
    ]
    for command, expected in cases:
        assert refused(pccc.command(command)) == expected, command
    assert t.read("L12:0") == 0 and t.read("F8:0") == 0.0
    assert [kind for kind, _ in pccc.counted] == ["pccc"] * 4 + ["read-only"] + ["pccc"] * 2
    assert refused(pccc(0x0F, 0x99, b"")) == (P.STS_ILLEGAL, None)
    t.create_file("SI", 15, 2)  # a Logix SINT file: no PCCC type, its tag serves it
    assert refused(pccc.command(P.WordRangeRead(0, 1, P.Plc5Address(15, 0), 1))) == (P.STS_EXTENDED,
                                                                                     P.EXT_NOT_USABLE)
    response = route(pccc.router, 0x4C, PCCC_PATH, b"", pccc.access)  # not Execute PCCC
    assert response.status == cip_status.SERVICE_NOT_SUPPORTED


def test_echo_and_diagnostic_status():
    pccc = Pccc(table())
    assert pccc(0x06, 0x00, b"are you there").data == b"are you there"
    assert pccc(0x06, 0x03, b"").data[5:16] == b"softplc_lit"


# -- pycomm3's SLCDriver against the module -----------------------------------------------------

SLC_LADDER = """DATA N7 20
DATA F8 4
DATA B3 4
DATA L12 2
DATA ST9 2
DATA T4 2
DATA C5 2
DATA A13 2
MOV N7:0 N11:0
"""


@pytest.fixture
def slc_plc(enips_apps):
    return enips_apps.start(ladder=SLC_LADDER)


def test_slc_driver_reads_every_file_type(slc_plc):
    t = slc_plc.engine.table
    for address, value in (("N7:2", -7), ("F8:1", 2.5), ("L12:1", 100_000), ("ST9:0", "hello"), ("B3:1/3", 1),
                           ("T4:0.ACC", 42), ("T4:0.PRE", 500), ("C5:1.ACC", 9), ("S:30", 17), ("O:0", 0x55),
                           ("I:0", 3), ("A13:0", 0x4142)):
        t.write(address, value)
    t.write("T4:0/DN", 1)
    written_at = slc_plc.engine.scans
    slc_plc.wait_for(lambda: slc_plc.engine.scans > written_at + 2, "the values in a published scan")
    with SLCDriver(f"127.0.0.1:{slc_plc.port}") as slc:
        expected = {"N7:2": -7, "N7:0{3}": [0, 0, -7], "F8:1": 2.5, "L12:1": 100_000, "ST9:0": "hello",
                    "B3:1/3": True, "T4:0.ACC": 42, "T4:0.PRE": 500, "T4:0.DN": True, "C5:1.ACC": 9,
                    "S:30": 17, "O:0": 0x55, "I:0": 3, "A13:0": "AB"}
        for tag, value in expected.items():
            got = slc.read(tag)
            assert got.error is None and got.value == value, (tag, got)
        assert slc.get_processor_type() == "softplc_lit"


def test_slc_driver_writes_land_through_the_scan(slc_plc):
    t = slc_plc.engine.table
    with SLCDriver(f"127.0.0.1:{slc_plc.port}") as slc:
        for tag, value, address in (("N7:1", 42, "N7:1"), ("F8:0", 1.5, "F8:0"), ("ST9:0", "bye", "ST9:0"),
                                    ("L12:0", -5, "L12:0"), ("B3:0/5", True, "B3:0/5"), ("B3:0/5", False, "B3:0/5")):
            assert slc.write((tag, value)).error is None, tag
            assert t.read(address) == value, tag  # answered once the scan applied it
        assert slc.write(("N7:0{3}", [1, 2, 3])).error is None
        assert [t.read(f"N7:{k}") for k in range(3)] == [1, 2, 3]


def test_slc_driver_refusals_and_their_counts(enips_apps):
    plc = enips_apps.start(enips_xml('  <Writable address="N7:0" count="5"/>\n'), ladder=SLC_LADDER)
    with SLCDriver(f"127.0.0.1:{plc.port}") as slc:
        assert slc.write(("N7:10", 1)).error == "Error code in EXT STS Byte"  # no <Writable>: EXT STS 0x0B
        assert plc.read("N7:10") == 0
        assert slc.read("N7:99").error == "Error code in EXT STS Byte"  # N7 has 20 elements: EXT STS 0x06
        assert slc.read("N77:0").error is not None  # no such file
        # pycomm3 1.2 sends a timer's PRE and ACC writes alike (sub-element 0, a 6-byte size, 2 bytes of
        # data): which word is meant cannot be told, so the write is refused (EXT STS 0x07)
        assert slc.write(("T4:0.PRE", 9)).error is not None
    plc.wait_for(lambda: plc.status(S.W_READ_ONLY) == 1 and plc.status(S.W_PCCC_ERRORS) == 3,
                 "one read-only refusal, three PCCC errors")
