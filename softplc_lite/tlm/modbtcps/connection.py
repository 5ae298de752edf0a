"""One client connection of the Modbus TCP server, with the rules a PLC's
server needs around pymodbus's request handler (docs/modbtcps.md, "Safe by
default"): the allow-list and the connection limit at connect, the request
rate per client address, a malformed frame closing its connection, an idle
connection (half-open, slowloris) closed after idleTimeout, and a client
that sends faster than it reads its replies no longer read. Every refusal is
counted (status.py) and logged at debug 1.
"""

from __future__ import annotations

import asyncio
import contextvars
import ipaddress
from collections import deque
from typing import TYPE_CHECKING

from pymodbus.constants import ExcCodes
from pymodbus.pdu import ExceptionResponse
from pymodbus.pdu.register_message import MaskWriteRegisterRequest
from pymodbus.server.requesthandler import ServerRequestHandler

from . import status as C

if TYPE_CHECKING:
    from .serverproc import Server

KIND_OF_FUNCTION = {1: "coils", 5: "coils", 15: "coils", 2: "discrete_inputs",
                    3: "holding_registers", 6: "holding_registers", 16: "holding_registers",
                    22: "holding_registers", 23: "holding_registers", 4: "input_registers"}
PEER: contextvars.ContextVar[str] = contextvars.ContextVar("peer", default="?")  # whose request a task serves
MAX_QUEUED = 64  # requests queued on one connection; past it the connection is not read until served
MBAP = 7  # transaction, protocol, length, unit
MAX_LENGTH = 254  # the MBAP length field: unit id + the largest PDU (253)


