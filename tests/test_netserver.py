"""The network-server layer (softplc_lite/netserver) serving a protocol that
is not Modbus: a protocol of text lines written against its interface
only, over the layer's plain TCP listener, in a real server process beside
a real engine's scans."""

from __future__ import annotations

import ipaddress
import os
import socket
import threading
import time
from pathlib import Path

import pytest

from softplc_lite.ladder import Engine, Mode, load_text
from softplc_lite.netserver import APPLIED, IGNORED, Handler, Malformed, Protocol, Refusal, ServerHandle, Settings
from softplc_lite.netserver import counters as C
from softplc_lite.netserver.image import Segments

pytestmark = pytest.mark.timeout(120)

LIMIT_S = 20.0
WORDS = 10  # N7:0..N7:9 served
MAX_LINE = 32
BAD = "bad"  # the protocol's one refusal code: a request it does not know
STATUS = C.StatusWords(
    bits=0, rate=1, writes_applied=2, refusals=3,
    copied=((4, C.REQUESTS), (5, C.MALFORMED), (6, C.OWN)),
    refusal_names=(("bad request", C.OWN), ("malformed", C.MALFORMED)))


class LineProtocol(Protocol):
    """``R i``: word i; ``W i v``: write v to word i; one reply line each."""

    name = "LINES"
    segments = Segments("lines")

    def regions(self):
        return [("N7", 0, WORDS, 0)]

    @property
    def image_bytes(self) -> int:
        return 2 * WORDS

    def apply(self, payload: bytes, table) -> str:
        index, value = (int(x) for x in payload.split())
        if index >= WORDS:
            return IGNORED
        table.file("N7").data[index] = value
        return APPLIED

    def handler(self, server):
        return LineHandler(server)


class LineHandler(Handler):
    """``N``: the requests this connection made; ``K``: the connections closed so far."""

    busy, failure = "busy", "failed"
    closed_connections = 0

    def opened(self, link):
        return {"requests": 0, "peer": link.peername()}

    def closed(self, state):
        assert state["requests"] >= 0
        LineHandler.closed_connections += 1

    def frame_length(self, data, at):
        end = data.find(b"\n", at)
        if end < 0:
            if len(data) - at > MAX_LINE:
                raise Malformed(f"a line over {MAX_LINE} bytes")
            return None
        return end + 1 - at

    def header(self, frame, state):
        state["requests"] += 1
        return state

    def decode(self, frame, header):
        words = frame.split()
        if words == [b"N"]:
            return ("N", header["requests"])
        if words == [b"K"]:
            return ("K", LineHandler.closed_connections)
        if len(words) == 2 and words[0] == b"R" and words[1].isdigit() and int(words[1]) < WORDS:
            return ("R", int(words[1]))
        if len(words) == 3 and words[0] == b"W" and words[1].isdigit() and int(words[1]) < WORDS \
                and words[2].lstrip(b"-").isdigit():
            return ("W", int(words[1]), int(words[2]))
        return Refusal(BAD, f"not a request: {frame[:20]!r}")

    async def serve(self, request):
        if request[0] in "NK":
            return b"%d\n" % request[1]
        if request[0] == "R":
            (raw,) = await self.server.read([(2 * request[1], 2)])
            return b"%d\n" % int.from_bytes(raw, "little", signed=True)
        if not await self.server.through_scan(b"%d %d" % request[1:]):
            return Refusal(BAD, "refused by the scan")
        return b"ok\n"

    def refusal_reply(self, code, header):
        return f"error {code}\n".encode()

    def counter(self, code):
        return C.OWN if code == BAD else C.REFUSED_RATE


