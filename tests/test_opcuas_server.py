"""OPCUAS served to asyncua's Client over real sockets: the address space
browsed, every kind of variable read, the PLC's mode, fault code and scan
time, refused writes with their status codes, subscriptions that see every
change of a counter the ladder increments, one notification a scan."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

from helpers.modbtcps_apps import LIMIT_S
from helpers.opcua_apps import LADDER, OpcUaApps, client_run

asyncua = pytest.importorskip("asyncua")
from asyncua import ua  # noqa: E402

NS = "urn:softplc-lite:opcuas"


# The checks that only read share one running app: a server start costs seconds of CPU (asyncua
# builds its standard address space), and the suite has a budget. Its ladder is the helpers' LADDER
# with two commented rungs on N7:20..22, scanned every 100 ms of the wall clock (the subscription
# test sees every count). Tests that stop or change the engine start their own.
pytestmark = pytest.mark.xdist_group("opcuas_server")
SHARED_LADDER = LADDER + "SYMBOL Checks N7:20\n// Counts the checks.\nADD Checks 1 Checks\nMOV N7:20 N7:21\n" \
                         "// Copies the check.\nMOV N7:20 N7:22\n"


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    a = OpcUaApps(tmp_path_factory.mktemp("opcuas_server"))
    yield a.start(ladder=SHARED_LADDER, scan_ms=100)
    a.close()


@pytest.fixture
def apps(tmp_path):
    a = OpcUaApps(tmp_path)
    yield a
    a.close()


async def _node(client, text):
    ns = await client.get_namespace_index(NS)
    return client.get_node(f"ns={ns};s={text}")


def test_every_kind_of_variable_reads_as_its_opc_ua_type(shared):
    r = shared
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


def test_writes_are_refused_with_their_status_codes(shared):
    r = shared
    refused_before = r.status(8)

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
    r.wait_for(lambda: r.status(8) - refused_before == 4, "the refusals counted in status word 8")


def test_the_address_space_browses_from_the_app_down_to_bits_with_descriptions(shared):
    r = shared

    async def work(client):
        ns = await client.get_namespace_index(NS)
        names = lambda nodes: asyncio.gather(*(n.read_browse_name() for n in nodes))  # noqa: E731
        top = [q.Name for q in await names(await client.nodes.objects.get_children())]
        app = client.get_node(f"ns={ns};s=$APP")
        under_app = {q.Name for q in await names(await app.get_children())}
        files = {q.Name for q in await names(await client.get_node(f"ns={ns};s=$DataFiles").get_children())}
        n7 = [q.Name for q in await names(await client.get_node(f"ns={ns};s=N7").get_children())]
        bits = [q.Name for q in await names(await client.get_node(f"ns={ns};s=B3:0").get_children())]
        timer = {q.Name for q in await names(await client.get_node(f"ns={ns};s=T4:0").get_children())}
        described = [(await client.get_node(f"ns={ns};s={t}").read_description()).Text for t in ("Count", "N7:5")]
        return top, (await app.read_browse_name()).Name, under_app, files, n7, bits, timer, described

    top, app_name, under_app, files, n7, bits, timer, described = client_run(r.port, work)
    assert app_name == r.app_dir.name and r.app_dir.name in top
    assert {"DataFiles", "PLC", "Count", "Speed", "Note", "Run", "Dwell", "Total"} <= under_app
    assert {"O0", "I1", "S2", "B3", "T4", "N7", "F8", "ST9", "L12", "N40"} <= files
    assert n7[:6] == ["N7:0", "N7:1", "N7:2", "N7:3", "N7:4", "N7:5"]
    assert bits == [str(b) for b in range(16)]
    assert timer == {"PRE", "ACC", "EN", "TT", "DN"}
    assert described == ["N7:5", "Symbol Count"]


def test_rung_comments_describe_the_elements_their_rungs_name(shared):
    async def work(client):
        return [(await (await _node(client, t)).read_description()).Text for t in ("Checks", "N7:20", "N7:21", "N7:22")]

    assert client_run(shared.port, work) == ["N7:20: Counts the checks.", "Symbol Checks: Counts the checks.", "",
                                             "Copies the check."]


def test_a_subscription_gets_every_change_of_a_counter_once_a_scan(shared):
    # the counter adds 1 each 100 ms scan of the wall clock; the values notified must run on by
    # one each, none twice, none missed; a word the ladder never changes is notified once
    r = shared

    class Handler:
        def __init__(self):
            self.seen: dict[str, list] = {"Count": [], "N7:0": []}

        def datachange_notification(self, node, value, data):
            self.seen[node.nodeid.Identifier].append(value)

    async def work(client):
        handler = Handler()
        sub = await client.create_subscription(20, handler)
        await sub.subscribe_data_change([await _node(client, "Count"), await _node(client, "N7:0")], queuesize=100)
        for _ in range(600):
            if len(handler.seen["Count"]) >= 12:
                break
            await asyncio.sleep(0.05)
        await sub.delete()
        return handler.seen

    seen = client_run(r.port, work)
    counts = seen["Count"]
    assert len(counts) >= 12
    assert counts == list(range(counts[0], counts[0] + len(counts))), counts
    assert seen["N7:0"] == [0]


def test_an_item_is_sampled_at_its_sampling_interval(shared):
    # Count and Checks both add 1 each 100 ms scan. Count sampled every 500 ms is notified at most
    # once each 500 ms, with the value then (steps of about five); Checks sampled at 0 (the
    # fastest: every scan) gets every change. OPC 10000-4 5.12.1.2.
    class Handler:
        def __init__(self):
            self.seen: dict[str, list] = {"Count": [], "N7:20": []}

        def datachange_notification(self, node, value, data):
            self.seen[node.nodeid.Identifier].append(value)

    async def work(client):
        handler = Handler()
        sub = await client.create_subscription(50, handler)
        count = await sub.subscribe_data_change(await _node(client, "Count"), queuesize=100, sampling_interval=0.0)
        await sub.subscribe_data_change(await _node(client, "N7:20"), queuesize=100, sampling_interval=0.0)
        revised = (await sub.modify_monitored_item(count, 500.0, 100))[0].RevisedSamplingInterval
        handler.seen["Count"].clear()
        await asyncio.sleep(2.6)
        await sub.delete()
        return revised, handler.seen

    revised, seen = client_run(shared.port, work)
    assert revised == 500.0
    checks, counts = seen["N7:20"], seen["Count"]
    assert len(checks) >= 15 and checks == list(range(checks[0], checks[0] + len(checks))), checks
    steps = [b - a for a, b in zip(counts[1:], counts[2:])]  # the first after the change: any time
    assert 3 <= len(counts) <= 8 and steps and min(steps) >= 3, counts


def test_the_mode_variable_follows_the_engine(apps):
    from softplc_lite.ladder.engine import Mode

    r = apps.start()
    r.runner.request_stop()
    r.thread.join(LIMIT_S)
    stop = threading.Event()

    def scan() -> None:
        while not stop.is_set():
            r.engine.scan()
            time.sleep(0.005)

    async def work(client, mode):
        node = await _node(client, "$PLC.Mode")
        for _ in range(200):
            if await node.read_value() == mode:
                break
            await asyncio.sleep(0.02)
        return await node.read_value(), await (await _node(client, "$PLC.FaultCode")).read_value()

    seen = []
    for mode in ("PROGRAM", "TEST"):
        r.engine.set_mode(Mode.PROGRAM)
        r.engine.set_mode(Mode[mode])
        stop.clear()
        t = threading.Thread(target=scan, daemon=True)
        t.start()
        try:
            seen.append(client_run(r.port, lambda client: work(client, mode)))
        finally:
            stop.set()
            t.join(LIMIT_S)
    assert seen == [("PROGRAM", 0), ("TEST", 0)]
