"""Messages between the runtime and its server process, over pipes.

Each message is a 4-byte length and a body whose first byte says what it
is. The server sends WRITE (a client's write, in arrival order: a sequence
number and the protocol's own bytes, which only the protocol's ``apply``
reads), READY (listening, with the port bound) and FAILED (cannot listen,
why); the runtime sends REFUSED (this write was not applied: the protocol's
``apply`` refused it; before the ACK that covers it) and ACK (every other
write up to this sequence number is in the data table and in the image),
and stops the server by closing the pipe. The protocol and the settings go
first, pickled: both ends are this package, never a client.
"""

from __future__ import annotations

import struct

LENGTH = struct.Struct("=I")
WRITE, READY, FAILED, ACK, REFUSED = b"W", b"R", b"F", b"A", b"X"
_U32 = struct.Struct("=I")


def frame(body: bytes) -> bytes:
    return LENGTH.pack(len(body)) + body


def write(seq: int, payload: bytes) -> bytes:
    return frame(WRITE + _U32.pack(seq) + payload)


def ack(seq: int) -> bytes:
    return frame(ACK + _U32.pack(seq))


def refused(seq: int) -> bytes:
    return frame(REFUSED + _U32.pack(seq))


def ready(port: int) -> bytes:
    return frame(READY + _U32.pack(port))


def failed(why: str) -> bytes:
    return frame(FAILED + why.encode("utf-8", "replace"))


def decode(body: bytes) -> tuple:
    """A message body as a tuple: (WRITE, seq, payload), (READY, port),
    (FAILED, why), (REFUSED, seq) or (ACK, seq)."""
    tag, rest = body[:1], body[1:]
    if tag == WRITE:
        return WRITE, _U32.unpack_from(rest)[0], rest[_U32.size:]
    if tag in (READY, ACK, REFUSED):
        return tag, _U32.unpack(rest)[0]
    if tag == FAILED:
        return FAILED, rest.decode("utf-8", "replace")
    raise ValueError(f"not a server message: {body[:16]!r}")  # both ends are this package: a bug


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
