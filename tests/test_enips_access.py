"""The table access the EtherNet/IP services are written against, on a real DataTable."""

import asyncio

from softplc_lite.datatable import DataTable
from softplc_lite.tlm.enips.access import TableAccessOnTable


def test_files_reads_and_writes_on_a_table():
    t = DataTable()
    t.reference("N7:9")
    t.reference("ST9:1")
    t.write("N7:2", -5)
    t.write("F8:0", 1.5)
    access = TableAccessOnTable(t, writable={"N7"})
    n7 = access.file("N", 7)
    assert (n7.name, n7.elements, n7.items_per_element, n7.writable) == ("N7", 10, 1, True)
    assert access.file("F", 7) is None and access.file("N", 99) is None
    assert access.file("ST", 9).items_per_element == 83 and access.file("T", 4).items == 3
    assert asyncio.run(access.read([("N7", 1, 3), ("F8", 0, 1)])) == [[0, -5, 0], [1.5]]
    assert asyncio.run(access.write("N7", 0, [1, 2])) and t.read("N7:1") == 2
    assert not asyncio.run(access.write("F8", 0, [2.0])) and t.read("F8:0") == 1.5
    assert asyncio.run(access.write_masked("N7", 2, 0x00FF, 0x8000)) and t.read("N7:2") == -32517  # 0x80FB
    try:
        asyncio.run(access.read([("N7", 9, 2)]))
    except IndexError as e:
        assert "past its end" in str(e)
    else:
        raise AssertionError("a read past the end must raise")
