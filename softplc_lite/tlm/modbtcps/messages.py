"""Messages between the runtime and its server process, over pipes.

Each message is a 4-byte length and a body whose first byte says what it
is. The server sends WRITE and MASK (a client's write, in arrival order),
READY (listening, with the port bound) and FAILED (cannot listen, why); the
runtime sends REFUSED (this write was not applied: a mask write whose result
is not a string length; before the ACK that covers it) and ACK (every other
write up to this sequence number is in the data table and in the image), and
stops the server by closing the pipe. The
configuration goes first, pickled: both ends are this package, never a
client.
"""

from __future__ import annotations

import struct
from array import array

LENGTH = struct.Struct("=I")
WRITE, MASK, READY, FAILED, ACK, REFUSED = b"W", b"M", b"R", b"F", b"A", b"X"
_WRITE = struct.Struct("=IBBHH")  # sequence, unit, kind (0 coils, 1 registers), address, count
_MASK = struct.Struct("=IBHHH")  # sequence, unit, address, and-mask, or-mask
_U32 = struct.Struct("=I")
KIND_CODES = {"coils": 0, "holding_registers": 1}
KINDS_BY_CODE = {v: k for k, v in KIND_CODES.items()}


def frame(body: bytes) -> bytes:
    return LENGTH.pack(len(body)) + body


def write(seq: int, unit: int, kind: str, address: int, values: list[int]) -> bytes:
    return frame(WRITE + _WRITE.pack(seq, unit, KIND_CODES[kind], address, len(values))
                 + array("H", values).tobytes())


def mask(seq: int, unit: int, address: int, and_mask: int, or_mask: int) -> bytes:
    return frame(MASK + _MASK.pack(seq, unit, address, and_mask, or_mask))


def ack(seq: int) -> bytes:
    return frame(ACK + _U32.pack(seq))


def refused(seq: int) -> bytes:
    return frame(REFUSED + _U32.pack(seq))


def ready(port: int) -> bytes:
    return frame(READY + _U32.pack(port))


def failed(why: str) -> bytes:
    return frame(FAILED + why.encode("utf-8", "replace"))


def decode(body: bytes) -> tuple:
    """A message body as a tuple: (WRITE, seq, unit, kind, address, values),
    (MASK, seq, unit, address, and, or), (READY, port), (FAILED, why),
    (REFUSED, seq) or (ACK, seq)."""
    tag, rest = body[:1], body[1:]
    if tag == WRITE:
        seq, unit, kind, address, count = _WRITE.unpack_from(rest)
        return WRITE, seq, unit, KINDS_BY_CODE[kind], address, array("H", rest[_WRITE.size:]).tolist()
    if tag == MASK:
        return (MASK, *_MASK.unpack(rest))
    if tag in (READY, ACK, REFUSED):
        return tag, _U32.unpack(rest)[0]
    if tag == FAILED:
        return FAILED, rest.decode("utf-8", "replace")
    raise ValueError(f"not a MODBTCPS message: {body[:16]!r}")  # both ends are this package: a bug


class Reader:
    """Whole messages out of a byte stream read in pieces."""

    def __init__(self) -> None:
        self.buffer = bytearray()

    def feed(self, data: bytes) -> list[tuple]:
        self.buffer += data
        out = []
        while len(self.buffer) >= 4:
            n = LENGTH.unpack_from(self.buffer)[0]
            if len(self.buffer) < 4 + n:
                break
            out.append(decode(bytes(self.buffer[4:4 + n])))
            del self.buffer[:4 + n]
        return out
