"""Modbus PDUs (function code + data) of functions 1, 2, 3, 4, 5, 6, 15, 16,
22, 23 and the exception response: one place to import them from, and the
decoder tables.

Follows "Modbus Application Protocol Specification V1.1b3": PDU layout and
its 253-byte limit, section 4.1; big-endian fields, section 4.2; the
functions, sections 6.1 (01 Read Coils), 6.2 (02 Read Discrete Inputs), 6.3
(03 Read Holding Registers), 6.4 (04 Read Input Registers), 6.5 (05 Write
Single Coil), 6.6 (06 Write Single Register), 6.11 (15 Write Multiple Coils),
6.12 (16 Write Multiple Registers), 6.16 (22 Mask Write Register), 6.17 (23
Read/Write Multiple Registers); exception responses and codes, section 7.

The classes live in ``request_pdus`` and ``response_pdus`` (one frozen
dataclass per PDU, pymodbus-style: ``function_code`` and limits such as
``MAX_COUNT`` as class constants, ``encode() -> bytes`` giving the whole PDU,
the classmethod ``decode(pdu)`` taking it back). Constructors refuse fields
no valid PDU can carry (ValueError). ``decode`` refuses a malformed PDU with
``ModbusDecodeError``, whose ``exception_code`` is what a slave answers (the
spec's flow charts): 01 for an unknown function, 03 for a wrong length,
quantity, byte count or coil value, 02 when start address + quantity passes
address 65535.

Here: the exception codes and ``ModbusDecodeError`` (from ``errors``), the
decoder tables ``REQUESTS`` and ``RESPONSES`` (function code -> class),
``decode_request`` and ``decode_response`` (a function code with bit 0x80
set is an ``ExceptionResponse``), and the data-moving helpers ``pack_bits``,
``unpack_bits``, ``registers_to_bytes``, ``bytes_to_registers`` (from
``packing``: the hot path of a master, whole buffers at a time).

>>> request = decode_request(bytes.fromhex("03 00 00 00 7D"))
>>> request, request.expected_response_length()
(ReadHoldingRegistersRequest(address=0, count=125), 252)
>>> decode_response(bytes.fromhex("83 02"))
ExceptionResponse(function_code=3, exception_code=2)
>>> try:
...     decode_request(bytes.fromhex("03 00 00 00 00"))
... except ModbusDecodeError as error:
...     print(error.exception_code, error)
3 ReadHoldingRegistersRequest: quantity 0 out of range 1..125 (exception 03 ILLEGAL DATA VALUE)
"""

from __future__ import annotations

from ._fields import MAX_PDU_LENGTH
from .errors import (
    ACKNOWLEDGE, EXCEPTION_NAMES, GATEWAY_PATH_UNAVAILABLE, GATEWAY_TARGET_FAILED_TO_RESPOND,
    ILLEGAL_DATA_ADDRESS, ILLEGAL_DATA_VALUE, ILLEGAL_FUNCTION, MEMORY_PARITY_ERROR,
    NEGATIVE_ACKNOWLEDGE, SLAVE_DEVICE_BUSY, SLAVE_DEVICE_FAILURE, ModbusDecodeError,
)
from .packing import bytes_to_registers, pack_bits, registers_to_bytes, unpack_bits
from .request_pdus import (
    MaskWriteRegisterRequest, ReadCoilsRequest, ReadDiscreteInputsRequest,
    ReadHoldingRegistersRequest, ReadInputRegistersRequest, ReadWriteMultipleRegistersRequest,
    WriteMultipleCoilsRequest, WriteMultipleRegistersRequest, WriteSingleCoilRequest,
    WriteSingleRegisterRequest,
)
from .response_pdus import (
    ExceptionResponse, MaskWriteRegisterResponse, ReadCoilsResponse, ReadDiscreteInputsResponse,
    ReadHoldingRegistersResponse, ReadInputRegistersResponse, ReadWriteMultipleRegistersResponse,
    WriteMultipleCoilsResponse, WriteMultipleRegistersResponse, WriteSingleCoilResponse,
    WriteSingleRegisterResponse,
)

