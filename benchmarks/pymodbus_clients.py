"""pymodbus's own masters, the baselines of the Modbus benchmarks: its sync
and async serial clients reading 125 holding registers of slave 2 in a loop,
RTU at 38400 8N1, as bench_modbus_master.py and bench_modbmast.py both
measure them.

Each reads ``warmup`` times untimed, then either ``transactions`` times or
for ``window_s`` seconds of wall time, and returns (transactions done,
seconds, the last reply) for the caller to check.
"""

from __future__ import annotations

import asyncio
import time

from pymodbus import FramerType
from pymodbus.client import AsyncModbusSerialClient, ModbusSerialClient


class ClientFailed(RuntimeError):
    """A pymodbus client could not open its port."""


def _stop(transactions: int | None, window_s: float | None):
    """A test "go on?" for the loop: a count or a wall-clock window."""
    if transactions is not None:
        return lambda done, now: done < transactions
    return lambda done, now, end=time.perf_counter() + window_s: now < end


def sync_reads(port: str, warmup: int, transactions: int | None = None, window_s: float | None = None):
    client = ModbusSerialClient(port, framer=FramerType.RTU, baudrate=38400, timeout=1, retries=0)
    if not client.connect():
        raise ClientFailed(f"sync: cannot open {port}")
    try:
        read = client.read_holding_registers
        for _ in range(warmup):
            read(0, count=125, device_id=2)
        go_on = _stop(transactions, window_s)
        now = time.perf_counter
        done, t0, reply = 0, now(), None
        while go_on(done, now()):
            reply = read(0, count=125, device_id=2)
            done += 1
        return done, now() - t0, reply
    finally:
        client.close()


def async_reads(port: str, warmup: int, transactions: int | None = None, window_s: float | None = None):
    async def run():
        client = AsyncModbusSerialClient(port, framer=FramerType.RTU, baudrate=38400, timeout=1, retries=0)
        if not await client.connect():
            raise ClientFailed(f"async: cannot open {port}")
        try:
            read = client.read_holding_registers
            for _ in range(warmup):
                await read(0, count=125, device_id=2)
            go_on = _stop(transactions, window_s)
            now = time.perf_counter
            done, t0, reply = 0, now(), None
            while go_on(done, now()):
                reply = await read(0, count=125, device_id=2)
                done += 1
            return done, now() - t0, reply
        finally:
            client.close()

    return asyncio.run(run())
