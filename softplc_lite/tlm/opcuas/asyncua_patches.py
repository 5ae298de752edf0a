"""The patches of asyncua's classes OPCUAS makes, installed once a process
(one server a process): asyncua_glue.py's Listener gives them its counts.
Written against asyncua >=2.1,<2.2, as asyncua_glue.py is (its
``missing()`` checks the methods below exist). They rely on these internals:

- ``UaProcessor._process_message`` and its ``_connection`` (its
  ``security_policy`` and ``_policies``): asyncua opens a channel with
  SecurityPolicy None even where no endpoint offers None (GetEndpoints must
  work on one, OPC 10000-4 5.4.4), and then creates and activates a session
  on it; ``refuse_unoffered`` refuses CreateSession and ActivateSession on a
  channel whose policy and mode no endpoint offers (BadSecurityPolicyRejected);
  ``check_passwords_aside`` reads an ActivateSession's identity token
  (``struct_from_binary`` of the request body, ``Buffer.copy``) and
  decrypts it (``iserver.decrypt_user_token``, the processor's ``session``)
  to check its password in a thread before asyncua's synchronous
  ``activate_session`` asks the user manager (asyncua 2.1 cannot await a
  coroutine ``get_user``);
- ``OPCUAProtocol`` (binary_server_asyncio.py), one connection:
  ``connection_made`` (it closes a connection when its ``clients`` number
  ``iserver.max_connections``: counted first), ``data_received`` and its ``_buffer``, ``transport`` and
  ``processor`` (its ``_limits.max_recv_buffer`` and
  ``_connection.security_token``), ``_process_one_msg``
  and ``_activation_watchdog`` (taken over: after
  ``iserver.max_pending_activation_seconds`` it closes a connection whose
  ``processor.session`` is not ``is_activated()``, counted idle); ``check_transport``
  answers a chunk that is not OPC UA, or that asyncua fails to process,
  with an Error message and closes the connection (OPC 10000-6 7.1.5),
  where asyncua would log it and keep the connection;
- ``MonitoredItemService.datachange_callback`` (and its
  ``_monitored_datachange``, ``_monitored_items``), taken over by
  ``sample_items``: asyncua queues every change of a value whatever the
  item's sampling interval, where OPC 10000-4 5.12.1.2 samples at it; the
  glue gives each item its ``sampler``.
"""

from __future__ import annotations

import asyncio
import struct

from asyncua import ua
from asyncua.server.binary_server_asyncio import OPCUAProtocol
from asyncua.server.monitored_item_service import MonitoredItemService
from asyncua.server.uaprocessor import UaProcessor
from asyncua.ua.ua_binary import struct_from_binary, uatcp_to_binary

# The Listener's counts, by kind: "channel" (a session on an unoffered
# channel), "limit", "malformed", "idle"; each takes the message to log.
# One server a process: the patches below are installed once and count here.
COUNT: dict = {}
_INSTALLED: set = set()  # the patches installed in this process, by name


def _first(name: str) -> bool:
    """True the first time a patch is installed in this process, then False."""
    if name in _INSTALLED:
        return False
    _INSTALLED.add(name)
    return True


def _count(kind: str, message: str) -> None:
    count = COUNT.get(kind)
    if count is not None:
        count(message)


_SESSION_REQUESTS = frozenset((ua.ObjectIds.CreateSessionRequest_Encoding_DefaultBinary,
                               ua.ObjectIds.ActivateSessionRequest_Encoding_DefaultBinary))  # namespace 0


def refuse_unoffered() -> None:
    """Make asyncua refuse a session (BadSecurityPolicyRejected) on a channel
    whose policy and mode no endpoint offers: a None channel serves
    discovery only, unless the config allows None."""
    if not _first("unoffered"):
        return
    original = UaProcessor._process_message

    async def _process_message(self, typeid, requesthdr, seqhdr, body):
        if typeid.Identifier in _SESSION_REQUESTS and typeid.NamespaceIndex == 0:  # every request passes here
            conn = self._connection
            policy, offered = conn.security_policy, getattr(conn, "_policies", None) or []
            if not any(p.matches(policy.URI, policy.Mode) for p in offered):
                _count("channel", f"session refused: {policy.URI.rsplit('#', 1)[-1]} is not offered")
                raise ua.UaStatusCodeError(ua.StatusCodes.BadSecurityPolicyRejected)
        return await original(self, typeid, requesthdr, seqhdr, body)
    UaProcessor._process_message = _process_message


