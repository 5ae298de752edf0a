"""ENIPS against the clients the field uses, over real sockets to the
module's server process: pycomm3's LogixDriver and CIPDriver, and pylogix.
Every file type as a CIP tag, bits, sub-elements, strings, floats, long
runs that need the fragmented services, symbols as tags, the tag browse,
and the refusals with the statuses those clients report."""

from __future__ import annotations

import pytest
from pycomm3 import CIPDriver, LogixDriver
from pylogix import PLC

from softplc_lite.tlm.enips import status as S

from helpers.enips_apps import enips_xml

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def plc(enips_apps):
    return enips_apps.start()


@pytest.fixture
def logix(plc):
    with LogixDriver(f"127.0.0.1:{plc.port}") as driver:
        yield driver


def test_identity_names_softplc_lite_and_the_app(plc):
    with CIPDriver(f"127.0.0.1:{plc.port}") as driver:
        info = driver.get_module_info(0)
    assert info["product_name"] == "softplc_lite app1"
    assert info["vendor"] == "Rockwell Automation/Allen-Bradley"
    assert info["product_type"] == "Programmable Logic Controller"


def test_logix_reads_every_kind_of_tag(plc, logix):
    table = plc.engine.table
    table.write("F8:1", 2.5)
    table.write("ST9:0", "hello")
    table.write("L12:1", 100_000)
    table.write("N7:2", -7)
    table.write("B3:0/4", 1)
    plc.wait_for(lambda: logix.read("SPEED").value == 2.5, "the published F8:1")
    assert logix.read("NOTE").value == "hello"
    assert logix.read("ST9[0]").value == "hello"
    assert logix.read("L12[1]").value == 100_000
    assert logix.read("N7[2]").value == -7
    assert logix.read("B3[0].4").value is True
    assert logix.read("RUN").value is True
    count = logix.read("COUNT")
    assert count.type == "INT" and count.value > 0
    # a timer is INT[n, 3] to pycomm3 (docs/enips.md): word 0 the status bits, 1 PRE, 2 ACC
    plc.wait_for(lambda: logix.read("T4[0,0]").value & (1 << 13), "the timer done (DN, bit 13)")
    assert logix.read("T4[0,1]").value == 500 and logix.read("T4[0,2]").value == 500
    assert logix.read("T4[0]{3}").value[1:] == [500, 500]


def test_logix_writes_land_through_the_scan(plc, logix):
    assert logix.write("N7[1]", 42).error is None  # answered once the scan applied it
    assert plc.read("N7:1") == 42
    plc.wait_for(lambda: plc.read("N11:0") == 42, "the ladder using the written word")
    assert logix.write(("SPEED", 12.5), ("F8[3]", -1.0), ("L12[0]", -5)) and plc.read("F8:1") == 12.5
    assert plc.read("F8:3") == -1.0 and plc.read("L12:0") == -5
    assert logix.write("F8[0]{4}", [0.25, 0.5, 0.75, 1.0]).error is None and plc.read("F8:2") == 0.75
    assert logix.write("NOTE", "check seal").error is None and plc.read("ST9:0") == "check seal"
    assert logix.write("RUN", True).error is None
    plc.wait_for(lambda: plc.read("O:0/1") == 1, "the output of the written bit")
    assert logix.write("T4[0,1]", 900).error is None and plc.read("T4:0.PRE") == 900


def test_a_long_run_is_read_and_written_in_fragments(enips_apps):
    """3000 words (6000 bytes) are more than a reply holds (480 bytes here, a
    Large_Forward_Open connection's 4002 bytes for pycomm3): pycomm3 reads
    them with Read Tag Fragmented and writes them with Write Tag Fragmented,
    pylogix reads them in pieces."""
    words = 3000
    plc = enips_apps.start(enips_xml(f'  <Writable address="N11:0" count="{words}"/>\n'),
                           ladder=f"DATA N11 {words}\nMOV N7:0 N7:1\n")
    values = [(k * 7) % 32768 for k in range(words)]
    with LogixDriver(f"127.0.0.1:{plc.port}") as logix:
        assert logix.write(f"N11[0]{{{words}}}", values).error is None
        assert [plc.read(f"N11:{k}") for k in range(0, words, 97)] == values[::97]
        assert plc.read(f"N11:{words - 1}") == values[-1]
        assert logix.read(f"N11[0]{{{words}}}").value == values
    with PLC("127.0.0.1") as comm:
        comm.Port = plc.port
        assert comm.Read("N11[2000]", 500).Value == values[2000:2500]


