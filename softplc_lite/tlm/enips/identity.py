"""The Identity object (class 0x01, CIP Volume 1, 5A-2) and the identity item
ListIdentity answers with (Volume 2, 2-4.2.3): who this server is.

Our choices: vendor 1 (Rockwell Automation, as PLC-5 and Logix clients
expect), device type 0x0E (programmable logic controller), product code 1,
revision 1.1, and a serial number stable per app: the first four bytes of a
SHA-256 of the app's name, so a client sees the same device at every start."""

from __future__ import annotations

import hashlib
import struct
from dataclasses import dataclass

from ...cip import cpf, encap, status
from ...cip.encap import EncapMessage
from .objects import CipObject, CipReply

CLASS_ID = 0x01
GET_ATTRIBUTE_ALL = 0x01
GET_ATTRIBUTE_SINGLE = 0x0E
VENDOR = 1
DEVICE_TYPE = 0x0E
PRODUCT_CODE = 1
REVISION = (1, 1)
STATE_OPERATIONAL = 0x03


def serial_for(app_name: str) -> int:
    return int.from_bytes(hashlib.sha256(app_name.encode()).digest()[:4], "little")


@dataclass(frozen=True)
class Identity:
    app_name: str = "APP"
    status_word: int = 0

    @property
    def serial(self) -> int:
        return serial_for(self.app_name)

    @property
    def product_name(self) -> str:
        return f"softplc_lite {self.app_name}"[:32]

    def attributes(self) -> dict[int, bytes]:
        name = self.product_name.encode("ascii", "replace")
        return {1: struct.pack("<H", VENDOR), 2: struct.pack("<H", DEVICE_TYPE),
                3: struct.pack("<H", PRODUCT_CODE), 4: bytes(REVISION),
                5: struct.pack("<H", self.status_word), 6: struct.pack("<I", self.serial),
                7: bytes((len(name),)) + name}

    def list_identity_item(self, host: str, port: int) -> cpf.Item:
        attrs = self.attributes()
        body = (struct.pack("<H", 1) + cpf.sockaddr(host, port)
                + b"".join(attrs[n] for n in range(1, 8)) + bytes((STATE_OPERATIONAL,)))
        return cpf.Item(cpf.LIST_IDENTITY, body)


class IdentityObject(CipObject):
    class_id = CLASS_ID

    def __init__(self, identity: Identity | None = None):
        self.identity = identity or Identity()

    async def serve(self, request, access):
        _, instance, attribute = request.logical
        if instance not in (None, 0, 1):
            return CipReply.error(request, status.OBJECT_DOES_NOT_EXIST)
        attrs = self.identity.attributes()
        if request.service == GET_ATTRIBUTE_ALL:
            return CipReply.ok(request, b"".join(attrs[n] for n in range(1, 8)))
        if request.service == GET_ATTRIBUTE_SINGLE:
            if attribute not in attrs:
                return CipReply.error(request, status.ATTRIBUTE_NOT_SUPPORTED)
            return CipReply.ok(request, attrs[attribute])
        return CipReply.error(request, status.SERVICE_NOT_SUPPORTED)


def list_identity_reply(identity: Identity, data: bytes, host: str, tcp_port: int) -> bytes | None:
    """The reply to a ListIdentity datagram (CIP Volume 2, 2-4.2.1): the
    identity item naming the TCP listener; None for any other datagram,
    which is dropped unanswered (a choice: UDP carries no session to refuse)."""
    if len(data) < encap.HEADER_SIZE or struct.unpack_from("<H", data)[0] != encap.LIST_IDENTITY:
        return None
    message = EncapMessage.decode(data[:encap.HEADER_SIZE])
    return message.reply(cpf.encode([identity.list_identity_item(host, tcp_port)])).encode()
