"""ENIPS.XML: the documented example, every attribute's range, the
<Writable> rules, every problem at once with its place, and the file as
`softplc check` and `softplc run` meet it."""

from __future__ import annotations

import ipaddress
import re
from pathlib import Path

import pytest

from softplc_lite.datatable import DataTable, parse_address
from softplc_lite.tlm.enips.config import PORT, ServerConfig, config_references, load_config, parse_config
from softplc_lite.tlm.enips.protocol import build_slots
from softplc_lite.tlm.errors import ModuleError, ModuleErrors

from helpers.apps import make_app
from helpers.cli import softplc_here
from helpers.located import locate, where

DOC = Path(__file__).resolve().parent.parent / "docs" / "enips.md"


def doc_example() -> str:
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## The configuration file: ENIPS.XML"):]
    return re.search(r"```xml\n(.*?)```", section, re.S).group(1)


def problems(xml: str) -> list[ModuleError]:
    with pytest.raises(ModuleErrors) as info:
        parse_config(xml.encode())
    return info.value.problems


def test_the_doc_example_parses_to_the_model():
    text = doc_example()
    c = parse_config(text.encode())
    assert (c.host, c.port, c.max_connections, c.max_requests_per_second, c.idle_timeout_ms,
            c.max_cip_connections, c.list_identity_udp, c.debug) == ("127.0.0.1", PORT, 32, 1000, 60000, 32, True, 0)
    assert c.status == parse_address("N40:0")
    assert c.allow == (ipaddress.ip_network("127.0.0.0/8"), ipaddress.ip_network("192.168.1.0/24"))
    assert [(str(w.address), w.count, (w.line, w.column)) for w in c.writable] == [
        ("N7:0", 10, locate(text, '<Writable address="N7:0"')), ("B3:0", 2, locate(text, '<Writable address="B3:0"')),
        ("ST9:0", 1, locate(text, '<Writable address="ST9:0"'))]
    assert c.warnings == []


def test_defaults_are_safe():
    c = parse_config(b"<EtherNetIpServer/>")
    assert c == ServerConfig(allow=c.allow)
    assert c.host == "127.0.0.1" and c.writable == () and c.status is None
    assert all(net.is_loopback for net in c.allow)


def test_every_problem_at_once_each_in_its_place():
    text = """<EtherNetIpServer port="70000" maxCipConnections="0" status="F8:0" udpListIdentity="maybe" colour="red">
  <Allow network="10.0.0.0/33"/>
  <Writable address="N7:0/3"/>
  <Writable address="T4:0.ACC"/>
  <Writable address="#N7:3"/>
  <Writable address="N7:9999" count="5"/>
  <Writable address="Q7:0"/>
  <Writable count="2"/>
  <Unit id="1"/>
</EtherNetIpServer>
"""
    found = problems(text)
    messages = [p.message for p in found]
    places = [where(p) for p in found]
    expected = [
        (locate(text, 'port="70000"'), "port='70000': expected an integer 1..65535"),
        (locate(text, 'maxCipConnections'), "expected an integer 1..1000"),
        (locate(text, 'udpListIdentity'), "expected 'yes' or 'no'"),
        (locate(text, 'colour'), "colour"),
        (locate(text, 'status='), "expected a direct word address of an N or B file"),
        (locate(text, 'network='), "expected a client network"),
        (locate(text, 'address="N7:0/3"'), "expected a whole element"),
        (locate(text, 'address="T4:0.ACC"'), "expected a whole element"),
        (locate(text, 'address="#N7:3"'), "expected a whole element"),
        (locate(text, 'count="5"'), "run past the end of a file"),
        (locate(text, 'address="Q7:0"'), "unknown file type 'Q'"),
        (locate(text, '<Writable count="2"'), "needs the attribute address"),
        (locate(text, '<Unit'), "unknown element <Unit>"),
    ]
    for (line, column), words in expected:
        hits = [m for m, place in zip(messages, places) if place == (line, column) and words in m]
        assert hits, f"nothing at {line}:{column} says {words!r}:\n" + ModuleErrors(found).report()
    assert len(found) == len(expected), ModuleErrors(found).report()


def test_a_region_over_the_status_words_is_refused_and_regions_may_touch():
    (p,) = problems('<EtherNetIpServer status="N40:0"><Writable address="N40:12" count="8"/></EtherNetIpServer>')
    assert "covers the status words N40:0..N40:15" in p.message
    c = parse_config(b'<EtherNetIpServer status="N40:0"><Writable address="N40:16" count="4"/>'
                     b'<Writable address="N7:0" count="2"/><Writable address="N7:2" count="2"/></EtherNetIpServer>')
    table = DataTable()
    for address in config_references(c):
        table.reference(address)
    slots = {s.info.name: s for s in build_slots(table, c)}
    assert slots["N7"].writable == ((0, 4),) and slots["N7"].may_write(1, 3) and not slots["N7"].may_write(3, 2)
    assert slots["N40"].writable == ((16, 20),) and not slots["N40"].may_write(15, 1)
    assert not slots["F8"].info.writable and slots["F8"].writable == ()
    assert [s.offset % 8 for s in slots.values()] == [0] * len(slots)  # every file aligned in the image


def test_timer_and_string_regions_open_their_whole_elements():
    c = parse_config(b'<EtherNetIpServer><Writable address="T4:1"/><Writable address="ST9:0"/></EtherNetIpServer>')
    table = DataTable()
    for address in config_references(c):
        table.reference(address)
    slots = {s.info.name: s for s in build_slots(table, c)}
    assert slots["T4"].writable == ((3, 6),)  # T4:1's control word, PRE and ACC
    assert slots["ST9"].writable == ((0, 83),)  # LEN and 82 characters


def test_listening_beyond_this_machine_without_an_allow_list_warns():
    c = parse_config(b'<EtherNetIpServer address="0.0.0.0"/>')
    assert len(c.warnings) == 1 and "no <Allow> is given" in c.warnings[0]
    assert all(net.is_loopback for net in c.allow)


def test_a_missing_file_says_what_it_holds(tmp_path):
    with pytest.raises(ModuleError) as info:
        load_config(tmp_path)
    assert "ENIPS.XML" in str(info.value) and "docs/enips.md" in str(info.value)


def test_softplc_check_reports_the_file_located(tmp_path):
    app = make_app(tmp_path / "app", "XIC B3:0/0 OTE O:0/0\n", MODULES_LST="ENIPS\n",
                   ENIPS_XML='<EtherNetIpServer port="x">\n  <Writable address="B3:0/1"/>\n</EtherNetIpServer>\n')
    result = softplc_here("check", str(app))
    assert result.returncode != 0
    assert f"{app / 'ENIPS.XML'}:1:19: port='x'" in result.stderr
    assert f"{app / 'ENIPS.XML'}:2:13: address='B3:0/1'" in result.stderr
    assert "Traceback" not in result.stderr
    (app / "ENIPS.XML").write_text('<EtherNetIpServer status="N40:0"><Writable address="B3:0"/></EtherNetIpServer>\n')
    ok = softplc_here("check", str(app))
    assert ok.returncode == 0 and "module ENIPS" in ok.stdout
