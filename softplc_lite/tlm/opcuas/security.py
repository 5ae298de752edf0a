"""The OPC UA server's security: its certificate, the client certificates it
trusts, and the policy an asyncua ``Server`` is given (docs/opcuas.md,
"Security").

Where things are (a choice: beside the config, as ``OPCUAS.USERS`` is, so
an app's security travels with it and a test's copy of an app has its own)::

    APP/OPCUAS.PKI/server_cert.der   the server's certificate (DER)
    APP/OPCUAS.PKI/server_key.pem    its private key (PEM, mode 0600; the directory 0700)
    APP/OPCUAS.PKI/trusted/          client certificates trusted to write (DER or PEM)

The policy :func:`apply_security` sets:

* endpoints Basic256Sha256, Aes128_Sha256_RsaOaep and Aes256_Sha256_RsaPss
  (the policies OPC 10000-7 profiles as current), SignAndEncrypt; Sign too
  only if the settings allow it; SecurityPolicy None only if they allow it
  (with no certificate then, None is all there is, and no password is taken
  over it);
* a client's application certificate passes asyncua's basic checks (valid
  now, its URI the client's ApplicationUri); with ``trusted_clients_only``
  it must also be one of ``trusted/``;
* identities: anonymous (if allowed), user name and password from the
  user file, a certificate. Anonymous sessions and ``read`` users may do
  everything but Write; ``write`` users and sessions whose certificate
  (the identity token's, else the channel's) is one of ``trusted/`` may
  write. A wrong password or an untrusted certificate identity is refused
  (BadUserAccessDenied). Trust is the exact certificate, not a CA chain (a
  choice: a PLC's few clients are each known).

asyncua touches beyond its Server's public methods (kept to these):
``server.iserver.set_user_manager`` (the Server constructor is the only
other way in, and the glue builds the Server), and the permission ruleset
protocol of ``asyncua.crypto.permission_rules`` (``check_validity`` and the
request type lists ``USER_TYPES``) with its ``User``/``UserRole``.
"""

from __future__ import annotations

import asyncio
import os
import socket
from dataclasses import dataclass, field
from pathlib import Path

from ...errors import file_error
from ..errors import ModuleError
from .users import Users

DIR_NAME = "OPCUAS.PKI"
CERT_NAME, KEY_NAME, TRUSTED_NAME = "server_cert.der", "server_key.pem", "trusted"
DAYS = 3650  # a choice: a PLC's certificate outlives a web server's; replacing it means re-trusting it everywhere


@dataclass(frozen=True)
class CertPaths:
    """Where the server's certificate, its key and the trusted clients are."""

    cert: Path
    key: Path
    trusted: Path

    @classmethod
    def for_app(cls, app_dir: str | os.PathLike[str]) -> "CertPaths":
        base = Path(app_dir) / DIR_NAME
        return cls(base / CERT_NAME, base / KEY_NAME, base / TRUSTED_NAME)


@dataclass(frozen=True)
class SecuritySettings:
    """What the config may loosen; the defaults are the secure ones."""

    allow_none: bool = False          # an endpoint with SecurityPolicy None
    allow_sign: bool = False          # Sign-only endpoints beside SignAndEncrypt
    anonymous: bool = True            # anonymous sessions (read only)
    trusted_clients_only: bool = False  # refuse a channel whose certificate is not in trusted/


class SecurityError(ModuleError):
    """The server cannot be secured as configured (no certificate, a bad
    trusted certificate file): located at the file concerned."""


def application_uri(app_name: str, hostname: str | None = None) -> str:
    """The default ApplicationUri of an app's server: unique per host and app
    (OPC 10000-4 7.2 asks a globally unique URI)."""
    return f"urn:{hostname or socket.gethostname()}:softplc_lite:{app_name}"


def create_certificate(cert_path: Path, key_path: Path, uri: str, common_name: str,
                       hostname: str | None = None, days: int = DAYS, client: bool = False) -> None:
    """A new RSA 2048 key and a self-signed application instance certificate
    for it, the ApplicationUri in its SubjectAltName (OPC 10000-6 6.2.2),
    the host's name and 127.0.0.1 beside it. ``client``: for a client
    application (tests, examples) rather than a server."""
    import ipaddress

    from asyncua.crypto import cert_gen
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import Encoding
    from cryptography.x509.oid import ExtendedKeyUsageOID

    host = hostname or socket.gethostname()
    key = cert_gen.generate_private_key()
    names = [x509.UniformResourceIdentifier(uri), x509.DNSName(host),
             x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]
    usage = [ExtendedKeyUsageOID.CLIENT_AUTH] if client else [ExtendedKeyUsageOID.SERVER_AUTH,
                                                              ExtendedKeyUsageOID.CLIENT_AUTH]
    cert = cert_gen.generate_self_signed_app_certificate(key, common_name, {}, names, extended=usage, days=days)
    _write_private(key_path, cert_gen.dump_private_key_as_pem(key))
    _write(cert_path, cert.public_bytes(Encoding.DER))


