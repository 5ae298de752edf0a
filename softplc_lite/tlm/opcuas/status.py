"""OPCUAS's status words: the 16 words the ladder reads, and the counters
they copy (the server's, netserver/counters.py, and OPC UA's own).

The layout is a softplc choice in MODBTCPS's shape (docs/opcuas.md,
"Status words"), so a rung that alarms on one server's refusals reads
another's at the same offsets where they mean the same.
"""

from __future__ import annotations

from ...netserver.counters import (  # noqa: F401 - the counters and words by name, for the tests
    COMMON_COPIED, STATUS_WORDS, W_BITS, W_CONNECTED, W_IDLE, W_MALFORMED, W_RATE, W_REFUSALS, W_REFUSED_LIMIT,
    W_WRITES_APPLIED,
    CONNECTED, IDLE, MALFORMED, OWN, REFUSED_LIMIT, REFUSED_NETWORK, REFUSED_RATE, StatusWords)

# OPC UA's own counters, after the server's.
REFUSED_WRITES = OWN  # Write operations refused: a read-only node (BadNotWritable), an unknown one (BadNodeIdUnknown)
REFUSED_ITEMS = OWN + 1  # monitored items over maxMonitoredItems (BadTooManyMonitoredItems)
REFUSED_SUBSCRIPTIONS = OWN + 2  # subscriptions over maxSubscriptions (BadTooManySubscriptions)
REFUSED_IDENTITIES = OWN + 3  # sessions refused: a wrong password, an untrusted certificate, anonymous where not allowed
SKIPPED_SCANS = OWN + 4  # scans whose values no client was given: the server took a later one (not a refusal)

W_REFUSED_WRITES = 8
W_REFUSED_ITEMS = 9
W_REFUSED_SUBSCRIPTIONS = 10
W_REFUSED_IDENTITIES = 11
W_SKIPPED_SCANS = 15

COPIED = COMMON_COPIED + ((W_REFUSED_WRITES, REFUSED_WRITES), (W_REFUSED_ITEMS, REFUSED_ITEMS),
                          (W_REFUSED_SUBSCRIPTIONS, REFUSED_SUBSCRIPTIONS), (W_REFUSED_IDENTITIES, REFUSED_IDENTITIES),
                          (W_SKIPPED_SCANS, SKIPPED_SCANS))
# every refusal, by the name the watch view gives it (word 14 is their sum)
REFUSAL_NAMES = (("session limit", REFUSED_LIMIT), ("write refused", REFUSED_WRITES),
                 ("monitored item limit", REFUSED_ITEMS), ("subscription limit", REFUSED_SUBSCRIPTIONS),
                 ("identity refused", REFUSED_IDENTITIES), ("malformed", MALFORMED), ("idle", IDLE))
# the counts the watch view shows beside the refusals, not among them
NOTED_NAMES = (("scans skipped", SKIPPED_SCANS),)

LAYOUT = StatusWords(bits=W_BITS, rate=W_RATE, writes_applied=W_WRITES_APPLIED, refusals=W_REFUSALS,
                     copied=COPIED, refusal_names=REFUSAL_NAMES, noted_names=NOTED_NAMES, words=STATUS_WORDS)