class Connection(ServerRequestHandler):
    """One client connection, with the server's rules around pymodbus's handler.

    Requests are answered in arrival order (a client may pipeline them, and
    a read after a write sees the write), by one task per connection: a
    write waiting for the scan holds up this client only. pymodbus's own
    receive buffer is bypassed (``data_received``): it drops everything when
    more than 264 bytes arrive at once (pipelined requests) and is cleared by
    every reply sent (the next request's first bytes)."""

    def __init__(self, owner: Server, *args) -> None:
        super().__init__(owner, *args)
        self.owner = owner
        self.peer = "?"
        self.address = "?"  # the client's address, whose request rate is limited
        self.idle_timer: asyncio.TimerHandle | None = None
        self.counted = False
        self.inbox = bytearray()  # received, not yet a whole frame
        self.queue: deque = deque()  # requests to serve in order: a PDU, or an exception response ready
        self.worker: asyncio.Task | None = None
        self.serving = False  # the worker awaits a request's answer (a write: the scan)
        self.paused: set[str] = set()  # why reading is paused: "queue" full, "writing" (replies unread)
        self.can_write = asyncio.Event()  # cleared while the client leaves its replies unread
        self.can_write.set()

    def callback_connected(self) -> None:
        owner = self.owner
        peer = self.transport.get_extra_info("peername") or ("?", 0)
        self.peer, self.address = f"{peer[0]}:{peer[1]}", str(peer[0])
        try:
            ip = ipaddress.ip_address(self.address.split("%")[0])
            ip = getattr(ip, "ipv4_mapped", None) or ip  # ::ffff:10.1.2.3 is 10.1.2.3 for the allow-list
        except ValueError:
            ip = None
        if ip is None or not any(ip in net for net in owner.config.allow):
            owner.count(C.REFUSED_NETWORK, f"{self.peer}: refused, not in the allow-list")
            self.close()
            return
        if owner.open_connections >= owner.config.max_connections:
            owner.count(C.REFUSED_LIMIT, f"{self.peer}: refused, maxConnections "
                                         f"{owner.config.max_connections} reached")
            self.close()
            return
        self.counted = True
        owner.open_connections += 1
        owner.image.add(C.CONNECTIONS)
        owner.image.set(C.CONNECTED, owner.open_connections)
        owner.log(2, f"{self.peer}: connected")
        self._rearm()

    def callback_disconnected(self, exc) -> None:
        super().callback_disconnected(exc)
        self._drop()

    def close(self, reconnect: bool = False) -> None:
        if self.transport is not None:  # replies it has not read are dropped: a client that stops
            self.transport.abort()  # reading must not keep its socket and their memory (close() waits)
        super().close(reconnect)
        self._drop()

    def _drop(self) -> None:
        """The connection's end: its timer and its task go with it (a write
        it sent still lands: the scan has it)."""
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
            self.owner.open_connections -= 1
            self.owner.image.set(C.CONNECTED, self.owner.open_connections)
            self.owner.log(2, f"{self.peer}: disconnected")

    def _rearm(self) -> None:
        if self.idle_timer is not None:
            self.idle_timer.cancel()
        self.idle_timer = self.owner.loop.call_later(self.owner.config.idle_timeout_ms / 1000, self._idle)

    def _idle(self) -> None:
        self.idle_timer = None
        if self.serving:  # waiting for the scan to apply its write: not idle
            self._rearm()
            return
        self.owner.count(C.IDLE, f"{self.peer}: closed, no whole request for "
                                 f"{self.owner.config.idle_timeout_ms} ms")
        self.close()

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
        if not self.paused and self.transport is not None:
            self.transport.pause_reading()
        self.paused.add(why)

    def _resume(self, why: str) -> None:
        if why in self.paused:
            self.paused.discard(why)
            if not self.paused and self.transport is not None:
                self.transport.resume_reading()

    # -- requests ---------------------------------------------------------------------------------
    def data_received(self, data: bytes) -> None:
        if self.transport is not None:
            self.inbox += data
            self._take_frames()

    def _take_frames(self) -> None:
        """Queue the whole frames received, up to MAX_QUEUED (the rest wait
        in ``inbox`` as bytes: one read may bring thousands)."""
        try:
            used = self.callback_data(self.inbox)
        except Exception as exc:  # noqa: BLE001 - a bug here must cost this connection only, and be said
            self.owner.log(1, f"{self.peer}: closed, {type(exc).__name__}: {exc}")
            self.close()
            return
        del self.inbox[:used]

    def callback_data(self, data: bytearray, addr=None) -> int:
        """The whole frames at the start of ``data`` queued (MAX_QUEUED at
        most); the bytes used."""
        used = 0
        while len(data) - used >= MBAP and len(self.queue) < MAX_QUEUED:
            pid = int.from_bytes(data[used + 2:used + 4], "big")
            length = int.from_bytes(data[used + 4:used + 6], "big")
            if pid != 0 or not 2 <= length <= MAX_LENGTH:
                self.owner.count(C.MALFORMED, f"{self.peer}: closed, not a Modbus TCP frame "
                                              f"(protocol id {pid}, length {length})")
                self.close()
                return len(data)
            end = used + 6 + length
            if len(data) < end:
                break
            self._request(bytes(data[used:end]))
            used = end
        if len(self.queue) >= MAX_QUEUED:
            self._pause("queue")
        return used

    def _request(self, frame: bytes) -> None:
        """Check one frame; queue the PDU it holds, or the exception that answers it."""
        owner = self.owner
        self._rearm()
        tid, unit, function = int.from_bytes(frame[:2], "big"), frame[6], frame[7]

        def refused(counter: int, code: ExcCodes, why: str) -> None:
            owner.count(counter, f"{self.peer}: exception {int(code):02X}, {why}")
            self._queue(ExceptionResponse(function & 0x7F, code, device_id=unit, transaction=tid))

        if not owner.rate_ok(self.address):
            return refused(C.REFUSED_RATE, ExcCodes.DEVICE_BUSY, "over maxRequestsPerSecond")
        if function not in KIND_OF_FUNCTION:
            return refused(C.EXCEPTION_01, ExcCodes.ILLEGAL_FUNCTION, f"function {function} is not served")
        pdu = owner.decoder.decode(frame[7:])
        if pdu is None:  # a quantity out of range, a byte count that disagrees (Modbus spec 7: exception 03)
            return refused(C.EXCEPTION_03, ExcCodes.ILLEGAL_VALUE, f"function {function} with a body "
                                                                   "that does not decode")
        if unit not in owner.units:
            return refused(C.EXCEPTION_0B, ExcCodes.GATEWAY_NO_RESPONSE, f"unit id {unit} is not configured")
        pdu.dev_id, pdu.transaction_id = unit, tid
        owner.log(2, f"{self.peer}: {pdu}")
        self._queue(pdu)
        return None

    def _queue(self, item) -> None:
        self.queue.append(item)
        if self.worker is None:
            self.worker = self.owner.loop.create_task(self._work())

    async def _work(self) -> None:
        """Answer the queued requests in order, until none is left."""
        PEER.set(self.peer)  # this task's log lines name its client
        try:
            while self.queue and self.transport is not None:
                await self.can_write.wait()
                item = self.queue.popleft()
                if "queue" in self.paused and len(self.queue) <= MAX_QUEUED // 2:
                    self._take_frames()  # those received already first, then the socket again
                    if len(self.queue) < MAX_QUEUED:
                        self._resume("queue")
                if isinstance(item, ExceptionResponse):
                    response = item
                else:
                    self.serving = True
                    response = await self._serve(item)
                    self.serving = False
                if self.transport is not None:
                    self.pdu_send(response)
        except Exception as exc:  # noqa: BLE001 - a reply that cannot be built: this connection ends, said
            self.owner.log(1, f"{self.peer}: closed, {type(exc).__name__}: {exc}")
            self.close()
        finally:
            if self.worker is asyncio.current_task():
                self.worker = None

    async def _serve(self, pdu):
        owner = self.owner
        try:
            if isinstance(pdu, MaskWriteRegisterRequest):
                response = await owner.mask_write(pdu)
            else:
                response = await pdu.datastore_update(owner.context, pdu.dev_id)
        except Exception as exc:  # noqa: BLE001 - pymodbus or this module: exception 04, nothing else stops
            owner.log(1, f"{self.peer}: exception 04: {type(exc).__name__}: {exc}")
            response = ExceptionResponse(pdu.function_code, ExcCodes.DEVICE_FAILURE)
        if not isinstance(response, ExceptionResponse):
            owner.image.add(C.REQUESTS)
        response.dev_id, response.transaction_id = pdu.dev_id, pdu.transaction_id
        return response
