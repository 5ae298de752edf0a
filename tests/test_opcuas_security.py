"""The OPC UA server's security policy (softplc_lite/tlm/opcuas/security.py)
on a plain asyncua Server, with asyncua's Client on real sockets: which
channels and identities are let in, and what each may do."""

from __future__ import annotations

import asyncio
import shutil
import stat

import pytest
from asyncua import Client, ua
from asyncua.crypto.security_policies import SecurityPolicyAes128Sha256RsaOaep, SecurityPolicyAes256Sha256RsaPss
from asyncua.ua.uaerrors import BadUserAccessDenied, UaError, UaStatusCodeError
from cryptography import x509

from helpers.cli import softplc_here
from helpers.opcuas_security import ServedInThread, client_cert, secure_client, secured_server
from softplc_lite.tlm.opcuas.security import CertPaths, SecurityError, SecuritySettings, certificate_uri, role_of, \
    user_can_write
from softplc_lite.tlm.opcuas.users import Users

PASSWORD = "correct horse battery"
# The tests of the default settings share one server (``shared``), which trusts one client
# certificate and knows the users of ``users()``; each counts from what it found.
pytestmark = pytest.mark.xdist_group("opcuas_security")


@pytest.fixture(scope="module")
def made_app(tmp_path_factory):
    """An app directory with a server certificate made by the command, once a
    module (a command's run and an RSA key cost a second)."""
    app = tmp_path_factory.mktemp("pki") / "tank"
    app.mkdir()
    proc = softplc_here("opcua-cert", str(app), "--uri", "urn:example:tank")
    assert proc.returncode == 0, proc.stderr
    return app


@pytest.fixture
def app(tmp_path, made_app):
    """A test's own copy of ``made_app`` (modes kept: the key stays 0600)."""
    app = tmp_path / "tank"
    shutil.copytree(made_app, app)
    return app


def users() -> Users:
    u = Users()
    u.set("operator", PASSWORD, can_write=True)
    u.set("viewer", PASSWORD, can_write=False)
    return u


@pytest.fixture(scope="module")
def trusted(tmp_path_factory):
    """(certificate, key) of the client ``shared`` trusts."""
    return client_cert(tmp_path_factory.mktemp("trusted"), "scada")


@pytest.fixture(scope="module")
def shared(made_app, trusted, tmp_path_factory):
    """A secured server of the default settings, for every test of them."""
    app = tmp_path_factory.mktemp("shared") / "tank"
    shutil.copytree(made_app, app)
    (CertPaths.for_app(app).trusted / "scada.der").write_bytes(trusted[0].read_bytes())
    server = ServedInThread(app, users=users())
    yield server.served
    server.close()


async def _write(client: Client, node: ua.NodeId, value: int) -> None:
    await client.get_node(node).write_value(ua.DataValue(ua.Variant(value, ua.VariantType.Int16)))


def test_the_cert_command_makes_a_certificate_asyncua_serves(made_app, shared):
    paths = CertPaths.for_app(made_app)
    cert = x509.load_der_x509_certificate(paths.cert.read_bytes())
    assert certificate_uri(cert) == "urn:example:tank"
    assert stat.S_IMODE(paths.key.stat().st_mode) == 0o600
    assert paths.trusted.is_dir()

    found = asyncio.run(Client(shared.url).connect_and_get_server_endpoints())
    assert {(e.SecurityPolicyUri.rsplit("#")[-1], e.SecurityMode) for e in found} == {
        (p, ua.MessageSecurityMode.SignAndEncrypt) for p in ("Basic256Sha256", "Aes128_Sha256_RsaOaep",
                                                             "Aes256_Sha256_RsaPss")}
    assert all(e.ServerCertificate == paths.cert.read_bytes() for e in found)
    assert {e.Server.ApplicationUri for e in found} == {"urn:example:tank"}


