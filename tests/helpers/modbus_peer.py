"""A third-party Modbus slave line for tests and benchmarks: pymodbus's
serial server, run in a background thread with its own asyncio loop.

``port`` is a serial device (one end of a socat pty pair) or
``socket://127.0.0.1:PORT``, where pymodbus listens on TCP with serial
framing (testing notes). Like real RS-485 slaves the line stays silent for
unit ids it does not have (pymodbus would answer those with exception 04).

Two kinds of line: ``ModbusPeer(port, registers)`` is one slave (id 2 by
default) whose holding registers are ``registers``; ``ModbusPeer(port,
ids=[1, 2], size=200)`` has one slave per id, each with four tables of
``size`` entries holding what our simulated slave holds
(``modbus_slave.initial_value(k, table, unit=position)``), so a test
expects the same values from either. ``framer`` is "rtu" or "ascii".
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from pymodbus.server import ModbusSerialServer
from pymodbus.simulator import DataType, SimData, SimDevice

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)


def _ephemeral_low() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768  # Linux's default


# A port found free is handed to a server that binds it a moment later. A
# port the kernel picked (bind to port 0) is from the ephemeral range, which
# every client connection of every test also draws its own port from: one
# could take it in that moment. So ports come from below that range, each
# xdist worker from its own block, never twice in one process, and only
# ones nothing listens on now (a user's running PLC keeps its own).
_BLOCK = 1500
_FIRST = 10000
_handed: set[int] = set()


def free_tcp_port() -> int:
    blocks = max(1, (_ephemeral_low() - _FIRST) // _BLOCK)
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    start = _FIRST + (index % blocks) * _BLOCK
    for port in range(start, start + _BLOCK):
        if port in _handed:
            continue
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
        _handed.add(port)
        return port
    with socket.socket() as s:  # a whole block used: the kernel's pick
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_tcp(port: int, seconds: float = 5.0) -> None:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            return
        except OSError:
            time.sleep(0.01)
    raise TimeoutError(f"nothing listens on 127.0.0.1:{port} after {seconds} s")


class ModbusPeer:
    """pymodbus's serial server: unit ``device_id`` with ``registers`` as its
    holding registers (addresses 0..len-1), or the units ``ids`` with four
    tables each (see the module docstring)."""

    def __init__(self, port: str, registers: list[int] | None = None, device_id: int = 2, baudrate: int = 38400,
                 ids: list[int] | None = None, size: int = 200, framer: str = "rtu") -> None:
        self.port = port
        self.registers = list(registers or [])
        self.ids = list(ids) if ids is not None else [device_id]
        self.device_id = self.ids[0]
        self.size = size
        self.four_tables = ids is not None
        self.framer = framer
        self.baudrate = baudrate
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._server: ModbusSerialServer | None = None

    def _drop_other_ids(self, sending: bool, pdu):
        if not sending and pdu.dev_id not in self.ids:
            return None  # silence, as on a real multi-drop line
        return pdu

    def _devices(self) -> list[SimDevice]:
        if not self.four_tables:
            return [SimDevice(self.device_id, simdata=[SimData(0, values=self.registers, datatype=DataType.REGISTERS)])]
        from softplc_lite.ports.modbus_slave import initial_value

        def table(name: str, position: int, datatype: DataType) -> list[SimData]:
            return [SimData(0, values=[initial_value(k, name, unit=position) for k in range(self.size)],
                            datatype=datatype)]

        return [SimDevice(unit, simdata=(table("coil", k, DataType.BITS), table("discrete", k, DataType.BITS),
                                         table("holding", k, DataType.REGISTERS),
                                         table("input", k, DataType.REGISTERS)))
                for k, unit in enumerate(self.ids)]

    async def _start(self) -> None:
        from pymodbus.framer import FramerType

        devices = self._devices()
        framer = FramerType.ASCII if self.framer == "ascii" else FramerType.RTU
        self._server = ModbusSerialServer(devices if len(devices) > 1 else devices[0], framer=framer,
                                          port=self.port, baudrate=self.baudrate, trace_pdu=self._drop_other_ids)
        await self._server.serve_forever(background=True)

    def start(self) -> "ModbusPeer":
        ready = threading.Event()
        failure: list[BaseException] = []

        def run() -> None:
            loop = asyncio.new_event_loop()
            self._loop = loop
            asyncio.set_event_loop(loop)
            try:
                loop.run_until_complete(self._start())
            except BaseException as e:  # reported to start()'s caller
                failure.append(e)
                ready.set()
                return
            ready.set()
            loop.run_forever()
            loop.close()

        self._thread = threading.Thread(target=run, name="pymodbus-peer", daemon=True)
        self._thread.start()
        if not ready.wait(10):
            raise TimeoutError("pymodbus server did not start")
        if failure:
            raise failure[0]
        if self.port.startswith("socket://"):
            wait_for_tcp(int(self.port.rsplit(":", 1)[1]))
        return self

    def stop(self) -> None:
        loop, server = self._loop, self._server
        if loop is None or self._thread is None:
            return
        if server is not None:
            asyncio.run_coroutine_threadsafe(server.shutdown(), loop).result(10)
        loop.call_soon_threadsafe(loop.stop)
        self._thread.join(10)
        self._loop = self._thread = self._server = None

    def __enter__(self) -> "ModbusPeer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


_PEER_PROCESS = """
import json, sys
sys.path.insert(0, sys.argv[1])
from helpers.modbus_peer import ModbusPeer
peer = ModbusPeer(sys.argv[2], **json.loads(sys.argv[3])).start()
print("ready", flush=True)
sys.stdin.read()  # serve until the parent closes stdin (or dies)
peer.stop()
"""


class PeerProcess:
    """ModbusPeer in a process of its own, as a slave is on a real line. A
    master scanning free-running (scan_ms=0) in this process holds the GIL
    so much that an in-process pymodbus thread answers late, or after the
    250 ms timeout (measured: about 60 transactions/s and a few timeouts per
    thousand, against about 1,900/s and none with the server in another
    process)."""

    def __init__(self, port: str, registers: list[int] | None = None, **options) -> None:
        here = str(Path(__file__).resolve().parents[1])  # the tests directory, where the helpers package is
        if registers is not None:
            options["registers"] = registers
        self.proc = subprocess.Popen([sys.executable, "-c", _PEER_PROCESS, here, port, json.dumps(options)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        if self.proc.stdout.readline().strip() != "ready":
            self.stop()
            raise RuntimeError(f"the pymodbus process did not start on {port} (status {self.proc.returncode})")

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self.proc.stdout.close()
