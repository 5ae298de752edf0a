"""Message Router request and response (CIP Volume 1, 2-4): what rides in
unconnected and connected data items. A request is service, path size in
16-bit words, path, data; a response is service | 0x80, a reserved byte,
general status, the additional status size in words, those words, data."""

from __future__ import annotations

import struct
from dataclasses import dataclass


class MessageError(ValueError):
    """Bytes that are no Message Router request: a not-enough-data (0x13) or path-size (0x26) refusal."""


@dataclass(frozen=True)
class MessageRouterRequest:
    service: int
    path: bytes
    data: bytes = b""

    def encode(self) -> bytes:
        if len(self.path) % 2:
            raise ValueError("a padded EPATH has an even length")
        return bytes((self.service, len(self.path) // 2)) + self.path + self.data

    @classmethod
    def decode(cls, raw: bytes) -> "MessageRouterRequest":
        if len(raw) < 2:
            raise MessageError(f"a request is at least 2 bytes, got {len(raw)}")
        end = 2 + raw[1] * 2
        if end > len(raw):
            raise MessageError(f"the path is {raw[1]} words, only {(len(raw) - 2) // 2} follow")
        return cls(raw[0], bytes(raw[2:end]), bytes(raw[end:]))


@dataclass(frozen=True)
class MessageRouterResponse:
    service: int  # with the reply bit
    status: int = 0
    extended: tuple[int, ...] = ()
    data: bytes = b""

    def encode(self) -> bytes:
        return (bytes((self.service, 0, self.status, len(self.extended)))
                + struct.pack(f"<{len(self.extended)}H", *self.extended) + self.data)

    @classmethod
    def decode(cls, raw: bytes) -> "MessageRouterResponse":
        if len(raw) < 4:
            raise MessageError(f"a response is at least 4 bytes, got {len(raw)}")
        words = raw[3]
        end = 4 + 2 * words
        if end > len(raw):
            raise MessageError(f"{words} additional status words announced, fewer follow")
        return cls(raw[0], raw[2], struct.unpack_from(f"<{words}H", raw, 4), bytes(raw[end:]))