# OPC UA TCP's message types (OPC 10000-6 7.1.2.2), and those whose header holds a SecureChannelId.
MESSAGE_TYPES = frozenset((b"HEL", b"ACK", b"ERR", b"RHE", b"OPN", b"MSG", b"CLO"))
SECURE_TYPES = frozenset((b"OPN", b"MSG", b"CLO"))
CHUNK_TYPES = frozenset((b"F", b"C", b"A"))
CHUNK_HEADER = struct.Struct("<3scI")


def chunk_problem(kind: bytes, chunk: bytes, size: int, limit: int) -> tuple[int, str] | None:
    """What is wrong with a chunk's header (its message type, chunk type and
    size), as (the Error message's status code, why); None if nothing. A
    chunk is bigger than its header (asyncua closes one that is not,
    silently) and no bigger than ``limit``, the receive buffer (0: none)."""
    if kind not in MESSAGE_TYPES or chunk not in CHUNK_TYPES:
        return ua.StatusCodes.BadTcpMessageTypeInvalid, f"not an OPC UA TCP message type: {(kind + chunk)!r}"
    least = 13 if kind in SECURE_TYPES else 9
    if size < least:
        return ua.StatusCodes.BadDecodingError, f"a {kind.decode()} chunk of {size} bytes, under {least}"
    if limit and size > limit:
        return ua.StatusCodes.BadTcpMessageTooLarge, f"a chunk of {size} bytes, over the {limit} bytes buffer"
    return None


def _refuse(protocol, code: int, why: str) -> None:
    """Answer with an Error message and close the connection (OPC 10000-6
    7.1.5: on a fatal error the server sends Error and closes), counted
    malformed."""
    transport = protocol.transport
    if transport is None or transport.is_closing():
        return
    _count("malformed", f"connection closed: {why}")
    transport.write(uatcp_to_binary(ua.MessageType.Error, ua.ErrorMessage(ua.StatusCode(code), why[:4096])))
    transport.close()


def check_transport() -> None:
    """Make asyncua's connections count their refusals and end a malformed
    one as OPC UA says: a connection refused at ``max_connections`` is
    counted (limit); a chunk whose header is not OPC UA's, or that asyncua
    fails to process, is answered with an Error message and closed
    (malformed), where asyncua logs it and keeps the connection open; a
    connection that activates no session within
    ``max_pending_activation_seconds`` is closed and counted (idle). A
    client that only asks for the endpoints and closes is counted as
    nothing."""
    if not _first("transport"):
        return
    original_made, original_received = OPCUAProtocol.connection_made, OPCUAProtocol.data_received
    original_one = OPCUAProtocol._process_one_msg

    def connection_made(self, transport):
        if len(self.clients) >= self.iserver.max_connections:  # asyncua closes it
            _count("limit", f"connection refused: maxSessions={self.iserver.max_connections} reached")
        original_made(self, transport)

    def data_received(self, data):
        if self.transport is None or self.transport.is_closing():
            return
        pending, at = self._buffer + data, 0
        limit = self.processor._limits.max_recv_buffer if self.processor is not None else 0
        while len(pending) - at >= CHUNK_HEADER.size:  # each whole header: asyncua takes whole chunks in turn
            problem = chunk_problem(*CHUNK_HEADER.unpack_from(pending, at), limit)
            if problem is not None:
                self._buffer = b""
                _refuse(self, *problem)
                return
            at += CHUNK_HEADER.unpack_from(pending, at)[2]
        original_received(self, data)

    async def _process_one_msg(self, header, buf):
        try:
            return await original_one(self, header, buf)
        except Exception as e:  # asyncua would log it and go on with the connection
            code = getattr(e, "code", None)
            if not isinstance(code, int):
                code = ua.StatusCodes.BadDecodingError
                if header.MessageType in (b"ACK", b"RHE"):  # a client's Hello is answered, never these
                    code = ua.StatusCodes.BadTcpMessageTypeInvalid
                elif header.MessageType in (b"MSG", b"CLO") and self.processor is not None and \
                        header.ChannelId != self.processor._connection.security_token.ChannelId:
                    code = ua.StatusCodes.BadTcpSecureChannelUnknown
            _refuse(self, code, f"a {header.MessageType.decode('latin-1')} chunk not processed "
                                f"({type(e).__name__}: {str(e)[:200]})")
            return False

    async def _activation_watchdog(self):
        try:
            await asyncio.sleep(self.iserver.max_pending_activation_seconds)
        except asyncio.CancelledError:  # the connection ended before
            return
        session = self.processor.session if self.processor is not None else None
        if (session is None or not session.is_activated()) and self.transport is not None \
                and not self.transport.is_closing():
            _count("idle", f"connection closed: no session activated within "
                           f"{self.iserver.max_pending_activation_seconds:g} s")
            self.transport.close()

    OPCUAProtocol.connection_made = connection_made
    OPCUAProtocol.data_received = data_received
    OPCUAProtocol._process_one_msg = _process_one_msg
    OPCUAProtocol._activation_watchdog = _activation_watchdog


