"""OPCUAS against hostile clients while the ladder runs on the wall clock:
garbage bytes on the socket, a flood of sessions past maxSessions, a flood
of subscriptions past maxSubscriptions, a connection that never says a whole
message. Each refusal is answered as OPC UA says (garbage with an Error
message and the end of the connection, OPC 10000-6 7.1.5; the connection
refused; BadTooManySubscriptions; the silent connection closed) and each is
counted in its status word, exactly as often as the client did it (and a
client that only asks for the endpoints, nowhere); a good client
goes on reading all the while, and no scan is late: the server is a process
of its own and the scan never waits for it.

The clients run in another process (asyncua's Client in the test process
would hold the interpreter's lock the scan thread needs)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from helpers.opcua_apps import OpcUaApps, opcuas_xml

pytest.importorskip("asyncua")

from softplc_lite.tlm.opcuas import status as S  # noqa: E402

pytestmark = pytest.mark.timeout(180)
SESSIONS, SUBSCRIPTIONS = 4, 5
FLOOD_SESSIONS, FLOOD_SUBSCRIPTIONS = 12, 20

# One process: a good client reading Count in a loop from start to end, and beside it, in turn,
# garbage on fresh sockets, FLOOD_SESSIONS sessions opened and held, FLOOD_SUBSCRIPTIONS subscriptions
# asked of one session. Prints what each was answered, as JSON.
HOSTILE = r"""
import asyncio, json, logging, os, socket, struct, sys
from asyncua import Client, ua
for name in ("asyncua", "asyncua.client", "asyncua.common", "asyncua.uaprotocol"):
    logging.getLogger(name).setLevel(logging.CRITICAL)
port, sessions, subscriptions = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
url = f"opc.tcp://127.0.0.1:{port}/"
out = {"good_reads": 0, "good_values": [], "good_errors": [], "garbage": [], "sessions_ok": 0,
       "sessions_refused": 0, "subscriptions_ok": 0, "subscriptions_refused": 0, "other": [],
       "idle": None}

async def good(stop):
    async with Client(url, timeout=10) as c:
        ns = await c.get_namespace_index("urn:softplc-lite:opcuas")
        node = c.get_node(f"ns={ns};s=Count")
        while not stop.is_set():
            try:
                out["good_values"].append(await node.read_value())
                out["good_reads"] += 1
            except Exception as e:
                out["good_errors"].append(repr(e))
            await asyncio.sleep(0.01)

async def garbage():
    frames = [os.urandom(64), os.urandom(4096),
              b"XYZF" + struct.pack("<I", 16) + os.urandom(8),               # an unknown message type, whole
              b"HELX" + struct.pack("<I", 16) + os.urandom(8),               # an unknown chunk type
              b"HELF" + struct.pack("<I", 12) + b"\xff\xff\xff\xff",          # a Hello cut short
              b"MSGF" + struct.pack("<I", 32) + os.urandom(24),              # a message with no channel
              b"MSGF" + struct.pack("<I", 1 << 20) + os.urandom(24)]         # a chunk over the receive buffer
    for frame in frames:
        r, w = await asyncio.open_connection("127.0.0.1", port)
        w.write(frame)
        await w.drain()
        try:
            reply = await asyncio.wait_for(r.read(), 2.0)  # to the end: the server closes
            if reply[:4] == b"ERRF" and len(reply) >= 12:  # an Error message: its status code, then the end
                code = struct.unpack_from("<I", reply, 8)[0]
                out["garbage"].append("ERR " + ua.StatusCode(code).name)
            else:
                out["garbage"].append("closed" if not reply else "answered " + reply[:4].decode("latin-1"))
        except asyncio.TimeoutError:
            out["garbage"].append("held")
        except OSError:
            out["garbage"].append("reset")
        w.close()

async def idle():
    # a connection that says half a header and no more: closed by the server, idle
    r, w = await asyncio.open_connection("127.0.0.1", port)
    w.write(b"HEL")
    await w.drain()
    try:
        reply = await asyncio.wait_for(r.read(), 10.0)
        out["idle"] = "closed" if not reply else "answered"
    except (asyncio.TimeoutError, OSError) as e:
        out["idle"] = repr(e)
    w.close()

async def session_flood():
    held = []
    for _ in range(sessions):
        c = Client(url, timeout=1)
        try:
            await c.connect()
            held.append(c)
            out["sessions_ok"] += 1
        except (OSError, asyncio.TimeoutError, ua.UaError):
            out["sessions_refused"] += 1
    for c in held:
        await c.disconnect()

