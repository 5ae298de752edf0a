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

WRITE, MASK, GROUP = b"W", b"M", b"G"
_WRITE = struct.Struct("=HII")  # file number, first item, count; the items follow in the file's storage
_MASK = struct.Struct("=HIQQ")  # file number, item, and-mask, or-mask (unsigned, the item's width)
_PART = struct.Struct("=I")  # a group's part: its length, then a WRITE payload
MASKABLE = "bhiq"  # the typecodes of integer items: a masked write keeps their width
SEGMENTS = Segments("enips")  # the shared images' files: softplc-enips-PID-RANDOM
ST_LEN_MAX = 82


@dataclass(frozen=True)
class FileSlot:
    """One data file in the image."""

    info: FileInfo
    typecode: str  # the file's array typecode: "h", "f", or the 4-byte integer code
    itemsize: int
    offset: int  # in the image, bytes
    writable: tuple[tuple[int, int], ...]  # item ranges [first, end) clients may write; bit ranges in a B file

    def may_write(self, first: int, count: int) -> bool:
        if self.info.kind == "B":  # every bit of the words
            first, count = first * 16, count * 16
        return count > 0 and any(lo <= first and first + count <= hi for lo, hi in self.writable)

    def may_mask(self, index: int, and_mask: int, or_mask: int) -> bool:
        """Whether a masked write of item ``index`` changes only bits clients
        may write: in a B file, a Logix app's BOOL tags share words, and
        each is opened alone."""
        if self.info.kind != "B":
            return self.may_write(index, 1)
        touched = (~and_mask | or_mask) & 0xFFFF
        bits = [index * 16 + b for b in range(16) if touched >> b & 1]
        return all(any(lo <= bit < hi for lo, hi in self.writable) for bit in bits)


def build_slots(table, config: ServerConfig, extra: dict | None = None,
                closed: dict | None = None) -> tuple[FileSlot, ...]:
    """The table's files as the image lays them out, with the items each
    ``<Writable>`` opens to clients: its address's elements, and the item
    ranges in ``extra`` (a Logix app's tags, logixconfig.py), less those in
    ``closed`` (the storage of Read Only tags)."""
    ranges: dict[str, list[tuple[int, int]]] = {k: list(v) for k, v in (extra or {}).items()}
    for w in config.writable:
        if w.address is None:
            continue
        per = table.file(w.file).ftype.words_per_element
        if w.address.type_letter == "B":  # a B file's ranges count bits
            per = 16
        ranges.setdefault(w.file, []).append((w.address.element * per, (w.last + 1) * per))
    slots, offset = [], 0
    for f in table.files():
        per = f.ftype.words_per_element
        writable = tuple(sorted(_less(_merged(ranges.get(f.name, [])), (closed or {}).get(f.name, []))))
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


def _less(ranges: list[tuple[int, int]], closed: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """``ranges`` without the items of ``closed``."""
    for c_lo, c_hi in closed:
        out = []
        for lo, hi in ranges:
            if c_hi <= lo or hi <= c_lo:
                out.append((lo, hi))
                continue
            if lo < c_lo:
                out.append((lo, c_lo))
            if c_hi < hi:
                out.append((c_hi, hi))
        ranges = out
    return ranges


def write_payload(number: int, first: int, items: array) -> bytes:
    return WRITE + _WRITE.pack(number, first, len(items)) + items.tobytes()


def mask_payload(number: int, index: int, and_mask: int, or_mask: int) -> bytes:
    full = (1 << 64) - 1
    return MASK + _MASK.pack(number, index, and_mask & full, or_mask & full)


def group_payload(writes: list[bytes]) -> bytes:
    """Several WRITE or MASK payloads applied together at one input point,
    or none of them (a structure a client writes whole)."""
    return GROUP + b"".join(_PART.pack(len(w)) + w for w in writes)


def masked(old: int, and_mask: int, or_mask: int, bits: int) -> int:
    """``(old & and_mask) | or_mask`` on an item of ``bits`` bits, signed as it is stored."""
    full = (1 << bits) - 1
    new = ((old & full) & and_mask | or_mask) & full
    return new - (1 << bits) if new >> (bits - 1) else new

class EnipProtocol(Protocol):
    name = "ENIPS"
    process_module = "softplc_lite.tlm.enips.serverproc"
    segments = SEGMENTS

    def __init__(self, config: ServerConfig, slots: tuple[FileSlot, ...], identity: Identity,
                 symbols: dict[str, str], logix=None) -> None:
        self.config = config
        self.slots = slots
        self.identity = identity
        self.symbols = symbols  # symbol name -> address text: the CIP tags the app's symbols become
        self.logix = logix  # a Logix app's tags (logixview.LogixView): served in place of the files and symbols
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
        if tag == GROUP:
            parts = self._group_parts(rest)
            if parts is None:
                return REFUSED
            for part in parts:
                self._apply_part(part, table)
            return APPLIED
        part = self._checked_write(rest) if tag == WRITE else self._checked_mask(rest)
        if part is None:
            return REFUSED
        if len(part) == 4:  # a masked word of an ST element may be its LEN
            slot, index, and_mask, or_mask = part
            new = masked(table.file(slot.info.name).data[index], and_mask, or_mask, slot.itemsize * 8)
            if not _string_lengths_fit(slot, index, array(slot.typecode, [new])):
                return REFUSED
        self._apply_part(part, table)
        return APPLIED

    def _group_parts(self, rest: bytes) -> list | None:
        """A GROUP's parts, each checked; None if any may not be applied."""
        parts, at = [], 0
        while at < len(rest):
            (size,) = _PART.unpack_from(rest, at)
            body = rest[at + _PART.size:at + _PART.size + size]
            part = self._checked_write(body[1:]) if body[:1] == WRITE else self._checked_mask(body[1:])
            if part is None or (len(part) == 4 and part[0].info.kind == "ST"):
                return None
            parts.append(part)
            at += _PART.size + size
        return parts

    @staticmethod
    def _apply_part(part: tuple, table) -> None:
        if len(part) == 3:
            slot, first, items = part
            table.file(slot.info.name).data[first:first + len(items)] = items
        else:
            slot, index, and_mask, or_mask = part
            data = table.file(slot.info.name).data
            data[index] = masked(data[index], and_mask, or_mask, slot.itemsize * 8)  # TableAccess.write_masked's rule

    def _checked_write(self, rest: bytes):
        """A WRITE payload's (slot, first item, items), or None if it may not be applied."""
        number, first, count = _WRITE.unpack_from(rest)
        slot = self._by_number.get(number)
        if slot is None or not slot.may_write(first, count):
            return None
        items = array(slot.typecode)
        items.frombytes(rest[_WRITE.size:_WRITE.size + count * slot.itemsize])
        if len(items) != count or not _string_lengths_fit(slot, first, items):
            return None
        return slot, first, items

    def _checked_mask(self, rest: bytes):
        """A MASK payload's (slot, item, and-mask, or-mask), or None if it may not be applied."""
        number, index, and_mask, or_mask = _MASK.unpack(rest)
        slot = self._by_number.get(number)
        if slot is None or slot.typecode not in MASKABLE or not slot.may_mask(index, and_mask, or_mask):
            return None
        return slot, index, and_mask, or_mask

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
