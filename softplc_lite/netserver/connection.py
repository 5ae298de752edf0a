"""One client connection, with the rules a PLC's server needs around the
protocol's handler (docs/modbtcps.md, "Safe by default"): the allow-list and
the connection limit at connect, the request rate per client address, a
malformed frame closing its connection, an idle connection (half-open,
slowloris) closed after the idle timeout, and a client that sends faster
than it reads its replies no longer read. Every refusal is counted
(counters.py) and logged at debug 1.
"""

from __future__ import annotations

import asyncio
import contextvars
import ipaddress
from collections import deque
from typing import TYPE_CHECKING

from . import counters as C
from .protocol import Link, Malformed, Refusal

if TYPE_CHECKING:
    from .server import Server

PEER: contextvars.ContextVar[str] = contextvars.ContextVar("peer", default="?")  # whose request a task serves
MAX_QUEUED = 64  # requests queued on one connection; past it the connection is not read until served


def admitted(address: str, allow) -> bool:
    """Whether a client at ``address`` (text, an IPv6 scope allowed) is in
    one of the ``allow`` networks; ::ffff:10.1.2.3 counts as 10.1.2.3."""
    try:
        ip = ipaddress.ip_address(address.split("%")[0])
    except ValueError:
        return False
    ip = getattr(ip, "ipv4_mapped", None) or ip
    return any(ip in net for net in allow)


class _ToServe:
    """A decoded request in the queue, with what its reply needs."""

    __slots__ = ("header", "request")

    def __init__(self, header, request) -> None:
        self.header, self.request = header, request


