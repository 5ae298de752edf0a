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
from .framing import FRAMERS, AsciiFramer, FrameError, RtuFramer, rtu_intervals_ns
from .pdu import *  # noqa: F403  (PDUs, exception codes, decoder tables, packing helpers)
from .pdu import __all__ as _PDU_NAMES

__all__ = ["crc16", "lrc", "FRAMERS", "AsciiFramer", "FrameError", "RtuFramer", "rtu_intervals_ns", *_PDU_NAMES]
