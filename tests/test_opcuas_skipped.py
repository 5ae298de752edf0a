"""Scans a server that falls behind never gives its clients are counted in
status word 15 (scans skipped), and what it gives after is the newest scan,
not the ones it missed. The server process is paused (SIGSTOP) while the
ladder scans on, then resumed: the pause makes it fall behind by a number
of scans the test counts, whatever the machine's load."""

from __future__ import annotations

import asyncio
import os
import signal

import pytest

from helpers.opcua_apps import OpcUaApps, client_run

pytest.importorskip("asyncua")

from softplc_lite.tlm.opcuas import status as S  # noqa: E402
from softplc_lite.watch.serversview import refusals_text  # noqa: E402

NS = "urn:softplc-lite:opcuas"
PAUSED_SCANS = 10


@pytest.fixture
def apps(tmp_path):
    a = OpcUaApps(tmp_path)
    yield a
    a.close()


@pytest.mark.skipif(not hasattr(signal, "SIGSTOP"), reason="pauses a process with SIGSTOP")
def test_scans_a_paused_server_missed_are_counted_skipped_and_the_newest_follows(apps):
    # Count adds 1 a scan: a subscriber sampling every scan sees each value unless a scan is skipped
    r = apps.start(ladder="SYMBOL Count N7:5\nADD N7:5 1 N7:5\n", scan_ms=10)
    pid = r.module.server.process.pid

    def pause_for_scans() -> int:
        """The server paused while the ladder scans PAUSED_SCANS times; the count then."""
        os.kill(pid, signal.SIGSTOP)
        try:
            scans = r.engine.scans
            r.wait_for(lambda: r.engine.scans >= scans + PAUSED_SCANS, "the ladder scanning on")
            return r.read("N7:5")
        finally:
            os.kill(pid, signal.SIGCONT)

    # no subscription: a Read takes the newest scan, nothing is missed, nothing counted
    skipped_before = r.status(S.W_SKIPPED_SCANS)
    pause_for_scans()
    client_run(r.port, lambda client: asyncio.sleep(0.05))  # the server has taken the newest scan again
    scans = r.engine.scans
    r.wait_for(lambda: r.engine.scans >= scans + 3, "the counts copied to the status words")
    assert r.status(S.W_SKIPPED_SCANS) == skipped_before

    class Handler:
        def __init__(self):
            self.values: list[int] = []

        def datachange_notification(self, node, value, data):
            self.values.append(value)

    async def work(client):
        ns = await client.get_namespace_index(NS)
        handler = Handler()
        sub = await client.create_subscription(20, handler)
        await sub.subscribe_data_change(client.get_node(f"ns={ns};s=Count"), queuesize=1000, sampling_interval=0)
        while len(handler.values) < 5:
            await asyncio.sleep(0.02)
        seen = len(handler.values)
        before_resume = pause_for_scans()  # the newest scan's count when the server resumes
        while len(handler.values) < seen + 5:
            await asyncio.sleep(0.02)
        await sub.delete()
        return handler.values, before_resume

    values, before_resume = client_run(r.port, work)
    r.wait_for(lambda: r.status(S.W_SKIPPED_SCANS) - skipped_before >= PAUSED_SCANS - 1,
               "the scans published while the server was paused counted skipped")
    skipped = r.status(S.W_SKIPPED_SCANS) - skipped_before
    gaps = [(a, b) for a, b in zip(values, values[1:]) if b != a + 1]
    missed = sum(b - a - 1 for a, b in gaps)
    print(f"skipped {skipped}, gaps {gaps}")
    assert values == sorted(set(values)), "each value once, in order"
    # a value not notified is a scan skipped
    assert PAUSED_SCANS - 1 <= missed <= skipped
    # after the pause the server gives the newest scan: the value after the pause's gap is no older
    # than the ladder's when the server was resumed (never the scans it missed, one by one)
    resumed = [b for a, b in gaps if b - a - 1 >= PAUSED_SCANS - 1]
    assert len(resumed) == 1 and resumed[0] >= before_resume, (resumed, before_resume, values)
    assert r.status(S.W_REFUSALS) == 0, "skipped scans are not refusals"
    # the watch view's servers panel says them beside the refusals, not among them
    text = refusals_text(r.module.network_servers()[0])
    assert text.startswith("0; scans skipped ") and int(text.rsplit(" ", 1)[1]) >= skipped, text
