"""The running OPCUAS server secured as OPCUAS.XML says (docs/opcuas.md,
"Security"), through a real app's server process and asyncua's Client: by
default an encrypted session of a ``write`` user writes a <Writable> word,
which lands through the scan; an anonymous session on the same server
reads, and its write is refused (BadUserAccessDenied) and counted; a wrong
password is refused and counted; a client asking SecurityPolicy None finds
no endpoint. One server for all of it: each start costs seconds."""

from __future__ import annotations

import asyncio

import pytest

from softplc_lite.tlm.opcuas.users import FILE_NAME, Users

from helpers.opcua_apps import OpcUaApps, client_run, opcuas_xml, secure_app

asyncua = pytest.importorskip("asyncua")
from asyncua import Client, ua  # noqa: E402

NS = "urn:softplc-lite:opcuas"


def test_a_write_user_writes_anonymous_reads_and_none_is_refused(tmp_path):
    apps = OpcUaApps(tmp_path)
    xml = opcuas_xml(securityNone="no").replace("/>\n", '>\n  <Writable address="N7:0"/>\n</OpcUaServer>\n')
    app = apps.write(tmp_path / "plant", xml, "ADD N7:5 1 N7:5\n")
    secure_app(app, trust_client=False)  # the client's certificate encrypts; it gives no right to write
    users = Users()
    users.set("operator", "a long passphrase", can_write=True)
    users.save(app / FILE_NAME)
    from helpers.modbtcps_apps import Running
    r = Running(app, module="OPCUAS")
    apps.running.append(r)
    try:
        async def write(client, value):
            ns = await client.get_namespace_index(NS)
            node = client.get_node(f"ns={ns};s=N7:0")
            try:
                await node.write_value(ua.DataValue(ua.Variant(value, ua.VariantType.Int16)))
            except ua.UaStatusCodeError as e:
                return type(e).__name__
            return await node.read_value()

        assert client_run(r.port, lambda c: write(c, 321), secure=True, user="operator",
                          password="a long passphrase") == 321
        assert r.read("N7:0") == 321  # through the scan
        assert client_run(r.port, lambda c: write(c, 5), secure=True) == "BadUserAccessDenied"
        assert r.read("N7:0") == 321
        r.wait_for(lambda: r.status(8) == 1, "the anonymous write counted in status word 8")

        with pytest.raises(ua.UaStatusCodeError) as bad:
            client_run(r.port, lambda c: write(c, 6), secure=True, user="operator", password="a guess")
        assert type(bad.value).__name__ == "BadUserAccessDenied"
        r.wait_for(lambda: r.status(11) == 1, "the refused password counted in status word 11")

        async def plain():  # past asyncua's Client, which would not even ask: the server itself refuses
            client = Client(f"opc.tcp://127.0.0.1:{r.port}/", timeout=10)
            await client.connect_socket()
            try:
                await client.send_hello()
                await client.open_secure_channel()  # a None channel serves GetEndpoints (OPC 10000-4 5.4.4)
                endpoints = await client.get_endpoints()
                params = ua.CreateSessionParameters(
                    ClientDescription=ua.ApplicationDescription(ApplicationUri="urn:example:plain",
                                                                ApplicationType=ua.ApplicationType.Client),
                    EndpointUrl=client.server_url.geturl(), SessionName="plain", ClientNonce=b"0" * 32,
                    RequestedSessionTimeout=60_000, MaxResponseMessageSize=0)
                await client.uaclient.create_session(params)
                return "session created"
            except ua.UaStatusCodeError as e:
                return {e.__class__.__name__, *{p.SecurityPolicyUri.rsplit("#", 1)[-1] for p in endpoints}}
            finally:
                client.disconnect_socket()
        assert asyncio.run(plain()) == {"BadSecurityPolicyRejected", "Basic256Sha256", "Aes128_Sha256_RsaOaep",
                                        "Aes256_Sha256_RsaPss"}
        r.wait_for(lambda: r.status(11) == 2, "the None session counted in status word 11")
        r.wait_for(lambda: r.status(14) >= 2, "every refusal summed in status word 14")
    finally:
        apps.close()


def test_sign_and_trusted_clients_only_as_the_config_says(tmp_path):
    """securitySign="yes" offers Sign beside SignAndEncrypt, and a trusted
    client writes on a Sign channel; trustedClientsOnly="yes" refuses a
    client whose certificate is not in OPCUAS.PKI/trusted/ at its session
    (BadCertificateUntrusted), counted in status word 11."""
    from helpers.opcua_apps import certificates
    from helpers.opcuas_security import client_cert, secure_client

    apps = OpcUaApps(tmp_path)
    xml = opcuas_xml(securityNone="no", securitySign="yes", trustedClientsOnly="yes").replace(
        "/>\n", '>\n  <Writable address="N7:0"/>\n</OpcUaServer>\n')
    r = apps.start(xml, ladder="ADD N7:5 1 N7:5\n", secure=True)
    url = f"opc.tcp://127.0.0.1:{r.port}/"
    base = certificates()
    stranger = client_cert(tmp_path, "stranger")

    async def work():
        modes = {e.SecurityMode for e in await Client(url).connect_and_get_server_endpoints()}
        client = await secure_client(url, base / "client_cert.der", base / "client_key.pem",
                                     mode=ua.MessageSecurityMode.Sign)
        async with client:
            ns = await client.get_namespace_index(NS)
            node = client.get_node(f"ns={ns};s=N7:0")
            await node.write_value(ua.DataValue(ua.Variant(44, ua.VariantType.Int16)))
            written = await node.read_value()
        untrusted = await secure_client(url, *stranger)
        try:
            await untrusted.connect()
            refused = "connected"
        except ua.UaStatusCodeError as e:
            refused = type(e).__name__
        finally:
            untrusted.disconnect_socket()
        return modes, written, refused

    try:
        modes, written, refused = asyncio.run(work())
        assert modes == {ua.MessageSecurityMode.Sign, ua.MessageSecurityMode.SignAndEncrypt}
        assert written == 44 and r.read("N7:0") == 44
        assert refused == "BadCertificateUntrusted"
        r.wait_for(lambda: r.status(11) == 1, "the untrusted client counted in status word 11")
    finally:
        apps.close()
