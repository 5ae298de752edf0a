"""The PCCC object (class 0x67): Execute PCCC (0x4B) runs the PLC-5/SLC
commands of softplc_lite/cip/pccc.py on the data table (docs/enips.md,
"PCCC"). Reads come from one scan (``TableAccess.read``); writes go to the
scan's input point and are answered once applied; every refusal is a STS
(and EXT STS) of 1770-6.5.16, counted.

A file is seen as PCCC sees it, element after element in bytes
(``ELEMENT_BYTES``): words little-endian; F a float32 and L a 32-bit integer,
4 bytes; T, C, R three words (control, PRE or LEN, ACC or POS); ST 84 bytes,
``.LEN`` then 82 characters in byte-swapped pairs, as an SLC stores them.
An address's sub-element is a word of its element (T4:0 sub 2 is .ACC); for
O and I files, whose elements are single words, it counts words on from the
element (a rack's words).
"""

from __future__ import annotations

import struct

from ...cip import pccc as P
from ...cip import status as st
from .access import FileInfo, TableAccess
from .objects import CipObject, CipReply, CipRequest

CLASS_ID = 0x67
ELEMENT_BYTES = {"ST": 84, "T": 6, "C": 6, "R": 6, "F": 4, "L": 4}  # every other file: 2
# SI and LI files (Logix SINT, LINT) have no PCCC file type (1770-6.5.16):
# PCCC commands naming one are refused, the CIP tag services serve them.
NO_PCCC_TYPE = {"SI": "SINT", "LI": "LINT"}
WORD_FILES = frozenset("OISBNADTCR")  # 16-bit items: any word may be addressed and masked
MAX_DATA = 244  # bytes of data one reply carries (a choice: a PLC-5 typed read's most, 1770-6.5.16 ch. 7)
ST_CHARS = 82
# Typed read/write element types (1770-6.5.16 ch. 7, "data type" table)
ELEMENT_TYPES = {"T": P.DT_TIMER, "C": P.DT_COUNTER, "R": P.DT_CONTROL, "F": P.DT_FLOAT, "D": P.DT_BCD,
                 "ST": P.DT_BYTE_STRING}
DIAGNOSTIC_NAME = b"softplc_lit"  # the 11 bytes pycomm3's get_processor_type reads as the processor's name


class Refused(Exception):
    def __init__(self, sts: int, ext: int | None, why: str) -> None:
        super().__init__(why)
        self.sts, self.ext, self.why = sts, ext, why


def element_bytes(info: FileInfo) -> int:
    return ELEMENT_BYTES.get(info.kind, 2)


def _file(access: TableAccess, kind: str | None, number: int) -> FileInfo:
    """The file a command names; a file of another type than ``kind`` (None:
    any, the PLC-5 commands' addresses carry none) does not point to something usable."""
    if kind is None:
        info = next((f for f in access.files() if f.number == number), None)
    else:
        info = access.file(kind, number)
    if info is None:
        named = f"{kind or ''} file {number}"
        raise Refused(P.STS_EXTENDED, P.EXT_NOT_USABLE, f"there is no {named.strip()} in the table")
    if info.kind == "SL":
        raise Refused(P.STS_EXTENDED, P.EXT_NOT_USABLE,
                      f"{info.name} is a long string file: PCCC has no type for it (softplc_lite does not serve it)")
    if info.kind in NO_PCCC_TYPE:
        raise Refused(P.STS_EXTENDED, P.EXT_NOT_USABLE,
                      f"{info.name} is a Logix {NO_PCCC_TYPE[info.kind]} file: PCCC has no type for it "
                      "(its tag serves it)")
    return info


def _byte_offset(info: FileInfo, element: int, sub: int | None) -> int:
    """Where an address starts in its file, in bytes."""
    size = element_bytes(info)
    sub = sub or 0
    if element >= info.elements:
        raise Refused(P.STS_EXTENDED, P.EXT_NOT_USABLE, f"{info.name}:{element}: the file has {info.elements} "
                                                        "elements")
    if info.kind in ("O", "I"):
        return (element + sub) * 2
    if sub and (info.kind not in WORD_FILES and info.kind != "ST" or sub * 2 >= size):
        raise Refused(P.STS_EXTENDED, P.EXT_NOT_USABLE, f"{info.name}:{element} has no sub-element {sub}")
    return element * size + sub * 2


