"""CIP tag services on a real DataTable (TableAccessOnTable), with requests
built by pylogix's own request builders, as pylogix sends them."""

from __future__ import annotations

import asyncio
import struct

import pytest
from pylogix import PLC

from softplc_lite.cip.mr import MessageRouterRequest
from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips.access import TableAccessOnTable
from softplc_lite.tlm.enips.objects import CipRequest
from softplc_lite.tlm.enips.tags import SymbolObject, TagServices

SYMBOLS = {"Speed": "N7:3", "Running": "B3:1/4", "Level": "F8:2", "Total": "L10:1",
           "PollTimer": "T4:1", "Label": "ST9:1", "Late": "T4:1/DN", "Count": "C5:0.ACC"}


def table() -> DataTable:
    t = DataTable()
    for a in ("N7:299", "F8:3", "L10:3", "B3:3", "T4:2", "C5:1", "R6:1", "ST9:2", "A11:1", "D12:1"):
        t.reference(a)
    for k in range(300):
        t.write(f"N7:{k}", k * 3 - 100)
    t.write("F8:2", 2.5)
    t.write("L10:1", -70000)
    t.write("B3:1/4", 1)
    t.write("T4:1.PRE", 500)
    t.write("T4:1.ACC", 123)
    t.write("T4:1/DN", 1)
    t.write("C5:0.ACC", 7)
    t.write("R6:0.POS", 9)
    t.write("ST9:1", "hello")
    return t


@pytest.fixture
def plc():
    p = PLC()
    yield p
    p.Close()


def request(raw: bytes) -> CipRequest:
    """A pylogix-built service request as the router hands it on."""
    decoded = MessageRouterRequest.decode(raw)
    return CipRequest(decoded.service, decoded.path, None, decoded.data)


def serve(raw: bytes, t: DataTable | None = None, writable=frozenset({"N7", "F8", "L10", "B3", "T4", "ST9"}),
          obj=None):
    obj = obj or TagServices(SYMBOLS)
    access = TableAccessOnTable(t if t is not None else table(), writable)
    return asyncio.run(obj.serve(request(raw), access))


def read(plc: PLC, tag: str, count: int = 1, t=None):
    return serve(plc._add_read_service(plc._build_ioi(tag, 0xC3), count), t)


def test_read_every_file_type(plc):
    cases = {"N7[5]": ("<Hh", 0xC3, -85), "F8[2]": ("<Hf", 0xCA, 2.5), "L10[1]": ("<Hi", 0xC4, -70000),
             "B3[1]": ("<Hh", 0xC3, 16), "O0[0]": ("<Hh", 0xC3, 0), "S2[0]": ("<Hh", 0xC3, 0),
             "A11[1]": ("<Hh", 0xC3, 0), "D12[0]": ("<Hh", 0xC3, 0), "T4[1].ACC": ("<Hh", 0xC3, 123),
             "T4[1].PRE": ("<Hh", 0xC3, 500), "C5[0].ACC": ("<Hh", 0xC3, 7), "R6[0].POS": ("<Hh", 0xC3, 9),
             "T4[1].DN": ("<HB", 0xC1, 1), "T4[1].EN": ("<HB", 0xC1, 0)}
    for tag, (fmt, ctype, value) in cases.items():
        reply = read(plc, tag)
        assert (reply.service, reply.status) == (0xCC, 0), tag
        assert struct.unpack(fmt, reply.data) == (ctype, value), tag


def test_timer_as_int_rows_and_bit_by_number(plc):
    reply = read(plc, "T4[1]", 3)
    assert struct.unpack("<H3h", reply.data) == (0xC3, 1 << 13, 500, 123)
    assert struct.unpack("<Hh", read(plc, "T4[1,2]").data) == (0xC3, 123)
    # B3[1].4 sent with the bit as a member name
    raw = plc._add_read_service(plc._build_ioi("B3[1]", 0xC3) + b"\x91\x014\x00", 1)
    assert struct.unpack("<HB", serve(raw).data) == (0xC1, 1)


def test_string_is_logix_string(plc):
    reply = read(plc, "ST9[1]")
    assert reply.data[:4] == bytes([0xA0, 0x02, 0xCE, 0x0F])
    length = struct.unpack_from("<i", reply.data, 4)[0]
    assert reply.data[8:8 + length] == b"hello" and len(reply.data) == 4 + 88
    assert struct.unpack("<Hi", read(plc, "ST9[1].LEN").data) == (0xC4, 5)