ASIDE: dict = {}  # "manager": the Listener's UserManager, whose password checks run in a thread
_ACTIVATE = ua.ObjectIds.ActivateSessionRequest_Encoding_DefaultBinary


def check_passwords_aside() -> None:
    """Make an ActivateSession with a user name and password check the
    password in a thread before asyncua handles it: asyncua calls the user
    manager's ``get_user`` synchronously, on its event loop, and a password
    costs scrypt's 50 ms of CPU there (20 wrong passwords at once, checked
    there, stop a subscriber's notifications for half a second,
    docs/opcuas.md). The
    token is read and decrypted as asyncua will read it; a token that fails
    to is left to asyncua to refuse."""
    if not _first("aside"):
        return
    original = UaProcessor._process_message

    async def _process_message(self, typeid, requesthdr, seqhdr, body):
        manager = ASIDE.get("manager")
        if manager is None or typeid.Identifier != _ACTIVATE or typeid.NamespaceIndex != 0 or self.session is None:
            return await original(self, typeid, requesthdr, seqhdr, body)
        try:
            token = struct_from_binary(ua.ActivateSessionParameters, body.copy()).UserIdentityToken
            if not isinstance(token, ua.UserNameIdentityToken):
                return await original(self, typeid, requesthdr, seqhdr, body)
            username, password = self.iserver.decrypt_user_token(self.session, token)
        except Exception:  # asyncua refuses it, as it would
            return await original(self, typeid, requesthdr, seqhdr, body)
        key = await manager.check_aside(username, password)
        try:
            return await original(self, typeid, requesthdr, seqhdr, body)  # asyncua's get_user takes the result
        finally:
            manager.forget(key)
    UaProcessor._process_message = _process_message


class Sampler:
    """A monitored item's sampling: its interval (s), when its next sample
    is due (the event loop's time) and the newest change held until then.
    One attribute of asyncua's item holds it (``sampler``): slots keep it
    small, 56 bytes an item where three attributes of their own cost 365."""

    __slots__ = ("interval", "due", "held")

    def __init__(self, interval: float, due: float = 0.0) -> None:
        self.interval, self.due, self.held = interval, due, None


def sample_items() -> None:
    """Make asyncua's monitored items sample at their sampling interval: a
    change that comes sooner than an interval after the last one sampled is
    held, and the newest held is sampled when the interval is up (one
    notification an interval at most, the value current then). Items
    without a ``sampler`` get every scan's change."""
    if not _first("sample"):
        return
    original = MonitoredItemService.datachange_callback

    async def datachange_callback(self, handle, value, error=None):
        if error is None:
            sampler = getattr(self._monitored_items.get(self._monitored_datachange.get(handle)), "sampler", None)
            if sampler is not None:
                loop = asyncio.get_running_loop()
                now = loop.time()
                if now < sampler.due:
                    if sampler.held is None:
                        loop.call_at(sampler.due, lambda: loop.create_task(release(self, handle, sampler)))
                    sampler.held = value
                    return
                sampler.due = now + sampler.interval
        await original(self, handle, value, error)

    async def release(service, handle, sampler: Sampler) -> None:
        value, sampler.held = sampler.held, None
        if value is not None and handle in service._monitored_datachange:  # not deleted since
            sampler.due = asyncio.get_running_loop().time() + sampler.interval
            await original(service, handle, value)
    MonitoredItemService.datachange_callback = datachange_callback
