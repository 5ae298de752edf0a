"""The other processes of bench_modbus_server.py: pymodbus's own Modbus TCP
server (the baseline) and the clients that load a server.

    python benchmarks/modbus_server_load.py serve
        pymodbus's ModbusTcpServer on 127.0.0.1 (a port the system picks),
        unit 1 with REGISTERS holding registers in a plain datastore
        (SimData/SimDevice); prints "ready PORT PID" and serves until its
        standard input closes.

    python benchmarks/modbus_server_load.py clients SPEC_JSON
        K pymodbus AsyncModbusTcpClient connections in one asyncio loop,
        each reading (function 3) or writing (function 16) COUNT registers
        in a loop, one request at a time; prints one line of JSON. With
        "raw" in the spec, K connections of RawClient instead (reads built
        and checked by hand on asyncio streams: a lighter client, to see
        whether pymodbus's client set the pace).

A clients run connects every client and makes WARMUP requests on each
(untimed), then all start together at a moment on CLOCK_MONOTONIC (the same
clock in every process on Linux, so the parent can match the window with
the runtime's scans) and stop at its end; a request still out at the end is
not counted. Every reply is checked: a read must bring COUNT registers, and
each value must be in 0..READ_VALUE_MAX (what the bench's ladder and the
baseline hold); any exception response, timeout or wrong reply is counted
as an error (the parent fails the run on any). The CPU time this process
used in the window, and that of each pid in "watch" (from /proc/PID/stat),
are reported beside it, to say which process was the bottleneck.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import resource
import struct
import sys
import time

REGISTERS = 100
READ_VALUE_MAX = 30_099  # the bench ladder's N10 words stay in 0..30099
TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float | None:
    """utime + stime of ``pid`` (all its threads), or None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / TICKS  # fields 14 and 15 of proc(5), counted from the state


def own_cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


# -- pymodbus's server: the baseline ------------------------------------------------------------------------


async def serve() -> None:
    from pymodbus.server import ModbusTcpServer
    from pymodbus.simulator import DataType, SimData, SimDevice

    values = [k * 7 for k in range(REGISTERS)]
    device = SimDevice(1, simdata=[SimData(0, values=values, datatype=DataType.REGISTERS)])
    server = ModbusTcpServer(device, address=("127.0.0.1", 0))
    await server.serve_forever(background=True)
    port = server.transport.sockets[0].getsockname()[1]
    print(f"ready {port} {os.getpid()}", flush=True)
    loop = asyncio.get_running_loop()
    closed = loop.create_future()

    def stdin_readable() -> None:
        if not os.read(0, 4096) and not closed.done():
            closed.set_result(None)

    loop.add_reader(0, stdin_readable)
    await closed
    loop.remove_reader(0)
    await server.shutdown()


# -- the clients -------------------------------------------------------------------------------------------


class Tally:
    def __init__(self) -> None:
        self.done = 0
        self.errors = 0
        self.first_error: str | None = None

    def error(self, what: str) -> None:
        self.errors += 1
        if self.first_error is None:
            self.first_error = what


def _wrong(reply, function: int, count: int) -> str | None:
    """What is wrong with a reply, or None."""
    if reply.isError():
        return f"exception response {reply}"
    if function == 3:
        regs = reply.registers
        if len(regs) != count:
            return f"{len(regs)} registers instead of {count}"
        if not all(0 <= v <= READ_VALUE_MAX for v in regs):
            return f"a value outside 0..{READ_VALUE_MAX}: {regs[:8]}..."
    return None


async def one_client(spec: dict, start_at: float, end_at: float, tally: Tally, ready: asyncio.Queue) -> None:
    from pymodbus.client import AsyncModbusTcpClient

    client = AsyncModbusTcpClient("127.0.0.1", port=spec["port"], timeout=spec["timeout_s"], retries=0)
    if not await client.connect():
        tally.error(f"cannot connect to 127.0.0.1:{spec['port']}")
        await ready.put(False)
        return
    function, count, address = spec["function"], spec["count"], spec["address"]
    values = list(range(count))

    async def request():
        if function == 3:
            return await client.read_holding_registers(address, count=count, device_id=1)
        return await client.write_registers(address, values, device_id=1)

    try:
        try:
            for _ in range(spec["warmup"]):
                await request()
        except Exception as exc:  # said, and this client sits the window out
            tally.error(f"warm-up: {type(exc).__name__}: {exc}")
            await ready.put(False)
            return
        await ready.put(True)
        await asyncio.sleep(max(0.0, start_at - time.monotonic()))
        while time.monotonic() < end_at:
            try:
                reply = await request()
            except Exception as exc:  # a timeout or a closed connection: an error of the run
                tally.error(f"{type(exc).__name__}: {exc}")
                continue
            if time.monotonic() > end_at:
                break  # answered after the window: not counted
            problem = _wrong(reply, function, count)
            if problem is None:
                tally.done += 1
            else:
                tally.error(problem)
    finally:
        client.close()


