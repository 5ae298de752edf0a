"""One TCP connection's encapsulation state (CIP Volume 2, 2-4): the
session it registered, and the reply to each encapsulation message. The
network side frames messages by the header's length field and hands each
whole message here.

Our choices: one session per connection (a second RegisterSession is
refused with incorrect data, 0x03); a message naming another session is
answered with invalid session handle (0x64) and the data ignored; an unknown
command gets invalid command (0x01)."""

from __future__ import annotations

import itertools
import struct

from ...cip import cpf, encap
from ...cip.encap import EncapMessage
from .access import TableAccess
from ...cip.mr import MessageRouterResponse
from .connmgr import CLASS_ID as CONNECTION_MANAGER
from .connmgr import OWNER
from .identity import Identity
from .router import MessageRouter

_handles = itertools.count(0x1001)
PROTOCOL_VERSION = 1


class EncapSession:
    def __init__(self, router: MessageRouter, access: TableAccess, identity: Identity,
                 host: str = "127.0.0.1", port: int = 44818):
        self.router, self.access, self.identity = router, access, identity
        self.host, self.port = host, port
        self.session = 0

    async def reply(self, message: EncapMessage) -> EncapMessage | None:
        """The reply to one message, or None (NOP and UnRegisterSession get none)."""
        token = OWNER.set(self)  # the CIP connections this message opens are this session's
        try:
            return await self._reply(message)
        finally:
            OWNER.reset(token)

    def close(self) -> int:
        """The TCP connection ended: the CIP connections it opened close with
        it (CIP Volume 2, 2-5.3); how many."""
        self.session = 0
        manager = self.router.objects.get(CONNECTION_MANAGER)
        return manager.close_owned(self) if manager is not None else 0

    def refusal(self, message: EncapMessage, general_status: int) -> EncapMessage:
        """The reply that refuses ``message`` before it is served (a busy
        server): a Message Router reply with ``general_status`` where the
        message carries a CIP request, else the encapsulation status
        "insufficient memory" (0x0002: the one an encapsulation layer has
        for a receiver that cannot take a command now)."""
        items = _items(message) if message.command in (encap.SEND_RR_DATA, encap.SEND_UNIT_DATA) else None
        if not items or len(items) != 2 or not self.session or message.session != self.session:
            return message.reply(status=encap.INSUFFICIENT_MEMORY)
        address, data = items
        service = (data.data[2 if message.command == encap.SEND_UNIT_DATA else 0:][:1] or b"\x00")[0]
        response = MessageRouterResponse(service | 0x80, general_status).encode()
        if message.command == encap.SEND_RR_DATA:
            return _unconnected_reply(message, response)
        manager = self.router.objects.get(CONNECTION_MANAGER)
        o_t_id = struct.unpack("<I", address.data)[0] if len(address.data) == 4 else 0
        connection = manager.connections.get(o_t_id) if manager is not None else None
        if connection is None or manager.owners.get(o_t_id) is not self:
            return message.reply(status=encap.INCORRECT_DATA)
        return _connected_reply(message, connection[0], data.data[:2], response)

    async def _reply(self, message: EncapMessage) -> EncapMessage | None:
        command = message.command
        if command == encap.NOP:
            return None
        if command == encap.LIST_IDENTITY:
            return message.reply(cpf.encode([self.identity.list_identity_item(self.host, self.port)]))
        if command == encap.LIST_SERVICES:
            name = b"Communications\x00\x00"
            # version 1; capability bit 5: CIP encapsulation over TCP
            item = cpf.Item(cpf.LIST_SERVICES, struct.pack("<HH", 1, 1 << 5) + name)
            return message.reply(cpf.encode([item]))
        if command == encap.LIST_INTERFACES:
            return message.reply(struct.pack("<H", 0))
        if command == encap.REGISTER_SESSION:
            if self.session:
                return message.reply(message.data, encap.INCORRECT_DATA)
            if len(message.data) != 4:
                return message.reply(message.data, encap.INCORRECT_DATA)
            version, _ = struct.unpack("<HH", message.data)
            if version != PROTOCOL_VERSION:
                return message.reply(struct.pack("<HH", PROTOCOL_VERSION, 0), encap.UNSUPPORTED_PROTOCOL)
            self.session = next(_handles)
            return message.reply(message.data, session=self.session)
        if command not in encap.COMMANDS:
            return message.reply(status=encap.INVALID_COMMAND)
        if not self.session or message.session != self.session:
            return message.reply(status=encap.INVALID_SESSION)
        if command == encap.UNREGISTER_SESSION:
            self.session = 0
            return None
        if command == encap.SEND_RR_DATA:
            return await self.send_rr_data(message)
        return await self.send_unit_data(message)

    async def send_unit_data(self, message: EncapMessage) -> EncapMessage:
        """Interface handle, timeout, then a connected address item (our
        O->T connection id) and a connected data item: a sequence count and
        a Message Router request. The reply names the client's T->O id."""
        items = _items(message)
        if items is None:
            return message.reply(status=encap.INCORRECT_DATA)
        if (len(items) != 2 or items[0].type_id != cpf.CONNECTED_ADDRESS or len(items[0].data) != 4
                or items[1].type_id != cpf.CONNECTED_DATA or len(items[1].data) < 2):
            return message.reply(status=encap.INCORRECT_DATA)
        manager = self.router.objects.get(CONNECTION_MANAGER)
        o_t_id = struct.unpack("<I", items[0].data)[0]
        connection = manager.alive(o_t_id, self) if manager is not None else None
        if connection is None:
            return message.reply(status=encap.INCORRECT_DATA)
        response = await self.router.handle(items[1].data[2:], self.access)
        return _connected_reply(message, connection[0], items[1].data[:2], response)

    async def send_rr_data(self, message: EncapMessage) -> EncapMessage:
        """Interface handle (4), timeout (2), then the items: a null address
        and an unconnected data item holding a Message Router request."""
        items = _items(message)
        if items is None:
            return message.reply(status=encap.INCORRECT_DATA)
        data = [item for item in items if item.type_id == cpf.UNCONNECTED_DATA]
        if len(items) != 2 or items[0].type_id != cpf.NULL_ADDRESS or len(data) != 1:
            return message.reply(status=encap.INCORRECT_DATA)
        response = await self.router.handle(data[0].data, self.access)
        return _unconnected_reply(message, response)


def _unconnected_reply(message: EncapMessage, response: bytes) -> EncapMessage:
    """SendRRData's reply: the request's interface handle and timeout, a
    null address item and the Message Router response."""
    return message.reply(message.data[:6] + cpf.encode([cpf.Item(cpf.NULL_ADDRESS),
                                                        cpf.Item(cpf.UNCONNECTED_DATA, response)]))


def _connected_reply(message: EncapMessage, t_o_id: int, sequence: bytes, response: bytes) -> EncapMessage:
    """SendUnitData's reply: the client's T->O connection id, and the
    request's sequence count before the Message Router response."""
    return message.reply(message.data[:6] + cpf.encode([
        cpf.Item(cpf.CONNECTED_ADDRESS, struct.pack("<I", t_o_id)),
        cpf.Item(cpf.CONNECTED_DATA, sequence + response)]))


def _items(message: EncapMessage) -> list | None:
    """The item list after SendRRData's and SendUnitData's interface handle
    (4 bytes) and timeout (2), or None when there is none to decode."""
    if len(message.data) < 6:
        return None
    try:
        return cpf.decode(message.data[6:])
    except cpf.CpfError:
        return None