# -- bytes <-> items ------------------------------------------------------------------------------

def _to_bytes(info: FileInfo, items: list) -> bytes:
    if info.kind == "F":
        return struct.pack(f"<{len(items)}f", *items)
    if info.kind == "L":
        return struct.pack(f"<{len(items)}i", *items)
    if info.kind == "ST":
        out = bytearray()
        for e in range(0, len(items), info.items_per_element):
            length, chars = items[e], [c if 0 <= c <= 255 else ord("?") for c in items[e + 1:e + 1 + ST_CHARS]]
            out += struct.pack("<h", length)
            for j in range(0, ST_CHARS, 2):
                out += bytes((chars[j + 1], chars[j]))
        return bytes(out)
    return struct.pack(f"<{len(items)}h", *items)


def _to_items(info: FileInfo, data: bytes) -> list:
    if info.kind == "F":
        return list(struct.unpack(f"<{len(data) // 4}f", data))
    if info.kind == "L":
        return list(struct.unpack(f"<{len(data) // 4}i", data))
    if info.kind == "ST":
        items = []
        for e in range(0, len(data), 84):
            length = struct.unpack_from("<H", data, e)[0]
            if length > ST_CHARS:
                raise Refused(P.STS_EXTENDED, P.EXT_BAD_PARAMETER, f"a string LEN of {length} (at most {ST_CHARS})")
            raw = data[e + 2:e + 84]
            chars = [0] * ST_CHARS
            for j in range(0, ST_CHARS, 2):
                chars[j], chars[j + 1] = raw[j + 1], raw[j]
            items += [length] + chars
        return items
    return list(struct.unpack(f"<{len(data) // 2}h", data))


# -- reads and writes of byte ranges --------------------------------------------------------------

async def read_range(access: TableAccess, info: FileInfo, offset: int, size: int) -> bytes:
    """``size`` bytes of ``info`` from byte ``offset``, of one scan."""
    esize = element_bytes(info)
    if size > MAX_DATA:
        raise Refused(P.STS_ILLEGAL, None, f"{size} bytes asked; one reply carries at most {MAX_DATA}")
    if offset + size > info.elements * esize:
        raise Refused(P.STS_EXTENDED, P.EXT_TOO_LARGE, f"{size} bytes from byte {offset} of {info.name} run past its "
                                                       f"end ({info.elements} elements)")
    first, last = offset // esize, (offset + size - 1) // esize if size else offset // esize
    per = info.items_per_element
    (items,) = await access.read([(info.name, first * per, (last - first + 1) * per)])
    raw = _to_bytes(info, items)
    start = offset - first * esize
    return raw[start:start + size]


def _write_items(info: FileInfo, offset: int, data: bytes) -> tuple[int, list]:
    """(first item, items) that ``data`` at byte ``offset`` writes: words on
    any word of a word file, whole floats and longs, whole strings (a string's
    data may stop early, as pycomm3 sends it: the rest of its 82 characters
    are 0)."""
    esize = element_bytes(info)
    if info.kind in WORD_FILES:
        if offset % 2 or len(data) % 2:
            raise Refused(P.STS_EXTENDED, P.EXT_WRONG_SIZE, f"{len(data)} bytes at byte {offset}: words are 2 bytes")
        return offset // 2, _to_items(info, data)
    if info.kind == "ST":
        if offset % esize or not data or len(data) > esize and len(data) % esize:
            raise Refused(P.STS_EXTENDED, P.EXT_WRONG_SIZE, f"{len(data)} bytes at byte {offset}: strings are written "
                                                            f"whole, {esize} bytes each")
        data = data + bytes(-len(data) % esize)
        return offset // esize * info.items_per_element, _to_items(info, data)
    if offset % esize or len(data) % esize:
        raise Refused(P.STS_EXTENDED, P.EXT_WRONG_SIZE, f"{len(data)} bytes at byte {offset}: {info.name}'s "
                                                        f"elements are {esize} bytes, written whole")
    return offset // esize, _to_items(info, data)


