"""ENIPS's status words: the 16 words the ladder reads, and the counters
they copy (the server's, netserver/counters.py, and EtherNet/IP's own).

The layout is a softplc choice in MODBTCPS's shape (docs/enips.md, "Status
words"), so a rung that alarms on one server's refusals reads the other's
at the same offsets where they mean the same.
"""

from __future__ import annotations

from ...netserver.counters import (  # noqa: F401 - the counters and words by name, for the tests and the benchmarks
    COMMON_COPIED, STATUS_WORDS, W_BITS, W_CONNECTED, W_IDLE, W_MALFORMED, W_RATE, W_REFUSALS, W_REFUSED_LIMIT,
    W_REFUSED_NETWORK, W_REFUSED_RATE, W_REQUESTS, W_WRITES_APPLIED,
    CONNECTED, CONNECTIONS, IDLE, MALFORMED, OWN, REFUSED_LIMIT, REFUSED_NETWORK, REFUSED_RATE, REQUESTS, WRITES,
    StatusWords)

# EtherNet/IP's own counters, after the server's.
ENCAP_ERRORS = OWN  # encapsulation replies with an error status: no session, an unknown command, bad items
CIP_ERRORS = OWN + 1  # CIP replies with a general status other than 0 (a Multiple Service Packet's services each)
PCCC_ERRORS = OWN + 2  # Execute PCCC replies with a STS other than 0
READ_ONLY = OWN + 3  # writes refused because no <Writable> covers them (CIP 0x0F, PCCC STS 0xF0 EXT 0x0B)
TIMED_OUT = OWN + 4  # CIP connections closed by their RPI timeout (not a refusal)

# Status words (offsets in the status block): the layer's (netserver.counters), and these.
W_ENCAP_ERRORS = 8
W_CIP_ERRORS = 9
W_PCCC_ERRORS = 10
W_READ_ONLY = 11
W_TIMED_OUT = 15

COPIED = COMMON_COPIED + ((W_ENCAP_ERRORS, ENCAP_ERRORS), (W_CIP_ERRORS, CIP_ERRORS), (W_PCCC_ERRORS, PCCC_ERRORS),
                          (W_READ_ONLY, READ_ONLY), (W_TIMED_OUT, TIMED_OUT))
REFUSAL_NAMES = (("not allowed", REFUSED_NETWORK), ("connection limit", REFUSED_LIMIT), ("rate limit", REFUSED_RATE),
                 ("encapsulation", ENCAP_ERRORS), ("CIP status", CIP_ERRORS), ("PCCC status", PCCC_ERRORS),
                 ("read-only", READ_ONLY), ("malformed", MALFORMED), ("idle", IDLE))

LAYOUT = StatusWords(bits=W_BITS, rate=W_RATE, writes_applied=W_WRITES_APPLIED, refusals=W_REFUSALS,
                     copied=COPIED, refusal_names=REFUSAL_NAMES, words=STATUS_WORDS)
