"""What a server counts, the status words a protocol copies them into, and
the server as the watch view shows it.

The server process counts in the shared image (image.py): the counters
below are every protocol's; the indices from ``OWN`` on are the protocol's
own (its kinds of refusal: Modbus's exception codes). At each output point
the scan copies them into the status block a protocol's configuration names,
laid out by the protocol's ``StatusWords``, so a rung can alarm on refusals.
"""

from __future__ import annotations

from dataclasses import dataclass

# The counters (u32, wrapping), by index in the shared image.
CONNECTED = 0  # connections open now
CONNECTIONS = 1  # connections accepted, ever
REQUESTS = 2  # requests answered normally
REFUSED_NETWORK = 3  # connections refused: client address not in the allow-list
REFUSED_LIMIT = 4  # connections refused: maxConnections reached
REFUSED_RATE = 5  # requests refused busy: over the request rate, or too many writes wait for the scan
MALFORMED = 6  # connections closed: bytes that are not a frame of the protocol
IDLE = 7  # connections closed: no whole request for the idle timeout
WRITES = 8  # write requests passed to the scan
LISTENING = 9  # 1 while the server listens
PORT = 10  # the port it listens on
OWN = 11  # the first of the protocol's own counters
COUNTERS = 16

# The status words every protocol's block has at the same offsets (its own
# kinds of refusal take 8..11, and 15).
W_BITS = 0  # /0 listening, /1 server failed, /2 a client is connected
W_CONNECTED = 1
W_RATE = 2  # requests answered in the last whole second
W_REQUESTS = 3
W_WRITES_APPLIED = 4
W_REFUSED_NETWORK = 5
W_REFUSED_LIMIT = 6
W_REFUSED_RATE = 7
W_MALFORMED = 12
W_IDLE = 13
W_REFUSALS = 14  # the sum of words 5..13
STATUS_WORDS = 16
COMMON_COPIED = ((W_CONNECTED, CONNECTED), (W_REQUESTS, REQUESTS), (W_REFUSED_NETWORK, REFUSED_NETWORK),
                 (W_REFUSED_LIMIT, REFUSED_LIMIT), (W_REFUSED_RATE, REFUSED_RATE), (W_MALFORMED, MALFORMED),
                 (W_IDLE, IDLE))

# The bits of a status block's first word.
BIT_LISTENING = 1
BIT_FAILED = 2
BIT_CLIENT = 4


@dataclass(frozen=True)
class StatusWords:
    """Where a protocol's status block holds each count (offsets in the
    block): the bits word (/0 listening, /1 failed, /2 a client connected),
    the requests a second, the writes applied, the sum of the refusals, and
    the words copied from counters."""

    bits: int
    rate: int
    writes_applied: int
    refusals: int
    copied: tuple[tuple[int, int], ...]  # (status word, counter)
    refusal_names: tuple[tuple[str, int], ...]  # every refusal counter, by the name the watch view gives it
    words: int = 16
    noted_names: tuple[tuple[str, int], ...] = ()  # counters the watch view shows that are not refusals

    @property
    def refusal_counters(self) -> tuple[int, ...]:
        return tuple(counter for _, counter in self.refusal_names)


def word(value: int) -> int:
    """A count as a data table word: its low 16 bits, signed (it wraps as a PLC counter word does)."""
    value &= 0xFFFF
    return value - 0x10000 if value & 0x8000 else value


@dataclass
class ServerStatus:
    """The server as the watch view shows it."""

    listening: str  # "127.0.0.1:502", or why not
    up: bool
    clients: int = 0
    rate: int = 0  # requests per second
    requests: int = 0
    writes: int = 0
    refusals: int = 0
    refused: dict[str, int] | None = None  # by kind, only those not zero
    noted: dict[str, int] | None = None  # counts that are not refusals (scans skipped), only those not zero
    pending: bool = False  # not started yet, or starting: neither up nor failed
