"""Modbus response PDUs (function code + data) of functions 1, 2, 3, 4, 5,
6, 15, 16, 22 and 23, and the exception response.

Follows "Modbus Application Protocol Specification V1.1b3": the response
parts of sections 6.1-6.6, 6.11, 6.12, 6.16 and 6.17 (same functions as
``request_pdus``), big-endian fields (section 4.2), exception responses
(section 7: function code + 0x80, exception code).

As for requests: frozen dataclasses, ``function_code`` and limits as class
constants, ``encode()`` / ``decode(pdu)`` (``ModbusDecodeError`` for a wrong
length or byte count), constructors refusing illegal fields (ValueError).
The echoes of functions 5, 6 and 22 share their request's layout.

>>> ReadHoldingRegistersResponse(values=(1, 0xBEEF)).encode().hex(" ")
'03 04 00 01 be ef'
>>> ReadCoilsResponse.decode(bytes.fromhex("01 01 05")).bits[:3]  # all 8 bits; trim to the count
(True, False, True)
>>> ExceptionResponse(function_code=3, exception_code=2).encode().hex(" ")
'83 02'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from ._fields import (
    FC_B, check_pdu_length, check_pdu_start, check_quantity,
    refuse, require_bits, require_range, require_registers,
)
from .errors import EXCEPTION_NAMES, ILLEGAL_FUNCTION
from .packing import bytes_to_registers, pack_bits, registers_to_bytes, unpack_bits
from .request_pdus import (  # the echoes share their request's layout
    WriteMultipleCoilsRequest, WriteMultipleRegistersRequest, _AddressQuantity, _MaskWrite, _SingleCoil,
    _SingleRegister,
)

__all__ = [
    "ReadCoilsResponse", "ReadDiscreteInputsResponse", "ReadHoldingRegistersResponse",
    "ReadInputRegistersResponse", "WriteSingleCoilResponse", "WriteSingleRegisterResponse",
    "WriteMultipleCoilsResponse", "WriteMultipleRegistersResponse", "MaskWriteRegisterResponse",
    "ReadWriteMultipleRegistersResponse", "ExceptionResponse",
]


@dataclass(frozen=True)
class _BitsResponse:
    """Functions 1 and 2 (sections 6.1, 6.2): byte count, then the bits, 8 a
    byte, the first in the lowest bit. ``decode`` gives every bit of the
    bytes (a multiple of 8); the caller trims them to the count it asked for."""

    function_code: ClassVar[int]
    MAX_COUNT: ClassVar[int] = 2000
    MAX_BYTE_COUNT: ClassVar[int] = 250

    bits: tuple[bool, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "bits", require_bits(type(self).__name__, self.bits, self.MAX_COUNT))

    def encode(self) -> bytes:
        data = pack_bits(self.bits)
        return FC_B.pack(self.function_code, len(data)) + data

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        check_pdu_start(cls, pdu, FC_B.size)
        byte_count = pdu[1]
        check_quantity(cls, "byte count", byte_count, cls.MAX_BYTE_COUNT)
        check_pdu_length(cls, pdu, FC_B.size + byte_count)
        return cls(tuple(unpack_bits(pdu[FC_B.size:], 8 * byte_count)))


class ReadCoilsResponse(_BitsResponse):
    """01 Read Coils response; ``decode`` gives a multiple of 8 bits (trim them)."""

    function_code = 1


class ReadDiscreteInputsResponse(_BitsResponse):
    """02 Read Discrete Inputs response; ``decode`` gives a multiple of 8 bits (trim them)."""

    function_code = 2


@dataclass(frozen=True)
class _RegistersResponse:
    """Functions 3, 4 and 23 (sections 6.3, 6.4, 6.17): byte count, then
    1..125 registers, big-endian."""

    function_code: ClassVar[int]
    MAX_COUNT: ClassVar[int] = 125

    values: tuple[int, ...]

    def __post_init__(self) -> None:
        values = require_registers(type(self).__name__, self.values, self.MAX_COUNT)
        object.__setattr__(self, "values", values)

    def encode(self) -> bytes:
        return FC_B.pack(self.function_code, 2 * len(self.values)) + registers_to_bytes(self.values)

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        check_pdu_start(cls, pdu, FC_B.size)
        byte_count = pdu[1]
        if byte_count % 2 or not 2 <= byte_count <= 2 * cls.MAX_COUNT:
            refuse(cls, f"byte count {byte_count} is not an even number 2..{2 * cls.MAX_COUNT}")
        check_pdu_length(cls, pdu, FC_B.size + byte_count)
        return cls(tuple(bytes_to_registers(pdu[FC_B.size:])))


class ReadHoldingRegistersResponse(_RegistersResponse):
    """03 Read Holding Registers response."""

    function_code = 3


class ReadInputRegistersResponse(_RegistersResponse):
    """04 Read Input Registers response."""

    function_code = 4


class ReadWriteMultipleRegistersResponse(_RegistersResponse):
    """23 Read/Write Multiple Registers response: the registers read."""

    function_code = 23


class WriteSingleCoilResponse(_SingleCoil):
    """05 Write Single Coil response: the request echoed."""


class WriteSingleRegisterResponse(_SingleRegister):
    """06 Write Single Register response: the request echoed."""


class MaskWriteRegisterResponse(_MaskWrite):
    """22 Mask Write Register response: the request echoed."""


class _WriteMultipleResponse(_AddressQuantity):
    """Functions 15 and 16 (sections 6.11, 6.12): start address and quantity written."""


class WriteMultipleCoilsResponse(_WriteMultipleResponse):
    """15 Write Multiple Coils response."""

    function_code = 15
    MAX_COUNT = WriteMultipleCoilsRequest.MAX_COUNT


class WriteMultipleRegistersResponse(_WriteMultipleResponse):
    """16 Write Multiple Registers response."""

    function_code = 16
    MAX_COUNT = WriteMultipleRegistersRequest.MAX_COUNT


@dataclass(frozen=True)
class ExceptionResponse:
    """An exception response (section 7): ``function_code`` is the request's
    (1..127); on the wire it is sent with bit 0x80 set, then ``exception_code``."""

    function_code: int
    exception_code: int

    def __post_init__(self) -> None:
        require_range("ExceptionResponse", "function_code", self.function_code, 1, 0x7F)
        require_range("ExceptionResponse", "exception_code", self.exception_code, 1, 0xFF)

    @property
    def name(self) -> str:
        """The exception's name, e.g. "ILLEGAL DATA ADDRESS"."""
        return EXCEPTION_NAMES.get(self.exception_code, f"EXCEPTION {self.exception_code:#04x}")

    def encode(self) -> bytes:
        return bytes((self.function_code | 0x80, self.exception_code))

    @classmethod
    def decode(cls, pdu: bytes) -> ExceptionResponse:
        if not pdu or not pdu[0] & 0x80 or pdu[0] == 0x80:
            refuse(cls, f"PDU {bytes(pdu[:1]).hex()!r} does not start with a function code "
                   "0x81..0xFF", ILLEGAL_FUNCTION)
        check_pdu_length(cls, pdu, 2)
        if not pdu[1]:
            refuse(cls, "exception code 0")
        return cls(pdu[0] & 0x7F, pdu[1])
