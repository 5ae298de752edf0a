"""PCCC, the PLC-5/SLC command set, as CIP's Execute PCCC service (0x4B to
the PCCC object, class 0x67) carries it: one class per command with
``decode`` and ``encode`` (pymodbus's shape), apart from the object that
serves them (tlm/enips/pccc_object.py).

Sources: AB's *DF1 Protocol and Command Set* (1770-6.5.16): chapter 6 "Command
and reply message packet format" (CMD, STS, TNS, FNC, EXT STS), chapter 7
"Communication commands" (echo 06/00, diagnostic status 06/03, word range
read 0F/01 and write 0F/00, read-modify-write 0F/26, typed read 0F/68 and
typed write 0F/67, protected typed logical read/write with two and three
address fields 0F/A1 A2 A9 AA and the masked write 0F/AB), chapter 7's
"PLC-5 logical binary addressing" (the mask byte, then one field a level)
and "data type/parameter" bytes; the Execute PCCC request's requestor ID
(length 7, vendor, serial) as pycomm3 and libplctag send it.

An address field is one byte, or 0xFF then two bytes little-endian (values
255 and up)."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

EXECUTE_PCCC = 0x4B
REPLY_FLAG = 0x40  # CMD | 0x40 in a reply (1770-6.5.16, ch. 6)

# STS (1770-6.5.16, ch. 8 "Error codes", local and remote STS)
STS_OK = 0x00
STS_ILLEGAL = 0x10  # illegal command or format
STS_ADDRESS = 0x50  # addressing problem or memory protect rungs
STS_PROTECTED = 0x60  # function not allowed due to command protection selection
STS_EXTENDED = 0xF0  # the EXT STS byte after TNS says what

# EXT STS, after STS 0xF0 (1770-6.5.16, ch. 8, the extended status of the
# typed and word-range commands; libplctag's pccc_decode_error names them the same)
EXT_ADDRESS_CONVERSION = 0x01  # error converting block address
EXT_TOO_FEW_LEVELS = 0x02  # fewer levels in the address than any address has
EXT_TOO_MANY_LEVELS = 0x03  # more levels than the system supports
EXT_NOT_USABLE = 0x06  # the address does not point to something usable (no such file, wrong type)
EXT_WRONG_SIZE = 0x07  # the file is the wrong size (data and size disagree)
EXT_TOO_LARGE = 0x0A  # transaction size plus word address is too large (past the file's end)
EXT_ACCESS_DENIED = 0x0B  # access denied, improper privilege
EXT_DATA_TYPE = 0x11  # illegal data type
EXT_BAD_PARAMETER = 0x12  # invalid parameter or invalid data

# File type codes of the SLC typed logical commands (1770-6.5.16 ch. 7;
# pycomm3's PCCC_DATA_TYPE; libplctag's list). O and I have two codes each:
# pycomm3 sends 0x82/0x83, libplctag 0x8B/0x8C; both are taken.
FILE_TYPES = {0x82: "O", 0x8B: "O", 0x83: "I", 0x8C: "I", 0x84: "S", 0x85: "B", 0x86: "T", 0x87: "C", 0x88: "R",
              0x89: "N", 0x8A: "F", 0x8D: "ST", 0x8E: "A", 0x8F: "D", 0x91: "L"}
TYPE_CODES = {"O": 0x82, "I": 0x83, "S": 0x84, "B": 0x85, "T": 0x86, "C": 0x87, "R": 0x88, "N": 0x89, "F": 0x8A,
              "ST": 0x8D, "A": 0x8E, "D": 0x8F, "L": 0x91}

# Data type/parameter type numbers (1770-6.5.16 ch. 7, "data type" table).
DT_BIT, DT_BIT_STRING, DT_BYTE_STRING, DT_INTEGER = 1, 2, 3, 4
DT_TIMER, DT_COUNTER, DT_CONTROL, DT_FLOAT, DT_ARRAY, DT_ADDRESS, DT_BCD = 5, 6, 7, 8, 9, 15, 16


class PcccError(ValueError):
    """A command that cannot be decoded: the STS (and EXT STS) that refuse it."""

    def __init__(self, sts: int, ext: int | None = None, why: str = "") -> None:
        super().__init__(why)
        self.sts, self.ext, self.why = sts, ext, why


# -- fields ---------------------------------------------------------------------------------

class Reader:
    """Reads a command's fields in order; running out is an illegal format."""

    def __init__(self, data: bytes, at: int = 0) -> None:
        self.data, self.at = data, at

    def take(self, n: int) -> bytes:
        if self.at + n > len(self.data):
            raise PcccError(STS_ILLEGAL, None, f"the command ends after {len(self.data)} bytes; a field needs {n} more")
        out = self.data[self.at:self.at + n]
        self.at += n
        return out

    def byte(self) -> int:
        return self.take(1)[0]

    def word(self) -> int:
        return struct.unpack("<H", self.take(2))[0]

    def field(self) -> int:
        """An address field: a byte, or 0xFF then a word."""
        value = self.byte()
        return self.word() if value == 0xFF else value

    def rest(self) -> bytes:
        out = self.data[self.at:]
        self.at = len(self.data)
        return out

    def end(self) -> None:
        if self.at != len(self.data):
            raise PcccError(STS_ILLEGAL, None, f"{len(self.data) - self.at} bytes past the command's fields")


