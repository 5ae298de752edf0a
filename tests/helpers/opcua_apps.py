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
    """An OPCUAS.XML for a test: SecurityPolicy None allowed (the tests that
    are not about security read anonymously, without certificates)."""
    attrs = {"port": port or free_tcp_port(), "status": "N40:0", "securityNone": "yes", **root}
    text = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return f'<?xml version="1.0"?>\n<OpcUaServer {text}/>\n'


class OpcUaApps(Apps):
    """OPCUAS apps started by a test, each stopped after it."""

    secure = False  # the next app gets the server certificate and trusts the test client's (secure_app)

    def write(self, directory: Path, xml: str | None, ladder: str) -> Path:
        app = make_app(directory, ladder, MODULES_LST="OPCUAS\n", OPCUAS_XML=xml or opcuas_xml())
        if self.secure:
            secure_app(app)
        return app

    def start(self, xml: str | None = None, ladder: str = LADDER, secure: bool = False, **kw) -> Running:
        self.secure = secure
        return super().start(xml, ladder, module="OPCUAS", **kw)


_CERTS: list[Path] = []  # a directory holding a server's and a client's certificates, made once a process


def certificates() -> Path:
    """A directory with a server certificate (OPCUAS.PKI/) and a client
    certificate, made once a process (an RSA key costs a fraction of a second)."""
    if not _CERTS:
        from softplc_lite.tlm.opcuas.security import CertPaths, create_certificate

        from helpers.opcuas_security import client_cert
        base = Path(tempfile.mkdtemp(prefix="softplc-opcuas-certs-"))
        atexit.register(shutil.rmtree, base, True)
        paths = CertPaths.for_app(base)
        create_certificate(paths.cert, paths.key, "urn:example:softplc-test-server", "test server", "localhost", 2)
        client_cert(base)
        _CERTS.append(base)
    return _CERTS[0]


def secure_app(app_dir: Path, trust_client: bool = True) -> None:
    """Give an app the server certificate; ``trust_client``: and the test
    client's certificate in OPCUAS.PKI/trusted/ (so its sessions may write)."""
    base = certificates()
    shutil.copytree(base / "OPCUAS.PKI", app_dir / "OPCUAS.PKI", dirs_exist_ok=True)
    if trust_client:
        (app_dir / "OPCUAS.PKI" / "trusted").mkdir(exist_ok=True)
        shutil.copy(base / "client_cert.der", app_dir / "OPCUAS.PKI" / "trusted" / "client_cert.der")


def client_run(port: int, work, timeout: float = 30.0, secure: bool = False, user: str | None = None,
               password: str | None = None):
    """``await work(client)`` with an asyncua Client connected to the server on
    ``port``; ``secure``: on a Basic256Sha256 SignAndEncrypt channel with the
    test client's certificate (``secure_app`` trusts it), as ``user`` if named."""
    from asyncua import Client

    async def main():
        if secure:
            from helpers.opcuas_security import secure_client
            base = certificates()
            client = await secure_client(f"opc.tcp://127.0.0.1:{port}/", base / "client_cert.der",
                                         base / "client_key.pem", user=user, password=password)
            client.session_timeout = 600_000
            async with client:
                return await work(client)
        client = Client(f"opc.tcp://127.0.0.1:{port}/", timeout=timeout)
        client.session_timeout = 600_000  # what asyncua's server grants at most: no warning that it cut it
        async with client:
            return await work(client)

    return asyncio.run(main())