class Connection:
    """One client connection, with the server's rules around the protocol's handler.

    Requests are answered in arrival order (a client may pipeline them, and
    a read after a write sees the write), by one task per connection: a
    write waiting for the scan holds up this client only. Every refusal
    answer goes through ``Server.refused``, which counts it. ``link`` is
    the listener's connection (protocol.Link), which calls ``connected``,
    ``received``, ``pause_writing``/``resume_writing`` and ``ended``."""

    def __init__(self, owner: Server, link: Link) -> None:
        self.owner = owner
        self.link = link
        self.handler = owner.handler
        self.peer = "?"
        self.address = "?"  # the client's address, whose request rate is limited
        self.idle_timer: asyncio.TimerHandle | None = None
        self.counted = False
        self.inbox = bytearray()  # received, not yet a whole frame
        self.queue: deque = deque()  # requests to serve in order: a _ToServe, or a reply ready
        self.worker: asyncio.Task | None = None
        self.serving = False  # the worker awaits a request's answer (a write: the scan)
        self.paused: set[str] = set()  # why reading is paused: "queue" full, "writing" (replies unread)
        self.can_write = asyncio.Event()  # cleared while the client leaves its replies unread
        self.can_write.set()
        self.state = None  # the protocol's own, per connection (Handler.opened)

    def connected(self) -> None:
        owner = self.owner
        peer = self.link.peername() or ("?", 0)
        self.peer, self.address = f"{peer[0]}:{peer[1]}", str(peer[0])
        if not admitted(self.address, owner.settings.allow):
            owner.count(C.REFUSED_NETWORK, f"{self.peer}: refused, not in the allow-list")
            self.link.abort()
            return
        if owner.open_connections >= owner.settings.max_connections:
            owner.count(C.REFUSED_LIMIT, f"{self.peer}: refused, maxConnections "
                                         f"{owner.settings.max_connections} reached")
            self.link.abort()
            return
        self.counted = True
        self.state = self.handler.opened(self.link)
        owner.open_connections += 1
        owner.image.add(C.CONNECTIONS)
        owner.image.set(C.CONNECTED, owner.open_connections)
        owner.log(2, f"{self.peer}: connected")
        self._rearm()

    def ended(self) -> None:
        """The connection's end, however it came (said once): its timer and
        its task go with it (a write it sent still lands: the scan has it)."""
        if self.idle_timer is not None:
            self.idle_timer.cancel()
            self.idle_timer = None
        self.queue.clear()
        self.inbox.clear()
        if self.worker is not None:
            self.worker.cancel()
            self.worker = None
        if self.counted:
            self.counted = False
            self.handler.closed(self.state)
            self.owner.open_connections -= 1
            self.owner.image.set(C.CONNECTED, self.owner.open_connections)
            self.owner.log(2, f"{self.peer}: disconnected")

    def _rearm(self) -> None:
        if self.idle_timer is not None:
            self.idle_timer.cancel()
        self.idle_timer = self.owner.loop.call_later(self.owner.settings.idle_timeout_ms / 1000, self._idle)

    def _idle(self) -> None:
        self.idle_timer = None
        if self.serving:  # waiting for the scan to apply its write: not idle
            self._rearm()
            return
        self.owner.count(C.IDLE, f"{self.peer}: closed, no whole request for "
                                 f"{self.owner.settings.idle_timeout_ms} ms")
        self.link.abort()

    # -- flow control: a client that sends faster than it reads stops being served and read --------
    def pause_writing(self) -> None:
        """Its unread replies passed the transport's high-water mark (64 KiB)."""
        self.owner.log(2, f"{self.peer}: does not read its replies; not read until it does")
        self.can_write.clear()
        self._pause("writing")

    def resume_writing(self) -> None:
        self.can_write.set()
        self._resume("writing")

    def _pause(self, why: str) -> None:
        if not self.paused:
            self.link.pause_reading()
        self.paused.add(why)

    def _resume(self, why: str) -> None:
        if why in self.paused:
            self.paused.discard(why)
            if not self.paused:
                self.link.resume_reading()

    # -- requests ---------------------------------------------------------------------------------
    def received(self, data: bytes) -> None:
        self.inbox += data
        self._take_frames()

    def _take_frames(self) -> None:
        """Queue the whole frames received, up to MAX_QUEUED (the rest wait
        in ``inbox`` as bytes: one read may bring thousands)."""
        try:
            used = self._frames(self.inbox)
        except Exception as exc:  # noqa: BLE001 - a bug here must cost this connection only, and be said
            self.owner.log(1, f"{self.peer}: closed, {type(exc).__name__}: {exc}")
            self.link.abort()
            return
        del self.inbox[:used]

    def _frames(self, data: bytearray) -> int:
        """The whole frames at the start of ``data`` queued (MAX_QUEUED at
        most); the bytes used."""
        used = 0
        frame_length = self.handler.frame_length
        while len(self.queue) < MAX_QUEUED:
            try:
                n = frame_length(data, used)
            except Malformed as e:
                self.owner.count(C.MALFORMED, f"{self.peer}: closed, {e}")
                self.link.abort()
                return len(data)
            if n is None:
                break
            self._request(bytes(data[used:used + n]))
            used += n
        if len(self.queue) >= MAX_QUEUED:
            self._pause("queue")
        return used

    def _request(self, frame: bytes) -> None:
        """Take one frame: queue the request it holds, or the reply that refuses it."""
        owner, handler = self.owner, self.handler
        self._rearm()
        header = handler.header(frame, self.state)
        if not owner.rate_ok(self.address):
            self._queue(owner.refused(Refusal(handler.busy, "over maxRequestsPerSecond"), header))
            return
        request = handler.decode(frame, header)
        if isinstance(request, Refusal):
            self._queue(owner.refused(request, header))
            return
        owner.log(2, f"{self.peer}: {request}")
        self._queue(_ToServe(header, request))

    def _queue(self, item) -> None:
        self.queue.append(item)
        if self.worker is None:
            self.worker = self.owner.loop.create_task(self._work())

    async def _work(self) -> None:
        """Answer the queued requests in order, until none is left."""
        PEER.set(self.peer)  # this task's log lines name its client
        try:
            while self.queue and self.link.is_open:
                await self.can_write.wait()
                item = self.queue.popleft()
                if "queue" in self.paused and len(self.queue) <= MAX_QUEUED // 2:
                    self._take_frames()  # those received already first, then the socket again
                    if len(self.queue) < MAX_QUEUED:
                        self._resume("queue")
                if isinstance(item, _ToServe):
                    self.serving = True
                    response = await self._serve(item)
                    self.serving = False
                    self._rearm()  # a client that waited for its answer has a whole idleTimeout after it
                else:
                    response = item
                if self.link.is_open:
                    self.link.reply(response)
        except Exception as exc:  # noqa: BLE001 - a reply that cannot be built: this connection ends, said
            self.owner.log(1, f"{self.peer}: closed, {type(exc).__name__}: {exc}")
            self.link.abort()
        finally:
            if self.worker is asyncio.current_task():
                self.worker = None

    async def _serve(self, item: _ToServe):
        owner, handler = self.owner, self.handler
        try:
            answer = await handler.serve(item.request)
        except Exception as exc:  # noqa: BLE001 - a bug in the protocol: its failure answer, nothing else stops
            owner.log(1, f"{self.peer}: {handler.code_words(handler.failure)}: {type(exc).__name__}: {exc}")
            return handler.refusal_reply(handler.failure, item.header)
        if isinstance(answer, Refusal):
            return owner.refused(answer, item.header)
        owner.image.add(C.REQUESTS)
        return answer
