"""The EtherNet/IP encapsulation header (CIP Volume 2, "Encapsulation
Protocol", 2-3): 24 bytes, little-endian, before every TCP and UDP message:
command, length of the data that follows, session handle, status, 8 bytes of
sender context echoed back, options."""

from __future__ import annotations

import struct
from dataclasses import dataclass

HEADER = struct.Struct("<HHII8sI")
HEADER_SIZE = HEADER.size  # 24

# Commands (Volume 2, Table 2-3.2).
NOP = 0x00
LIST_SERVICES = 0x04
LIST_IDENTITY = 0x63
LIST_INTERFACES = 0x64
REGISTER_SESSION = 0x65
UNREGISTER_SESSION = 0x66
SEND_RR_DATA = 0x6F
SEND_UNIT_DATA = 0x70
COMMANDS = frozenset({NOP, LIST_SERVICES, LIST_IDENTITY, LIST_INTERFACES, REGISTER_SESSION,
                      UNREGISTER_SESSION, SEND_RR_DATA, SEND_UNIT_DATA})

# Encapsulation status codes (Volume 2, Table 2-3.3).
SUCCESS = 0x0000
INVALID_COMMAND = 0x0001
INSUFFICIENT_MEMORY = 0x0002
INCORRECT_DATA = 0x0003
INVALID_SESSION = 0x0064
INVALID_LENGTH = 0x0065
UNSUPPORTED_PROTOCOL = 0x0069


class EncapError(ValueError):
    """Bytes that are no encapsulation header."""


@dataclass(frozen=True)
class EncapHeader:
    command: int
    length: int
    session: int = 0
    status: int = SUCCESS
    context: bytes = bytes(8)
    options: int = 0

    def encode(self) -> bytes:
        return HEADER.pack(self.command, self.length, self.session, self.status,
                           self.context, self.options)

    @classmethod
    def decode(cls, data: bytes) -> "EncapHeader":
        if len(data) < HEADER_SIZE:
            raise EncapError(f"an encapsulation header is {HEADER_SIZE} bytes, got {len(data)}")
        return cls(*HEADER.unpack_from(data))


@dataclass(frozen=True)
class EncapMessage:
    """A header and its data; ``encode`` sets the length from the data."""

    command: int
    data: bytes = b""
    session: int = 0
    status: int = SUCCESS
    context: bytes = bytes(8)
    options: int = 0

    def encode(self) -> bytes:
        header = EncapHeader(self.command, len(self.data), self.session, self.status,
                             self.context, self.options)
        return header.encode() + self.data

    @classmethod
    def decode(cls, data: bytes) -> "EncapMessage":
        header = EncapHeader.decode(data)
        body = data[HEADER_SIZE:]
        if len(body) != header.length:
            raise EncapError(f"the header says {header.length} data bytes, got {len(body)}")
        return cls(header.command, bytes(body), header.session, header.status,
                   header.context, header.options)

    def reply(self, data: bytes = b"", status: int = SUCCESS, session: int | None = None) -> "EncapMessage":
        """The reply to this message: same command, context and session."""
        return EncapMessage(self.command, data, self.session if session is None else session,
                            status, self.context, self.options)