async def write_range(access: TableAccess, info: FileInfo, offset: int, data: bytes) -> None:
    if len(data) > MAX_DATA + 2:
        raise Refused(P.STS_ILLEGAL, None, f"{len(data)} bytes of data; a command carries at most {MAX_DATA}")
    if offset + len(data) > info.elements * element_bytes(info) and info.kind != "ST":
        raise Refused(P.STS_EXTENDED, P.EXT_TOO_LARGE, f"{len(data)} bytes from byte {offset} of {info.name} run past "
                                                       "its end")
    first, items = _write_items(info, offset, data)
    if first + len(items) > info.items:
        raise Refused(P.STS_EXTENDED, P.EXT_TOO_LARGE, f"a string write past the end of {info.name}")
    _writable(access, info, first, len(items))
    if not await access.write(info.name, first, items):
        raise Refused(P.STS_EXTENDED, P.EXT_ACCESS_DENIED, f"{info.name}: the scan refused the write")


def _writable(access: TableAccess, info: FileInfo, first: int, count: int) -> None:
    if not access.writable(info.name, first, count):
        raise Refused(P.STS_EXTENDED, P.EXT_ACCESS_DENIED, f"{info.name} items {first}..{first + count - 1}: no "
                                                           "<Writable> covers them")


def check_masked(access: TableAccess, info: FileInfo, writes: list[tuple[int, int, int]]) -> None:
    """Refused unless every masked write (item, AND, OR) is of a word a client may write."""
    if info.kind not in WORD_FILES:
        raise Refused(P.STS_EXTENDED, P.EXT_DATA_TYPE, f"{info.name}: a masked write is of 16-bit words only")
    for item, _, _ in writes:
        _writable(access, info, item, 1)


async def masked_words(access: TableAccess, info: FileInfo, writes: list[tuple[int, int, int]],
                       checked: bool = False) -> None:
    """Masked writes of words (item, AND, OR), all checked (unless
    ``checked`` already) before any is sent."""
    if not checked:
        check_masked(access, info, writes)
    for item, and_mask, or_mask in writes:
        if not await access.write_masked(info.name, item, and_mask & 0xFFFF, or_mask & 0xFFFF):
            raise Refused(P.STS_EXTENDED, P.EXT_ACCESS_DENIED, f"{info.name}: the scan refused the write")


# -- the object -----------------------------------------------------------------------------------

