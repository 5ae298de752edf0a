"""The server process: pymodbus's Modbus TCP server over the shared image.

Run by the module (``python -m softplc_lite.tlm.modbtcps.serverproc FD``):
its own process, so that however busy the clients keep it, the scan never
waits for it (no shared interpreter lock). It reads its configuration from
standard input, answers reads from the image the scan publishes, and passes
writes to the scan through the pipe FD, answering a write once the scan has
applied it (so a read that follows sees it). It exits when standard input
closes: when the runtime stops, or dies.

pymodbus does the protocol (the PDUs, their encoding); connection.py adds
what a PLC's server needs around each client: the allow-list, the connection
and request-rate limits, idle connections closed, malformed frames closing
their connection, and every refusal counted (status.py).
"""

from __future__ import annotations

import asyncio
import logging
import os
import pickle
import signal
import socket
import sys
import time

from pymodbus.constants import ExcCodes
from pymodbus.datastore import ModbusServerContext
from pymodbus.pdu import ExceptionResponse
from pymodbus.pdu.register_message import MaskWriteRegisterResponse
from pymodbus.server import ModbusTcpServer

from ...datatable.filetypes import STRING_CHARS
from . import messages as msg
from . import status as C
from .connection import KIND_OF_FUNCTION, PEER, Connection
from .image import SharedImage
from .layout import STRING_WORDS, Layout

WRITES = {5, 6, 15, 16, 22, 23}
MAX_READ = {"coils": 2000, "discrete_inputs": 2000, "holding_registers": 125, "input_registers": 125}
MAX_PENDING = 10_000  # writes waiting for the scan; more are answered busy (06)
MAX_BUCKETS = 4096  # client addresses remembered by the rate limit
LOGGED_PER_SECOND = 20  # refusals logged one by one each second at debug 1; the rest summed


class TableContext(ModbusServerContext):
    """The data table as pymodbus's datastore: reads from the image, writes
    through the scan."""

    def __init__(self, server: Server) -> None:  # no super().__init__: it builds pymodbus's own store
        self.server = server
        self.old_simulator = True  # pymodbus then calls this object as it is
        self.simdevices = []
        self._devices = {}

    def device_ids(self) -> list[int]:
        return sorted(self.server.units)

    async def async_getValues(self, device_id, func_code, address, count=1):
        kind = KIND_OF_FUNCTION[func_code]
        if func_code not in WRITES and not 1 <= count <= MAX_READ[kind]:
            return self.server.refuse(ExcCodes.ILLEGAL_VALUE)
        pieces = self.server.layout.find(device_id, kind, address, count)
        if pieces is None:
            return self.server.refuse(ExcCodes.ILLEGAL_ADDRESS)
        spans = Layout.spans(pieces)
        while (raws := self.server.image.read(spans)) is None:
            await asyncio.sleep(0)  # the scan is publishing: a few microseconds
        values = Layout.values(pieces, raws)
        return [bool(v) for v in values] if kind in ("coils", "discrete_inputs") else values

    async def async_setValues(self, device_id, func_code, address, values):
        values = [int(v) for v in values]
        problem = self.server.write_refused(device_id, func_code, address, len(values), values)
        if problem is not None:
            return problem
        kind = KIND_OF_FUNCTION[func_code]
        await self.server.through_scan(lambda seq: msg.write(seq, device_id, kind, address, values))
        return None


def string_lengths_fit(pieces, values) -> bool:
    """A string's LEN register takes 0..82 (its character count)."""
    k = 0
    for s, off, n in pieces:
        if s.value == "string" and s.string_format == "ucs2":  # a packed string has no LEN register
            for j in range(n):
                if (off + j) % STRING_WORDS == 0 and values[k + j] > STRING_CHARS:
                    return False
        k += n
    return True


