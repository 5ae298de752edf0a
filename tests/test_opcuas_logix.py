"""A Studio 5000 export's tags over OPC UA: programs/logix/tank_line.L5X
copied into the test's directory with a tank_line.OPCUAS.XML beside it,
its server on a free port; asyncua's Client browses and reads the tags by
their paths, structures and arrays as objects, and is refused writes."""

from __future__ import annotations

import shutil

import pytest

from helpers.modbtcps_apps import Running
from helpers.opcua_apps import client_run, opcuas_xml
from helpers.shipped_apps import PROGRAMS

asyncua = pytest.importorskip("asyncua")
from asyncua import ua  # noqa: E402

NS = "urn:softplc-lite:opcuas"


@pytest.fixture
def line(tmp_path):
    export = tmp_path / "tank_line.L5X"
    shutil.copy(PROGRAMS / "logix" / "tank_line.L5X", export)
    (tmp_path / "tank_line.OPCUAS.XML").write_text(opcuas_xml(status=None).replace(' status="None"', ""))
    plc = Running(export, module="OPCUAS")
    yield plc
    plc.stop()


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
        try:
            await node("Tanks[1].Setpoint").write_value(ua.DataValue(ua.Variant(1.0, ua.VariantType.Float)))
            refused = None
        except ua.UaStatusCodeError as e:
            refused = type(e).__name__
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


def test_a_bad_configuration_beside_an_export_is_located(tmp_path):
    from softplc_lite.app import AppError, load_app

    export = tmp_path / "tank_line.L5X"
    shutil.copy(PROGRAMS / "logix" / "tank_line.L5X", export)
    (tmp_path / "tank_line.opcuas.xml").write_text('<OpcUaServer port="99999"/>\n')
    with pytest.raises(AppError) as info:
        load_app(export)
    assert f"{tmp_path / 'tank_line.opcuas.xml'}:1:14: port='99999'" in str(info.value)
