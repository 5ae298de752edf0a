"""The STRING template and the program name as pycomm3's LogixDriver reads
them at connect, decoded with pycomm3's own parsers."""

from __future__ import annotations

import asyncio
import struct

from pycomm3 import LogixDriver
from pycomm3.custom_types import StructTemplateAttributes

from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips.access import TableAccessOnTable
from softplc_lite.tlm.enips.objects import CipRequest
from softplc_lite.tlm.enips.templates import ProgramName, TemplateObject

ACCESS = TableAccessOnTable(DataTable())


def serve(obj, service: int, instance: int, data: bytes):
    path = bytes([0x20, obj.class_id]) + struct.pack("<BBH", 0x25, 0, instance)
    return asyncio.run(obj.serve(CipRequest(service, path, (obj.class_id, instance, None), data), ACCESS))


def test_string_template_as_pycomm3_parses_it():
    obj = TemplateObject()
    reply = serve(obj, 0x03, 0x0FCE, struct.pack("<5H", 4, 4, 5, 2, 1))
    attrs = StructTemplateAttributes.decode(reply.data)
    template = {"object_definition_size": attrs["object_definition_size"]["size"],
                "structure_size": attrs["structure_size"]["size"],
                "member_count": attrs["member_count"]["count"],
                "structure_handle": attrs["structure_handle"]["handle"]}
    assert template["structure_size"] == 88 and template["member_count"] == 2
    assert template["structure_handle"] == 0x0FCE
    # pycomm3's _read_template: ask size * 4 - 21 bytes from offset 0
    want = template["object_definition_size"] * 4 - 21
    reply = serve(obj, 0x4C, 0x0FCE, struct.pack("<IH", 0, want))
    assert reply.status == 0
    driver = LogixDriver("127.0.0.1")
    data_type = driver._parse_template_data(reply.data, template, 0x8FCE)
    assert data_type["name"] == "STRING" and data_type["string"] == 82
    assert serve(obj, 0x4C, 0x0FCF, struct.pack("<IH", 0, want)).status == 0x05
    assert serve(obj, 0x4C, 0x0FCE, struct.pack("<IH", 999, 1)).extended == (0x2104,)


def test_template_attributes_where_pylogix_reads_them():
    # pylogix's _get_udt: attributes 4, 3, 2, 1; definition size at data[6],
    # member count at data[20]; then it reads (size * 4 - 23) rounded up to 4
    reply = serve(TemplateObject(), 0x03, 0x0FCE, struct.pack("<5H", 4, 4, 3, 2, 1))
    size = struct.unpack_from("<I", reply.data, 6)[0]
    assert struct.unpack_from("<H", reply.data, 20)[0] == 2
    want = -(-(size * 4 - 23) // 4) * 4
    first = serve(TemplateObject(), 0x4C, 0x0FCE, struct.pack("<IH", 0, want))
    names = first.data[16:].split(b"\x00")
    assert names[:3] == [b"ASCIISTRING82", b"LEN", b"DATA"] and b";" not in first.data
    # what is left of its request past the end is refused, which ends its loop
    assert serve(TemplateObject(), 0x4C, 0x0FCE, struct.pack("<IH", len(first.data), want - len(first.data))).status


def test_program_name():
    reply = serve(ProgramName("pumps"), 0x01, 1, b"")
    assert reply.data == b"\x05\x00pumps"
    assert serve(ProgramName("pumps"), 0x0E, 1, b"").status == 0x08
