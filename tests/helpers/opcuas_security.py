"""A plain asyncua Server secured by softplc_lite.tlm.opcuas.security, and
asyncua Clients for it, for the security tests (tests/test_opcuas_security.py).

``secured_server(app_dir, settings, users)`` serves one writable Int16
variable on 127.0.0.1 at a port the system picks; it yields a ``Served``
(url, the variable's node id, the UserManager apply_security returned and
the users the server saw read, each as asyncua's User). ``client_cert``
makes a client application certificate in a test's directory."""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from pathlib import Path

from asyncua import Client, Server, ua
from asyncua.common.callback import CallbackType

from softplc_lite.tlm.opcuas.security import CertPaths, SecuritySettings, UserManager, apply_security, \
    create_certificate
from softplc_lite.tlm.opcuas.asyncua_glue import end_clock
from softplc_lite.tlm.opcuas.users import Users

CLIENT_URI = "urn:example:softplc-test-client"


@dataclass
class Served:
    url: str
    node: ua.NodeId
    manager: UserManager
    readers: list = field(default_factory=list)  # asyncua User of each read, in order


@contextlib.asynccontextmanager
async def secured_server(app_dir: Path, settings: SecuritySettings = SecuritySettings(),
                         users: Users | None = None, refuse_writes: bool = True) -> AsyncIterator[Served]:
    server = Server()
    await server.init()
    server.set_endpoint("opc.tcp://127.0.0.1:0/")
    manager = await apply_security(server, settings, users or Users(), CertPaths.for_app(app_dir),
                                   refuse_writes=refuse_writes)
    idx = await server.register_namespace("urn:example:test")
    var = await server.nodes.objects.add_variable(idx, "Level", ua.Variant(7, ua.VariantType.Int16))
    await var.set_writable()
    served = Served("", var.nodeid, manager)

    async def seen(event, _dispatcher) -> None:
        if event.is_external:
            served.readers.append(event.user)
    server.subscribe_server_callback(CallbackType.PreRead, seen)
    await server.start()
    try:
        served.url = f"opc.tcp://127.0.0.1:{server.bserver.port}/"
        yield served
    finally:
        await end_clock(server)  # a stop in milliseconds, not a second (asyncua_glue.end_clock)
        await server.stop()


class ServedInThread:
    """``secured_server`` kept running in a thread of its own (its own event
    loop), so that several tests, each with ``asyncio.run`` of its own
    clients, share one server: a server start costs a second of CPU."""

    def __init__(self, app_dir: Path, settings: SecuritySettings = SecuritySettings(),
                 users: Users | None = None) -> None:
        self.served: Served | None = None
        self.error: BaseException | None = None
        self._ready = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=asyncio.run, args=(self._serve(app_dir, settings, users),),
                                        name="secured-server", daemon=True)
        self._thread.start()
        if not self._ready.wait(30) or self.served is None:
            raise RuntimeError(f"the secured server did not start: {self.error!r}")

    async def _serve(self, app_dir, settings, users) -> None:
        self._loop, self._stop = asyncio.get_running_loop(), asyncio.Event()
        try:
            async with secured_server(app_dir, settings, users) as served:
                self.served = served
                self._ready.set()
                await self._stop.wait()
        except BaseException as e:  # the fixture's caller sees it
            self.error = e
            self._ready.set()

    def close(self) -> None:
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(30)


def client_cert(directory: Path, name: str = "client") -> tuple[Path, Path]:
    """(certificate, key) of a new client application certificate for CLIENT_URI."""
    cert, key = directory / f"{name}_cert.der", directory / f"{name}_key.pem"
    create_certificate(cert, key, CLIENT_URI, name, "localhost", days=2, client=True)
    return cert, key


async def secure_client(url: str, cert: Path, key: Path, policy=None,
                        mode: ua.MessageSecurityMode = ua.MessageSecurityMode.SignAndEncrypt,
                        user: str | None = None, password: str | None = None) -> Client:
    """A Client (not yet connected) on an encrypted channel with ``cert``."""
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
    client = Client(url, timeout=10)
    client.application_uri = CLIENT_URI
    if user is not None:
        client.set_user(user)
        client.set_password(password or "")
    await client.set_security(policy or SecurityPolicyBasic256Sha256, str(cert), str(key), mode=mode)
    return client
