"""What the server counts, and the 16 status words the ladder reads.

The server process counts (in the shared image, image.py); at each output
point the module copies the counts into the status block named by
MODBTCPS.XML's ``status`` attribute, so a rung can alarm on refusals as it
does on a MODBMAST slave's status. The layout is a softplc choice, listed in
docs/modbtcps.md ("Status words").
"""

from __future__ import annotations

from dataclasses import dataclass

# The server's counters (u32, wrapping), by index in the shared image.
CONNECTED = 0  # connections open now
CONNECTIONS = 1  # connections accepted, ever
REQUESTS = 2  # requests answered normally
REFUSED_NETWORK = 3  # connections refused: client address not in the allow-list
REFUSED_LIMIT = 4  # connections refused: maxConnections reached
REFUSED_RATE = 5  # requests answered exception 06: the client passed maxRequestsPerSecond
EXCEPTION_01 = 6  # illegal function: a function not served, or a write to a unit with no writable region of it
EXCEPTION_02 = 7  # illegal data address: outside the map, or not writable
EXCEPTION_03 = 8  # illegal data value: a count out of range, a string length over 82
EXCEPTION_0B = 9  # unit id not configured (gateway target did not respond)
MALFORMED = 10  # connections closed: a frame that is not Modbus TCP
IDLE = 11  # connections closed: no whole request for idleTimeout
WRITES = 12  # write requests passed to the scan
LISTENING = 13  # 1 while the server listens
PORT = 14  # the port it listens on
COUNTERS = 16

# Status words (offsets in the status block).
W_BITS = 0  # /0 listening, /1 server failed, /2 a client is connected
W_CONNECTED = 1
W_RATE = 2  # requests answered in the last whole second
W_REQUESTS = 3
W_WRITES_APPLIED = 4
W_REFUSED_NETWORK = 5
W_REFUSED_LIMIT = 6
W_REFUSED_RATE = 7
W_EXCEPTION_02 = 8
W_EXCEPTION_01 = 9
W_EXCEPTION_03 = 10
W_EXCEPTION_0B = 11
W_MALFORMED = 12
W_IDLE = 13
W_REFUSALS = 14  # the sum of words 5..13
STATUS_WORDS = 16

BIT_LISTENING = 1
BIT_FAILED = 2
BIT_CLIENT = 4

# status word <- counter
COPIED = ((W_CONNECTED, CONNECTED), (W_REQUESTS, REQUESTS), (W_REFUSED_NETWORK, REFUSED_NETWORK),
          (W_REFUSED_LIMIT, REFUSED_LIMIT), (W_REFUSED_RATE, REFUSED_RATE), (W_EXCEPTION_02, EXCEPTION_02),
          (W_EXCEPTION_01, EXCEPTION_01), (W_EXCEPTION_03, EXCEPTION_03), (W_EXCEPTION_0B, EXCEPTION_0B),
          (W_MALFORMED, MALFORMED), (W_IDLE, IDLE))
# every refusal, by the name the watch view gives it
REFUSAL_NAMES = (("not allowed", REFUSED_NETWORK), ("connection limit", REFUSED_LIMIT), ("rate limit", REFUSED_RATE),
                 ("exception 01", EXCEPTION_01), ("exception 02", EXCEPTION_02), ("exception 03", EXCEPTION_03),
                 ("exception 0B", EXCEPTION_0B), ("malformed", MALFORMED), ("idle", IDLE))
REFUSAL_COUNTERS = tuple(counter for _, counter in REFUSAL_NAMES)


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
    pending: bool = False  # not started yet, or starting: neither up nor failed