def _write_private(path: Path, data: bytes) -> None:
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    _write(path, data, 0o600)


def _write(path: Path, data: bytes, mode: int = 0o644) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, mode)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(temp, mode)  # os.open's mode is masked by the umask; the key's must not be
        os.replace(temp, path)
    except OSError as e:
        temp.unlink(missing_ok=True)
        raise file_error(e, path, "write") from None


def load_certificate(path: Path):
    """An x509 certificate from a DER or PEM file; SecurityError when not one."""
    from cryptography import x509
    try:
        data = path.read_bytes()
    except OSError as e:
        raise file_error(e, path) from None
    try:
        return x509.load_pem_x509_certificate(data) if data.lstrip().startswith(b"-----BEGIN") \
            else x509.load_der_x509_certificate(data)
    except ValueError:
        raise SecurityError("expected an X.509 certificate in DER or PEM form", str(path)) from None


def certificate_uri(cert) -> str | None:
    """The ApplicationUri a certificate names in its SubjectAltName."""
    from cryptography import x509
    try:
        san = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    except x509.ExtensionNotFound:
        return None
    uris = san.get_values_for_type(x509.UniformResourceIdentifier)
    return uris[0] if uris else None


def trusted_certificates(directory: Path) -> set[bytes]:
    """The DER bytes of every certificate in ``directory`` (none when it is
    absent); SecurityError naming a file that is not a certificate."""
    from cryptography.hazmat.primitives.serialization import Encoding
    if not directory.is_dir():
        return set()
    return {load_certificate(p).public_bytes(Encoding.DER)
            for p in sorted(directory.iterdir()) if p.is_file() and not p.name.startswith(".")}


# --- the roles a session has -------------------------------------------------------------

def user_can_write(user) -> bool:
    """Whether a session's user (asyncua's ``User``, as a server callback or
    ``session.user`` has it) may write: a ``write`` user or a trusted
    certificate. None (no session yet) may not."""
    from asyncua.crypto.permission_rules import UserRole
    return user is not None and user.role in (UserRole.User, UserRole.Admin)


def role_of(user) -> str:
    """``anonymous``, ``read`` or ``write``: what a session may do, as the
    watch view and the refusal counts name it."""
    if user_can_write(user):
        return "write"
    return "read" if user is not None and user.name else "anonymous"


@dataclass
class UserManager:
    """asyncua's user manager protocol (``get_user``): a session's identity
    from its token; None refuses the session (BadUserAccessDenied)."""

    users: Users
    trusted: set[bytes]
    settings: SecuritySettings
    refused: dict[str, int] = field(default_factory=lambda: {"password": 0, "anonymous": 0, "certificate": 0})
    checked: dict = field(default_factory=dict)  # (name, password): the entry a check aside found, until taken

    async def check_aside(self, username: str, password: str) -> tuple[str, str]:
        """Check a password in a thread (scrypt: some 50 ms of CPU that
        ``get_user``, which asyncua calls on its event loop, would take
        there, stopping every client's service meanwhile); ``get_user`` takes
        the result. The key to ``forget`` it by once the session is answered."""
        key = (username, password)
        self.checked[key] = await asyncio.to_thread(self.users.check, username, password)
        return key

    def forget(self, key: tuple[str, str]) -> None:
        self.checked.pop(key, None)

    def get_user(self, iserver, username=None, password=None, certificate=None):
        from asyncua.crypto.permission_rules import User, UserRole
        if username is not None:
            key = (username, password)
            entry = self.checked.pop(key) if key in self.checked else self.users.check(username, password)
            if entry is None:
                self.refused["password"] += 1
                return None
            return User(role=UserRole.User if entry.can_write else UserRole.Anonymous, name=entry.name)
        der = _der(certificate)
        if der is not None and der in self.trusted:
            return User(role=UserRole.User, name=f"certificate {_common_name(der)}")
        if not self.settings.anonymous:
            self.refused["anonymous" if der is None else "certificate"] += 1
            return None
        return User(role=UserRole.Anonymous)


def _der(certificate) -> bytes | None:
    if certificate is None or isinstance(certificate, bytes):
        return certificate or None
    from cryptography.hazmat.primitives.serialization import Encoding
    return certificate.public_bytes(Encoding.DER)


def _common_name(der: bytes) -> str:
    from cryptography import x509
    from cryptography.x509.oid import NameOID
    names = x509.load_der_x509_certificate(der).subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(names[0].value) if names else "(no common name)"


