"""OPCUAS served to asyncua's Client over real sockets: the address space
browsed, every kind of variable read, the PLC's mode, fault code and scan
time, refused writes with their status codes, subscriptions that see every
change of a counter the ladder increments, one notification a scan."""

from __future__ import annotations

import asyncio

import pytest

from helpers.opcua_apps import OpcUaApps, client_run, register

asyncua = pytest.importorskip("asyncua")
from asyncua import ua  # noqa: E402

NS = "urn:softplc-lite:opcuas"


@pytest.fixture
def apps(tmp_path, monkeypatch):
    register(tmp_path, monkeypatch)
    a = OpcUaApps(tmp_path)
    yield a
    a.close()


async def _node(client, text):
    ns = await client.get_namespace_index(NS)
    return client.get_node(f"ns={ns};s={text}")


def test_every_kind_of_variable_reads_as_its_opc_ua_type(apps):
    r = apps.start()
    r.wait_for(lambda: r.read("N7:5") > 3, "a few scans")

    async def work(client):
        out = {}
        for text in ("Count", "Speed", "Note", "Run", "Total", "Dwell.PRE", "Dwell.DN", "N7:5", "F8:1",
                     "T4:0.PRE", "T4:0/EN", "B3:0/4", "O:0/1", "L12:0", "$PLC.Mode", "$PLC.FaultCode",
                     "$PLC.ScanTime"):
            node = await _node(client, text)
            out[text] = (await node.read_value(), await node.read_data_type_as_variant_type())
        return out

    got = client_run(r.port, work)
    assert got["Count"][1] == ua.VariantType.Int16 and got["Count"][0] >= 3
    assert got["Speed"] == (2.5, ua.VariantType.Float)
    assert got["Note"] == ("", ua.VariantType.String)
    assert got["Run"] == (False, ua.VariantType.Boolean)
    assert got["Total"] == (70000, ua.VariantType.Int32)
    assert got["Dwell.PRE"] == (500, ua.VariantType.Int16) == got["T4:0.PRE"]
    assert got["Dwell.DN"][1] == ua.VariantType.Boolean
    assert got["$PLC.Mode"] == ("RUN", ua.VariantType.String)
    assert got["$PLC.FaultCode"] == (0, ua.VariantType.Int16)
    assert got["$PLC.ScanTime"][1] == ua.VariantType.Int16


def test_writes_are_refused_with_their_status_codes(apps):
    r = apps.start()

    async def work(client):
        codes = {}
        for text in ("Count", "N7:5", "$PLC.Mode", "N7:9999x"):
            node = await _node(client, text)
            try:
                await node.write_value(ua.DataValue(ua.Variant(1, ua.VariantType.Int16)))
                codes[text] = "written"
            except ua.UaStatusCodeError as e:
                codes[text] = type(e).__name__
        return codes

    codes = client_run(r.port, work)
    assert codes == {"Count": "BadNotWritable", "N7:5": "BadNotWritable", "$PLC.Mode": "BadNotWritable",
                     "N7:9999x": "BadNodeIdUnknown"}
    r.wait_for(lambda: r.status(8) == 4, "the refusals counted in status word 8")