def test_the_cert_command_keeps_a_certificate_unless_forced(app):
    before = CertPaths.for_app(app).cert.read_bytes()
    again = softplc_here("opcua-cert", str(app))
    assert again.returncode == 1 and "--force" in again.stderr
    assert CertPaths.for_app(app).cert.read_bytes() == before
    assert softplc_here("opcua-cert", str(app), "--force").returncode == 0
    assert CertPaths.for_app(app).cert.read_bytes() != before


@pytest.mark.parametrize("policy", [None, SecurityPolicyAes128Sha256RsaOaep, SecurityPolicyAes256Sha256RsaPss],
                         ids=["Basic256Sha256", "Aes128_Sha256_RsaOaep", "Aes256_Sha256_RsaPss"])
def test_an_encrypted_anonymous_session_reads_and_is_refused_writes(shared, tmp_path, policy):
    cert, key = client_cert(tmp_path)

    async def session():
        async with await secure_client(shared.url, cert, key, policy) as client:
            value = await client.get_node(shared.node).read_value()
            with pytest.raises(BadUserAccessDenied):
                await _write(client, shared.node, value + 1)
            return value, await client.get_node(shared.node).read_value(), shared.readers[-1]
    before, after, user = asyncio.run(session())
    assert before == after
    assert role_of(user) == "anonymous" and not user_can_write(user)


def test_writes_can_be_left_to_the_servers_own_write_handler(app, tmp_path):
    """refuse_writes=False: the ruleset lets an anonymous Write through to
    the server's handler (here asyncua's own, which writes), which must then
    ask user_can_write itself."""
    cert, key = client_cert(tmp_path)

    async def session():
        async with secured_server(app, refuse_writes=False) as served:
            async with await secure_client(served.url, cert, key) as client:
                await _write(client, served.node, 3)
                return await client.get_node(served.node).read_value(), served.readers[-1]
    value, user = asyncio.run(session())
    assert value == 3 and not user_can_write(user)


def test_a_write_user_writes_and_a_read_user_reads(shared, tmp_path):
    cert, key = client_cert(tmp_path)
    seen = len(shared.readers)

    async def sessions():
        async with await secure_client(shared.url, cert, key, user="operator", password=PASSWORD) as client:
            await _write(client, shared.node, 42)
            wrote = await client.get_node(shared.node).read_value()
        async with await secure_client(shared.url, cert, key, user="viewer", password=PASSWORD) as client:
            with pytest.raises(BadUserAccessDenied):
                await _write(client, shared.node, 1)
            read = await client.get_node(shared.node).read_value()
        return wrote, read, [role_of(u) for u in shared.readers[seen:]]
    wrote, read, roles = asyncio.run(sessions())
    assert (wrote, read) == (42, 42)
    assert roles == ["write", "read"]


@pytest.mark.parametrize("name,password", [("operator", "wrong password"), ("nobody", PASSWORD)])
def test_a_wrong_password_or_an_unknown_user_is_refused(shared, tmp_path, name, password):
    cert, key = client_cert(tmp_path)
    refused = shared.manager.refused["password"]

    async def session():
        client = await secure_client(shared.url, cert, key, user=name, password=password)
        with pytest.raises(BadUserAccessDenied):
            await client.connect()
        client.disconnect_socket()
        return shared.manager.refused["password"]
    assert asyncio.run(session()) == refused + 1


def test_security_none_is_refused_unless_the_settings_allow_it(app, shared):
    async def read(served):
        client = Client(served.url, timeout=10)
        try:
            async with client:
                return await client.get_node(served.node).read_value()
        except UaError as e:  # asyncua finds no None endpoint to match
            return e

    async def allowed():
        async with secured_server(app, SecuritySettings(allow_none=True)) as served:
            return await read(served)
    refused = asyncio.run(read(shared))
    assert isinstance(refused, UaError) and "No matching endpoints" in str(refused)
    assert asyncio.run(allowed()) == 7


