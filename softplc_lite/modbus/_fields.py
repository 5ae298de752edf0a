"""Field checks and struct layouts shared by the PDU classes (internal).

Two families: ``require_*`` for constructors, raising ValueError so that no
illegal PDU can be built; ``check_*`` for decoders, raising
``ModbusDecodeError`` with the exception code a slave answers ("Modbus
Application Protocol Specification V1.1b3", section 7 and the flow charts of
section 6). Addresses are 0..65535, and a block of ``count`` items from
``address`` must end at 65535 at the latest (sections 4.3 and 4.4, the data
and addressing models: up to 65536 items per table, addressed 0..65535); the
quantity limits are those of section 6.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from typing import NoReturn

from .errors import ILLEGAL_DATA_ADDRESS, ILLEGAL_DATA_VALUE, ILLEGAL_FUNCTION, ModbusDecodeError

ADDRESS_SPACE = 0x10000  # addresses 0..65535
# Section 4.1: a PDU is 253 bytes at most (the 256-byte serial ADU less address and CRC).
MAX_PDU_LENGTH = 253

FC_HH = struct.Struct(">BHH")  # function code, two 16-bit fields
FC_HHH = struct.Struct(">BHHH")  # function code, three 16-bit fields
FC_HHB = struct.Struct(">BHHB")  # function code, address, quantity, byte count
FC_HHHHB = struct.Struct(">BHHHHB")  # function 23: read address, count, write address, count, byte count
FC_B = struct.Struct(">BB")  # function code, byte count


# --- constructors: ValueError ---------------------------------------------------

def require_range(owner: str, name: str, value: object, low: int, high: int) -> None:
    """``value`` must be an int (a bool counts) in ``low..high``."""
    if not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"{owner}: {name} must be an integer {low}..{high}, not {value!r}")


def require_block(owner: str, address: int, count: int, max_count: int, name: str = "address") -> None:
    """``count`` 1..``max_count`` items from ``address``, all within 0..65535."""
    require_range(owner, name, address, 0, ADDRESS_SPACE - 1)
    require_range(owner, "quantity", count, 1, max_count)
    if address + count > ADDRESS_SPACE:
        raise ValueError(f"{owner}: {name} {address} + quantity {count} passes address 65535")


def require_registers(owner: str, values: Iterable[int], max_count: int) -> tuple[int, ...]:
    """``values`` as a tuple of 1..``max_count`` register values 0..65535."""
    values = tuple(values)
    require_range(owner, "number of values", len(values), 1, max_count)
    for value in values:
        require_range(owner, "register value", value, 0, 0xFFFF)
    return values


def require_bits(owner: str, bits: Iterable[bool], max_count: int) -> tuple[bool, ...]:
    """``bits`` as a tuple of 1..``max_count`` bools."""
    bits = tuple(map(bool, bits))
    require_range(owner, "number of bits", len(bits), 1, max_count)
    return bits


# --- decoders: ModbusDecodeError ------------------------------------------------

def refuse(cls: type, message: str, code: int = ILLEGAL_DATA_VALUE) -> NoReturn:
    raise ModbusDecodeError(f"{cls.__name__}: {message}", code)


def check_pdu_start(cls: type, pdu: bytes, min_length: int) -> None:
    """``pdu`` starts with ``cls.function_code`` (else exception 01) and has at
    least ``min_length`` bytes (else 03)."""
    if not pdu or pdu[0] != cls.function_code:
        refuse(cls, f"PDU {bytes(pdu[:1]).hex()!r} does not start with function code "
               f"{cls.function_code:#04x}", ILLEGAL_FUNCTION)
    if len(pdu) < min_length:
        refuse(cls, f"PDU of {len(pdu)} bytes, at least {min_length} needed")


def check_pdu_length(cls: type, pdu: bytes, length: int) -> None:
    if len(pdu) != length:
        refuse(cls, f"PDU of {len(pdu)} bytes, must be {length}")


def unpack_fixed(cls: type, pdu: bytes, layout: struct.Struct) -> tuple[int, ...]:
    """The fields after the function code of a PDU of fixed length."""
    check_pdu_start(cls, pdu, layout.size)
    check_pdu_length(cls, pdu, layout.size)
    return layout.unpack(pdu)[1:]


def check_quantity(cls: type, name: str, count: int, max_count: int) -> None:
    if not 1 <= count <= max_count:
        refuse(cls, f"{name} {count} out of range 1..{max_count}")


def check_address_block(cls: type, address: int, count: int) -> None:
    """Exception 02 when ``count`` items from ``address`` pass address 65535."""
    if address + count > ADDRESS_SPACE:
        refuse(cls, f"address {address} + quantity {count} passes address 65535", ILLEGAL_DATA_ADDRESS)


def check_byte_count(cls: type, pdu: bytes, header_length: int, byte_count: int, needed: int) -> None:
    """The byte count must be what the quantity needs and the number of bytes sent."""
    if byte_count != needed:
        refuse(cls, f"byte count {byte_count}, the quantity needs {needed}")
    check_pdu_length(cls, pdu, header_length + byte_count)
