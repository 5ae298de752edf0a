"""The baseline server and the clients of bench_opcuas.py.

    python benchmarks/opcuas_load.py serve VARIABLES CHANGING PERIOD_MS

``serve``: asyncua's own plain Server (no softplc in it), VARIABLES Int16
variables ``V0``.. under one object, with no security (as the bench's
OPCUAS endpoint), the first CHANGING of them given a new value every
PERIOD_MS, as a scan would; prints "ready PORT PID" and serves until its
standard input closes.

The clients (``reads``, ``notifications``, ``hold_items``) are coroutines
bench_opcuas.py runs in its own process against either server: asyncua's
Client reading the same COUNT variables in a loop, or subscribed to them.
"""

from __future__ import annotations

import asyncio
import logging
import os
import sys
import time

from modbus_server_load import cpu_seconds

NS = "urn:softplc-lite:bench-baseline"


def quiet_asyncua() -> None:
    for name in ("asyncua", "asyncua.client", "asyncua.server", "asyncua.uaprotocol", "asyncua.common"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


async def serve(variables: int, changing: int, period_ms: int) -> None:
    from asyncua import Server, ua

    quiet_asyncua()
    server = Server()
    await server.init()
    server.set_endpoint("opc.tcp://127.0.0.1:0/")
    server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
    iserver = server.iserver
    iserver.max_connections = 80
    iserver.max_subscriptions = 1000
    ns = await server.register_namespace(NS)
    attrs = ua.VariableAttributes(Value=ua.Variant(0, ua.VariantType.Int16), DataType=ua.NodeId(ua.ObjectIds.Int16),
                                  ValueRank=-1, AccessLevel=ua.AccessLevel.CurrentRead.mask,
                                  UserAccessLevel=ua.AccessLevel.CurrentRead.mask)
    items = [ua.AddNodesItem(RequestedNewNodeId=ua.NodeId("Bench", ns), BrowseName=ua.QualifiedName("Bench", ns),
                             NodeClass=ua.NodeClass.Object, ParentNodeId=ua.NodeId(ua.ObjectIds.ObjectsFolder),
                             ReferenceTypeId=ua.NodeId(ua.ObjectIds.Organizes),
                             TypeDefinition=ua.NodeId(ua.ObjectIds.BaseObjectType),
                             NodeAttributes=ua.ObjectAttributes(DisplayName=ua.LocalizedText("Bench")))]
    items += [ua.AddNodesItem(RequestedNewNodeId=ua.NodeId(f"V{k}", ns), BrowseName=ua.QualifiedName(f"V{k}", ns),
                              NodeClass=ua.NodeClass.Variable, ParentNodeId=ua.NodeId("Bench", ns),
                              ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasComponent),
                              TypeDefinition=ua.NodeId(ua.ObjectIds.BaseDataVariableType), NodeAttributes=attrs)
              for k in range(variables)]
    iserver.node_mgt_service.add_nodes(items)
    nodes = [ua.NodeId(f"V{k}", ns) for k in range(changing)]
    await server.start()
    port = server.bserver._server.sockets[0].getsockname()[1]
    print(f"ready {port} {os.getpid()}", flush=True)
    loop = asyncio.get_running_loop()
    stdin_closed = loop.create_future()
    loop.add_reader(0, lambda: stdin_closed.done() or (os.read(0, 4096) or stdin_closed.set_result(None)))
    value, period = 0, period_ms / 1000
    next_at = time.monotonic()
    aspace, value_id = iserver.aspace, ua.AttributeIds.Value
    from datetime import datetime, timezone
    while not stdin_closed.done():
        value = (value + 1) % 30000
        now = datetime.now(timezone.utc)
        for k, node in enumerate(nodes):  # what OPCUAS does with a scan's changed values
            dv = ua.DataValue(ua.Variant((value + k) % 30000, ua.VariantType.Int16), SourceTimestamp=now,
                              ServerTimestamp=now)
            await aspace.write_attribute_value(node, value_id, dv)
        next_at += period
        await asyncio.sleep(max(0.0, next_at - time.monotonic()))
    await server.stop()


