"""A Studio 5000 export's tags over OPC UA: programs/logix/tank_line.L5X
copied into the test's directory with a tank_line.OPCUAS.XML beside it,
its server on a free port (one for the module's tests); asyncua's Client
browses and reads the tags by their paths, structures and arrays as
objects, writes the tags a ``<Writable tag>`` opens on an encrypted session
with a trusted certificate, and is refused the others."""

from __future__ import annotations

import shutil

import pytest

from helpers.modbtcps_apps import Running
from helpers.opcua_apps import client_run, opcuas_xml, secure_app
from helpers.shipped_apps import PROGRAMS

asyncua = pytest.importorskip("asyncua")
from asyncua import ua  # noqa: E402

pytestmark = pytest.mark.xdist_group("opcuas_logix")  # one server for the module's tests

NS = "urn:softplc-lite:opcuas"
# A DINT tag, a REAL tag, a whole array element (Tanks[1]: its BOOL and REAL members), a UDT member, a
# BOOL member (Tanks[0].Fill, whose neighbour Drain shares its storage and stays closed), a
# whole structure (Batches: every member), a STRING; Tanks[0].Setpoint, SettleTimer.PRE and Running stay
# closed. The line stays stopped (Start is never pressed), so no rung writes what the tests write.
WRITABLE = ("Active", "FillRate", "Tanks[1]", "Tanks[0].Level", "Tanks[0].Fill", "Batches", "Banner")


def _config(tmp_path, body: str = "") -> str:
    root = opcuas_xml(status=None).replace(' status="None"', "").replace("/>\n", ">\n")
    return root + body + "</OpcUaServer>\n"


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("line")
    export = tmp_path / "tank_line.L5X"
    shutil.copy(PROGRAMS / "logix" / "tank_line.L5X", export)
    body = "".join(f'  <Writable tag="{t}"/>\n' for t in WRITABLE)
    (tmp_path / "tank_line.OPCUAS.XML").write_text(_config(tmp_path, body))
    secure_app(tmp_path)  # the server's certificate; the test client's trusted: its sessions may write
    plc = Running(export, module="OPCUAS")
    yield plc
    plc.stop()


def value(plc: Running, path: str):
    """A tag's value as the scan holds it, by its path."""
    return plc.engine.table.read(str(plc.engine.program.symbols.resolve_path(path)))


async def _write(client, text: str, v, kind) -> str:
    """The status code's name a write of ``v`` as ``kind`` to the tag ``text`` gets."""
    ns = await client.get_namespace_index(NS)
    try:
        await client.get_node(f"ns={ns};s={text}").write_value(ua.DataValue(ua.Variant(v, kind)))
        return "Good"
    except ua.UaStatusCodeError as e:
        return type(e).__name__


def test_tags_browse_and_read_by_their_paths(line):
    async def work(client):
        ns = await client.get_namespace_index(NS)
        node = lambda text: client.get_node(f"ns={ns};s={text}")  # noqa: E731
        names = [(await n.read_browse_name()).Name for n in await node("$APP").get_children()]
        tank = {(await n.read_browse_name()).Name for n in await node("Tanks[1]").get_children()}
        timer = {(await n.read_browse_name()).Name for n in await node("SettleTimer").get_children()}
        values = {t: await node(t).read_value() for t in ("Tanks[1].Setpoint", "Tanks[0].Setpoint", "SettleTimer.PRE",
                                                           "SettleTimer.DN", "Banner", "Tanks[0].Fill")}
        kinds = {t: (await node(t).read_data_type_as_variant_type()).name for t in values}
        refused = await _write(client, "Tanks[0].Setpoint", 1.0, ua.VariantType.Float)
        return names, tank, timer, values, kinds, refused

    names, tank, timer, values, kinds, refused = client_run(line.port, work)
    assert {"Tanks", "SettleTimer", "Banner", "PLC"} <= set(names) and "DataFiles" not in names
    assert any(n.startswith("Program:") for n in names)
    assert tank == {"Fill", "Drain", "Level", "Setpoint", "Fills"}
    assert timer == {"PRE", "ACC", "EN", "TT", "DN"}  # CTL is hidden, as in Logix
    assert values == {"Tanks[1].Setpoint": 80.0, "Tanks[0].Setpoint": 40.0, "SettleTimer.PRE": 2000,
                      "SettleTimer.DN": False, "Banner": "idle", "Tanks[0].Fill": values["Tanks[0].Fill"]}
    assert kinds == {"Tanks[1].Setpoint": "Float", "Tanks[0].Setpoint": "Float", "SettleTimer.PRE": "Int32",
                     "SettleTimer.DN": "Boolean", "Banner": "String", "Tanks[0].Fill": "Boolean"}
    assert refused == "BadNotWritable"


