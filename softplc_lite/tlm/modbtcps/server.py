"""The Modbus TCP server of the server process (serverproc.py): pymodbus's
server (through pymodbus_glue.py) with the rules a PLC's server needs, each
request served from the image the scan publishes and each write passed to
the scan, answered once applied. Every exception answer is made and counted
in ``Server.refused``.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time

from . import messages as msg
from . import rules
from . import status as C
from .connection import PEER, Connection
from .image import SharedImage
from .layout import Layout, string_lengths_fit
from .pymodbus_glue import ServerBase, exception_response, response
from .rules import KIND_OF_FUNCTION, Refusal, Request

MAX_PENDING = 10_000  # writes waiting for the scan; more are answered busy (06)
MAX_BUCKETS = 4096  # client addresses remembered by the rate limit
LOGGED_PER_SECOND = 20  # refusals logged one by one each second at debug 1; the rest summed
COUNTER_OF_CODE = {rules.ILLEGAL_FUNCTION: C.EXCEPTION_01, rules.ILLEGAL_ADDRESS: C.EXCEPTION_02,
                   rules.ILLEGAL_VALUE: C.EXCEPTION_03, rules.DEVICE_BUSY: C.REFUSED_RATE,
                   rules.GATEWAY_NO_RESPONSE: C.EXCEPTION_0B}


class Server(ServerBase):
    def __init__(self, config, layout: Layout, image: SharedImage, out_fd: int, address) -> None:
        self.config = config
        self.layout = layout
        self.image = image
        self.units = set(config.units)  # a unit with no regions answers exception 02 to everything
        self.open_connections = 0
        self.out_fd = out_fd
        self.sequence = 0
        self.pending: dict[int, asyncio.Future] = {}
        self.outbox = bytearray()
        self.writer_armed = False
        self.buckets: dict[str, list[float]] = {}
        self.log_second, self.logged, self.unlogged = 0.0, 0, 0
        super().__init__(address)

    def new_connection(self) -> Connection:
        return Connection(self)

    # -- rules -------------------------------------------------------------------------------
    def log(self, level: int, message: str) -> None:
        if self.config.debug >= level:
            print(f"MODBTCPS: {time.strftime('%H:%M:%S')} {message}", file=sys.stderr, flush=True)

    def count(self, counter: int, message: str) -> None:
        """A refusal: counted always, logged at debug 1 up to LOGGED_PER_SECOND
        (a flood of bad requests must not become a flood of lines)."""
        self.image.add(counter)
        if self.config.debug < 1:
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

    def refused(self, refusal: Refusal, function: int, unit: int, tid: int):
        """The exception response of a refusal, counted: every exception
        answer of the server is made here."""
        self.count(COUNTER_OF_CODE[refusal.code], f"{PEER.get()}: exception {refusal.code:02X}, {refusal.why}")
        return exception_response(function, refusal.code, unit, tid)

    def rate_ok(self, client: str) -> bool:
        """A token bucket per client address: maxRequestsPerSecond, with a
        burst of one second's worth."""
        limit = self.config.max_requests_per_second
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

    # -- serving a request ---------------------------------------------------------------------
    async def serve(self, r: Request):
        """The response to a request whose body is checked (rules.py), or
        the Refusal that answers it. Every check is made before the write
        goes to the scan: a refused request changes nothing."""
        kind = KIND_OF_FUNCTION[r.function]
        if r.function not in rules.WRITES:
            values = await self.read(r.unit, kind, r.address, r.count)
            return values if isinstance(values, Refusal) else response(r, values)
        refusal = self.write_refused(r)
        if refusal is not None:
            return refusal
        if r.function == 22:
            outcome = await self.through_scan(
                lambda seq: msg.mask(seq, r.unit, r.address, r.and_mask, r.or_mask))
        else:
            outcome = await self.through_scan(lambda seq: msg.write(seq, r.unit, kind, r.address, r.values))
        if outcome is not None:
            return outcome
        if r.function in (5, 6):  # the item as the scan left it (Modbus spec 6.5, 6.6: the echo)
            values = await self.read(r.unit, kind, r.address, 1)
        elif r.function == 23:  # the write first, then the read (Modbus spec 6.17)
            values = await self.read(r.unit, kind, r.read_address, r.read_count)
        else:
            values = None
        return values if isinstance(values, Refusal) else response(r, values)

    async def read(self, unit: int, kind: str, address: int, count: int) -> list[int] | Refusal:
        pieces = self.layout.find(unit, kind, address, count)
        if pieces is None:
            return Refusal(rules.ILLEGAL_ADDRESS, f"{kind.replace('_', ' ')} {address}..{address + count - 1} "
                                                  f"are not all in unit {unit}'s map")
        spans = Layout.spans(pieces)
        while (raws := self.image.read(spans)) is None:
            await asyncio.sleep(0)  # the scan is publishing: a few microseconds
        return Layout.values(pieces, raws)

    def write_refused(self, r: Request) -> Refusal | None:
        """Why a write is refused, or None: every check a write gets before
        it goes to the scan, Read/Write Multiple Registers' read part
        included."""
        kind = KIND_OF_FUNCTION[r.function]
        if not self.layout.takes_writes(r.unit, kind):  # the function is not an allowable action here
            return Refusal(rules.ILLEGAL_FUNCTION, f"unit {r.unit} takes no writes of {kind.replace('_', ' ')}")
        pieces = self.layout.find(r.unit, kind, r.address, r.count)
        if pieces is None or not all(s.writable for s, _, _ in pieces):
            return Refusal(rules.ILLEGAL_ADDRESS, f"{kind.replace('_', ' ')} {r.address}..{r.address + r.count - 1} "
                                                  f"are not all writable in unit {r.unit}'s map")
        if r.function == 23 and self.layout.find(r.unit, kind, r.read_address, r.read_count) is None:
            return Refusal(rules.ILLEGAL_ADDRESS, f"the read part, holding registers {r.read_address}.."
                                                  f"{r.read_address + r.read_count - 1}, is not all in unit "
                                                  f"{r.unit}'s map")
        if len(self.pending) >= MAX_PENDING:  # the scan is not taking writes (stopped): busy
            return Refusal(rules.DEVICE_BUSY, f"{MAX_PENDING} writes wait for the scan")
        # a mask write's result is known only where the scan applies it: the scan checks its LEN there
        if kind == "holding_registers" and r.function != 22 and not string_lengths_fit(pieces, r.values):
            return Refusal(rules.ILLEGAL_VALUE, "a string's LEN register written over 82")
        return None

    # -- writes through the scan --------------------------------------------------------------
    async def through_scan(self, make) -> Refusal | None:
        """Send a write to the scan; return when the scan has applied it
        (None), or refused it (the Refusal)."""
        self.sequence += 1
        seq = self.sequence
        future = self.loop.create_future()
        self.pending[seq] = future
        self.image.add(C.WRITES)
        self.send(make(seq))
        return await future

    def acked(self, seq: int) -> None:
        for k in [k for k in self.pending if k <= seq]:
            future = self.pending.pop(k)
            if not future.done():
                future.set_result(None)

    def refused_by_scan(self, seq: int) -> None:
        future = self.pending.pop(seq, None)
        if future is not None and not future.done():
            future.set_result(Refusal(rules.ILLEGAL_VALUE, "a mask write whose result is a string's LEN over 82"))

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