class Server(ModbusTcpServer):
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
        super().__init__(TableContext(self), address=address)

    def callback_new_connection(self) -> Connection:
        return Connection(self, self.trace_packet, self.trace_pdu, self.trace_connect)

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

    def refuse(self, code: ExcCodes) -> ExcCodes:
        counter = {ExcCodes.ILLEGAL_FUNCTION: C.EXCEPTION_01, ExcCodes.ILLEGAL_ADDRESS: C.EXCEPTION_02,
                   ExcCodes.ILLEGAL_VALUE: C.EXCEPTION_03}[code]
        self.count(counter, f"{PEER.get()}: exception {int(code):02X}")
        return code

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

    def write_refused(self, unit: int, function: int, address: int, count: int,
                      values: list[int] | None = None) -> ExcCodes | None:
        """The exception that refuses a write (counted), or None. ``values``:
        the registers written, when known (a mask write's are not)."""
        kind = KIND_OF_FUNCTION[function]
        if not self.layout.takes_writes(unit, kind):
            return self.refuse(ExcCodes.ILLEGAL_FUNCTION)  # this unit takes no writes of this kind at all
        pieces = self.layout.find(unit, kind, address, count)
        if pieces is None or not all(s.writable for s, _, _ in pieces):
            return self.refuse(ExcCodes.ILLEGAL_ADDRESS)
        if len(self.pending) >= MAX_PENDING:  # the scan is not taking writes (stopped): busy
            self.count(C.REFUSED_RATE, f"{PEER.get()}: exception 06, {MAX_PENDING} writes wait for the scan")
            return ExcCodes.DEVICE_BUSY
        if values is not None and kind == "holding_registers" and not string_lengths_fit(pieces, values):
            return self.refuse(ExcCodes.ILLEGAL_VALUE)
        return None

    # -- writes through the scan --------------------------------------------------------------
    async def through_scan(self, make) -> None:
        """Send a write to the scan; return when the scan has applied it."""
        self.sequence += 1
        seq = self.sequence
        future = self.loop.create_future()
        self.pending[seq] = future
        self.image.add(C.WRITES)
        self.send(make(seq))
        await future

    async def mask_write(self, pdu):
        problem = self.write_refused(pdu.dev_id, 22, pdu.address, 1)
        if problem is not None:
            return ExceptionResponse(22, problem)
        await self.through_scan(lambda seq: msg.mask(seq, pdu.dev_id, pdu.address, pdu.and_mask, pdu.or_mask))
        return MaskWriteRegisterResponse(address=pdu.address, and_mask=pdu.and_mask, or_mask=pdu.or_mask,
                                         dev_id=pdu.dev_id, transaction_id=pdu.transaction_id)

    def acked(self, seq: int) -> None:
        for k in [k for k in self.pending if k <= seq]:
            future = self.pending.pop(k)
            if not future.done():
                future.set_result(None)

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


def _bind_problem(host: str, port: int) -> str | None:
    """Why the address cannot be listened on, in words (pymodbus only logs it)."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except OSError as e:
        return f"cannot listen on {host}:{port}: {e.strerror or e}"
    family, kind, proto, _, sockaddr = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(sockaddr)
        except OSError as e:
            return f"cannot listen on {host}:{port}: {e.strerror or e}"
    return None


async def serve(init: dict) -> None:
    config, layout = init["config"], init["layout"]
    image = SharedImage.attach(init["image"], init["size"])
    out_fd = init["out_fd"]
    problem = _bind_problem(config.host, config.port)
    if problem is not None:
        os.write(out_fd, msg.failed(problem))  # blocking still: a few bytes into an empty pipe
        return
    server = Server(config, layout, image, out_fd, (config.host, config.port))
    await server.serve_forever(background=True)
    port = server.transport.sockets[0].getsockname()[1]
    image.set(C.LISTENING, 1)
    server.log(1, f"listening on {config.host}:{port}")
    os.set_blocking(out_fd, False)
    server.send(msg.ready(port))

    loop = asyncio.get_running_loop()
    done = loop.create_future()
    reader = msg.Reader()
    stdin = 0
    os.set_blocking(stdin, False)

    def from_runtime() -> None:
        try:
            data = os.read(stdin, 65536)
        except BlockingIOError:
            return
        if not data:  # the runtime closed the pipe: stopped, or gone
            if not done.done():
                done.set_result(None)
            return
        for m in reader.feed(data):
            if m[0] == msg.ACK:
                server.acked(m[1])

    loop.add_reader(stdin, from_runtime)
    await done
    loop.remove_reader(stdin)
    image.set(C.LISTENING, 0)
    await server.shutdown()


def _read_exactly(fd: int, n: int) -> bytes:
    out = bytearray()
    while len(out) < n:
        chunk = os.read(fd, n - len(out))
        if not chunk:
            break
        out += chunk
    return bytes(out)


def main() -> int:
    # Ctrl-C reaches the whole terminal's process group: the runtime decides when this process ends
    # (it closes standard input after its final scan), so a Ctrl-C does not end it first.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # this module says what matters, counted
    out_fd = int(sys.argv[1])
    try:
        header = _read_exactly(0, 4)
        if len(header) < 4:
            return 1
        init = pickle.loads(_read_exactly(0, msg.LENGTH.unpack(header)[0]))
        init["out_fd"] = out_fd
        asyncio.run(serve(init))
    except Exception as exc:  # said in one line, to the runtime if it still waits for READY; no traceback
        why = f"the server process failed: {type(exc).__name__}: {exc}"
        print(f"MODBTCPS: {why}", file=sys.stderr, flush=True)
        try:
            os.write(out_fd, msg.failed(why))
        except OSError:
            pass
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