class Quiet:
    def datachange_notification(self, *a):
        pass

async def subscription_flood():
    async with Client(url, timeout=10) as c:
        subs = []
        for _ in range(subscriptions):
            try:
                subs.append(await c.create_subscription(100, Quiet()))
                out["subscriptions_ok"] += 1
            except ua.uaerrors.BadTooManySubscriptions:
                out["subscriptions_refused"] += 1
            except Exception as e:
                out["other"].append(repr(e))
        for s in subs:
            await s.delete()

async def main():
    stop = asyncio.Event()
    reader = asyncio.create_task(good(stop))
    await asyncio.sleep(0.5)
    await garbage()
    out["endpoints"] = len(await Client(url, timeout=10).connect_and_get_server_endpoints())  # discovery: no refusal
    await session_flood()
    idler = asyncio.create_task(idle())  # beside the subscription flood: a slot of maxSessions each
    await subscription_flood()
    await idler
    await asyncio.sleep(0.5)
    stop.set()
    await reader
asyncio.run(main())
print(json.dumps(out))
"""


@pytest.fixture
def apps(tmp_path):
    a = OpcUaApps(tmp_path)
    yield a
    a.close()


@pytest.mark.alone  # counts late real-time scans (docs/testing.md)
def test_garbage_and_floods_are_refused_and_a_good_client_is_served_with_no_late_scan(apps):
    # the good client holds one session of maxSessions, the subscription flood another
    xml = opcuas_xml(maxSessions=SESSIONS, maxSubscriptions=SUBSCRIPTIONS, idleTimeout=1000)  # idle closed in 1 s
    r = apps.start(xml, ladder="SYMBOL Count N7:5\nADD N7:5 1 N7:5\nMOV N7:5 N7:6\n", scan_ms=10)
    r.wait_for(lambda: r.engine.scans > 20, "scans running")
    late_before = r.runner.late_scans
    words = (S.W_REFUSED_LIMIT, S.W_MALFORMED, S.W_IDLE, S.W_REFUSED_SUBSCRIPTIONS, S.W_REFUSALS)
    before = {w: r.status(w) for w in words}
    run = subprocess.run([sys.executable, "-c", HOSTILE, str(r.port), str(FLOOD_SESSIONS), str(FLOOD_SUBSCRIPTIONS)],
                         capture_output=True, text=True, timeout=150, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout)
    late = r.runner.late_scans - late_before
    print(f"late scans {late}, max lateness {r.runner.max_lateness_ms:.1f} ms; garbage: {out['garbage']}; "
          f"sessions {out['sessions_ok']} ok {out['sessions_refused']} refused; subscriptions "
          f"{out['subscriptions_ok']} ok {out['subscriptions_refused']} refused; good reads {out['good_reads']}")
    assert out["other"] == [] and out["good_errors"] == []
    # the good client's session is one of SESSIONS: the flood gets the rest, and no more
    assert out["sessions_ok"] == SESSIONS - 1 and out["sessions_refused"] == FLOOD_SESSIONS - SESSIONS + 1
    assert out["subscriptions_ok"] == SUBSCRIPTIONS
    assert out["subscriptions_refused"] == FLOOD_SUBSCRIPTIONS - SUBSCRIPTIONS
    # garbage is never answered as if it were a request: an Error message, then the end of the connection
    assert out["garbage"] == ["ERR BadTcpMessageTypeInvalid"] * 4 + [
        "ERR BadDecodingError", "ERR BadTcpSecureChannelUnknown", "ERR BadTcpMessageTooLarge"], out["garbage"]
    assert out["idle"] == "closed" and out["endpoints"] >= 1, out
    expected = {S.W_REFUSED_LIMIT: out["sessions_refused"], S.W_MALFORMED: len(out["garbage"]), S.W_IDLE: 1,
                S.W_REFUSED_SUBSCRIPTIONS: out["subscriptions_refused"]}
    expected[S.W_REFUSALS] = sum(expected.values())
    r.wait_for(lambda: {w: r.status(w) - before[w] for w in words} == expected,
               f"each refusal counted in its status word: {expected}")
    values = out["good_values"]
    assert out["good_reads"] >= 20 and values == sorted(values) and values[-1] > values[0], values[-5:]
    assert late == 0, f"{late} late scans under hostile clients"
    assert r.engine.fault is None