def test_writable_tags_are_written_through_the_scan(line):
    V = ua.VariantType
    writes = {"Active": (1, V.Int32), "FillRate": (2.5, V.Float), "Tanks[1].Fill": (True, V.Boolean),
              "Tanks[1].Level": (12.25, V.Float), "Tanks[0].Level": (3.5, V.Float), "Batches.PRE": (7, V.Int32),
              "Banner": ("filling", V.String)}
    shown = ("Active", "Tanks[1].Drain", "Batches.DN", "Tanks[1].Fills", "Tanks[0].Setpoint", "SettleTimer.PRE",
             "Tanks[0].Fill", "Tanks[0].Drain")

    async def work(client):
        ns = await client.get_namespace_index(NS)
        codes = {t: await _write(client, t, v, kind) for t, (v, kind) in writes.items()}
        back = {t: await client.get_node(f"ns={ns};s={t}").read_value() for t in writes}
        in_table = {t: value(line, t) for t in ("Active", "FillRate", "Tanks[1].Level", "Batches.PRE", "Banner")}
        access = {t: await client.get_node(f"ns={ns};s={t}").read_attribute(ua.AttributeIds.AccessLevel)
                  for t in shown}
        restored = await _write(client, "Banner", "idle", V.String)  # the browse test reads the export's text
        return codes, back, in_table, {t: bool(a.Value.Value & ua.AccessLevel.CurrentWrite.mask)
                                       for t, a in access.items()}, restored

    codes, back, in_table, access, restored = client_run(line.port, work, secure=True)
    assert codes == {t: "Good" for t in writes} and restored == "Good"
    assert back == {t: v for t, (v, _) in writes.items()}  # answered once applied: the read sees it
    assert in_table == {"Active": 1, "FillRate": 2.5, "Tanks[1].Level": 12.25, "Batches.PRE": 7, "Banner": "filling"}
    assert access == {"Active": True, "Tanks[1].Drain": True, "Batches.DN": True, "Tanks[1].Fills": False,
                      "Tanks[0].Setpoint": False, "SettleTimer.PRE": False, "Tanks[0].Fill": True,
                      "Tanks[0].Drain": False}
    assert value(line, "Banner") == "idle"


def test_tags_not_opened_and_bad_values_are_refused(line):
    V = ua.VariantType

    async def work(client):
        return {
            "closed": await _write(client, "Tanks[0].Setpoint", 1.0, V.Float),  # no <Writable> names it
            "timer": await _write(client, "SettleTimer.PRE", 5, V.Int32),
            "neighbour": await _write(client, "Tanks[0].Drain", True, V.Boolean),  # beside the opened Fill
            "read only": await _write(client, "Tanks[1].Fills", 5, V.Int32),  # inside Tanks[1]; the export's Read Only
            "long": await _write(client, "Banner", "x" * 83, V.String),  # a STRING holds 82 characters
            "type": await _write(client, "Active", 1.0, V.Float),  # a DINT written as a Float
        }

    codes = client_run(line.port, work, secure=True)
    assert codes == {"closed": "BadNotWritable", "timer": "BadNotWritable", "neighbour": "BadNotWritable",
                     "read only": "BadNotWritable",
                     "long": "BadOutOfRange", "type": "BadTypeMismatch"}
    assert (value(line, "Tanks[0].Setpoint"), value(line, "SettleTimer.PRE")) == (40.0, 2000)
    anonymous = client_run(line.port, lambda client: _write(client, "FillRate", 9.0, V.Float))
    assert anonymous == "BadUserAccessDenied"  # an anonymous session reads only


def test_a_bad_configuration_beside_an_export_is_located(tmp_path):
    from softplc_lite.app import AppError, load_app

    export = tmp_path / "tank_line.L5X"
    shutil.copy(PROGRAMS / "logix" / "tank_line.L5X", export)
    (tmp_path / "tank_line.opcuas.xml").write_text('<OpcUaServer port="99999"/>\n')
    with pytest.raises(AppError) as info:
        load_app(export)
    assert f"{tmp_path / 'tank_line.opcuas.xml'}:1:14: port='99999'" in str(info.value)


def test_an_address_beside_an_export_is_a_located_warning(tmp_path):
    """<Writable address> beside an export opens nothing a client sees: check says so, at the element."""
    from helpers.cli import softplc_here

    export = tmp_path / "tank_line.L5X"
    shutil.copy(PROGRAMS / "logix" / "tank_line.L5X", export)
    config = tmp_path / "tank_line.OPCUAS.XML"
    config.write_text(_config(tmp_path, '  <Writable address="N7:0"/>\n'))
    r = softplc_here("check", str(export))
    assert r.returncode == 0, r.stderr
    assert f"{config}:3:3: <Writable address=N7:0> opens nothing a client sees" in r.stderr
