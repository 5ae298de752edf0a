"""Building MODBTCPS apps for tests: an app directory with MODULES.LST,
MODBTCPS.XML and a ladder file, and a Runner scanning it in a thread of the
test process (the server is its own process either way), stopped and closed
after the test."""

from __future__ import annotations

import socket
import struct
import threading
import time
from pathlib import Path

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner

from helpers.modbus_peer import free_tcp_port
from helpers.apps import make_app

LIMIT_S = 15.0  # any one wait; a step normally takes well under a second

UNIT_1 = """
  <Unit id="1">
    <Coils            start="0"   count="40" address="B3/0"   writable="yes"/>
    <Coils            start="100" count="8"  address="O:0/0"/>
    <DiscreteInputs   start="0"   count="20" address="I:0/4"/>
    <HoldingRegisters start="0"   count="20" address="N7:0"   writable="yes"/>
    <HoldingRegisters start="50"  count="5"  address="N7:50"/>
    <HoldingRegisters start="100" count="4"  address="F8:0"   writable="yes"/>
    <HoldingRegisters start="110" count="2"  address="F8:10"  writable="yes" wordOrder="low-high"/>
    <HoldingRegisters start="200" count="2"  address="ST9:0"  writable="yes"/>
    <HoldingRegisters start="400" count="2"  address="ST9:2"  writable="yes" stringFormat="packed"/>
    <InputRegisters   start="0"   count="10" address="N11:0"/>
    <InputRegisters   start="20"  count="2"  address="F8:20"/>
  </Unit>
"""


def server_xml(units: str = UNIT_1, port: int | None = None, **root: object) -> str:
    attrs = {"port": port or free_tcp_port(), "status": "N40:0", **root}
    text = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return f'<?xml version="1.0"?>\n<ModbusTcpServer {text}>\n{units}</ModbusTcpServer>\n'


def write_app(directory: Path, xml: str, ladder: str = "ADD N11:0 1 N11:0\n", modules: str = "MODBTCPS\n",
              extra: dict[str, str] | None = None) -> Path:
    return make_app(directory, ladder, MODULES_LST=modules, MODBTCPS_XML=xml, **(extra or {}))


def raw_request(port: int, pdu: bytes, unit: int = 1) -> bytes:
    """One request as bytes on a new socket (what pymodbus's client refuses
    to send); the reply's PDU. The transaction id must come back."""
    with socket.create_connection(("127.0.0.1", port), timeout=LIMIT_S) as s:
        s.sendall(struct.pack(">HHHB", 7, 0, len(pdu) + 1, unit) + pdu)
        reply = b""
        while len(reply) < 6 or len(reply) < 6 + struct.unpack(">H", reply[4:6])[0]:
            chunk = s.recv(512)
            assert chunk, "the server closed the connection"
            reply += chunk
    assert reply[:2] == b"\x00\x07", "the transaction id comes back"
    return reply[7:]


class Running:
    """A runner scanning in a background thread until ``stop``."""

    def __init__(self, app_dir: Path, realtime: bool = True, scan_ms: int | None = None,
                 module: str = "MODBTCPS") -> None:
        self.app_dir = Path(app_dir)
        app = load_app(app_dir)
        if scan_ms is not None:
            app.settings.scan_ms = scan_ms
        self.runner = Runner(app, RunOptions(realtime=realtime, save_state=False))
        self.engine = self.runner.engine
        self.module = next(m for m in self.engine.modules if m.name == module)
        self.error: BaseException | None = None
        self.stopped = False
        self.thread = threading.Thread(target=self._run, name=f"{module.lower()}-test-runner", daemon=True)
        self.thread.start()
        self.module.wait_until_listening(LIMIT_S)  # the first scan starts the server: the test starts with it up

    def _run(self) -> None:
        try:
            self.runner.run(None)
        except BaseException as e:  # the test sees it in stop()
            self.error = e

    @property
    def port(self) -> int:
        """The port the server listens on (the first scan starts it)."""
        port = self.module.wait_until_listening(LIMIT_S)
        assert port is not None, f"the server is not listening: {self.module.failed}"
        return port

    def read(self, address: str):
        return self.engine.table.read(address)

    def status(self, word: int) -> int:
        return self.engine.table.read(f"N40:{word}")

    def wait_for(self, condition, what: str, limit: float = LIMIT_S) -> None:
        deadline = time.monotonic() + limit
        while not condition():
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out waiting for {what}")
            time.sleep(0.01)

    def stop(self) -> None:
        if self.stopped:
            return
        self.stopped = True
        self.runner.request_stop()
        self.thread.join(LIMIT_S)
        self.runner.close()
        if self.error is not None:
            raise self.error


class Apps:
    """Makes running apps and stops them after the test."""

    def __init__(self, tmp_path: Path) -> None:
        self.tmp_path = tmp_path
        self.running: list[Running] = []
        self.count = 0

    def start(self, xml: str | None = None, ladder: str = "ADD N11:0 1 N11:0\n", **kw) -> Running:
        self.count += 1
        app = self.write(self.tmp_path / f"app{self.count}", xml, ladder)
        r = Running(app, **kw)
        self.running.append(r)
        return r

    def write(self, directory: Path, xml: str | None, ladder: str) -> Path:
        return write_app(directory, xml or server_xml(), ladder)

    def close(self) -> None:
        for r in self.running:
            try:
                r.stop()
            except BaseException:  # the test has failed already, or says so itself
                pass
