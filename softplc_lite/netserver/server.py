"""The server of the server process (process.py): the protocol's handler
(protocol.py) behind the rules a PLC's server needs (connection.py), each
request served from the image the scan publishes and each write passed to
the scan, answered once applied. Every refusal is counted in
``Server.refused``.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time

from . import counters as C
from . import messages as msg
from .connection import PEER, Connection
from .image import SharedImage
from .protocol import Link, Protocol, Refusal, Settings

MAX_PENDING = 10_000  # writes waiting for the scan; more are answered busy
MAX_BUCKETS = 4096  # client addresses remembered by the rate limit
LOGGED_PER_SECOND = 20  # refusals logged one by one each second at debug 1; the rest summed


class Server:
    def __init__(self, protocol: Protocol, settings: Settings, image: SharedImage, out_fd: int) -> None:
        self.protocol = protocol
        self.settings = settings
        self.image = image
        self.open_connections = 0
        self.out_fd = out_fd
        self.sequence = 0
        self.pending: dict[int, asyncio.Future] = {}
        self.outbox = bytearray()
        self.writer_armed = False
        self.buckets: dict[str, list[float]] = {}
        self.log_second, self.logged, self.unlogged = 0.0, 0, 0
        self.loop: asyncio.AbstractEventLoop | None = None
        self.handler = protocol.handler(self)
        self.listener = self.handler.listener()

    async def start(self) -> int:
        """Listen; the port bound."""
        self.loop = asyncio.get_running_loop()
        return await self.listener.start()

    async def stop(self) -> None:
        await self.listener.stop()

    def connect(self, link: Link) -> Connection:
        """A new client connection, which ``link`` carries."""
        return Connection(self, link)

    # -- rules -------------------------------------------------------------------------------
    def log(self, level: int, message: str) -> None:
        if self.settings.debug >= level:
            print(f"{self.protocol.name}: {time.strftime('%H:%M:%S')} {message}", file=sys.stderr, flush=True)

    def count(self, counter: int, message: str) -> None:
        """A refusal: counted always, logged at debug 1 up to LOGGED_PER_SECOND
        (a flood of bad requests must not become a flood of lines)."""
        self.image.add(counter)
        if self.settings.debug < 1:
            return
        now = time.monotonic()
        if now - self.log_second >= 1.0:
            if self.unlogged:
                self.log(1, f"{self.unlogged} more refusals not logged one by one (the status words count them)")
            self.log_second, self.logged, self.unlogged = now, 0, 0
        if self.logged < LOGGED_PER_SECOND:
            self.logged += 1
            self.log(1, message)
        else:
            self.unlogged += 1

    def refused(self, refusal: Refusal, header):
        """The reply that refuses a request, counted: every refusal of the
        server is made here. ``header``: the handler's, of the request's frame."""
        handler = self.handler
        self.count(handler.counter(refusal.code), f"{PEER.get()}: {handler.code_words(refusal.code)}, {refusal.why}")
        return handler.refusal_reply(refusal.code, header)

    def rate_ok(self, client: str) -> bool:
        """A token bucket per client address: maxRequestsPerSecond, with a
        burst of one second's worth."""
        limit = self.settings.max_requests_per_second
        now = time.monotonic()
        bucket = self.buckets.get(client)
        if bucket is None:
            if len(self.buckets) >= MAX_BUCKETS:  # forget the addresses whose buckets are full again
                self.buckets = {k: b for k, b in self.buckets.items() if now - b[1] < 1.0}
            bucket = self.buckets[client] = [float(limit), now]
        bucket[0] = min(float(limit), bucket[0] + (now - bucket[1]) * limit)
        bucket[1] = now
        if bucket[0] < 1.0:
            return False
        bucket[0] -= 1.0
        return True

    # -- what a handler uses ---------------------------------------------------------------------
    async def read(self, spans: list[tuple[int, int]]) -> list[bytes]:
        """The bytes of each (offset, length) span of the image, all from one
        publication of the scan."""
        while (raws := self.image.read(spans)) is None:
            await asyncio.sleep(0)  # the scan is publishing: a few microseconds
        return raws

    def busy(self) -> str | None:
        """Why a write would be refused busy now (the scan is not taking
        writes: stopped), or None."""
        if len(self.pending) >= MAX_PENDING:
            return f"{MAX_PENDING} writes wait for the scan"
        return None

    # -- writes through the scan --------------------------------------------------------------
    async def through_scan(self, payload: bytes) -> bool:
        """Send a write (the protocol's bytes, for its ``apply``) to the
        scan; return when the scan has applied it (True), or refused it."""
        self.sequence += 1
        seq = self.sequence
        future = self.loop.create_future()
        self.pending[seq] = future
        self.image.add(C.WRITES)
        self.send(msg.write(seq, payload))
        return await future

    def acked(self, seq: int) -> None:
        for k in [k for k in self.pending if k <= seq]:
            future = self.pending.pop(k)
            if not future.done():
                future.set_result(True)

    def refused_by_scan(self, seq: int) -> None:
        future = self.pending.pop(seq, None)
        if future is not None and not future.done():
            future.set_result(False)

    def send(self, data: bytes) -> None:
        """To the runtime; what the pipe cannot take now waits here (the
        runtime may be stopped between scans: reads go on meanwhile)."""
        self.outbox += data
        self._flush()

    def _flush(self) -> None:
        while self.outbox:
            try:
                n = os.write(self.out_fd, self.outbox)
            except BlockingIOError:
                if not self.writer_armed:
                    self.writer_armed = True
                    self.loop.add_writer(self.out_fd, self._flush)
                return
            except OSError:  # the runtime is gone: standard input closes next, and this process ends
                self.outbox.clear()
                return
            del self.outbox[:n]
        if self.writer_armed:
            self.writer_armed = False
            self.loop.remove_writer(self.out_fd)