def test_sign_only_is_offered_only_when_allowed(app, shared):
    async def modes(url):
        return {e.SecurityMode for e in await Client(url).connect_and_get_server_endpoints()}

    async def allowed():
        async with secured_server(app, SecuritySettings(allow_sign=True)) as served:
            return await modes(served.url)
    assert asyncio.run(modes(shared.url)) == {ua.MessageSecurityMode.SignAndEncrypt}
    assert asyncio.run(allowed()) == {ua.MessageSecurityMode.SignAndEncrypt, ua.MessageSecurityMode.Sign}


def test_a_trusted_client_certificate_writes(shared, trusted):
    cert, key = trusted

    async def session():
        async with await secure_client(shared.url, cert, key) as client:
            await _write(client, shared.node, 5)
            return await client.get_node(shared.node).read_value(), shared.readers[-1]
    value, user = asyncio.run(session())
    assert value == 5 and role_of(user) == "write" and user.name == "certificate scada"


def test_only_trusted_clients_when_configured(app, tmp_path):
    cert, key = client_cert(tmp_path)

    async def session():
        async with secured_server(app, SecuritySettings(trusted_clients_only=True)) as served:
            client = await secure_client(served.url, cert, key)
            with pytest.raises(UaStatusCodeError) as refused:
                await client.connect()
            client.disconnect_socket()
            return refused.value.code
    assert asyncio.run(session()) == ua.StatusCodes.BadCertificateUntrusted


def test_no_anonymous_when_configured(app, tmp_path):
    cert, key = client_cert(tmp_path)

    async def session():
        async with secured_server(app, SecuritySettings(anonymous=False)) as served:
            client = await secure_client(served.url, cert, key)
            with pytest.raises(UaStatusCodeError) as refused:
                await client.connect()
            client.disconnect_socket()
            return refused.value.code
    assert asyncio.run(session()) == ua.StatusCodes.BadIdentityTokenRejected


def test_no_certificate_is_a_located_error_unless_none_is_allowed(tmp_path):
    async def start(settings):
        async with secured_server(tmp_path, settings) as served:
            return {e.SecurityPolicyUri.rsplit("#")[-1] for e in await Client(served.url).connect_and_get_server_endpoints()}
    with pytest.raises(SecurityError) as missing:
        asyncio.run(start(SecuritySettings()))
    assert "softplc opcua-cert" in missing.value.report() and "OPCUAS.PKI" in missing.value.report()
    assert asyncio.run(start(SecuritySettings(allow_none=True))) == {"None"}


def test_a_trusted_file_that_is_no_certificate_is_named(app):
    bad = CertPaths.for_app(app).trusted / "notes.txt"
    bad.write_text("not a certificate\n")
    with pytest.raises(SecurityError) as error:
        asyncio.run(start_only(app))
    assert error.value.report() == f"{bad}: expected an X.509 certificate in DER or PEM form"


async def start_only(app):
    async with secured_server(app):
        pass


def test_a_password_checked_aside_is_checked_in_another_thread_once():
    # asyncua asks get_user on its event loop; check_aside runs scrypt in a thread before, and
    # get_user takes its result: one derivation, none of it on the loop's thread
    import threading

    from softplc_lite.tlm.opcuas.security import UserManager

    class Counted(Users):
        def check(self, name, password):
            threads.append(threading.get_ident())
            return super().check(name, password)

    threads: list[int] = []
    users = Counted()
    users.set("operator", "a long passphrase", can_write=True)
    manager = UserManager(users, set(), SecuritySettings())

    async def activate(password):
        key = await manager.check_aside("operator", password)
        try:
            return manager.get_user(None, username="operator", password=password), threading.get_ident()
        finally:
            manager.forget(key)

    user, loop_thread = asyncio.run(activate("a long passphrase"))
    assert user is not None and user.name == "operator"
    refused, _ = asyncio.run(activate("a guess"))
    assert refused is None and manager.refused["password"] == 1
    assert len(threads) == 2 and loop_thread not in threads
    assert manager.checked == {}, "no password kept once the session is answered"
