"""A third-party Modbus RTU slave for tests and benchmarks: pymodbus's
serial server, run in a background thread with its own asyncio loop.

``port`` is a serial device (one end of a socat pty pair) or
``socket://127.0.0.1:PORT``, where pymodbus listens on TCP with RTU
framing (testing notes). Like a real RS-485 slave it stays silent for
other unit ids (pymodbus would answer those with exception 04).
"""

from __future__ import annotations

import asyncio
import json
import logging
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from pymodbus.server import ModbusSerialServer
from pymodbus.simulator import DataType, SimData, SimDevice

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)


def free_tcp_port() -> int:
    with socket.socket() as s:
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
    """pymodbus's RTU server for unit ``device_id`` with ``registers``
    holding registers (addresses 0..len-1)."""

    def __init__(self, port: str, registers: list[int], device_id: int = 2, baudrate: int = 38400) -> None:
        self.port = port
        self.registers = list(registers)
        self.device_id = device_id
        self.baudrate = baudrate
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._server: ModbusSerialServer | None = None

    def _drop_other_ids(self, sending: bool, pdu):
        if not sending and pdu.dev_id != self.device_id:
            return None  # silence, as on a real multi-drop line
        return pdu

    async def _start(self) -> None:
        device = SimDevice(self.device_id, simdata=[
            SimData(0, values=self.registers, datatype=DataType.REGISTERS)])
        self._server = ModbusSerialServer(device, port=self.port, baudrate=self.baudrate,
                                          trace_pdu=self._drop_other_ids)
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
from modbus_peer import ModbusPeer
peer = ModbusPeer(sys.argv[2], json.loads(sys.argv[3])).start()
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

    def __init__(self, port: str, registers: list[int]) -> None:
        here = str(Path(__file__).resolve().parent)
        self.proc = subprocess.Popen([sys.executable, "-c", _PEER_PROCESS, here, port, json.dumps(registers)],
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
