"""A client's write of one variable: the checks it gets in the server
process before it goes to the scan, the bytes that carry it there, and how
the scan applies them to the data table (at its input point, in arrival
order: the network-server layer's ``through_scan``).

The status codes are OPC 10000-4's (5.10.4, the Write service, and 7.38,
the common StatusCodes), by name; asyncua_glue.py turns them into asyncua's.
"""

from __future__ import annotations

import struct
from array import array

from ...datatable.filetypes import STRING_CHARS
from ...datatable.table import store_text
from ...netserver import APPLIED, REFUSED
from .space import Space, Var

_HEAD = struct.Struct("=HIb")  # file (its index in Space.slots), item, bit (-1: the whole item); the value follows
NON_NEGATIVE = {"T": (1, 2), "R": (1, 2)}  # timer PRE/ACC, control LEN/POS: 0..32767 (a choice, PLC-5's ranges)


def item_of(space: Space, var: Var) -> int:
    slot = space.slots[var.slot]
    return (var.offset - slot.offset) // slot.itemsize


def check(space: Space, var: Var, value) -> tuple[str | None, bytes]:
    """(the status code's name that refuses ``value``, or None; the payload
    that carries it to the scan). Its type is checked already: a value of
    the node's DataType (BadTypeMismatch otherwise, OPC 10000-4 5.10.4)."""
    slot = space.slots[var.slot]
    item = item_of(space, var)
    head = _HEAD.pack(var.slot, item, var.bit)
    if var.kind == "Boolean":
        return None, head + bytes([1 if value else 0])
    if var.kind == "String":
        if len(value) > STRING_CHARS or any(ord(c) > 0xFFFF for c in value):
            return "BadOutOfRange", b""  # 82 UCS-2 characters at most (docs/datatable.md)
        return None, head + value.encode("utf-8")
    word = item % slot.per
    if value < 0 and word in NON_NEGATIVE.get(slot.letter, ()):
        return "BadOutOfRange", b""
    return None, head + array(slot.typecode, [value]).tobytes()


def apply(space: Space, payload: bytes, table) -> str:
    """The write as the scan applies it; the scan checks its element is
    writable again (the server checked it against the same space)."""
    k, item, bit = _HEAD.unpack_from(payload)
    slot = space.slots[k]
    if not space.may_write(slot, item, bit):
        return REFUSED
    data = table.file(slot.name).data
    rest = payload[_HEAD.size:]
    if bit >= 0:  # a bit of a word (or of a Logix host item, whose width the file's items give)
        width = 8 * slot.itemsize
        word = data[item] & ((1 << width) - 1)
        word = word | (1 << bit) if rest[0] else word & ~(1 << bit)
        data[item] = word - (1 << width) if word >> (width - 1) else word
    elif slot.letter in ("ST", "SL"):
        store_text(data, item, rest.decode("utf-8"), slot.per - 1)
    else:
        data[item] = array(slot.typecode, rest)[0]
    return APPLIED
