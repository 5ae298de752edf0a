"""Modbus request PDUs (function code + data) of functions 1, 2, 3, 4, 5, 6,
15, 16, 22 and 23.

Follows "Modbus Application Protocol Specification V1.1b3": sections 6.1 (01
Read Coils), 6.2 (02 Read Discrete Inputs), 6.3 (03 Read Holding Registers),
6.4 (04 Read Input Registers), 6.5 (05 Write Single Coil), 6.6 (06 Write
Single Register), 6.11 (15 Write Multiple Coils), 6.12 (16 Write Multiple
Registers), 6.16 (22 Mask Write Register) and 6.17 (23 Read/Write Multiple
Registers); fields big-endian (section 4.2).

One frozen dataclass per request: ``function_code`` and the quantity limits
as class constants, ``encode()`` giving the PDU (function code first),
``decode(pdu)`` (classmethod, ``pdu`` with its function code) checking the
length, quantity and byte count (``ModbusDecodeError``, exception 03) and the
address range (exception 02), and ``expected_response_length()``, the PDU
length of the normal response. Constructors refuse illegal fields
(ValueError).

>>> ReadHoldingRegistersRequest(address=0, count=125).encode().hex(" ")
'03 00 00 00 7d'
>>> request = WriteMultipleCoilsRequest.decode(bytes.fromhex("0F 00 13 00 0A 02 CD 01"))
>>> request.address, request.count, request.values[:4]
(19, 10, (True, False, True, True))
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from ._fields import (
    ADDRESS_SPACE, FC_HH, FC_HHB, FC_HHH, FC_HHHHB, check_address_block, check_byte_count,
    check_pdu_start, check_quantity, refuse, require_bits, require_block, require_range,
    require_registers, unpack_fixed,
)
from .packing import bytes_to_registers, pack_bits, registers_to_bytes, unpack_bits

__all__ = [
    "ReadCoilsRequest", "ReadDiscreteInputsRequest", "ReadHoldingRegistersRequest",
    "ReadInputRegistersRequest", "WriteSingleCoilRequest", "WriteSingleRegisterRequest",
    "WriteMultipleCoilsRequest", "WriteMultipleRegistersRequest", "MaskWriteRegisterRequest",
    "ReadWriteMultipleRegistersRequest",
]


@dataclass(frozen=True)
class _AddressQuantity:
    """A PDU that is a start address and a quantity: the requests of
    functions 1-4 (sections 6.1-6.4) and the responses of 15 and 16 (6.11,
    6.12)."""

    function_code: ClassVar[int]
    MAX_COUNT: ClassVar[int]

    address: int
    count: int

    def __post_init__(self) -> None:
        require_block(type(self).__name__, self.address, self.count, self.MAX_COUNT)

    def encode(self) -> bytes:
        return FC_HH.pack(self.function_code, self.address, self.count)

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        address, count = unpack_fixed(cls, pdu, FC_HH)
        check_quantity(cls, "quantity", count, cls.MAX_COUNT)
        check_address_block(cls, address, count)
        return cls(address, count)


class _ReadRequest(_AddressQuantity):
    """Functions 1-4: read ``count`` items from ``address`` (sections 6.1-6.4)."""


class _ReadBitsRequest(_ReadRequest):
    MAX_COUNT = 2000  # 0x07D0

    def expected_response_length(self) -> int:
        """Function code, byte count, one byte per 8 bits."""
        return 2 + (self.count + 7) // 8


class _ReadRegistersRequest(_ReadRequest):
    MAX_COUNT = 125  # 0x007D

    def expected_response_length(self) -> int:
        """Function code, byte count, two bytes per register."""
        return 2 + 2 * self.count


class ReadCoilsRequest(_ReadBitsRequest):
    """01 Read Coils (section 6.1): ``count`` 1..2000 coils from ``address``."""

    function_code = 1


class ReadDiscreteInputsRequest(_ReadBitsRequest):
    """02 Read Discrete Inputs (section 6.2): ``count`` 1..2000 inputs."""

    function_code = 2


class ReadHoldingRegistersRequest(_ReadRegistersRequest):
    """03 Read Holding Registers (section 6.3): ``count`` 1..125 registers."""

    function_code = 3


class ReadInputRegistersRequest(_ReadRegistersRequest):
    """04 Read Input Registers (section 6.4): ``count`` 1..125 registers."""

    function_code = 4


@dataclass(frozen=True)
class _SingleCoil:
    """Function 5 request and its echo (section 6.5): ON is 0xFF00, OFF 0x0000
    on the wire; any other value is illegal (exception 03)."""

    function_code: ClassVar[int] = 5
    ON: ClassVar[int] = 0xFF00
    OFF: ClassVar[int] = 0x0000

    address: int
    value: bool

    def __post_init__(self) -> None:
        owner = type(self).__name__
        require_range(owner, "address", self.address, 0, ADDRESS_SPACE - 1)
        require_range(owner, "value", self.value, 0, 1)  # a bool (or 0 / 1)
        object.__setattr__(self, "value", bool(self.value))

    def encode(self) -> bytes:
        return FC_HH.pack(self.function_code, self.address, self.ON if self.value else self.OFF)

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        address, value = unpack_fixed(cls, pdu, FC_HH)
        if value not in (cls.ON, cls.OFF):
            refuse(cls, f"coil value {value:#06x} is neither 0xFF00 (ON) nor 0x0000 (OFF)")
        return cls(address, value == cls.ON)


class WriteSingleCoilRequest(_SingleCoil):
    """05 Write Single Coil (section 6.5): ``value`` True (ON) or False (OFF)."""

    def expected_response_length(self) -> int:
        return 5  # an echo of the request


@dataclass(frozen=True)
class _SingleRegister:
    """Function 6 request and its echo (section 6.6)."""

    function_code: ClassVar[int] = 6

    address: int
    value: int

    def __post_init__(self) -> None:
        owner = type(self).__name__
        require_range(owner, "address", self.address, 0, ADDRESS_SPACE - 1)
        require_range(owner, "value", self.value, 0, 0xFFFF)

    def encode(self) -> bytes:
        return FC_HH.pack(self.function_code, self.address, self.value)

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        return cls(*unpack_fixed(cls, pdu, FC_HH))


class WriteSingleRegisterRequest(_SingleRegister):
    """06 Write Single Register (section 6.6): ``value`` 0..65535 to ``address``."""

    def expected_response_length(self) -> int:
        return 5  # an echo of the request


@dataclass(frozen=True)
class WriteMultipleCoilsRequest:
    """15 Write Multiple Coils (section 6.11): 1..1968 ``values`` from
    ``address``. On decode, the unused high bits of the last byte are not
    checked (the spec asks the sender to zero them)."""

    function_code: ClassVar[int] = 15
    MAX_COUNT: ClassVar[int] = 1968  # 0x07B0

    address: int
    values: tuple[bool, ...]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "values", require_bits(owner, self.values, self.MAX_COUNT))
        require_block(owner, self.address, len(self.values), self.MAX_COUNT)

    @property
    def count(self) -> int:
        return len(self.values)

    def encode(self) -> bytes:
        data = pack_bits(self.values)
        return FC_HHB.pack(self.function_code, self.address, len(self.values), len(data)) + data

    @classmethod
    def decode(cls, pdu: bytes) -> WriteMultipleCoilsRequest:
        check_pdu_start(cls, pdu, FC_HHB.size)
        _, address, count, byte_count = FC_HHB.unpack_from(pdu)
        check_quantity(cls, "quantity", count, cls.MAX_COUNT)
        check_byte_count(cls, pdu, FC_HHB.size, byte_count, (count + 7) // 8)
        check_address_block(cls, address, count)
        return cls(address, tuple(unpack_bits(pdu[FC_HHB.size:], count)))

    def expected_response_length(self) -> int:
        return 5  # function code, address, quantity


@dataclass(frozen=True)
class WriteMultipleRegistersRequest:
    """16 Write Multiple Registers (section 6.12): 1..123 ``values`` from ``address``."""

    function_code: ClassVar[int] = 16
    MAX_COUNT: ClassVar[int] = 123  # 0x007B

    address: int
    values: tuple[int, ...]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "values", require_registers(owner, self.values, self.MAX_COUNT))
        require_block(owner, self.address, len(self.values), self.MAX_COUNT)

    @property
    def count(self) -> int:
        return len(self.values)

    def encode(self) -> bytes:
        count = len(self.values)
        header = FC_HHB.pack(self.function_code, self.address, count, 2 * count)
        return header + registers_to_bytes(self.values)

    @classmethod
    def decode(cls, pdu: bytes) -> WriteMultipleRegistersRequest:
        check_pdu_start(cls, pdu, FC_HHB.size)
        _, address, count, byte_count = FC_HHB.unpack_from(pdu)
        check_quantity(cls, "quantity", count, cls.MAX_COUNT)
        check_byte_count(cls, pdu, FC_HHB.size, byte_count, 2 * count)
        check_address_block(cls, address, count)
        return cls(address, tuple(bytes_to_registers(pdu[FC_HHB.size:])))

    def expected_response_length(self) -> int:
        return 5  # function code, address, quantity


@dataclass(frozen=True)
class _MaskWrite:
    """Function 22 request and its echo (section 6.16): the register becomes
    (current AND and_mask) OR (or_mask AND NOT and_mask)."""

    function_code: ClassVar[int] = 22

    address: int
    and_mask: int
    or_mask: int

    def __post_init__(self) -> None:
        owner = type(self).__name__
        require_range(owner, "address", self.address, 0, ADDRESS_SPACE - 1)
        require_range(owner, "and_mask", self.and_mask, 0, 0xFFFF)
        require_range(owner, "or_mask", self.or_mask, 0, 0xFFFF)

    def encode(self) -> bytes:
        return FC_HHH.pack(self.function_code, self.address, self.and_mask, self.or_mask)

    @classmethod
    def decode(cls, pdu: bytes) -> Self:
        return cls(*unpack_fixed(cls, pdu, FC_HHH))


class MaskWriteRegisterRequest(_MaskWrite):
    """22 Mask Write Register (section 6.16)."""

    def expected_response_length(self) -> int:
        return 7  # an echo of the request


@dataclass(frozen=True)
class ReadWriteMultipleRegistersRequest:
    """23 Read/Write Multiple Registers (section 6.17): write 1..121 ``values``
    from ``write_address``, then read ``read_count`` 1..125 registers from
    ``read_address``."""

    function_code: ClassVar[int] = 23
    MAX_READ_COUNT: ClassVar[int] = 125  # 0x007D
    MAX_WRITE_COUNT: ClassVar[int] = 121  # 0x0079

    read_address: int
    read_count: int
    write_address: int
    values: tuple[int, ...]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(self, "values", require_registers(owner, self.values, self.MAX_WRITE_COUNT))
        require_block(owner, self.read_address, self.read_count, self.MAX_READ_COUNT, "read_address")
        require_block(owner, self.write_address, len(self.values), self.MAX_WRITE_COUNT, "write_address")

    @property
    def write_count(self) -> int:
        return len(self.values)

    def encode(self) -> bytes:
        count = len(self.values)
        header = FC_HHHHB.pack(self.function_code, self.read_address, self.read_count,
                               self.write_address, count, 2 * count)
        return header + registers_to_bytes(self.values)

    @classmethod
    def decode(cls, pdu: bytes) -> ReadWriteMultipleRegistersRequest:
        check_pdu_start(cls, pdu, FC_HHHHB.size)
        _, read_address, read_count, write_address, write_count, byte_count = FC_HHHHB.unpack_from(pdu)
        check_quantity(cls, "read quantity", read_count, cls.MAX_READ_COUNT)
        check_quantity(cls, "write quantity", write_count, cls.MAX_WRITE_COUNT)
        check_byte_count(cls, pdu, FC_HHHHB.size, byte_count, 2 * write_count)
        check_address_block(cls, read_address, read_count)
        check_address_block(cls, write_address, write_count)
        values = tuple(bytes_to_registers(pdu[FC_HHHHB.size:]))
        return cls(read_address, read_count, write_address, values)

    def expected_response_length(self) -> int:
        """Function code, byte count, two bytes per register read."""
        return 2 + 2 * self.read_count