def test_refusals_carry_the_status_clients_report(plc, logix):
    assert logix.write("N11[0]", 5).error == "Permission denied"  # pycomm3's name for 0x0F
    past = logix.read("N7[60]")  # N7 holds 50 elements: the server's 0x05
    assert past.error is not None and "destination unknown" in past.error.lower()
    with PLC("127.0.0.1") as comm:  # pylogix asks the server, which refuses
        comm.Port = plc.port
        assert comm.Write("N11[0]", 5).Status == "Privilege violation"
        assert comm.Read("NOSUCHTAG").Status == "Path destination unknown"
    assert plc.read("N11:0") == plc.read("N7:1")  # the ladder's value, not the client's
    plc.wait_for(lambda: plc.status(S.W_READ_ONLY) == 2, "both read-only refusals in the status words")
    plc.wait_for(lambda: plc.status(S.W_CIP_ERRORS) >= 2, "both unknown-destination refusals in the status words")
    assert plc.status(S.W_REFUSALS) == sum(plc.status(w) for w in range(S.W_REFUSED_NETWORK, S.W_REFUSALS))
    status = plc.module.server_status()
    assert status.refused["read-only"] == 2 and status.refused["CIP status"] >= 2


def test_the_tag_browse_lists_files_and_symbols(plc, logix):
    names = {tag["tag_name"] for tag in logix.get_tag_list()}
    assert {"N7", "F8", "B3", "T4", "ST9", "L12", "COUNT", "SPEED", "NOTE", "RUN"} <= names


def test_pylogix_reads_writes_and_browses(plc):
    with PLC("127.0.0.1") as comm:
        comm.Port = plc.port
        assert comm.Write("N7[3]", 77).Status == "Success"
        assert plc.read("N7:3") == 77
        assert comm.Read("N7[3]").Value == 77
        assert comm.Read("SPEED").Status == "Success"
        assert comm.Read("T4[0].PRE").Value == 500 and comm.Read("DWELL.PRE").Value == 500
        assert comm.Write("T4[0].PRE", 600).Status == "Success" and plc.read("T4:0.PRE") == 600
        refused = comm.Write("N11[2]", 1)
        assert refused.Status != "Success" and plc.read("N11:2") == 0
        tags = comm.GetTagList()
        assert tags.Status == "Success"
        assert {"N7", "COUNT"} <= {t.TagName for t in tags.Value}


EVERY_FILE = """  <Writable address="O:0"/>
  <Writable address="I:0"/>
  <Writable address="S:30"/>
  <Writable address="B3:1"/>
  <Writable address="T4:1"/>
  <Writable address="C5:0"/>
  <Writable address="R6:0"/>
  <Writable address="N7:0"/>
  <Writable address="F8:0"/>
  <Writable address="ST9:1"/>
  <Writable address="L12:0"/>
  <Writable address="A13:0"/>
  <Writable address="D14:0"/>
"""
# (tag, its address in the table, a value to write)
EVERY_KIND = [("O0[0]", "O:0", 0x55), ("I1[0]", "I:0", -2), ("S2[30]", "S:30", 7), ("B3[1]", "B3:1", 0x0F0F),
              ("B3[1].9", "B3:1/9", True), ("T4[1].ACC", "T4:1.ACC", 123), ("C5[0].PRE", "C5:0.PRE", 40),
              ("R6[0].LEN", "R6:0.LEN", 12), ("N7[0]", "N7:0", -32768), ("F8[0]", "F8:0", -0.5),
              ("ST9[1]", "ST9:1", "ok"), ("L12[0]", "L12:0", -2_000_000), ("A13[0]", "A13:0", 0x4142),
              ("D14[0]", "D14:0", 0x1234)]


def test_every_file_type_is_written_and_read_back_by_pylogix(enips_apps):
    plc = enips_apps.start(enips_xml(EVERY_FILE),
                           ladder="DATA A13 4\nDATA D14 4\nDATA C5 2\nDATA R6 2\nDATA L12 2\nDATA ST9 2\n"
                                  "DATA T4 2\nDATA B3 2\nMOV N7:1 N7:2\n")
    with PLC("127.0.0.1") as comm:
        comm.Port = plc.port
        for tag, address, value in EVERY_KIND:
            written = comm.Write(tag, value)
            assert written.Status == "Success", (tag, written.Status)
            expected = int(value) if isinstance(value, bool) else value
            assert plc.read(address) == expected, tag
            assert comm.Read(tag).Value == value, tag