# -- the clients (run in bench_opcuas.py's process) ------------------------------------------------


async def connect(port: int):
    from asyncua import Client

    client = Client(f"opc.tcp://127.0.0.1:{port}/", timeout=30)
    await client.connect()
    return client


async def reads(port: int, pid: int, node_ids: list[str], clients: int, window_s: float) -> dict:
    """``clients`` clients each reading all of ``node_ids`` in one Read, in a
    loop for the window: reads done (values checked), the server's CPU time."""
    cs = [await connect(port) for _ in range(clients)]
    done = [0]
    bad: list[str] = []
    try:
        nodes = [[c.get_node(n) for n in node_ids] for c in cs]
        for c, ns in zip(cs, nodes):
            await c.read_values(ns)  # warm up

        async def one(c, ns, end):
            while time.monotonic() < end:
                values = await c.read_values(ns)
                if len(values) != len(ns) or not all(isinstance(v, int) for v in values):
                    bad.append(repr(values[:3]))
                done[0] += 1

        cpu0, start = cpu_seconds(pid), time.monotonic()
        await asyncio.gather(*(one(c, ns, start + window_s) for c, ns in zip(cs, nodes)))
        end, cpu1 = time.monotonic(), cpu_seconds(pid)
        return {"done": done[0], "errors": len(bad), "first_error": bad[0] if bad else None, "start": start,
                "end": end, "server_cpu_s": cpu1 - cpu0}
    finally:
        for c in cs:
            await c.disconnect()


class Counter:
    def __init__(self) -> None:
        self.n = 0
        self.counting = False

    def datachange_notification(self, node, value, data) -> None:
        if self.counting:
            self.n += 1


async def notifications(port: int, pid: int, node_ids: list[str], window_s: float, interval_ms: float) -> dict:
    """One client subscribed to ``node_ids`` (publishing every interval_ms):
    the data changes it is sent in the window, and the server's CPU time."""
    c = await connect(port)
    try:
        counter = Counter()
        sub = await c.create_subscription(interval_ms, counter)
        # sampling 0, the fastest: every change (asyncua's client asks 50 ms unless told, which OPCUAS
        # honours and asyncua's own server does not)
        await sub.subscribe_data_change([c.get_node(n) for n in node_ids], queuesize=10, sampling_interval=0.0)
        await asyncio.sleep(1.0)  # the first values, then the steady flow
        cpu0, start = cpu_seconds(pid), time.monotonic()
        counter.counting = True
        await asyncio.sleep(window_s)
        counter.counting = False
        end, cpu1 = time.monotonic(), cpu_seconds(pid)
        await sub.delete()
        return {"done": counter.n, "errors": 0, "first_error": None, "start": start, "end": end,
                "server_cpu_s": cpu1 - cpu0}
    finally:
        await c.disconnect()


def rss_kib(pid: int) -> int:
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))


async def item_memory(port: int, pid: int, node_ids: list[str], settle_s: float) -> dict:
    """The server process's resident memory with one subscription of no item,
    then of len(node_ids) monitored items: KiB, and bytes an item."""
    c = await connect(port)
    try:
        sub = await c.create_subscription(100, Counter())
        await asyncio.sleep(settle_s)
        before = rss_kib(pid)
        handles = await sub.subscribe_data_change([c.get_node(n) for n in node_ids], queuesize=1)
        await asyncio.sleep(settle_s)
        after = rss_kib(pid)
        refused = sum(1 for h in handles if not isinstance(h, int))
        await sub.delete()
        return {"items": len(node_ids), "refused": refused, "rss_kib_0": before, "rss_kib_items": after,
                "bytes_per_item": 1024 * (after - before) / len(node_ids)}
    finally:
        await c.disconnect()


def main() -> int:
    if sys.argv[1] != "serve":
        print(__doc__)
        return 2
    asyncio.run(serve(int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
