"""Two runtimes, one reading the other through EtherNet/IP: runtime B
serves its table with ENIPS; runtime A's ladder is an EtherNet/IP client
written with COMGENIUS over a ``socket://`` port: it registers a session,
keeps the handle the server gave it, and polls B's ``N7[0]`` x 10 with an
unconnected Read Tag (SendRRData), as the bytes of CIP Vol. 2 (2-3, 2-4,
2-6) and 1756-PM020 (Read Tag Service) lay them out."""

from __future__ import annotations

import time

import pytest

from helpers.apps import make_app
from helpers.enips_apps import LIMIT_S, enips_xml
from helpers.modbus_peer import free_tcp_port, wait_for_tcp
from helpers.runtimes import Runtime, printed, prints, wait_for_a_client

pytestmark = pytest.mark.timeout(120)

ZEROS = "\\x00" * 16  # status, sender context, options
SESSION_REPLY_TAIL = ZEROS + "\\x01\\x00\\x00\\x00"  # version 1, no options
# A Read Tag of "N7" element 0, 10 elements: service 4C, path 3 words (91 02 'N7' 28 00), count 10.
READ_TAG = "\\x4c\\x03\\x91\\x02N7\\x28\\x00\\x0a\\x00"
CLIENT_STRINGS = f"""\
[DRIVER]
DEBUG=0

[PORTS]
0, loop://, ISO-8859-1, 9600, 8, N, 1, 500

[STRINGS]
1 "\\x65\\x00\\x04\\x00\\x00\\x00\\x00\\x00{SESSION_REPLY_TAIL}"
2 "\\x65\\x00\\x04\\x00%.4c{SESSION_REPLY_TAIL}"
3 "\\x6f\\x00\\x1a\\x00%.4c{ZEROS}\\x00\\x00\\x00\\x00\\x0a\\x00\\x02\\x00\\x00\\x00\\x00\\x00\\xb2\\x00\\x0a\\x00{READ_TAG}"
4 "\\x6f\\x00\\x2a\\x00%*.4c{ZEROS}\\x00\\x00\\x00\\x00%\\x0a\\x00\\x02\\x00\\x00\\x00\\x00\\x00\\xb2\\x00\\x1a\\x00\\xcc\\x00\\x00\\x00\\xc3\\x00%.20c"
"""
# In format 4, "%\x0a" matches the timeout's byte 0x0A itself: a bare LF in a scan format would
# match any run of whitespace (docs/comgenius.md, "Input matching").
# B3/0 registered, B3/1 registering, B3/2 a poll under way.
CLIENT_LADDER = """SYMBOL Session N20:0
DATA N20 2
DATA N10 10
DATA N11 10
// RegisterSession once (format 1), then keep the handle the reply gives (format 2).
XIO B3/0 XIO B3/1 BST COMPRINT R6:0 0 1 NXB OTL B3/1 BND
XIC B3/1 COMSCAN R6:1 0 2 Session
XIC R6:1/DN XIO R6:1/ER BST OTL B3/0 NXB OTU B3/1 BND
// Poll every 50 ms: SendRRData holding the Read Tag, the session handle in its header.
XIC B3/0 XIO B3/2 XIO R6:3/EN TON T4:0 0.01 5 0
XIC T4:0/DN XIO B3/2 BST COMPRINT R6:2 0 3 Session NXB OTL B3/2 BND
XIC B3/2 COMSCAN R6:3 0 4 N10:0
// A whole good reply: the 10 words to the safe copy N11, counted.
XIC R6:3/DN XIO R6:3/ER BST COP #N10:0 #N11:0 10 NXB CTU C5:1 32767 0 NXB OTU B3/2 BND
// A timeout or a reply that does not match: counted, the input cleared, the next poll tries again.
BST XIC R6:3/EM NXB XIC R6:3/DN XIC R6:3/ER BND BST COMRCVCLEAR 0 NXB CTU C5:3 32767 0 NXB OTU B3/2 BND
"""


def test_one_runtime_reads_another_through_ethernet_ip(tmp_path):
    port = free_tcp_port()
    server = make_app(tmp_path / "b", "ADD N7:0 1 N7:0\nMOV 4242 N7:5\nMOV N7:9 N7:8\n", MODULES_LST="ENIPS\n",
                      ENIPS_XML=enips_xml("", port=port))
    client = make_app(tmp_path / "a", CLIENT_LADDER, MODULES_LST="COMGENIUS\n", COMGENIUS_LST=CLIENT_STRINGS)
    b = Runtime(server)
    a = None
    try:
        wait_for_tcp(port, LIMIT_S)
        a = Runtime(client, "--port", f"0=socket://127.0.0.1:{port}",
                    *prints(["N11:0", "N11:5", "N20:0", "N20:1", "C5:1.ACC", "C5:3.ACC", "B3/0"]))
        wait_for_a_client(port)
        time.sleep(3.0)
    finally:
        try:
            out_a, err_a = a.stop() if a is not None else ("", "")
        finally:
            out_b, err_b = b.stop()
    values = printed(out_a)
    assert values["B3/0"] == "1", (out_a, err_a)  # a session registered
    assert (int(values["N20:0"]) | int(values["N20:1"])) != 0  # the handle B gave
    assert int(values["C5:1.ACC"]) >= 10, (out_a, err_a)  # good replies: about one every 60 ms
    assert values["N11:5"] == "4242" and int(values["N11:0"]) > 0
    assert values["C5:3.ACC"] == "0", (out_a, err_a)  # no timeout, no reply that did not match