@pytest.fixture
def served(monkeypatch):
    """(engine, handle): an engine in RUN adding 1 to N7:0 each scan, its
    LineProtocol server listening, scans running on a thread."""
    # the server process unpickles LineProtocol: it imports this file as the test run does
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(Path(__file__).parent), os.environ.get("PYTHONPATH", "")]))
    engine = Engine(load_text("ADD N7:0 1 N7:0\n"))
    engine.table.reference("N7:9")
    engine.table.reference("N40:15")
    settings = Settings(host="127.0.0.1", port=0, allow=(ipaddress.ip_network("127.0.0.0/8"),), max_connections=4,
                        max_requests_per_second=1000, idle_timeout_ms=60_000)
    lines: list[str] = []
    handle = ServerHandle(LineProtocol(), settings, lines.append, "the test's settings", STATUS)
    handle.attach(engine.table, "N40:0")
    engine.input_hooks.append(handle.on_input)
    engine.output_hooks.append(handle.on_output)
    engine.set_mode(Mode.RUN)
    engine.scan()  # simulated time: the first scan waits until the server listens
    assert handle.failed is None and handle.port, lines
    stop = threading.Event()

    def scans() -> None:
        while not stop.is_set():
            engine.scan()
            time.sleep(0.002)

    thread = threading.Thread(target=scans, daemon=True)
    thread.start()
    try:
        yield engine, handle
    finally:
        stop.set()
        thread.join(LIMIT_S)
        handle.close()


def ask(client: socket.socket, line: bytes) -> bytes:
    client.sendall(line)
    reply = b""
    while not reply.endswith(b"\n"):
        chunk = client.recv(100)
        if not chunk:
            break
        reply += chunk
    return reply


def wait_for(condition, what: str) -> None:
    deadline = time.monotonic() + LIMIT_S
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.01)


def test_a_second_protocol_reads_the_published_scan_and_its_writes_land_through_the_scan(served):
    engine, handle = served
    with socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as client:
        first = int(ask(client, b"R 0\n"))
        wait_for(lambda: int(ask(client, b"R 0\n")) > first, "N7:0 counting in the published image")
        assert ask(client, b"W 3 -42\n") == b"ok\n"  # answered once the scan applied it
        assert engine.table.read("N7:3") == -42
        assert ask(client, b"R 3\n") == b"-42\n"  # a read after the write sees it
        assert ask(client, b"X 1\n") == b"error bad\n"
    wait_for(lambda: engine.table.read("N40:3") == 1, "the refusal in the status words")
    assert engine.table.read("N40:6") == 1 and engine.table.read("N40:2") == 1  # its own counter; one write
    assert engine.table.read("N40:0") & C.BIT_LISTENING
    status = handle.server_status()
    assert status.up and status.refused == {"bad request": 1} and status.writes == 1


def test_a_protocol_keeps_state_per_connection_and_hears_of_each_end(served):
    engine, handle = served
    with socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as one, \
            socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as two:
        closed = int(ask(one, b"K\n"))
        for _ in range(3):
            ask(one, b"R 0\n")
        assert ask(one, b"N\n") == b"5\n"  # K, three reads, N: this connection's own count
        assert ask(two, b"N\n") == b"1\n"
    with socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as three:
        wait_for(lambda: int(ask(three, b"K\n")) == closed + 2, "both ends told to the protocol")


def test_bytes_that_are_not_a_frame_close_their_connection_counted(served):
    engine, handle = served
    with socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as client:
        client.sendall(b"R" * (MAX_LINE + 8))
        assert client.recv(100) == b""  # closed by the server
    wait_for(lambda: engine.table.read("N40:5") == 1, "the malformed count in the status words")
    with socket.create_connection(("127.0.0.1", handle.port), timeout=LIMIT_S) as client:
        assert ask(client, b"R 9\n") == b"0\n"  # the server goes on
    assert handle.server_status().refused == {"malformed": 1}


def test_the_server_process_is_the_layers_own_and_ends_with_close(served):
    engine, handle = served
    process = handle.process
    cmdline = Path(f"/proc/{process.pid}/cmdline").read_bytes() if Path("/proc").exists() else b""
    assert not cmdline or b"softplc_lite.netserver.process" in cmdline
    assert not [n for n in os.listdir(Segments.segment_directory()) if n.startswith(f"softplc-lines-{os.getpid()}-")]
    handle.close()
    assert process.poll() is not None
