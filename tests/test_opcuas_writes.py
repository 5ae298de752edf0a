"""Writes by asyncua's Client to the variables a <Writable> opens: applied
by the scan at its input point and answered once applied, in RUN and in
PROGRAM mode; refused with OPC UA's status codes where the type, the range
or the node does not allow them, each refusal counted. The client writes
on an encrypted channel with a trusted certificate (helpers.opcua_apps
secure=True): an anonymous session may not write."""

from __future__ import annotations

import threading

import pytest

from helpers.modbtcps_apps import LIMIT_S
from helpers.opcua_apps import OpcUaApps, client_run, opcuas_xml

asyncua = pytest.importorskip("asyncua")
from asyncua import ua  # noqa: E402

NS = "urn:softplc-lite:opcuas"
WRITABLE = """  <Writable address="N7:0" count="2"/>
  <Writable address="F8:3"/>
  <Writable address="ST9:0"/>
  <Writable address="T4:0"/>
  <Writable address="B3:0"/>
  <Writable address="L12:0" count="2"/>
"""


# The writes that leave the engine running share one app (a server start costs seconds of CPU);
# each test writes its own elements and counts from what it found.
pytestmark = pytest.mark.xdist_group("opcuas_writes")


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    a = OpcUaApps(tmp_path_factory.mktemp("opcuas_writes"))
    yield a.start(xml(), secure=True)
    a.close()


@pytest.fixture
def apps(tmp_path):
    a = OpcUaApps(tmp_path)
    yield a
    a.close()


def xml() -> str:
    return opcuas_xml().replace("/>\n", f">\n{WRITABLE}</OpcUaServer>\n")


async def write(client, text, value, kind):
    ns = await client.get_namespace_index(NS)
    node = client.get_node(f"ns={ns};s={text}")
    try:
        await node.write_value(ua.DataValue(ua.Variant(value, kind)))
    except ua.UaStatusCodeError as e:
        return type(e).__name__
    return await node.read_value()  # the write answered once applied: the read sees it


def test_writes_land_through_the_scan_and_read_back(shared):
    r = shared
    applied_before = r.status(4)
    V = ua.VariantType

    async def work(client):
        return [await write(client, "N7:0", 555, V.Int16), await write(client, "F8:3", -1.5, V.Float),
                await write(client, "Note", "check seal", V.String), await write(client, "Dwell.PRE", 900, V.Int16),
                await write(client, "Run", True, V.Boolean), await write(client, "L12:1", -70000, V.Int32)]

    assert client_run(r.port, work, secure=True) == [555, -1.5, "check seal", 900, True, -70000]
    assert (r.read("N7:0"), r.read("F8:3"), r.read("ST9:0"), r.read("T4:0.PRE")) == (555, -1.5, "check seal", 900)
    assert r.read("L12:1") == -70000 and r.read("B3:0/4") == 1
    r.wait_for(lambda: r.read("O:0/1") == 1, "the ladder using the written bit")
    r.wait_for(lambda: r.status(4) - applied_before >= 6, "the writes applied counted in status word 4")


def test_writes_are_refused_by_type_range_and_region(shared):
    r = shared
    V = ua.VariantType
    refused_before, before = r.status(8), (r.read("N7:1"), r.read("ST9:0"))

    async def work(client):
        return [await write(client, "N7:1", 5, V.Int32), await write(client, "Note", "x" * 83, V.String),
                await write(client, "T4:0.ACC", -1, V.Int16), await write(client, "Count", 1, V.Int16),
                await write(client, "N7:2", 1, V.Int16), await write(client, "N7:9x", 1, V.Int16)]

    assert client_run(r.port, work, secure=True) == ["BadTypeMismatch", "BadOutOfRange", "BadOutOfRange",
                                                     "BadNotWritable", "BadNotWritable", "BadNodeIdUnknown"]
    assert (r.read("N7:1"), r.read("ST9:0")) == before
    r.wait_for(lambda: r.status(8) - refused_before == 6, "the refusals counted in status word 8")


def test_writes_land_in_program_mode(apps):
    from softplc_lite.ladder.engine import Mode

    r = apps.start(xml(), secure=True)
    r.runner.request_stop()
    r.thread.join(LIMIT_S)
    r.engine.set_mode(Mode.PROGRAM)
    stop = threading.Event()

    def scan() -> None:
        while not stop.is_set():
            r.engine.scan()

    t = threading.Thread(target=scan, daemon=True)
    t.start()
    try:
        async def work(client):
            return await write(client, "N7:1", 77, ua.VariantType.Int16)

        assert client_run(r.port, work, secure=True) == 77
        assert r.read("N7:1") == 77 and r.read("O:0/1") == 0  # outputs idle: no ladder ran
    finally:
        stop.set()
        t.join(LIMIT_S)


def test_a_write_to_a_forced_bit_follows_the_force(shared):
    """A write lands before the forces at the input point (docs/opcuas.md,
    Writes): a forced bit stays forced, and the client reads the forced value."""
    from softplc_lite.watch.forces import Forces, parse_force

    r = shared
    forces = Forces(r.engine)
    r.runner.between_scans.append(lambda runner: None)  # forces hook themselves into the scan
    forces.set(parse_force("B3/12=1"))
    try:
        r.wait_for(lambda: r.read("B3/12") == 1, "the force applied")

        async def work(client):
            return await write(client, "B3:0/12", False, ua.VariantType.Boolean)

        assert client_run(r.port, work, secure=True) is True
        assert r.read("B3/12") == 1
    finally:
        forces.clear()
