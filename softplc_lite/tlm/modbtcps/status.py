"""MODBTCPS's status words: the 16 words the ladder reads, and the
counters they copy (the server's, netserver/counters.py, and Modbus's own
exception counts).

At each output point the server's counts go into the status block named by
MODBTCPS.XML's ``status`` attribute, so a rung can alarm on refusals as it
does on a MODBMAST slave's status. The layout is a softplc choice, listed in
docs/modbtcps.md ("Status words").
"""

from __future__ import annotations

from ...netserver.counters import (  # noqa: F401 - the counters by name, for the benchmarks and the tests
    BIT_CLIENT, BIT_FAILED, BIT_LISTENING, CONNECTED, CONNECTIONS, COUNTERS, IDLE, LISTENING, MALFORMED, OWN, PORT,
    REFUSED_LIMIT, REFUSED_NETWORK, REFUSED_RATE, REQUESTS, WRITES, StatusWords)

# Modbus's own counters, after the server's.
EXCEPTION_01 = OWN  # illegal function: a function not served, or a write to a unit with no writable region of it
EXCEPTION_02 = OWN + 1  # illegal data address: outside the map, or not writable
EXCEPTION_03 = OWN + 2  # illegal data value: a count out of range, a string length over 82
EXCEPTION_0B = OWN + 3  # unit id not configured (gateway target did not respond)

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

# status word <- counter
COPIED = ((W_CONNECTED, CONNECTED), (W_REQUESTS, REQUESTS), (W_REFUSED_NETWORK, REFUSED_NETWORK),
          (W_REFUSED_LIMIT, REFUSED_LIMIT), (W_REFUSED_RATE, REFUSED_RATE), (W_EXCEPTION_02, EXCEPTION_02),
          (W_EXCEPTION_01, EXCEPTION_01), (W_EXCEPTION_03, EXCEPTION_03), (W_EXCEPTION_0B, EXCEPTION_0B),
          (W_MALFORMED, MALFORMED), (W_IDLE, IDLE))
# every refusal, by the name the watch view gives it
REFUSAL_NAMES = (("not allowed", REFUSED_NETWORK), ("connection limit", REFUSED_LIMIT), ("rate limit", REFUSED_RATE),
                 ("exception 01", EXCEPTION_01), ("exception 02", EXCEPTION_02), ("exception 03", EXCEPTION_03),
                 ("exception 0B", EXCEPTION_0B), ("malformed", MALFORMED), ("idle", IDLE))

LAYOUT = StatusWords(bits=W_BITS, rate=W_RATE, writes_applied=W_WRITES_APPLIED, refusals=W_REFUSALS,
                     copied=COPIED, refusal_names=REFUSAL_NAMES, words=STATUS_WORDS)
