"""Modbus exception codes and the error raised for a PDU that cannot be decoded.

The codes are those of "Modbus Application Protocol Specification V1.1b3",
section 7 (MODBUS Exception Responses); which code answers which malformed
request follows the flow charts of section 6 (e.g. 6.3 for function 03):
01 for a function the slave does not implement, 03 for a wrong quantity,
byte count, length or value, 02 for an address range outside the slave's.

>>> str(ModbusDecodeError("quantity 0 out of range 1..125"))
'quantity 0 out of range 1..125 (exception 03 ILLEGAL DATA VALUE)'
"""

from __future__ import annotations

__all__ = [
    "ILLEGAL_FUNCTION", "ILLEGAL_DATA_ADDRESS", "ILLEGAL_DATA_VALUE", "SLAVE_DEVICE_FAILURE",
    "ACKNOWLEDGE", "SLAVE_DEVICE_BUSY", "NEGATIVE_ACKNOWLEDGE", "MEMORY_PARITY_ERROR",
    "GATEWAY_PATH_UNAVAILABLE", "GATEWAY_TARGET_FAILED_TO_RESPOND", "EXCEPTION_NAMES",
    "ModbusDecodeError",
]

# Exception codes, section 7.
ILLEGAL_FUNCTION = 0x01
ILLEGAL_DATA_ADDRESS = 0x02
ILLEGAL_DATA_VALUE = 0x03
SLAVE_DEVICE_FAILURE = 0x04
ACKNOWLEDGE = 0x05
SLAVE_DEVICE_BUSY = 0x06
NEGATIVE_ACKNOWLEDGE = 0x07
MEMORY_PARITY_ERROR = 0x08
GATEWAY_PATH_UNAVAILABLE = 0x0A
GATEWAY_TARGET_FAILED_TO_RESPOND = 0x0B

EXCEPTION_NAMES: dict[int, str] = {
    ILLEGAL_FUNCTION: "ILLEGAL FUNCTION",
    ILLEGAL_DATA_ADDRESS: "ILLEGAL DATA ADDRESS",
    ILLEGAL_DATA_VALUE: "ILLEGAL DATA VALUE",
    SLAVE_DEVICE_FAILURE: "SLAVE DEVICE FAILURE",
    ACKNOWLEDGE: "ACKNOWLEDGE",
    SLAVE_DEVICE_BUSY: "SLAVE DEVICE BUSY",
    NEGATIVE_ACKNOWLEDGE: "NEGATIVE ACKNOWLEDGE",
    MEMORY_PARITY_ERROR: "MEMORY PARITY ERROR",
    GATEWAY_PATH_UNAVAILABLE: "GATEWAY PATH UNAVAILABLE",
    GATEWAY_TARGET_FAILED_TO_RESPOND: "GATEWAY TARGET DEVICE FAILED TO RESPOND",
}


class ModbusDecodeError(ValueError):
    """A PDU that cannot be decoded; ``exception_code`` is the exception a
    slave answers to such a request (section 7; for a response, it tells
    what is wrong the same way)."""

    def __init__(self, message: str, exception_code: int = ILLEGAL_DATA_VALUE) -> None:
        name = EXCEPTION_NAMES.get(exception_code, "exception")
        super().__init__(f"{message} (exception {exception_code:02X} {name})")
        self.exception_code = exception_code

