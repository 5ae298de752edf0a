"""EtherNet/IP as the network-server layer (softplc_lite/netserver) serves
it: every data file in the shared image, a client's write as the scan
applies it, and the handler (handler.py) the server process makes.

The image holds the whole table, each file at its own offset, so that any
read a client can name is one scan's values; a write travels to the scan as
(file number, first item, items) or a masked word, and the scan checks it
against the writable regions again before it applies it.
"""

from __future__ import annotations

import struct
from array import array
from dataclasses import dataclass

from ...netserver import APPLIED, REFUSED, Protocol
from ...netserver.image import Segments
from .access import FileInfo
from .config import ServerConfig
from .identity import Identity

WRITE, MASK = b"W", b"M"
_WRITE = struct.Struct("=HII")  # file number, first item, count; the items follow in the file's storage
_MASK = struct.Struct("=HIHH")  # file number, item, and-mask, or-mask (unsigned 16-bit)
SEGMENTS = Segments("enips")  # the shared images' files: softplc-enips-PID-RANDOM
ST_LEN_MAX = 82


@dataclass(frozen=True)
class FileSlot:
    """One data file in the image."""

    info: FileInfo
    typecode: str  # the file's array typecode: "h", "f", or the 4-byte integer code
    itemsize: int
    offset: int  # in the image, bytes
    writable: tuple[tuple[int, int], ...]  # item ranges [first, end) clients may write

    def may_write(self, first: int, count: int) -> bool:
        return count > 0 and any(lo <= first and first + count <= hi for lo, hi in self.writable)


def build_slots(table, config: ServerConfig) -> tuple[FileSlot, ...]:
    """The table's files as the image lays them out, with the items each
    ``<Writable>`` opens to clients."""
    ranges: dict[str, list[tuple[int, int]]] = {}
    for w in config.writable:
        per = table.file(w.file).ftype.words_per_element
        ranges.setdefault(w.file, []).append((w.address.element * per, (w.last + 1) * per))
    slots, offset = [], 0
    for f in table.files():
        per = f.ftype.words_per_element
        writable = tuple(sorted(_merged(ranges.get(f.name, []))))
        info = FileInfo(f.name, f.ftype.letter, f.number, len(f.data) // per, per, bool(writable))
        slots.append(FileSlot(info, f.data.typecode, f.data.itemsize, offset, writable))
        offset += len(f.data) * f.data.itemsize
        offset += -offset % 8  # each file aligned: a float or long file's items stay whole
    return tuple(slots)


def _merged(ranges: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Touching or overlapping ranges as one, so a write across two regions
    that together cover it is allowed."""
    out: list[list[int]] = []
    for lo, hi in sorted(ranges):
        if out and lo <= out[-1][1]:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return [(lo, hi) for lo, hi in out]


def write_payload(number: int, first: int, items: array) -> bytes:
    return WRITE + _WRITE.pack(number, first, len(items)) + items.tobytes()


def mask_payload(number: int, index: int, and_mask: int, or_mask: int) -> bytes:
    return MASK + _MASK.pack(number, index, and_mask & 0xFFFF, or_mask & 0xFFFF)


class EnipProtocol(Protocol):
    name = "ENIPS"
    process_module = "softplc_lite.tlm.enips.serverproc"
    segments = SEGMENTS

    def __init__(self, config: ServerConfig, slots: tuple[FileSlot, ...], identity: Identity,
                 symbols: dict[str, str]) -> None:
        self.config = config
        self.slots = slots
        self.identity = identity
        self.symbols = symbols  # symbol name -> address text: the CIP tags the app's symbols become
        self._by_number = {s.info.number: s for s in slots}

    # -- the runtime's side --------------------------------------------------------------------------
    def regions(self) -> list[tuple[str, int, int, int]]:
        return [(s.info.name, 0, s.info.items, s.offset) for s in self.slots]

    @property
    def image_bytes(self) -> int:
        last = self.slots[-1] if self.slots else None
        return last.offset + last.info.items * last.itemsize if last else 0

    def apply(self, payload: bytes, table) -> str:
        """A client's write at the scan's input point: checked against the
        writable regions again (the server checked it against the same), a
        string's LEN kept within 82."""
        tag, rest = payload[:1], payload[1:]
        if tag == WRITE:
            number, first, count = _WRITE.unpack_from(rest)
            slot = self._by_number.get(number)
            if slot is None or not slot.may_write(first, count):
                return REFUSED
            items = array(slot.typecode)
            items.frombytes(rest[_WRITE.size:_WRITE.size + count * slot.itemsize])
            if len(items) != count or not _string_lengths_fit(slot, first, items):
                return REFUSED
            table.file(slot.info.name).data[first:first + count] = items
            return APPLIED
        number, index, and_mask, or_mask = _MASK.unpack(rest)
        slot = self._by_number.get(number)
        if slot is None or slot.typecode != "h" or not slot.may_write(index, 1):
            return REFUSED
        data = table.file(slot.info.name).data
        new = ((data[index] & 0xFFFF) & and_mask) | or_mask  # TableAccess.write_masked's rule
        new = new - 0x10000 if new & 0x8000 else new
        if not _string_lengths_fit(slot, index, array("h", [new])):
            return REFUSED
        data[index] = new
        return APPLIED

    # -- the server process's side -------------------------------------------------------------------
    def handler(self, server):
        from .handler import EnipHandler

        return EnipHandler(server, self)


def _string_lengths_fit(slot: FileSlot, first: int, items) -> bool:
    """An ST element's LEN (its first item) stays 0..82 (docs/datatable.md)."""
    per = slot.info.items_per_element
    if slot.info.kind != "ST":
        return True
    start = -first % per  # the first LEN item among ``items``
    return all(0 <= items[k] <= ST_LEN_MAX for k in range(start, len(items), per))
