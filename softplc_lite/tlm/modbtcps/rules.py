"""What a request must be before anything is done with it.

The MODBUS Application Protocol Specification V1.1b3 gives each function
its quantities, byte count and values (sections 6.1-6.17) and answers a
request outside them with exception 03, illegal data value (section 7: "the
implied length is incorrect" included). These checks run on the request's
bytes, before pymodbus decodes it, so that every such refusal is counted
here and a refused request changes nothing.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from ...netserver import Refusal  # noqa: F401 - an exception answer: its code is one of those below

# exception codes (specification section 7)
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE, DEVICE_BUSY = 0x01, 0x02, 0x03, 0x04, 0x06
GATEWAY_NO_RESPONSE = 0x0B

KIND_OF_FUNCTION = {1: "coils", 5: "coils", 15: "coils", 2: "discrete_inputs",
                    3: "holding_registers", 6: "holding_registers", 16: "holding_registers",
                    22: "holding_registers", 23: "holding_registers", 4: "input_registers"}
WRITES = frozenset({5, 6, 15, 16, 22, 23})
COIL_ON, COIL_OFF = 0xFF00, 0x0000  # the only values of Write Single Coil (section 6.5)

_U16 = struct.Struct(">H")


@dataclass
class Request:
    """One decoded request. For function 23, ``address`` and ``values`` are
    its write part, ``read_address`` and ``read_count`` its read part."""

    function: int
    unit: int
    tid: int
    address: int = 0
    count: int = 0  # items read (1-4) or written (5, 6, 15, 16, 22, 23)
    values: list[int] = field(default_factory=list)  # written: bits 0/1, or registers
    read_address: int = 0
    read_count: int = 0
    and_mask: int = 0
    or_mask: int = 0

    def __str__(self) -> str:  # the debug="2" log line
        what = f"function {self.function}, unit {self.unit}, address {self.address}"
        if self.function == 22:
            return f"{what}, and 0x{self.and_mask:04X}, or 0x{self.or_mask:04X}"
        if self.function == 23:
            what += f", read {self.read_count} from {self.read_address}"
        return f"{what}, {'writes ' + str(self.values) if self.values else f'count {self.count}'}"


def _range(what: str, value: int, top: int, section: str) -> str | None:
    if 1 <= value <= top:
        return None
    return f"{what} {value} (1..{top}; Modbus spec {section})"


def body_problem(pdu: bytes) -> str | None:
    """Why the request PDU (function code first) is answered exception 03,
    in words; None when its length, quantities, byte count and values are
    what its function's section allows. Functions not served: None."""
    f, body = pdu[0], pdu[1:]
    n = len(body)
    if f in (1, 2, 3, 4, 5, 6):
        if n != 4:
            return f"function {f} with {n} data bytes (4)"
        value = _U16.unpack_from(body, 2)[0]
        if f in (1, 2):
            return _range("a quantity of", value, 2000, f"6.{f}")
        if f in (3, 4):
            return _range("a quantity of", value, 125, f"6.{f}")
        if f == 5 and value not in (COIL_ON, COIL_OFF):
            return f"function 5 with the value 0x{value:04X} (0xFF00 or 0x0000; Modbus spec 6.5)"
        return None
    if f == 22:
        return None if n == 6 else f"function 22 with {n} data bytes (6)"
    if f in (15, 16):
        if n < 5:
            return f"function {f} with {n} data bytes"
        count, byte_count = _U16.unpack_from(body, 2)[0], body[4]
        section = "6.11" if f == 15 else "6.12"
        problem = _range("a quantity of", count, 1968 if f == 15 else 123, section)
        if problem:
            return problem
        expected = (count + 7) // 8 if f == 15 else 2 * count
        if byte_count != expected:
            return f"a byte count of {byte_count} for {count} {'coils' if f == 15 else 'registers'} " \
                   f"({expected}; Modbus spec {section})"
        if n != 5 + byte_count:
            return f"{n - 5} data bytes after a byte count of {byte_count}"
        return None
    if f == 23:
        if n < 9:
            return f"function 23 with {n} data bytes"
        read_count, write_count, byte_count = _U16.unpack_from(body, 2)[0], _U16.unpack_from(body, 6)[0], body[8]
        problem = (_range("a read quantity of", read_count, 125, "6.17")
                   or _range("a write quantity of", write_count, 121, "6.17"))
        if problem:
            return problem
        if byte_count != 2 * write_count:
            return f"a byte count of {byte_count} for {write_count} registers ({2 * write_count}; Modbus spec 6.17)"
        if n != 9 + byte_count:
            return f"{n - 9} data bytes after a byte count of {byte_count}"
    return None
