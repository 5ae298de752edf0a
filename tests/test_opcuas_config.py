"""OPCUAS.XML checked: defaults, every problem at once with file, line and
column, and `softplc check` meeting it through MODULES.LST."""

from __future__ import annotations

import pytest

from softplc_lite.tlm.errors import ModuleError, ModuleErrors
from softplc_lite.tlm.opcuas.config import load_config, parse_config

from helpers.apps import make_app
from helpers.cli import softplc_here


def test_an_empty_root_takes_the_defaults():
    c = parse_config(b"<OpcUaServer/>")
    assert (c.host, c.port, c.symbols, c.data_files, c.tags) == ("127.0.0.1", 4840, True, True, True)
    assert (c.max_sessions, c.max_subscriptions, c.max_monitored_items, c.status) == (10, 100, 10_000, None)
    assert c.idle_timeout_ms == 5_000
    assert (c.allow_none, c.allow_sign, c.anonymous, c.trusted_clients_only) == (False, False, True, False)
    assert c.warnings == []


def test_the_security_attributes_are_read_and_checked():
    c = parse_config(b'<OpcUaServer securityNone="yes" securitySign="yes" anonymous="no" trustedClientsOnly="yes"/>')
    assert (c.allow_none, c.allow_sign, c.anonymous, c.trusted_clients_only) == (True, True, False, True)
    with pytest.raises(ModuleErrors) as info:
        parse_config(b'<OpcUaServer\n  securityNone="true" anonymous="read"/>', "OPCUAS.XML")
    text = [str(p) for p in info.value.problems]
    assert [t[:28] for t in text] == ["OPCUAS.XML:2:3: securityNone", "OPCUAS.XML:2:23: anonymous='"], text
    wide = parse_config(b'<OpcUaServer address="0.0.0.0" securityNone="yes"/>', "X.XML")
    assert len(wide.warnings) == 2 and "connect unencrypted" in wide.warnings[1]


def test_every_attribute_is_read():
    c = parse_config(b'<OpcUaServer address="::1" port="4841" symbols="no" dataFiles="yes" tags="no" '
                     b'maxSessions="2" maxSubscriptions="3" maxMonitoredItems="4" status="N40:0" debug="1" '
                     b'idleTimeout="1500"/>')
    assert (c.host, c.port, c.symbols, c.data_files, c.tags) == ("::1", 4841, False, True, False)
    assert (c.max_sessions, c.max_subscriptions, c.max_monitored_items, str(c.status), c.debug) == \
        (2, 3, 4, "N40:0", 1)
    assert c.idle_timeout_ms == 1500


def test_every_problem_is_located_at_once():
    with pytest.raises(ModuleErrors) as info:
        parse_config(b'<OpcUaServer port="0" maxSessions="x"\n  status="F8:0" colour="red">\n'
                     b'  <Writable address="N7:0/1"/>\n  <Writable address="N40:2"/>\n</OpcUaServer>', "OPCUAS.XML")
    text = [str(p) for p in info.value.problems]
    assert any(t.startswith("OPCUAS.XML:1:14: port='0'") for t in text), text
    assert any(t.startswith("OPCUAS.XML:1:23: maxSessions='x'") for t in text), text
    assert any(t.startswith("OPCUAS.XML:2:3: status='F8:0'") for t in text), text
    assert any("OPCUAS.XML:2:17: <OpcUaServer> has no attribute 'colour'" in t for t in text), text
    assert any(t.startswith("OPCUAS.XML:3:13: address='N7:0/1': expected a whole element") for t in text), text
    assert any(t.startswith("OPCUAS.XML:2:3: status='F8:0'") for t in text), text


def test_writable_regions_are_read_and_kept_off_the_status_words():
    c = parse_config(b'<OpcUaServer status="N40:0">\n  <Writable address="N7:0" count="3"/>\n'
                     b'  <Writable address="T4:1"/>\n</OpcUaServer>')
    assert [(str(w.address), w.count, w.line) for w in c.writable] == [("N7:0", 3, 2), ("T4:1", 1, 3)]
    with pytest.raises(ModuleErrors) as info:
        parse_config(b'<OpcUaServer status="N40:0">\n  <Writable address="N40:10" count="10"/>\n</OpcUaServer>',
                     "OPCUAS.XML")
    assert str(info.value.problems[0]).startswith("OPCUAS.XML:2:13: <Writable> N40:10..N40:19 covers the status words")


def test_exposing_nothing_is_refused_and_listening_wide_is_warned():
    with pytest.raises(ModuleErrors) as info:
        parse_config(b'<OpcUaServer symbols="no" dataFiles="no" tags="no"/>')
    assert "expose nothing" in str(info.value.problems[0])
    c = parse_config(b'<OpcUaServer address="0.0.0.0"/>', "X.XML")
    assert len(c.warnings) == 1 and c.warnings[0].startswith("X.XML:1: listening on 0.0.0.0")


