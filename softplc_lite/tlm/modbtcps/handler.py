"""Modbus TCP in the server process: the MBAP frames, each request checked
as the Modbus specification says (rules.py) and decoded by pymodbus, served
from the map (layout.py) through the network-server layer, and answered in
pymodbus's PDUs (pymodbus_glue.py), which pymodbus's server frames.
"""

from __future__ import annotations

import logging

from ...netserver import Handler, Malformed
from ...netserver import counters as C
from . import rules
from .layout import Layout, string_lengths_fit
from .protocol import ModbusProtocol, mask_payload, write_payload
from .pymodbus_glue import Listener, decode, exception_response, response
from .rules import KIND_OF_FUNCTION, Refusal, Request
from .status import EXCEPTION_01, EXCEPTION_02, EXCEPTION_03, EXCEPTION_0B

MBAP = 7  # transaction, protocol, length, unit
MAX_LENGTH = 254  # the MBAP length field: unit id + the largest PDU (253)
COUNTER_OF_CODE = {rules.ILLEGAL_FUNCTION: EXCEPTION_01, rules.ILLEGAL_ADDRESS: EXCEPTION_02,
                   rules.ILLEGAL_VALUE: EXCEPTION_03, rules.DEVICE_BUSY: C.REFUSED_RATE,
                   rules.GATEWAY_NO_RESPONSE: EXCEPTION_0B}


class ModbusHandler(Handler):
    busy = rules.DEVICE_BUSY
    failure = rules.DEVICE_FAILURE

    def __init__(self, server, protocol: ModbusProtocol) -> None:
        super().__init__(server)
        self.layout = protocol.layout
        self.units = set(protocol.config.units)  # a unit with no regions answers exception 02 to everything

    def listener(self) -> Listener:
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # this server says what matters, counted
        return Listener(self.server)

    # -- frames ------------------------------------------------------------------------------------
    def frame_length(self, data: bytearray, at: int) -> int | None:
        if len(data) - at < MBAP:
            return None
        pid = int.from_bytes(data[at + 2:at + 4], "big")
        length = int.from_bytes(data[at + 4:at + 6], "big")
        if pid != 0 or not 2 <= length <= MAX_LENGTH:
            raise Malformed(f"not a Modbus TCP frame (protocol id {pid}, length {length})")
        return 6 + length if len(data) - at >= 6 + length else None

    def header(self, frame: bytes, state) -> tuple[int, int, int]:
        """(function, unit, transaction id): what an exception answer needs."""
        return frame[7], frame[6], int.from_bytes(frame[:2], "big")

    def decode(self, frame: bytes, header) -> Request | Refusal:
        function, unit, tid = header
        if function not in KIND_OF_FUNCTION:
            return Refusal(rules.ILLEGAL_FUNCTION, f"function {function} is not served")
        problem = rules.body_problem(frame[7:])
        if problem is not None:  # Modbus spec 7: exception 03
            return Refusal(rules.ILLEGAL_VALUE, problem)
        request = decode(frame[7:], unit, tid)
        if request is None:
            return Refusal(rules.ILLEGAL_VALUE, f"function {function} with a body that does not decode")
        if unit not in self.units:
            return Refusal(rules.GATEWAY_NO_RESPONSE, f"unit id {unit} is not configured")
        return request

    # -- refusals ----------------------------------------------------------------------------------
    def refusal_reply(self, code: int, header):
        function, unit, tid = header
        return exception_response(function, code, unit, tid)

    def counter(self, code: int) -> int:
        return COUNTER_OF_CODE[code]

    def code_words(self, code: int) -> str:
        return f"exception {code:02X}"

    # -- serving a request -------------------------------------------------------------------------
    async def serve(self, r: Request):
        """The response to a request whose body is checked (rules.py), or
        the Refusal that answers it. Every check is made before the write
        goes to the scan: a refused request changes nothing."""
        kind = KIND_OF_FUNCTION[r.function]
        if r.function not in rules.WRITES:
            values = await self.read(r.unit, kind, r.address, r.count)
            return values if isinstance(values, Refusal) else response(r, values)
        refusal = self.write_refused(r)
        if refusal is not None:
            return refusal
        if r.function == 22:
            applied = await self.server.through_scan(mask_payload(r.unit, r.address, r.and_mask, r.or_mask))
        else:
            applied = await self.server.through_scan(write_payload(r.unit, kind, r.address, r.values))
        if not applied:
            return Refusal(rules.ILLEGAL_VALUE, "a mask write whose result is a string's LEN over 82")
        if r.function in (5, 6):  # the item as the scan left it (Modbus spec 6.5, 6.6: the echo)
            values = await self.read(r.unit, kind, r.address, 1)
        elif r.function == 23:  # the write first, then the read (Modbus spec 6.17)
            values = await self.read(r.unit, kind, r.read_address, r.read_count)
        else:
            values = None
        return values if isinstance(values, Refusal) else response(r, values)

    async def read(self, unit: int, kind: str, address: int, count: int) -> list[int] | Refusal:
        pieces = self.layout.find(unit, kind, address, count)
        if pieces is None:
            return Refusal(rules.ILLEGAL_ADDRESS, f"{kind.replace('_', ' ')} {address}..{address + count - 1} "
                                                  f"are not all in unit {unit}'s map")
        return Layout.values(pieces, await self.server.read(Layout.spans(pieces)))

    def write_refused(self, r: Request) -> Refusal | None:
        """Why a write is refused, or None: every check a write gets before
        it goes to the scan, Read/Write Multiple Registers' read part
        included."""
        kind = KIND_OF_FUNCTION[r.function]
        if not self.layout.takes_writes(r.unit, kind):  # the function is not an allowable action here
            return Refusal(rules.ILLEGAL_FUNCTION, f"unit {r.unit} takes no writes of {kind.replace('_', ' ')}")
        pieces = self.layout.find(r.unit, kind, r.address, r.count)
        if pieces is None or not all(s.writable for s, _, _ in pieces):
            return Refusal(rules.ILLEGAL_ADDRESS, f"{kind.replace('_', ' ')} {r.address}..{r.address + r.count - 1} "
                                                  f"are not all writable in unit {r.unit}'s map")
        if r.function == 23 and self.layout.find(r.unit, kind, r.read_address, r.read_count) is None:
            return Refusal(rules.ILLEGAL_ADDRESS, f"the read part, holding registers {r.read_address}.."
                                                  f"{r.read_address + r.read_count - 1}, is not all in unit "
                                                  f"{r.unit}'s map")
        busy = self.server.busy()
        if busy is not None:  # the scan is not taking writes (stopped)
            return Refusal(rules.DEVICE_BUSY, busy)
        # a mask write's result is known only where the scan applies it: the scan checks its LEN there
        if kind == "holding_registers" and r.function != 22 and not string_lengths_fit(pieces, r.values):
            return Refusal(rules.ILLEGAL_VALUE, "a string's LEN register written over 82")
        return None