def encode_field(value: int) -> bytes:
    return bytes((value,)) if value < 0xFF else b"\xff" + struct.pack("<H", value)


@dataclass(frozen=True)
class Plc5Address:
    """A PLC-5 logical binary address (1770-6.5.16 ch. 7): a mask byte whose
    bits say which levels follow (bit 0 the data table area, always 0 here;
    bit 1 the file, bit 2 the element, bit 3 the sub-element), then a field
    a level."""

    file: int
    element: int
    sub: int | None = None

    @classmethod
    def read(cls, r: Reader) -> "Plc5Address":
        mask = r.byte()
        levels = [bit for bit in range(8) if mask >> bit & 1]
        values = [r.field() for _ in levels]
        if 0 in levels and values[levels.index(0)] != 0:
            raise PcccError(STS_EXTENDED, EXT_NOT_USABLE, "a PLC-5 address outside the data table area")
        if 1 not in levels or 2 not in levels:
            raise PcccError(STS_EXTENDED, EXT_TOO_FEW_LEVELS, f"a PLC-5 address with levels {levels}: the file "
                                                              "and the element are needed")
        if max(levels) > 3:
            raise PcccError(STS_EXTENDED, EXT_TOO_MANY_LEVELS, f"a PLC-5 address with levels {levels}: a data table "
                                                               "address has at most file, element, sub-element")
        sub = values[levels.index(3)] if 3 in levels else None
        return cls(values[levels.index(1)], values[levels.index(2)], sub)

    def encode(self) -> bytes:
        mask = 0x06 | (0x08 if self.sub is not None else 0)
        out = bytes((mask,)) + encode_field(self.file) + encode_field(self.element)
        return out + (encode_field(self.sub) if self.sub is not None else b"")