def test_array_of_n_elements_and_partial_transfer(plc):
    reply = read(plc, "N7[10]", 50)
    assert reply.status == 0 and list(struct.unpack("<50h", reply.data[2:])) == [k * 3 - 100 for k in range(10, 60)]
    reply = read(plc, "N7[0]", 300)
    assert reply.status == 0x06  # more than one reply's worth
    got = list(struct.unpack(f"<{(len(reply.data) - 2) // 2}h", reply.data[2:]))
    ioi = plc._build_ioi("N7[0]", 0xC3)
    while reply.status == 0x06:
        plc.Offset = len(got) * 2
        reply = serve(plc._add_partial_read_service(ioi, 300))
        assert reply.service == 0xD2
        got += struct.unpack(f"<{(len(reply.data) - 2) // 2}h", reply.data[2:])
    assert got == [k * 3 - 100 for k in range(300)]


def test_symbols_as_tags(plc):
    assert struct.unpack("<Hh", read(plc, "Speed").data) == (0xC3, -91)
    assert struct.unpack("<HB", read(plc, "running").data) == (0xC1, 1)
    assert struct.unpack("<Hf", read(plc, "Level").data) == (0xCA, 2.5)
    assert struct.unpack("<Hi", read(plc, "Total").data) == (0xC4, -70000)
    assert struct.unpack("<Hh", read(plc, "PollTimer.ACC").data) == (0xC3, 123)
    assert struct.unpack("<HB", read(plc, "PollTimer.DN").data) == (0xC1, 1)
    assert struct.unpack("<HB", read(plc, "Late").data) == (0xC1, 1)
    assert struct.unpack("<Hh", read(plc, "Count").data) == (0xC3, 7)
    assert read(plc, "Label").data[8:13] == b"hello"


def test_writes_land_in_the_table(plc):
    t = table()
    for tag, ctype, value, addr in (("N7[4]", 0xC3, -5, "N7:4"), ("F8[1]", 0xCA, 1.25, "F8:1"),
                                    ("L10[2]", 0xC4, 123456, "L10:2"), ("T4[0].PRE", 0xC3, 42, "T4:0.PRE"),
                                    ("Speed", 0xC3, 77, "N7:3")):
        reply = serve(plc._add_write_service(plc._build_ioi(tag, ctype), [value], ctype), t)
        assert (reply.service, reply.status) == (0xCD, 0), tag
        assert t.read(addr) == value
    reply = serve(plc._add_write_service(plc._build_ioi("ST9[0]", 0xA0), ["PUMP"], 0xA0), t)
    assert reply.status == 0 and t.read("ST9:0") == "PUMP"
    reply = serve(plc._add_write_service(plc._build_ioi("Running", 0xC1), [0], 0xC1), t)
    assert reply.status == 0 and t.read("B3:1/4") == 0
    reply = serve(plc._add_write_service(plc._build_ioi("T4[0].TT", 0xC1), [1], 0xC1), t)
    assert reply.status == 0 and t.read("T4:0/TT") == 1 and t.read("T4:0/EN") == 0


def test_fragmented_write(plc):
    t = table()
    ioi = plc._build_ioi("N7[0]", 0xC3)
    values = list(range(1000, 1200))
    for start in range(0, 200, 100):
        plc.Offset = start * 2
        reply = serve(plc._add_frag_write_service(200, ioi, values[start:start + 100], 0xC3), t)
        assert (reply.service, reply.status) == (0xD3, 0)
    assert [t.read(f"N7:{k}") for k in range(200)] == values


def test_read_modify_write_masks(plc):
    t = table()
    t.write("B3:2", 0x00F0)
    # pylogix's mask order: OR mask, then AND mask
    reply = serve(plc._add_mod_write_service(plc._build_ioi("B3[2]", 0xC3), 0xC3, 0x0003, -129), t)  # AND 0xFF7F
    assert (reply.service, reply.status) == (0xCE, 0)
    assert t.read("B3:2") == 0x0073
    reply = serve(plc._add_mod_write_service(plc._build_ioi("F8[0]", 0xCA), 0xCA, 1.0, 0.0), t)
    assert (reply.status, reply.extended) == (0xFF, (0x2107,))


def test_refusals(plc):
    assert read(plc, "N99[0]").status == 0x05  # no such tag
    assert read(plc, "N7[300]").status == 0x05  # element past the array
    assert read(plc, "T4[0].XYZ").status == 0x04  # no such member
    reply = read(plc, "N7[290]", 20)  # count runs past the end
    assert (reply.status, reply.extended) == (0xFF, (0x2105,))
    reply = serve(plc._add_write_service(plc._build_ioi("N7[0]", 0xC4), [5], 0xC4))
    assert (reply.status, reply.extended) == (0xFF, (0x2107,))  # DINT to an INT
    reply = serve(plc._add_write_service(plc._build_ioi("C5[0].PRE", 0xC3), [5], 0xC3))
    assert reply.status == 0x0F  # C5 not writable
    assert serve(bytes([0x4B, 0x02]) + plc._build_ioi("N7", 0xC3)).status == 0x08
    assert serve(plc._add_read_service(plc._build_ioi("N7", 0xC3), 1)[:-1]).status == 0x13


