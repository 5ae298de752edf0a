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


def test_masked_writes_keep_each_items_width_and_a_group_lands_whole():
    """What a Logix app's bit writes and structure writes need of the
    image's protocol (protocol.py): a masked write of an 8-, 32- or 64-bit
    item, and several writes applied at one input point, or none."""
    from array import array

    from softplc_lite.netserver import APPLIED, REFUSED
    from softplc_lite.tlm.enips.config import ServerConfig
    from softplc_lite.tlm.enips.identity import Identity
    from softplc_lite.tlm.enips.protocol import EnipProtocol, build_slots, group_payload, mask_payload, write_payload

    t = DataTable()
    for letter, number in (("SI", 10), ("L", 11), ("LI", 12), ("F", 13)):
        t.create_file(letter, number, 4)
    opened = {"SI10": [(0, 4)], "L11": [(0, 4)], "LI12": [(0, 2)], "F13": [(0, 4)]}
    slots = build_slots(t, ServerConfig(), opened, {"F13": [(2, 3)]})
    protocol = EnipProtocol(ServerConfig(), slots, Identity("X"), {})
    assert protocol.apply(mask_payload(11, 1, ~(1 << 31), 1 << 31), t) == APPLIED and t.read("L11:1") == -2 ** 31
    assert protocol.apply(mask_payload(10, 0, 0xFF, 0x80), t) == APPLIED and t.read("SI10:0") == -128
    assert protocol.apply(mask_payload(12, 1, -1, 1 << 40), t) == APPLIED and t.read("LI12:1") == 2 ** 40
    assert protocol.apply(mask_payload(12, 3, -1, 1), t) == REFUSED  # past the opened items
    assert protocol.apply(mask_payload(13, 0, -1, 1), t) == REFUSED  # a float has no bits to mask
    good = write_payload(11, 2, array("i", [7, 8]))
    assert protocol.apply(group_payload([good, write_payload(13, 2, array("f", [1.0]))]), t) == REFUSED
    assert t.read("L11:2") == 0  # F13:2 is closed: nothing of the group is applied
    assert protocol.apply(group_payload([good, write_payload(13, 3, array("f", [1.0]))]), t) == APPLIED
    assert (t.read("L11:2"), t.read("L11:3"), t.read("F13:3")) == (7, 8, 1.0)
    access = TableAccessOnTable(t, writable={"L11"})
    assert asyncio.run(access.write_masked("L11", 0, -1, 1 << 30)) and t.read("L11:0") == 1 << 30


def test_a_b_files_bits_are_opened_one_by_one():
    """A Logix app's BOOL tags share the words of a B file: a tag opened to
    clients opens its bit alone (ranges of a B file count bits)."""
    from softplc_lite.netserver import APPLIED, REFUSED
    from softplc_lite.tlm.enips.config import ServerConfig, parse_config
    from softplc_lite.tlm.enips.identity import Identity
    from softplc_lite.tlm.enips.protocol import EnipProtocol, build_slots, mask_payload

    t = DataTable()
    t.create_file("B", 10, 2)
    slots = build_slots(t, ServerConfig(), {"B10": [(3, 4)]})
    b10 = next(s for s in slots if s.info.name == "B10")
    assert b10.may_mask(0, ~(1 << 3), 1 << 3) and not b10.may_mask(0, ~(1 << 4), 0) and not b10.may_write(0, 1)
    protocol = EnipProtocol(ServerConfig(), slots, Identity("X"), {})
    assert protocol.apply(mask_payload(10, 0, 0xFFFF, 1 << 3), t) == APPLIED and t.read("B10:0/3") == 1
    assert protocol.apply(mask_payload(10, 0, 0xFFFF, 1 << 5), t) == REFUSED and t.read("B10:0/5") == 0
    whole = parse_config(b'<EtherNetIpServer><Writable address="B10:1"/></EtherNetIpServer>')
    b10 = next(s for s in build_slots(t, whole) if s.info.name == "B10")
    assert b10.may_write(1, 1) and b10.may_mask(1, 0, 0xFFFF) and not b10.may_write(0, 1)
