"""What MODBMAST knows about each slave: the five-word status block of
Table 11 and the Present / Not Present state of Table 5.

Internal exception codes (Table 14, negative), and one softplc_lite adds:

====  =================  ===========================================================
code  name               when
====  =================  ===========================================================
-1    BAD CRC            the reply's CRC (RTU) or LRC (ASCII) does not match
-2    INCOMPLETE REPLY   an inter-character timeout within the reply
-3    NO REPLY           no reply byte within requestTimeout (after every attempt)
-4    NO CTS             CTS not raised within ModemControl's waitDelayCTS
-5    NO XMIT ROOM       the port did not take the whole request within requestTimeout
-6    WAIT XMITTED       the request was still in the port's output queue at the timeout
-7    BAD REPLY          (softplc_lite) a whole frame that is not the reply to the
                         request: another slave's address, another function, a
                         length or echo that does not match the request
====  =================  ===========================================================
"""

from __future__ import annotations

BAD_CRC, INCOMPLETE_REPLY, NO_REPLY, NO_CTS, NO_XMIT_ROOM, WAIT_XMITTED, BAD_REPLY = -1, -2, -3, -4, -5, -6, -7
INTERNAL_NAMES = {BAD_CRC: "BAD CRC", INCOMPLETE_REPLY: "INCOMPLETE REPLY", NO_REPLY: "NO REPLY",
                  NO_CTS: "NO CTS", NO_XMIT_ROOM: "NO XMIT ROOM", WAIT_XMITTED: "WAIT XMITTED",
                  BAD_REPLY: "BAD REPLY"}
# No byte came back from the slave: these make it Not Present (Table 5).
SILENT = frozenset({NO_REPLY, NO_CTS, NO_XMIT_ROOM, WAIT_XMITTED})

AVERAGE_WEIGHT = 8  # the floating average moves 1/8 of the way to each new response time


def code_name(code: int) -> str:
    from ...modbus.pdu import EXCEPTION_NAMES

    if code < 0:
        return INTERNAL_NAMES.get(code, str(code))
    return EXCEPTION_NAMES.get(code, f"exception {code}")


def _word(value: int) -> int:
    value &= 0xFFFF
    return value - 0x10000 if value & 0x8000 else value


class SlaveStatus:
    """One slave's Table 11 block, kept inside the driver (MBR_GETSTATUS
    copies it out, MBR_CLEARSTATUS zeroes it)."""

    __slots__ = ("average_ms", "no_replies", "exceptions", "failed_function", "last_code", "present",
                 "silent_requests", "demoted", "probe_at")

    def __init__(self) -> None:
        self.clear()
        self.present = True  # nothing is known against it before the first request
        self.silent_requests = 0  # requests in a row that got no reply (for demotion)
        self.demoted = False
        self.probe_at = 0

    def clear(self) -> None:
        """MBR_CLEARSTATUS: the five words to zero."""
        self.average_ms: float | None = None
        self.no_replies = 0
        self.exceptions = 0
        self.failed_function = 0
        self.last_code = 0

    def words(self) -> tuple[int, int, int, int, int]:
        """The five words as the data table holds them (signed 16-bit; the
        counters wrap through negative values, as Table 11 says)."""
        average = 0 if self.average_ms is None else min(int(self.average_ms + 0.5), 32767)
        return (average, _word(self.no_replies), _word(self.exceptions), self.failed_function,
                _word(self.last_code))

    def replied(self, response_ms: float) -> None:
        """A whole reply frame came back (good, exception or garbled)."""
        if self.average_ms is None:
            self.average_ms = response_ms
        else:
            self.average_ms += (response_ms - self.average_ms) / AVERAGE_WEIGHT
        self.present = True
        self.silent_requests = 0
        self.demoted = False

    def succeeded(self) -> None:
        """A request completed without error: word 3 and 4 go to zero."""
        self.failed_function = 0
        self.last_code = 0

    def failed(self, function: int, code: int) -> None:
        """A request failed for good (after its attempts): ``code`` is a
        Modbus exception (positive) or an internal code (negative)."""
        self.failed_function = function
        self.last_code = code
        if code > 0:
            self.exceptions += 1
        elif code == INCOMPLETE_REPLY:
            self.no_replies += 1
        if code in SILENT:
            self.present = False
            self.silent_requests += 1

    def timed_out(self) -> None:
        """One attempt got no reply within requestTimeout (word 1 counts
        every such attempt)."""
        self.no_replies += 1
