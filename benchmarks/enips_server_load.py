"""The client processes of bench_enips_server.py.

    python benchmarks/enips_server_load.py SPEC_JSON

One process a client for the blocking clients the field uses, so that no
two share an interpreter: "cip" (pycomm3's LogixDriver reading the tag
N10[0]{COUNT}), "pccc" (pycomm3's SLCDriver reading N10:0{COUNT}) and
"modbus" (pymodbus's client reading COUNT holding registers of MODBTCPS,
the baseline); "raw": K hand-made EtherNet/IP clients on one asyncio loop,
each a Read Tag of N10[0]{COUNT} and a Write Tag of its own word N12[k] in
turn (the busy clients). Every client connects and warms up, all start at
"start_at" on CLOCK_MONOTONIC and stop at the window's end; every reply is
checked (COUNT values in 0..READ_VALUE_MAX; a write answered without error).
Prints one line of JSON: requests done, errors, the first error, the window,
and the CPU time of this process and of each watched pid in it.
"""

from __future__ import annotations

import asyncio
import json
import struct
import sys
import time

from modbus_server_load import READ_VALUE_MAX, cpu_seconds, own_cpu_seconds


def _check(values, count: int) -> str | None:
    if values is None or len(values) != count:
        return f"{0 if values is None else len(values)} values, not {count}"
    if not all(0 <= v <= READ_VALUE_MAX for v in values):
        return "a value outside the ladder's range"
    return None


class Meter:
    """The CPU time of this process and of the watched pids over the window."""

    def __init__(self, watch: list[int], start_at: float) -> None:
        self.watch, self.start_at, self.late_s = watch, start_at, 0.0
        self.before: dict = {}
        self.used: dict = {}

    def start(self) -> None:
        if not self.before:
            self.before = {"clients": own_cpu_seconds(), **{str(pid): cpu_seconds(pid) for pid in self.watch}}
            self.late_s = max(0.0, time.monotonic() - self.start_at)

    def stop(self) -> None:
        if self.used or not self.before:
            return
        now = {"clients": own_cpu_seconds(), **{str(pid): cpu_seconds(pid) for pid in self.watch}}
        self.used = {k: now[k] - self.before[k] for k in now if now[k] is not None and self.before.get(k) is not None}


def blocking(spec: dict, meter: Meter) -> tuple[int, int, str | None]:
    """One blocking client in a loop until the window's end: (done, errors, first error)."""
    kind, port, count = spec["kind"], spec["port"], spec["count"]
    if kind == "modbus":
        from pymodbus.client import ModbusTcpClient

        client = ModbusTcpClient("127.0.0.1", port=port, timeout=5, retries=0)
        client.connect()

        def read():
            r = client.read_holding_registers(0, count=count, device_id=1)
            return None if r.isError() else r.registers
    else:
        from pycomm3 import LogixDriver, SLCDriver

        client = LogixDriver(f"127.0.0.1:{port}", init_tags=True) if kind == "cip" else SLCDriver(f"127.0.0.1:{port}")
        client.open()
        tag = f"N10[0]{{{count}}}" if kind == "cip" else f"N10:0{{{count}}}"

        def read():
            t = client.read(tag)
            return None if t.error else t.value
    try:
        for _ in range(spec["warmup"]):
            read()
        _sleep_until(spec["start_at"])
        meter.start()
        done, errors, first = 0, 0, None
        end = spec["start_at"] + spec["window_s"]
        while time.monotonic() < end:
            problem = _check(read(), count)
            if problem is None:
                done += 1
            else:
                errors += 1
                first = first or problem
        meter.stop()
        return done, errors, first
    finally:
        client.close()


def _frame(command: int, session: int, body: bytes) -> bytes:
    return struct.pack("<HHII8sI", command, len(body), session, 0, bytes(8), 0) + body


def _rr(session: int, request: bytes) -> bytes:
    return _frame(0x6F, session, struct.pack("<IHHHHHH", 0, 10, 2, 0, 0, 0xB2, len(request)) + request)


async def _exchange(reader, writer, message: bytes) -> bytes:
    writer.write(message)
    head = await reader.readexactly(24)
    data = await reader.readexactly(struct.unpack_from("<H", head, 2)[0])
    if struct.unpack_from("<I", head, 8)[0]:
        raise RuntimeError(f"encapsulation status 0x{struct.unpack_from('<I', head, 8)[0]:04X}")
    return head + data


def raw(spec: dict, meter: Meter) -> tuple[int, int, str | None]:
    """K raw clients, reads and writes in turn: (requests done, errors, first error)."""
    count = spec["count"]
    totals = {"done": 0, "errors": 0, "first": None}

    async def client(k: int) -> None:
        reader, writer = await asyncio.open_connection("127.0.0.1", spec["port"])
        reply = await _exchange(reader, writer, _frame(0x65, 0, b"\x01\x00\x00\x00"))
        session = struct.unpack_from("<I", reply, 4)[0]
        read = _rr(session, bytes.fromhex("4c049103") + b"N10\x00" + bytes.fromhex("2800") + struct.pack("<H", count))
        value = 0
        await asyncio.sleep(max(0.0, spec["start_at"] - time.monotonic()))
        meter.start()
        end = spec["start_at"] + spec["window_s"]
        while time.monotonic() < end:
            try:
                reply = await _exchange(reader, writer, read)
                if reply[40:44] != b"\xcc\x00\x00\x00" or len(reply) != 46 + 2 * count:
                    raise RuntimeError(f"a read answered {reply[40:44].hex()}")
                value = (value + 1) & 0x7FFF
                write = _rr(session, bytes.fromhex("4d049103") + b"N12\x00" + bytes((0x28, k))
                            + struct.pack("<HHh", 0xC3, 1, value))
                reply = await _exchange(reader, writer, write)
                if reply[40:44] != b"\xcd\x00\x00\x00":
                    raise RuntimeError(f"a write answered {reply[40:44].hex()}")
                totals["done"] += 2
            except (RuntimeError, OSError, asyncio.IncompleteReadError) as e:
                totals["errors"] += 1
                totals["first"] = totals["first"] or str(e)
                break
        writer.close()

    async def main() -> None:
        await asyncio.gather(*(client(k) for k in range(spec["clients"])))
        meter.stop()

    asyncio.run(main())
    return totals["done"], totals["errors"], totals["first"]


def _sleep_until(t: float) -> None:
    delay = t - time.monotonic()
    if delay > 0:
        time.sleep(delay)


def main() -> int:
    spec = json.loads(sys.argv[1])
    meter = Meter(spec.get("watch", []), spec["start_at"])
    done, errors, first = (raw if spec["kind"] == "raw" else blocking)(spec, meter)
    ready_late, cpu = meter.late_s, meter.used
    print(json.dumps({"done": done, "errors": errors, "first_error": first, "start": spec["start_at"],
                      "end": spec["start_at"] + spec["window_s"], "ready_late_s": ready_late, "cpu_s": cpu}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