def test_a_missing_file_says_what_it_holds(tmp_path):
    with pytest.raises(ModuleError) as info:
        load_config(tmp_path)
    assert "OPCUAS.XML" in str(info.value) and "docs/opcuas.md" in str(info.value)


def test_softplc_check_reports_the_file_located(tmp_path):
    app = make_app(tmp_path / "app", "XIC B3:0/0 OTE O:0/0\n", MODULES_LST="OPCUAS\n",
                   OPCUAS_XML='<OpcUaServer port="x"\n  maxMonitoredItems="0"/>\n')
    result = softplc_here("check", str(app))
    assert result.returncode != 0
    assert f"{app / 'OPCUAS.XML'}:1:14: port='x'" in result.stderr
    assert f"{app / 'OPCUAS.XML'}:2:3: maxMonitoredItems='0'" in result.stderr
    assert "Traceback" not in result.stderr
    (app / "OPCUAS.XML").write_text('<OpcUaServer status="N40:0"/>\n')
    bare = softplc_here("check", str(app))  # secure by default: no certificate, no endpoint
    assert bare.returncode != 0 and "Traceback" not in bare.stderr
    assert f"{app / 'OPCUAS.XML'}:1:1: no server certificate" in bare.stderr and "opcua-cert" in bare.stderr
    (app / "OPCUAS.XML").write_text('<OpcUaServer status="N40:0" securityNone="yes"/>\n')
    ok = softplc_here("check", str(app))
    assert ok.returncode == 0 and "module OPCUAS" in ok.stdout


def test_writable_tags_are_read_and_their_form_checked():
    c = parse_config(b'<OpcUaServer>\n  <Writable tag="Tanks[1].Level"/>\n  <Writable address="N7:0"/>\n</OpcUaServer>')
    assert [(w.tag, str(w.address), w.line) for w in c.writable] == [("Tanks[1].Level", "None", 2), (None, "N7:0", 3)]
    with pytest.raises(ModuleErrors) as info:
        parse_config(b'<OpcUaServer>\n  <Writable tag="Tanks" count="2"/>\n  <Writable tag="A" address="N7:0"/>\n'
                     b'  <Writable/>\n</OpcUaServer>', "OPCUAS.XML")
    text = [str(p) for p in info.value.problems]
    assert text[0].startswith("OPCUAS.XML:2:25: <Writable tag=...> takes no count"), text
    assert text[1].startswith("OPCUAS.XML:3:3: <Writable> needs the attribute address") and "one of them" in text[1]
    assert text[2].startswith("OPCUAS.XML:4:3: <Writable> needs the attribute address"), text


def test_softplc_check_locates_every_tag_the_export_does_not_open(tmp_path):
    from helpers.shipped_apps import PROGRAMS

    export = tmp_path / "tank_line.L5X"
    export.write_bytes((PROGRAMS / "logix" / "tank_line.L5X").read_bytes())
    config = tmp_path / "tank_line.OPCUAS.XML"
    config.write_text('<OpcUaServer securityNone="yes">\n  <Writable tag="Running"/>\n'
                      '  <Writable tag="Tanks[0].Fills"/>\n  <Writable tag="Nowhere"/>\n  <Writable tag="Tanks[5]"/>\n'
                      '  <Writable tag="Tanks[1]"/>\n</OpcUaServer>\n')
    result = softplc_here("check", str(export))
    assert result.returncode != 0 and "Traceback" not in result.stderr
    assert f"{config}:2:3: <Writable tag='Running'>: the export makes it Read Only" in result.stderr
    assert f"{config}:3:3: <Writable tag='Tanks[0].Fills'>: the export makes it Read Only" in result.stderr
    assert f"{config}:4:3: <Writable tag='Nowhere'>: no tag named 'Nowhere'" in result.stderr
    assert f"{config}:5:3: <Writable tag='Tanks[5]'>: Tanks: index 5 is past its end (2)" in result.stderr
    assert ":6:3:" not in result.stderr and "4 problems found" in result.stderr


def test_a_tag_in_an_app_directory_is_located(tmp_path):
    app = make_app(tmp_path / "app", "XIC B3:0/0 OTE O:0/0\n", MODULES_LST="OPCUAS\n",
                   OPCUAS_XML='<OpcUaServer securityNone="yes">\n  <Writable tag="Tanks"/>\n</OpcUaServer>\n')
    result = softplc_here("check", str(app))
    assert result.returncode != 0 and "Traceback" not in result.stderr
    assert f"{app / 'OPCUAS.XML'}:2:3: <Writable tag='Tanks'>: tag= names a tag of a Studio 5000 export's app" \
        in result.stderr