class PcccObject(CipObject):
    class_id = CLASS_ID

    def __init__(self) -> None:
        self.router = None  # the Message Router sets it: refusals are counted through it

    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        if request.service != P.EXECUTE_PCCC:
            return CipReply.error(request, st.SERVICE_NOT_SUPPORTED)
        try:
            pccc = P.PcccRequest.decode(request.data)
        except P.PcccError:  # no requestor ID to answer with: a CIP refusal
            return CipReply.error(request, st.NOT_ENOUGH_DATA)
        try:
            command = P.decode_command(pccc)
            data = await self.run(command, access)
        except (P.PcccError, Refused) as e:
            kind = "read-only" if e.ext == P.EXT_ACCESS_DENIED else "pccc"
            if self.router is not None:
                ext = f" EXT STS 0x{e.ext:02X}" if e.ext is not None else ""
                self.router.count(kind, f"PCCC CMD 0x{pccc.cmd:02X} FNC 0x{pccc.fnc:02X}: STS 0x{e.sts:02X}{ext}, "
                                        f"{e.why}")
            return CipReply.ok(request, P.PcccReply(pccc.requestor, pccc.cmd, pccc.tns, e.sts, e.ext).encode())
        return CipReply.ok(request, P.PcccReply(pccc.requestor, pccc.cmd, pccc.tns, data=data).encode())

    async def run(self, command, access: TableAccess) -> bytes:
        if isinstance(command, P.SlcTypedRead):
            a = command.address
            info = _file(access, a.kind, a.file)
            return await read_range(access, info, _byte_offset(info, a.element, a.sub), command.size)
        if isinstance(command, P.SlcTypedWrite):
            return await self._slc_write(command, access)
        if isinstance(command, P.WordRangeRead):
            info, offset = self._plc5(command.address, access)
            return await read_range(access, info, offset + 2 * command.offset, command.size)
        if isinstance(command, P.WordRangeWrite):
            info, offset = self._plc5(command.address, access)
            await write_range(access, info, offset + 2 * command.offset, command.data)
            return b""
        if isinstance(command, P.ReadModifyWrite):
            return await self._read_modify_write(command, access)
        if isinstance(command, P.TypedRead):
            return await self._typed_read(command, access)
        if isinstance(command, P.TypedWrite):
            return await self._typed_write(command, access)
        if isinstance(command, P.Echo):
            if len(command.data) > MAX_DATA:
                raise Refused(P.STS_ILLEGAL, None, f"an echo of {len(command.data)} bytes (at most {MAX_DATA})")
            return command.data
        # DiagnosticStatus: mode/status, type extender, interface and processor types, series and
        # revision, then the name (a choice: this server's own, in the bytes pycomm3 reads)
        return bytes((0x00, 0xEE, 0x31, 0x5B, 0x01)) + DIAGNOSTIC_NAME + bytes(8)

    async def _slc_write(self, command: P.SlcTypedWrite, access: TableAccess) -> bytes:
        a = command.address
        info = _file(access, a.kind, a.file)
        offset = _byte_offset(info, a.element, a.sub)
        data = command.data
        if command.mask is None or command.mask == 0xFFFF:
            # the size byte counts the data; pycomm3 sends a string shorter than its 84 bytes
            if len(data) != command.size and not (info.kind == "ST" and len(data) <= command.size):
                raise Refused(P.STS_EXTENDED, P.EXT_WRONG_SIZE, f"a size of {command.size} bytes with "
                                                                f"{len(data)} bytes of data")
            await write_range(access, info, offset, data)
            return b""
        if len(data) != command.size or len(data) % 2 or offset % 2:
            raise Refused(P.STS_EXTENDED, P.EXT_WRONG_SIZE, f"a masked write of size {command.size} with "
                                                            f"{len(data)} bytes of data")
        mask = command.mask
        words = struct.unpack(f"<{len(data) // 2}H", data)
        await masked_words(access, info, [(offset // 2 + k, ~mask, w & mask) for k, w in enumerate(words)])
        return b""

    @staticmethod
    def _plc5(address: P.Plc5Address, access: TableAccess) -> tuple[FileInfo, int]:
        info = _file(access, None, address.file)
        return info, _byte_offset(info, address.element, address.sub)

    async def _read_modify_write(self, command: P.ReadModifyWrite, access: TableAccess) -> bytes:
        by_file: dict[str, tuple[FileInfo, list]] = {}
        for address, and_mask, or_mask in command.sets:
            info, offset = self._plc5(address, access)
            by_file.setdefault(info.name, (info, []))[1].append((offset // 2, and_mask, or_mask))
        for info, writes in by_file.values():  # every file's sets checked before any is sent
            check_masked(access, info, writes)
        for info, writes in by_file.values():
            await masked_words(access, info, writes, checked=True)
        return b""

    @staticmethod
    def _element_type(info: FileInfo, address: P.Plc5Address) -> tuple[int, int]:
        """The data type and the bytes of one element a typed command moves:
        a sub-element is a word (an integer)."""
        if address.sub is not None and info.kind in ("T", "C", "R", "ST"):
            return P.DT_INTEGER, 2
        return ELEMENT_TYPES.get(info.kind, P.DT_INTEGER), element_bytes(info)

    async def _typed_read(self, command: P.TypedRead, access: TableAccess) -> bytes:
        info, offset = self._plc5(command.address, access)
        kind, size = self._element_type(info, command.address)
        data = await read_range(access, info, offset + command.offset * size, command.count * size)
        element = P.encode_type_param(kind, size)
        return P.encode_type_param(P.DT_ARRAY, len(element) + len(data)) + element + data

    async def _typed_write(self, command: P.TypedWrite, access: TableAccess) -> bytes:
        info, offset = self._plc5(command.address, access)
        kind, size = self._element_type(info, command.address)
        if (command.data_type, command.element_size) != (kind, size):
            raise Refused(P.STS_EXTENDED, P.EXT_DATA_TYPE, f"data type {command.data_type} of {command.element_size} "
                                                           f"bytes to {info.name}, whose elements are type {kind} "
                                                           f"of {size}")
        await write_range(access, info, offset + command.offset * size, command.data)
        return b""
