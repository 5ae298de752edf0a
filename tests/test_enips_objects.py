"""The CIP object interface and the status names the ENIPS services share."""

import asyncio

from softplc_lite.cip import status
from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips.access import TableAccessOnTable
from softplc_lite.tlm.enips.objects import CipObject, CipReply, CipRequest


class Echo(CipObject):
    class_id = 0x64

    async def serve(self, request, access):
        if request.service != 0x0E:
            return CipReply.error(request, status.SERVICE_NOT_SUPPORTED)
        (n7,) = await access.read([("N7", 0, 1)])
        return CipReply.ok(request, n7[0].to_bytes(2, "little", signed=True))


def test_an_object_answers_with_data_or_a_status():
    t = DataTable()
    t.write("N7:0", -2)
    access = TableAccessOnTable(t)
    get = CipRequest(0x0E, b"\x20\x64\x24\x01", (0x64, 1, None), b"")
    assert asyncio.run(Echo().serve(get, access)) == CipReply(0x8E, 0, (), b"\xfe\xff")
    bad = CipRequest(0x10, b"\x20\x64\x24\x01", (0x64, 1, None), b"")
    assert asyncio.run(Echo().serve(bad, access)) == CipReply(0x90, 0x08, (), b"")
    assert status.describe(0x05) == "0x05 (path destination unknown)"
    assert status.describe(0x7A) == "0x7A (unknown status)"