def browse(plc: PLC, obj, first: int = 0, attributes=(1, 2, 8)):
    plc.Offset = first
    raw = plc._build_tag_list_request(None)
    if attributes != (1, 2, 8):
        raw = raw[:-8] + struct.pack(f"<{len(attributes) + 1}H", len(attributes), *attributes)
    return serve(raw, obj=obj)


def test_browse_as_pylogix_parses_it(plc):
    from pylogix.lgx_tag import Tag

    obj = SymbolObject(SYMBOLS)
    tags, status, first = [], 0x06, 0
    while status == 0x06:
        reply = browse(plc, obj, first)
        status = reply.status
        data, at = reply.data, 0
        while at < len(data):
            size = struct.unpack_from("<H", data, at + 4)[0] + 20
            # pylogix parses each entry with its reply header before it
            tags.append(Tag.parse(b"\x00" * 0 + data[at:at + size], None))
            first = struct.unpack_from("<I", data, at)[0] + 1
            at += size
    assert status == 0
    by_name = {t.TagName: t for t in tags}
    assert by_name["N7"].DataTypeValue == 0xC3 and by_name["N7"].Array == 1 and by_name["N7"].Size == 300
    assert by_name["F8"].DataTypeValue == 0xCA and by_name["L10"].DataTypeValue == 0xC4
    assert by_name["T4"].Array == 2 and by_name["ST9"].Struct == 1
    assert by_name["Running"].DataTypeValue == 0xC1 and by_name["Speed"].Array == 0
    assert len(tags) == len({t.TagName for t in tags})


def test_browse_with_pycomm3_attributes(plc):
    reply = browse(plc, SymbolObject(SYMBOLS), 1, (1, 2, 3, 5, 6, 8, 10))
    instance, size = struct.unpack_from("<IH", reply.data, 0)
    name = reply.data[6:6 + size].decode()
    at = 6 + size
    ctype, _, _, _, d1, d2, d3, external = struct.unpack_from("<HIII3IB", reply.data, at)
    assert (instance, name, ctype, (d1, d2, d3), external) == (1, "O0", 0xC3 | 1 << 13, (32, 0, 0), 2)
    assert browse(plc, SymbolObject(SYMBOLS), 1, (1, 99)).status == 0x14


def test_read_by_symbol_instance(plc):
    obj = SymbolObject(SYMBOLS)
    t = table()
    names = [tg.name for tg in __import__("softplc_lite.tlm.enips.tagnames", fromlist=["Catalogue"])
             .Catalogue(TableAccessOnTable(t), SYMBOLS).tags]
    instance = names.index("N7") + 1
    raw = bytes([0x4C, 3, 0x20, 0x6B, 0x24, instance, 0x28, 5]) + struct.pack("<H", 1)
    assert struct.unpack("<Hh", serve(raw, t, obj=obj).data) == (0xC3, -85)


def test_browse_as_pycomm3_parses_it(plc):
    from types import SimpleNamespace

    from pycomm3 import LogixDriver

    driver = LogixDriver("127.0.0.1")
    driver._info["revision"] = {"major": 20}  # asks attribute 10 (external access) from v18
    obj, tag_list, first = SymbolObject(SYMBOLS), [], 0
    while first != -1:
        reply = browse(plc, obj, first, (1, 2, 3, 5, 6, 8, 10))
        first = driver._parse_instance_attribute_list(SimpleNamespace(data=reply.data, service_status=reply.status),
                                                      tag_list)
    # the STRING template as test_cip_templates.py has pycomm3 parse it from TemplateObject
    driver._cache = {"tag_name:id": {}, "id:struct": {}, "handle:id": {},
                     "id:udt": {0x0FCE: {"name": "STRING", "type_class": None}}}
    tags = {t["tag_name"]: t for t in driver._isolate_user_tags(tag_list)}
    assert tags["N7"]["data_type"] == "INT" and tags["N7"]["dimensions"] == [300, 0, 0]
    assert tags["T4"]["dim"] == 2 and tags["T4"]["dimensions"] == [3, 3, 0]
    assert tags["Level"]["data_type"] == "REAL" and tags["Running"]["data_type"] == "BOOL"
    assert tags["ST9"]["data_type_name"] == "STRING" and not tags["N7"]["alias"]
    assert tags["C5"]["external_access"] == "Read Only" and tags["N7"]["external_access"] == "Read/Write"


def test_the_tag_catalogue_is_built_again_only_when_the_files_change():
    t = table()
    access = TableAccessOnTable(t)
    services = TagServices(SYMBOLS)
    first = services.catalogue(access)
    assert services.catalogue(access) is first  # not at every request
    t.reference("N7:400")
    grown = services.catalogue(access)
    assert grown is not first and grown.by_name["N7"].dims == (401,)
