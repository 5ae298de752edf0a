"""Building OPCUAS apps for tests: an app directory with MODULES.LST,
OPCUAS.XML and a ladder file, scanned by a Runner in a thread of the test
process (the server is its own process either way), and asyncua's Client
to talk to it.

``register`` makes the OPCUAS entry point visible where the installed
distribution's metadata predates it (an editable install made before
pyproject.toml listed OPCUAS): a dist-info on sys.path, as test_tlm.py
installs its DEMO module, and on PYTHONPATH for a ``softplc`` subprocess;
once the project is installed again it does nothing."""

from __future__ import annotations

import asyncio
import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

from softplc_lite.tlm.registry import installed

from helpers.apps import make_app
from helpers.modbtcps_apps import Apps, Running
from helpers.modbus_peer import free_tcp_port

LADDER = """SYMBOL Count N7:5
SYMBOL Speed F8:1
SYMBOL Note ST9:0
SYMBOL Run B3:0/4
SYMBOL Dwell T4:0
SYMBOL Total L12:0
ADD N7:5 1 N7:5
XIC B3:0/4 OTE O:0/1
TON T4:0 0.01 500 0
MOV 70000 L12:0
MOV 2.5 F8:1
MOV ST9:0.LEN N7:48
"""


def register() -> None:
    """Make the OPCUAS entry point visible to this process and the
    ``softplc`` processes it starts, where the installed distribution's
    metadata predates it; nothing where it is installed. Called once by
    conftest.py; the directory goes when the process ends."""
    if "OPCUAS" in installed():
        return
    site = Path(tempfile.mkdtemp(prefix="softplc-opcuas-entry-"))
    atexit.register(shutil.rmtree, site, True)
    info = site / "softplc_opcuas_entry-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: softplc-opcuas-entry\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[softplc_lite.tlms]\nOPCUAS = softplc_lite.tlm.opcuas:OpcUaServer\n")
    sys.path.insert(0, str(site))
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(site), os.environ.get("PYTHONPATH")) if p)


def opcuas_xml(port: int | None = None, **root: object) -> str:
    attrs = {"port": port or free_tcp_port(), "status": "N40:0", **root}
    text = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return f'<?xml version="1.0"?>\n<OpcUaServer {text}/>\n'


class OpcUaApps(Apps):
    """OPCUAS apps started by a test, each stopped after it."""

    def write(self, directory: Path, xml: str | None, ladder: str) -> Path:
        return make_app(directory, ladder, MODULES_LST="OPCUAS\n", OPCUAS_XML=xml or opcuas_xml())

    def start(self, xml: str | None = None, ladder: str = LADDER, **kw) -> Running:
        return super().start(xml, ladder, module="OPCUAS", **kw)


def client_run(port: int, work, timeout: float = 30.0):
    """``await work(client)`` with an asyncua Client connected to the server on ``port``."""
    from asyncua import Client

    async def main():
        client = Client(f"opc.tcp://127.0.0.1:{port}/", timeout=timeout)
        client.session_timeout = 600_000  # what asyncua's server grants at most: no warning that it cut it
        async with client:
            return await work(client)

    return asyncio.run(main())