class RawClient:
    """A Modbus TCP client of a few lines (asyncio streams, frames built by
    hand): far less work a request than pymodbus's client, so the server,
    not the client, sets the pace. Reads only."""

    def __init__(self, spec: dict) -> None:
        self.port, self.count, self.address = spec["port"], spec["count"], spec["address"]
        self.timeout = spec["timeout_s"]
        self.tid = 0
        self.reader = self.writer = None
        self.reply_length = 9 + 2 * self.count  # MBAP 7, function, byte count, the registers

    async def connect(self) -> bool:
        try:
            self.reader, self.writer = await asyncio.open_connection("127.0.0.1", self.port)
        except OSError:
            return False
        return True

    async def read(self) -> str | None:
        """One read; what was wrong with it, or None."""
        self.tid = (self.tid + 1) & 0xFFFF
        self.writer.write(struct.pack(">HHHBBHH", self.tid, 0, 6, 1, 3, self.address, self.count))
        head = await asyncio.wait_for(self.reader.readexactly(9), self.timeout)
        tid, pid, length, unit, function, byte_count = struct.unpack(">HHHBBB", head)
        if function != 3:
            await self.reader.readexactly(length - 3)
            return f"exception response: function {function:#04x}, code {byte_count}"
        body = await asyncio.wait_for(self.reader.readexactly(byte_count), self.timeout)
        if (tid, pid, unit, byte_count) != (self.tid, 0, 1, 2 * self.count):
            return f"a wrong reply header: {head.hex()}"
        if not all(0 <= v <= READ_VALUE_MAX for v in struct.unpack(f">{self.count}H", body)):
            return f"a value outside 0..{READ_VALUE_MAX}"
        return None

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()


async def one_raw_client(spec: dict, start_at: float, end_at: float, tally: Tally, ready: asyncio.Queue) -> None:
    client = RawClient(spec)
    if not await client.connect():
        tally.error(f"cannot connect to 127.0.0.1:{spec['port']}")
        await ready.put(False)
        return
    try:
        for _ in range(spec["warmup"]):
            problem = await client.read()
            if problem is not None:
                tally.error(f"warm-up: {problem}")
                await ready.put(False)
                return
        await ready.put(True)
        await asyncio.sleep(max(0.0, start_at - time.monotonic()))
        while time.monotonic() < end_at:
            try:
                problem = await client.read()
            except (OSError, asyncio.IncompleteReadError, asyncio.TimeoutError) as exc:
                tally.error(f"{type(exc).__name__}: {exc}")
                return  # the stream is out of step: this client stops
            if time.monotonic() > end_at:
                break
            if problem is None:
                tally.done += 1
            else:
                tally.error(problem)
    finally:
        client.close()


async def run_clients(spec: dict) -> dict:
    """K clients, started together at ``start_at`` (CLOCK_MONOTONIC; the
    parent leaves time to connect and warm up, ``ready_late_s`` > 0 says it
    was not enough), for ``window_s``."""
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    tally = Tally()
    ready: asyncio.Queue = asyncio.Queue()
    k = spec["clients"]
    start_at = spec["start_at"]
    end_at = start_at + spec["window_s"]
    body = one_raw_client if spec.get("raw") else one_client
    tasks = [asyncio.create_task(body(spec, start_at, end_at, tally, ready)) for _ in range(k)]
    for _ in range(k):
        await ready.get()
    ready_late = time.monotonic() - start_at
    await asyncio.sleep(max(0.0, start_at - time.monotonic()))
    watched = {pid: cpu_seconds(pid) for pid in spec["watch"]}
    own = own_cpu_seconds()
    await asyncio.sleep(max(0.0, end_at - time.monotonic()))
    own = own_cpu_seconds() - own
    cpu = {"clients": own}
    for pid, before in watched.items():
        after = cpu_seconds(pid)
        cpu[str(pid)] = None if before is None or after is None else after - before
    await asyncio.gather(*tasks)
    return {"clients": k, "function": spec["function"], "raw": bool(spec.get("raw")), "done": tally.done,
            "errors": tally.errors, "first_error": tally.first_error, "start": start_at, "end": end_at,
            "window_s": spec["window_s"], "ready_late_s": ready_late, "cpu_s": cpu}


def main() -> int:
    if sys.argv[1:2] == ["serve"]:
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
        asyncio.run(serve())
        return 0
    if sys.argv[1:2] == ["clients"] and len(sys.argv) == 3:
        print(json.dumps(asyncio.run(run_clients(json.loads(sys.argv[2])))), flush=True)
        return 0
    print("usage: modbus_server_load.py serve | clients SPEC_JSON", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
