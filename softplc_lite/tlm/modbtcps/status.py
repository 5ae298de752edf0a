"""MODBTCPS's status words: the 16 words the ladder reads, and the
counters they copy (the server's, netserver/counters.py, and Modbus's own
exception counts).

At each output point the server's counts go into the status block named by
MODBTCPS.XML's ``status`` attribute, so a rung can alarm on refusals as it
does on a MODBMAST slave's status. The layout is a softplc choice, listed in
docs/modbtcps.md ("Status words").
"""

from __future__ import annotations

from ...netserver.counters import (  # noqa: F401 - the counters and words by name, for the benchmarks and the tests
    COMMON_COPIED, STATUS_WORDS, W_BITS, W_CONNECTED, W_IDLE, W_MALFORMED, W_RATE, W_REFUSALS, W_REFUSED_LIMIT,
    W_REFUSED_NETWORK, W_REFUSED_RATE, W_REQUESTS, W_WRITES_APPLIED,
    BIT_CLIENT, BIT_FAILED, BIT_LISTENING, CONNECTED, CONNECTIONS, COUNTERS, IDLE, LISTENING, MALFORMED, OWN, PORT,
    REFUSED_LIMIT, REFUSED_NETWORK, REFUSED_RATE, REQUESTS, WRITES, StatusWords)

# Modbus's own counters, after the server's.
EXCEPTION_01 = OWN  # illegal function: a function not served, or a write to a unit with no writable region of it
EXCEPTION_02 = OWN + 1  # illegal data address: outside the map, or not writable
EXCEPTION_03 = OWN + 2  # illegal data value: a count out of range, a string length over 82
EXCEPTION_0B = OWN + 3  # unit id not configured (gateway target did not respond)

# Status words (offsets in the status block): the layer's (netserver.counters), and these.
W_EXCEPTION_02 = 8
W_EXCEPTION_01 = 9
W_EXCEPTION_03 = 10
W_EXCEPTION_0B = 11

# status word <- counter
COPIED = COMMON_COPIED + ((W_EXCEPTION_02, EXCEPTION_02), (W_EXCEPTION_01, EXCEPTION_01),
                          (W_EXCEPTION_03, EXCEPTION_03), (W_EXCEPTION_0B, EXCEPTION_0B))
# every refusal, by the name the watch view gives it
REFUSAL_NAMES = (("not allowed", REFUSED_NETWORK), ("connection limit", REFUSED_LIMIT), ("rate limit", REFUSED_RATE),
                 ("exception 01", EXCEPTION_01), ("exception 02", EXCEPTION_02), ("exception 03", EXCEPTION_03),
                 ("exception 0B", EXCEPTION_0B), ("malformed", MALFORMED), ("idle", IDLE))

LAYOUT = StatusWords(bits=W_BITS, rate=W_RATE, writes_applied=W_WRITES_APPLIED, refusals=W_REFUSALS,
                     copied=COPIED, refusal_names=REFUSAL_NAMES, words=STATUS_WORDS)