__all__ = [
    "ILLEGAL_FUNCTION", "ILLEGAL_DATA_ADDRESS", "ILLEGAL_DATA_VALUE", "SLAVE_DEVICE_FAILURE",
    "ACKNOWLEDGE", "SLAVE_DEVICE_BUSY", "NEGATIVE_ACKNOWLEDGE", "MEMORY_PARITY_ERROR",
    "GATEWAY_PATH_UNAVAILABLE", "GATEWAY_TARGET_FAILED_TO_RESPOND", "EXCEPTION_NAMES",
    "MAX_PDU_LENGTH", "ModbusDecodeError",
    "ReadCoilsRequest", "ReadDiscreteInputsRequest", "ReadHoldingRegistersRequest",
    "ReadInputRegistersRequest", "WriteSingleCoilRequest", "WriteSingleRegisterRequest",
    "WriteMultipleCoilsRequest", "WriteMultipleRegistersRequest", "MaskWriteRegisterRequest",
    "ReadWriteMultipleRegistersRequest",
    "ReadCoilsResponse", "ReadDiscreteInputsResponse", "ReadHoldingRegistersResponse",
    "ReadInputRegistersResponse", "WriteSingleCoilResponse", "WriteSingleRegisterResponse",
    "WriteMultipleCoilsResponse", "WriteMultipleRegistersResponse", "MaskWriteRegisterResponse",
    "ReadWriteMultipleRegistersResponse", "ExceptionResponse",
    "ModbusRequest", "ModbusResponse", "REQUESTS", "RESPONSES", "decode_request", "decode_response",
    "pack_bits", "unpack_bits", "registers_to_bytes", "bytes_to_registers",
]

# Any request or response of this codec (for annotations and isinstance()).
ModbusRequest = (
    ReadCoilsRequest | ReadDiscreteInputsRequest | ReadHoldingRegistersRequest
    | ReadInputRegistersRequest | WriteSingleCoilRequest | WriteSingleRegisterRequest
    | WriteMultipleCoilsRequest | WriteMultipleRegistersRequest | MaskWriteRegisterRequest
    | ReadWriteMultipleRegistersRequest
)
ModbusResponse = (
    ReadCoilsResponse | ReadDiscreteInputsResponse | ReadHoldingRegistersResponse
    | ReadInputRegistersResponse | WriteSingleCoilResponse | WriteSingleRegisterResponse
    | WriteMultipleCoilsResponse | WriteMultipleRegistersResponse | MaskWriteRegisterResponse
    | ReadWriteMultipleRegistersResponse | ExceptionResponse
)

REQUESTS: dict[int, type] = {cls.function_code: cls for cls in (
    ReadCoilsRequest, ReadDiscreteInputsRequest, ReadHoldingRegistersRequest,
    ReadInputRegistersRequest, WriteSingleCoilRequest, WriteSingleRegisterRequest,
    WriteMultipleCoilsRequest, WriteMultipleRegistersRequest, MaskWriteRegisterRequest,
    ReadWriteMultipleRegistersRequest)}

RESPONSES: dict[int, type] = {cls.function_code: cls for cls in (
    ReadCoilsResponse, ReadDiscreteInputsResponse, ReadHoldingRegistersResponse,
    ReadInputRegistersResponse, WriteSingleCoilResponse, WriteSingleRegisterResponse,
    WriteMultipleCoilsResponse, WriteMultipleRegistersResponse, MaskWriteRegisterResponse,
    ReadWriteMultipleRegistersResponse)}


def decode_request(pdu: bytes) -> ModbusRequest:
    """The request in ``pdu``; ModbusDecodeError (exception 01) for a function
    not in ``REQUESTS``, or what the class's ``decode`` finds wrong.

    >>> decode_request(bytes.fromhex("05 00 07 FF 00"))
    WriteSingleCoilRequest(address=7, value=True)
    """
    if not pdu:
        raise ModbusDecodeError("empty PDU: no function code", ILLEGAL_FUNCTION)
    cls = REQUESTS.get(pdu[0])
    if cls is None:
        raise ModbusDecodeError(f"function code {pdu[0]:#04x} is not supported", ILLEGAL_FUNCTION)
    return cls.decode(pdu)


def decode_response(pdu: bytes) -> ModbusResponse:
    """The response in ``pdu``: an ``ExceptionResponse`` when the function
    code has bit 0x80 set, else the class in ``RESPONSES`` (ModbusDecodeError,
    exception 01, for another function).

    >>> decode_response(bytes.fromhex("03 04 00 01 FF FF"))
    ReadHoldingRegistersResponse(values=(1, 65535))
    """
    if not pdu:
        raise ModbusDecodeError("empty PDU: no function code", ILLEGAL_FUNCTION)
    if pdu[0] & 0x80:
        return ExceptionResponse.decode(pdu)
    cls = RESPONSES.get(pdu[0])
    if cls is None:
        raise ModbusDecodeError(f"function code {pdu[0]:#04x} is not supported", ILLEGAL_FUNCTION)
    return cls.decode(pdu)
