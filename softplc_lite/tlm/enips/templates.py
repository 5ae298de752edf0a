"""What pycomm3's LogixDriver asks of a controller at connect besides its
identity and tag list (docs/enips.md, "CIP tags"): the controller's program
name (class 0x64, Rockwell KB 23341 as pycomm3 cites it) and the template
of each structure type a tag has (Template object, class 0x6C). The data
table's only structure is Logix's STRING (ST files), whose template is
DINT LEN at offset 0 and SINT[82] DATA at offset 4, 88 bytes, which pycomm3
recognises as a string by those two member names and types; a Logix app
adds its structure types' (logixview.py).
"""

from __future__ import annotations

import struct

from ...cip import status as st
from .access import TableAccess
from .objects import REPLY, CipObject, CipReply, CipRequest
from .logixview import LogixView
from .tagnames import DINT, SINT, STRING_BYTES, STRING_CHARS, STRING_HANDLE
from .tags import EXT_OFFSET_OUT_OF_RANGE, REPLY_BYTES

GET_ATTRIBUTES_ALL, GET_ATTRIBUTE_LIST, READ_TEMPLATE = 0x01, 0x03, 0x4C

# Member info (UINT array size or bit, UINT type, UDINT offset) per member,
# then the template's name and the member names, NUL-terminated: the layout
# pycomm3's _parse_template_data and pylogix's _get_udt read. ASCIISTRING82
# is the name Logix gives its STRING template (pycomm3 maps it to STRING).
# No ";n..." after the name: pylogix reads member scope bytes from what
# follows a ';', and a predefined type's name may stand alone (pycomm3).
STRING_TEMPLATE = (struct.pack("<HHI", 0, DINT, 0) + struct.pack("<HHI", STRING_CHARS, SINT, 4)
                   + b"ASCIISTRING82\x00LEN\x00DATA\x00")
# A template's definition is whole 32-bit words, as Logix keeps it: padded,
# so a client that rounds the definition's size up to words (pylogix) reads
# it in one request and none past its end.
STRING_TEMPLATE += bytes(-len(STRING_TEMPLATE) % 4)
# Attribute 4 counts 32-bit words of the definition plus the 23 bytes a
# Logix template read adds (pycomm3 asks size * 4 - 21 bytes, so no less).
DEFINITION_WORDS = (len(STRING_TEMPLATE) + 23) // 4


class TemplateObject(CipObject):
    """Class 0x6C: Get_Attribute_List (attributes 1 handle, 2 member count,
    4 definition size, 5 structure size) and Read (0x4C: UDINT offset, UINT
    byte count) of each template: STRING's, instance 0x0FCE, and a Logix
    app's structure types'. Attribute 3 is served as a UINT (the handle
    again): pylogix asks 4, 3, 2, 1 and finds the member count where a
    2-byte attribute 3 puts it."""

    class_id = 0x6C

    def __init__(self, logix: LogixView | None = None) -> None:
        # instance -> (handle, member count, structure bytes, definition)
        self.templates = {STRING_HANDLE: (STRING_HANDLE, 2, STRING_BYTES, STRING_TEMPLATE)}
        for instance, t in (logix.templates.items() if logix is not None else ()):
            self.templates[instance] = (t.handle, len(t.members), t.size, t.definition())

    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        instance = request.logical[1] if request.logical else None
        template = self.templates.get(instance)
        if template is None:
            return CipReply.error(request, st.PATH_DESTINATION_UNKNOWN)
        definition = template[3]
        try:
            if request.service == GET_ATTRIBUTE_LIST:
                return _attributes(request, template)
            if request.service == READ_TEMPLATE:
                offset, count = struct.unpack_from("<IH", request.data)
                if offset >= len(definition):
                    return CipReply.error(request, st.GENERAL_ERROR, EXT_OFFSET_OUT_OF_RANGE)
                end = min(len(definition), offset + count)
                status = st.SUCCESS
                if end - offset > REPLY_BYTES:
                    end, status = offset + REPLY_BYTES, st.PARTIAL_TRANSFER
                return CipReply(request.service | REPLY, status, (), definition[offset:end])
        except struct.error:
            return CipReply.error(request, st.NOT_ENOUGH_DATA)
        return CipReply.error(request, st.SERVICE_NOT_SUPPORTED)


def _attributes(request: CipRequest, template: tuple) -> CipReply:
    handle, members, size, definition = template
    count = struct.unpack_from("<H", request.data)[0]
    numbers = struct.unpack_from(f"<{count}H", request.data, 2)
    words = (len(definition) + 23) // 4
    values = {1: struct.pack("<H", handle), 2: struct.pack("<H", members), 3: struct.pack("<H", handle),
              4: struct.pack("<I", words), 5: struct.pack("<I", size)}
    out = bytearray(struct.pack("<H", count))
    for number in numbers:
        if number in values:
            out += struct.pack("<HH", number, 0) + values[number]
        else:
            out += struct.pack("<HH", number, st.ATTRIBUTE_NOT_SUPPORTED)
    return CipReply.ok(request, bytes(out))


class ProgramName(CipObject):
    """Class 0x64 instance 1, Get_Attributes_All: the controller's program
    name as a UINT-length string, the app's name here."""

    class_id = 0x64

    def __init__(self, name: str) -> None:
        self.name = name.encode("ascii", "replace")[:255]

    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        if request.service != GET_ATTRIBUTES_ALL:
            return CipReply.error(request, st.SERVICE_NOT_SUPPORTED)
        return CipReply.ok(request, struct.pack("<H", len(self.name)) + self.name)