def _ruleset(refuse_writes: bool):
    """asyncua's SimpleRoleRuleset with anonymous and ``read`` sessions
    (UserRole.Anonymous) allowed every user request but Write (unless the
    caller refuses those writes itself), and no session the Admin requests
    (adding or deleting nodes)."""
    from asyncua import ua
    from asyncua.crypto.permission_rules import USER_TYPES, PermissionRuleset, UserRole

    allowed = {ua.NodeId(t) for t in USER_TYPES}
    write = ua.NodeId(ua.ObjectIds.WriteRequest_Encoding_DefaultBinary)
    reading = allowed - {write} if refuse_writes else allowed

    class ReadOnlyAnonymous(PermissionRuleset):
        def check_validity(self, user, action_type_id, body):
            role = user.role if user is not None else UserRole.Anonymous
            return action_type_id in (reading if role is UserRole.Anonymous else allowed)
    return ReadOnlyAnonymous()


def _validator(trusted: set[bytes], settings: SecuritySettings):
    from asyncua import ua
    from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
    from asyncua.ua.uaerrors import BadCertificateUntrusted
    from cryptography.hazmat.primitives.serialization import Encoding

    basic = CertificateValidator(CertificateValidatorOptions.BASIC_VALIDATION | CertificateValidatorOptions.PEER_CLIENT)

    async def validate(cert, app_description: ua.ApplicationDescription) -> None:
        await basic.validate(cert, app_description)
        if settings.trusted_clients_only and cert.public_bytes(Encoding.DER) not in trusted:
            raise BadCertificateUntrusted()
    return validate


def policy_types(settings: SecuritySettings, have_certificate: bool) -> list:
    """The endpoints' asyncua SecurityPolicyTypes for ``settings``."""
    from asyncua import ua
    t = ua.SecurityPolicyType
    types = []
    if have_certificate:
        types += [t.Basic256Sha256_SignAndEncrypt, t.Aes128Sha256RsaOaep_SignAndEncrypt,
                  t.Aes256Sha256RsaPss_SignAndEncrypt]
        if settings.allow_sign:
            types += [t.Basic256Sha256_Sign, t.Aes128Sha256RsaOaep_Sign, t.Aes256Sha256RsaPss_Sign]
    if settings.allow_none:
        types.append(t.NoSecurity)
    return types


async def apply_security(server, settings: SecuritySettings, users: Users, paths: CertPaths,
                         refuse_writes: bool = True) -> UserManager:
    """Give an asyncua Server (after ``await server.init()``, before
    ``start()``) this module's policy: its certificate and key, its
    ApplicationUri the certificate's, the endpoints, identities and
    permissions above. The UserManager returned counts refused identities
    (``refused``).

    ``refuse_writes``: a Write request of a session that may not write is
    refused whole here (a ServiceFault BadUserAccessDenied). False leaves
    it to the caller's write handler, which then asks :func:`user_can_write`
    of the session's user and answers BadUserAccessDenied per item (and can
    count each refusal).

    SecurityError when there is no certificate and None is not allowed, or
    a trusted file is not a certificate."""
    from asyncua import ua

    have = paths.cert.exists() and paths.key.exists()
    if not have and not settings.allow_none:
        raise SecurityError(f"no server certificate {paths.cert.name} and key {paths.key.name} here: "
                            "`softplc opcua-cert APP` makes them", str(paths.cert.parent))
    if have:
        cert = load_certificate(paths.cert)
        uri = certificate_uri(cert)
        if uri is None:
            raise SecurityError("expected the ApplicationUri in the certificate's SubjectAltName "
                                "(OPC 10000-6 6.2.2)", str(paths.cert))
        await server.load_certificate(str(paths.cert))
        try:
            key = paths.key.read_bytes()
        except OSError as e:
            raise file_error(e, paths.key) from None
        try:
            await server.load_private_key(key, format="pem" if key.lstrip().startswith(b"-----BEGIN") else "der")
        except (ValueError, TypeError):
            raise SecurityError("expected a private key in PEM or DER form", str(paths.key)) from None
        await server.set_application_uri(uri)
    trusted = trusted_certificates(paths.trusted)
    server.set_security_policy(policy_types(settings, have), permission_ruleset=_ruleset(refuse_writes))
    tokens = [ua.AnonymousIdentityToken] if settings.anonymous else []
    if have:  # a password or a certificate identity only where it is not sent in clear
        tokens += [ua.UserNameIdentityToken, ua.X509IdentityToken]
    server.set_identity_tokens(tokens)
    server.set_certificate_validator(_validator(trusted, settings))
    manager = UserManager(users, trusted, settings)
    server.iserver.set_user_manager(manager)
    return manager
