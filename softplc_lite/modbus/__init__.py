"""The Modbus codec of softplc_lite: every Modbus part of the project (the
master, the simulated slave, the tests) encodes and decodes through here.

Three layers, pure functions of bytes (no I/O, no timing, no threads):

- PDUs (``pdu``, with the classes in ``request_pdus`` and ``response_pdus``):
  requests and responses of functions 1, 2, 3, 4, 5, 6, 15, 16, 22, 23 and
  the exception response, after "Modbus Application Protocol Specification
  V1.1b3" (sections 4, 6 and 7); the decoder tables ``REQUESTS`` /
  ``RESPONSES``; the fast helpers for bits and registers (``packing``).
- Framers (``framing``): RTU and ASCII frames around a PDU, the RTU response
  length, the RTU silent intervals, after "Modbus over Serial Line
  Specification and Implementation Guide V1.02" (sections 2.3 and 2.5).
- Check sums (``crc``): the RTU CRC-16 and the ASCII LRC (same guide,
  sections 2.5.1.2, 2.5.2.2 and Appendix B).

A read of ten registers, wrapped and unwrapped:

>>> request = ReadHoldingRegistersRequest(address=0x1389, count=10)
>>> AsciiFramer.encode(0xF7, request.encode())
b':F7031389000A60\\r\\n'
>>> unit, pdu = RtuFramer.decode(RtuFramer.encode(0xF7, request.encode()))
>>> unit, decode_request(pdu) == request
(247, True)
"""

from .crc import crc16, lrc
from .errors import (
    ACKNOWLEDGE, EXCEPTION_NAMES, GATEWAY_PATH_UNAVAILABLE, GATEWAY_TARGET_FAILED_TO_RESPOND,
    ILLEGAL_DATA_ADDRESS, ILLEGAL_DATA_VALUE, ILLEGAL_FUNCTION, MEMORY_PARITY_ERROR,
    NEGATIVE_ACKNOWLEDGE, SLAVE_DEVICE_BUSY, SLAVE_DEVICE_FAILURE, ModbusDecodeError,
)
from .framing import FRAMERS, AsciiFramer, FrameError, RtuFramer, rtu_intervals_ns
from .packing import bytes_to_registers, pack_bits, registers_to_bytes, unpack_bits
from .pdu import (
    MAX_PDU_LENGTH, REQUESTS, RESPONSES, ModbusRequest, ModbusResponse, decode_request,
    decode_response,
)
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
    # check sums
    "crc16", "lrc",
    # exception codes and decode errors
    "ILLEGAL_FUNCTION", "ILLEGAL_DATA_ADDRESS", "ILLEGAL_DATA_VALUE", "SLAVE_DEVICE_FAILURE",
    "ACKNOWLEDGE", "SLAVE_DEVICE_BUSY", "NEGATIVE_ACKNOWLEDGE", "MEMORY_PARITY_ERROR",
    "GATEWAY_PATH_UNAVAILABLE", "GATEWAY_TARGET_FAILED_TO_RESPOND", "EXCEPTION_NAMES",
    "ModbusDecodeError",
    # PDUs
    "MAX_PDU_LENGTH", "REQUESTS", "RESPONSES", "ModbusRequest", "ModbusResponse",
    "decode_request", "decode_response",
    "ReadCoilsRequest", "ReadDiscreteInputsRequest", "ReadHoldingRegistersRequest",
    "ReadInputRegistersRequest", "WriteSingleCoilRequest", "WriteSingleRegisterRequest",
    "WriteMultipleCoilsRequest", "WriteMultipleRegistersRequest", "MaskWriteRegisterRequest",
    "ReadWriteMultipleRegistersRequest",
    "ReadCoilsResponse", "ReadDiscreteInputsResponse", "ReadHoldingRegistersResponse",
    "ReadInputRegistersResponse", "WriteSingleCoilResponse", "WriteSingleRegisterResponse",
    "WriteMultipleCoilsResponse", "WriteMultipleRegistersResponse", "MaskWriteRegisterResponse",
    "ReadWriteMultipleRegistersResponse", "ExceptionResponse",
    # data-moving helpers
    "pack_bits", "unpack_bits", "registers_to_bytes", "bytes_to_registers",
    # framers
    "FrameError", "RtuFramer", "AsciiFramer", "FRAMERS", "rtu_intervals_ns",
]