def encode_type_param(kind: int, size: int) -> bytes:
    """A data type/parameter field: a byte of two nibbles (type, size), each
    a value 0..7 or 8+n where n bytes of the value follow, type first."""
    def part(value: int) -> tuple[int, bytes]:
        if value <= 7:
            return value, b""
        raw = value.to_bytes(max(1, (value.bit_length() + 7) // 8), "little")
        return 0x08 | len(raw), raw
    t, t_bytes = part(kind)
    s, s_bytes = part(size)
    return bytes(((t << 4) | s,)) + t_bytes + s_bytes


def read_type_param(r: Reader) -> tuple[int, int]:
    first = r.byte()

    def part(nibble: int) -> int:
        if nibble & 0x08:
            return int.from_bytes(r.take(nibble & 0x07), "little")
        return nibble
    kind = part(first >> 4)
    size = part(first & 0x0F)
    return kind, size


# -- the message ----------------------------------------------------------------------------

@dataclass(frozen=True)
class PcccRequest:
    """Execute PCCC's request data: the requestor ID (length, vendor, serial,
    and any more bytes its length names), then CMD, STS, TNS, FNC and the
    function's data. CMD 0x06's functions and 0x0F's all have an FNC."""

    requestor: bytes  # the whole requestor ID, echoed in the reply
    cmd: int
    tns: int
    fnc: int
    body: bytes

    @classmethod
    def decode(cls, data: bytes) -> "PcccRequest":
        if not data or len(data) < data[0] + 5:
            raise PcccError(STS_ILLEGAL, None, f"an Execute PCCC request of {len(data)} bytes: no requestor ID "
                                               "and command header")
        if data[0] < 7:
            raise PcccError(STS_ILLEGAL, None, f"a requestor ID of {data[0]} bytes (7 or more: length, vendor, serial)")
        n = data[0]
        cmd, _sts, tns, fnc = struct.unpack_from("<BBHB", data, n)
        return cls(bytes(data[:n]), cmd, tns, fnc, bytes(data[n + 5:]))

    def encode(self) -> bytes:
        return self.requestor + struct.pack("<BBHB", self.cmd, 0, self.tns, self.fnc) + self.body


@dataclass(frozen=True)
class PcccReply:
    requestor: bytes
    cmd: int  # the request's CMD; encoded with the reply flag
    tns: int
    sts: int = STS_OK
    ext: int | None = None
    data: bytes = b""

    def encode(self) -> bytes:
        out = self.requestor + struct.pack("<BBH", self.cmd | REPLY_FLAG, self.sts, self.tns)
        if self.sts == STS_EXTENDED:
            out += bytes((self.ext or 0,))
        return out + (self.data if self.sts == STS_OK else b"")

    @classmethod
    def decode(cls, data: bytes) -> "PcccReply":
        n = data[0]
        cmd, sts, tns = struct.unpack_from("<BBH", data, n)
        ext = data[n + 4] if sts == STS_EXTENDED else None
        body = data[n + 4:] if sts == STS_OK else b""
        return cls(bytes(data[:n]), cmd & ~REPLY_FLAG, tns, sts, ext, bytes(body))


# -- commands: one class each ------------------------------------------------------------------

@dataclass(frozen=True)
class SlcAddress:
    """The SLC typed logical address: file number, file type, element and,
    with three address fields, the sub-element."""

    file: int
    kind: str  # "N", "ST", ...
    element: int
    sub: int = 0

    @classmethod
    def read(cls, r: Reader, three_fields: bool) -> "SlcAddress":
        file = r.field()
        code = r.byte()
        element = r.field()
        sub = r.field() if three_fields else 0
        if code not in FILE_TYPES:
            raise PcccError(STS_EXTENDED, EXT_DATA_TYPE, f"file type 0x{code:02X} is none the table has")
        return cls(file, FILE_TYPES[code], element, sub)

    def encode(self, three_fields: bool) -> bytes:
        out = encode_field(self.file) + bytes((TYPE_CODES[self.kind],)) + encode_field(self.element)
        return out + (encode_field(self.sub) if three_fields else b"")


@dataclass(frozen=True)
class SlcTypedRead:
    """Protected typed logical read with three (0xA2) or two (0xA1) address
    fields: byte size, address."""

    size: int
    address: SlcAddress
    three_fields: bool = True

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "SlcTypedRead":
        r = Reader(body)
        size = r.byte()
        address = SlcAddress.read(r, fnc == 0xA2)
        r.end()
        return cls(size, address, fnc == 0xA2)

    def encode(self) -> bytes:
        return bytes((self.size,)) + self.address.encode(self.three_fields)


@dataclass(frozen=True)
class SlcTypedWrite:
    """Protected typed logical write with three (0xAA) or two (0xA9) address
    fields, and the masked write with three (0xAB): byte size, address, the
    mask (0xAB: a word, applied to each word written), the data."""

    size: int
    address: SlcAddress
    data: bytes
    mask: int | None = None
    three_fields: bool = True

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "SlcTypedWrite":
        r = Reader(body)
        size = r.byte()
        address = SlcAddress.read(r, fnc in (0xAA, 0xAB))
        mask = r.word() if fnc == 0xAB else None
        return cls(size, address, r.rest(), mask, fnc in (0xAA, 0xAB))

    def encode(self) -> bytes:
        mask = struct.pack("<H", self.mask) if self.mask is not None else b""
        return bytes((self.size,)) + self.address.encode(self.three_fields) + mask + self.data


@dataclass(frozen=True)
class WordRangeRead:
    """PLC-5 word range read (0x01): packet offset and total transaction (in
    words), the PLC-5 address, the bytes to read in this packet."""

    offset: int
    total: int
    address: Plc5Address
    size: int

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "WordRangeRead":
        r = Reader(body)
        offset, total = r.word(), r.word()
        address = Plc5Address.read(r)
        size = r.byte()
        r.end()
        return cls(offset, total, address, size)

    def encode(self) -> bytes:
        return struct.pack("<HH", self.offset, self.total) + self.address.encode() + bytes((self.size,))


@dataclass(frozen=True)
class WordRangeWrite:
    """PLC-5 word range write (0x00): packet offset and total transaction (in
    words), the PLC-5 address, the data."""

    offset: int
    total: int
    address: Plc5Address
    data: bytes

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "WordRangeWrite":
        r = Reader(body)
        offset, total = r.word(), r.word()
        address = Plc5Address.read(r)
        return cls(offset, total, address, r.rest())

    def encode(self) -> bytes:
        return struct.pack("<HH", self.offset, self.total) + self.address.encode() + self.data


@dataclass(frozen=True)
class ReadModifyWrite:
    """PLC-5 read-modify-write (0x26): sets of (address, AND mask, OR mask),
    each a word: ``new = (old & AND) | OR`` (libplctag's bit writes)."""

    sets: tuple[tuple[Plc5Address, int, int], ...] = field(default_factory=tuple)

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "ReadModifyWrite":
        r = Reader(body)
        sets = []
        while r.at < len(body):
            address = Plc5Address.read(r)
            sets.append((address, r.word(), r.word()))
        if not sets:
            raise PcccError(STS_ILLEGAL, None, "a read-modify-write with no address")
        return cls(tuple(sets))

    def encode(self) -> bytes:
        return b"".join(a.encode() + struct.pack("<HH", and_mask, or_mask) for a, and_mask, or_mask in self.sets)


@dataclass(frozen=True)
class TypedRead:
    """PLC-5 typed read (0x68): packet offset and total transaction (in
    elements), the PLC-5 address, the elements to read. The reply is a data
    type/parameter field, then the data."""

    offset: int
    total: int
    address: Plc5Address
    count: int

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "TypedRead":
        r = Reader(body)
        offset, total = r.word(), r.word()
        address = Plc5Address.read(r)
        count = r.word()
        if r.at < len(body) and body[r.at:] != b"\x00":  # a pad byte to a whole word may follow (libplctag)
            r.end()
        return cls(offset, total, address, count)

    def encode(self) -> bytes:
        return struct.pack("<HH", self.offset, self.total) + self.address.encode() + struct.pack("<H", self.count)


@dataclass(frozen=True)
class TypedWrite:
    """PLC-5 typed write (0x67): packet offset and total transaction (in
    elements), the PLC-5 address, a data type/parameter field, the data."""

    offset: int
    total: int
    address: Plc5Address
    data_type: int
    element_size: int
    data: bytes

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "TypedWrite":
        r = Reader(body)
        offset, total = r.word(), r.word()
        address = Plc5Address.read(r)
        kind, size = read_type_param(r)
        if kind == DT_ARRAY:
            kind, size = read_type_param(r)
        return cls(offset, total, address, kind, size, r.rest())

    def encode(self) -> bytes:
        element = encode_type_param(self.data_type, self.element_size)
        return (struct.pack("<HH", self.offset, self.total) + self.address.encode()
                + encode_type_param(DT_ARRAY, len(element) + len(self.data)) + element + self.data)


@dataclass(frozen=True)
class Echo:
    """Echo (CMD 0x06, FNC 0x00): the data comes back as it was sent."""

    data: bytes

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "Echo":
        return cls(body)

    def encode(self) -> bytes:
        return self.data


@dataclass(frozen=True)
class DiagnosticStatus:
    """Diagnostic status (CMD 0x06, FNC 0x03): no data; the reply is the
    processor's status block."""

    @classmethod
    def decode(cls, fnc: int, body: bytes) -> "DiagnosticStatus":
        Reader(body).end()
        return cls()

    def encode(self) -> bytes:
        return b""


# (CMD, FNC) -> the command's class
COMMANDS = {(0x0F, 0xA1): SlcTypedRead, (0x0F, 0xA2): SlcTypedRead, (0x0F, 0xA9): SlcTypedWrite,
            (0x0F, 0xAA): SlcTypedWrite, (0x0F, 0xAB): SlcTypedWrite, (0x0F, 0x01): WordRangeRead,
            (0x0F, 0x00): WordRangeWrite, (0x0F, 0x26): ReadModifyWrite, (0x0F, 0x68): TypedRead,
            (0x0F, 0x67): TypedWrite, (0x06, 0x00): Echo, (0x06, 0x03): DiagnosticStatus}


def decode_command(request: PcccRequest):
    """The command a request holds; PcccError for an unknown one (STS 0x10)."""
    kind = COMMANDS.get((request.cmd, request.fnc))
    if kind is None:
        raise PcccError(STS_ILLEGAL, None, f"CMD 0x{request.cmd:02X} FNC 0x{request.fnc:02X} is not served")
    return kind.decode(request.fnc, request.body)
