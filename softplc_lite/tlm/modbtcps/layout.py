"""Where each mapped region lives: in the data table, in the shared image,
and in the Modbus address space; and the one conversion between data table
words and Modbus registers that both processes use.

A region's items become registers as follows (docs/modbtcps.md, "Data
formats"):

- a word (O I S B N): one register, its 16 bits as they are;
- a string (ST): 83 registers, the element's words as they are: LEN, then 82
  UCS-2 code units, one a register; or, with ``stringFormat="packed"``, 41
  registers of two 8-bit characters each (the HMI convention);
- a float (F): two registers holding the IEEE-754 single, the high half first
  ("high-low", the default) or the low half first ("low-high");
- a bit: one coil or discrete input; bits run on into the next word (B3/15,
  then B3/16 = B3:1/0).

The server reads registers from the image with ``Layout.read``; the scan
applies a client's write with ``Layout.store`` at its input point.
"""

from __future__ import annotations

import bisect
import sys
from array import array
from dataclasses import dataclass

from ...datatable.filetypes import STRING, STRING_CHARS, WORD_BITS
from .config import PACKED_STRING_REGISTERS, Region, ServerConfig

STRING_WORDS = STRING.words_per_element  # an ST element: LEN, then the code units
# The word order whose registers are the two halves of a float in memory, swapped.
_SWAPPED = "high-low" if sys.byteorder == "little" else "low-high"


@dataclass(frozen=True)
class Slot:
    """One region, placed."""

    unit: int
    kind: str
    start: int  # first protocol address
    end: int  # past the last
    value: str  # "bit", "word", "float", "string"
    word_order: str
    writable: bool
    file: str  # data file name (N7)
    index: int  # first word (or float) of the region in the file's array
    words: int  # words (floats for F) the image holds for it
    bit0: int  # bit regions: the first bit within the first word
    offset: int  # bytes into the image
    string_format: str = "ucs2"

    @property
    def itemsize(self) -> int:
        return 4 if self.value == "float" else 2

    @property
    def nbytes(self) -> int:
        return self.words * self.itemsize

    @property
    def per_element(self) -> tuple[int, int]:
        """(registers, words or floats) of one element, converted whole: a
        float is 2 registers of 1 float; a packed string 41 registers of its
        83 words; a word, or a UCS-2 string's word, 1 register of 1 word."""
        if self.value == "float":
            return 2, 1
        if self.value == "string" and self.string_format == "packed":
            return PACKED_STRING_REGISTERS, STRING_WORDS
        return 1, 1

    def table_range(self, off: int, n: int) -> tuple[int, int]:
        """The words (floats) of the region that protocol addresses
        start+off .. start+off+n-1 touch, as (first, past the last)."""
        if self.value == "bit":
            b = self.bit0 + off
            return b // WORD_BITS, (b + n - 1) // WORD_BITS + 1
        registers, words = self.per_element
        return off // registers * words, ((off + n - 1) // registers + 1) * words

    def skip(self, off: int) -> int:
        """Registers before ``off`` in the elements ``table_range`` converts."""
        registers, _ = self.per_element
        return off % registers


def _slot(region: Region, unit: int, offset: int, table) -> Slot:
    loc = table.resolve(region.address)
    if region.value == "bit":
        bit0 = loc.bit
        words = (bit0 + region.count - 1) // WORD_BITS + 1
    else:
        bit0 = 0
        words = region.count * (1 if region.value == "float" else STRING_WORDS if region.value == "string" else 1)
    return Slot(unit, region.kind, region.start, region.end, region.value, region.word_order, region.writable,
                loc.file.name, loc.index, words, bit0, offset, region.string_format)


class Layout:
    """Every slot of a configuration, found by (unit, kind) and address."""

    def __init__(self, slots: list[Slot]) -> None:
        self.slots = slots
        self.size = max((s.offset + s.nbytes for s in slots), default=0)
        self._by: dict[tuple[int, str], list[Slot]] = {}
        for s in sorted(slots, key=lambda s: s.start):
            self._by.setdefault((s.unit, s.kind), []).append(s)
        self._starts = {key: [s.start for s in v] for key, v in self._by.items()}

    @classmethod
    def build(cls, config: ServerConfig, table) -> "Layout":
        """Place the regions; ``table`` must already hold their addresses
        (config_references)."""
        slots, offset = [], 0
        for unit in config.units.values():
            for region in unit.regions:
                s = _slot(region, unit.id, offset, table)
                offset += s.nbytes + (-s.nbytes % 8)  # each region 8-byte aligned
                slots.append(s)
        return cls(slots)

    def takes_writes(self, unit: int, kind: str) -> bool:
        """Does the unit have a writable region of this table at all?"""
        return any(s.writable for s in self._by.get((unit, kind), ()))

    def find(self, unit: int, kind: str, address: int, count: int) -> list[tuple[Slot, int, int]] | None:
        """The (slot, offset in the slot, items) pieces that cover
        ``count`` items from ``address``; None when one is not mapped."""
        slots = self._by.get((unit, kind))
        if not slots:
            return None
        starts = self._starts[(unit, kind)]
        pieces, at, end = [], address, address + count
        while at < end:
            k = bisect.bisect_right(starts, at) - 1
            if k < 0 or slots[k].end <= at:
                return None
            s = slots[k]
            n = min(end, s.end) - at
            pieces.append((s, at - s.start, n))
            at += n
        return pieces

    # -- the server's side: from image bytes -------------------------------------------------
    @staticmethod
    def spans(pieces: list[tuple[Slot, int, int]]) -> list[tuple[int, int]]:
        out = []
        for s, off, n in pieces:
            first, past = s.table_range(off, n)
            out.append((s.offset + first * s.itemsize, (past - first) * s.itemsize))
        return out

    @staticmethod
    def values(pieces: list[tuple[Slot, int, int]], raws: list[bytes]) -> list[int]:
        """Registers (0..65535) or bits (0/1) from the bytes ``spans`` chose."""
        out: list[int] = []
        for (s, off, n), raw in zip(pieces, raws):
            first, _ = s.table_range(off, n)
            if s.value == "bit":
                words = array("H", raw)
                b = s.bit0 + off - first * WORD_BITS
                out += [(words[(b + k) >> 4] >> ((b + k) & 15)) & 1 for k in range(n)]
            else:
                regs = registers_of(s, raw)
                skip = s.skip(off)
                out += regs[skip:skip + n]
        return out

    # -- the scan's side: the data table itself -------------------------------------------------
    @staticmethod
    def load(pieces: list[tuple[Slot, int, int]], table) -> list[int]:
        """Registers or bits as they are in the data table now (what
        ``values`` makes of the image, read from the table instead)."""
        raws = []
        for s, off, n in pieces:
            first, past = s.table_range(off, n)
            raws.append(table.file(s.file).data[s.index + first:s.index + past].tobytes())
        return Layout.values(pieces, raws)

    @staticmethod
    def store(pieces: list[tuple[Slot, int, int]], values: list[int], table) -> None:
        """Write a client's registers or bits into the data table."""
        k = 0
        for s, off, n in pieces:
            data = table.file(s.file).data
            first, past = s.table_range(off, n)
            if s.value == "bit":
                for j in range(n):
                    w, bit = divmod(s.bit0 + off + j, WORD_BITS)
                    i = s.index + w
                    mask = 1 << bit if bit < 15 else -32768
                    data[i] = (data[i] | mask) if values[k + j] else (data[i] & ~mask)
            else:
                i, past_i = s.index + first, s.index + past
                regs = registers_of(s, data[i:past_i].tobytes())
                skip = s.skip(off)
                regs[skip:skip + n] = array("H", values[k:k + n])
                data[i:past_i] = array(data.typecode, raw_of(s, regs))
            k += n


def registers_of(s: Slot, raw: bytes) -> array:
    """Registers from a region's raw words (floats: in its word order;
    packed strings: two characters a register)."""
    if s.value == "string" and s.string_format == "packed":
        return _packed(array("H", raw))
    regs = array("H", raw)  # a float is [low half, high half] in memory here (little-endian)
    if s.value == "float" and s.word_order == _SWAPPED:
        regs[0::2], regs[1::2] = regs[1::2], regs[0::2]
    return regs


def raw_of(s: Slot, regs: array) -> bytes:
    """The inverse of ``registers_of``."""
    if s.value == "string" and s.string_format == "packed":
        return _unpacked(regs).tobytes()
    if s.value == "float" and s.word_order == _SWAPPED:
        regs = array("H", regs)
        regs[0::2], regs[1::2] = regs[1::2], regs[0::2]
    return regs.tobytes()


def _packed(words: array) -> array:
    """ST elements (LEN, 82 code units each) as packed registers: the LEN
    characters, 8 bits each (a code unit over 255 is ``?``), two a register,
    the first in the high byte, then NULs."""
    out = array("H")
    for e in range(0, len(words), STRING_WORDS):
        length = min(words[e], STRING_CHARS)
        chars = bytes(u if u < 256 else 0x3F for u in words[e + 1:e + 1 + length]).ljust(STRING_CHARS, b"\0")
        out.frombytes(chars)
    if sys.byteorder == "little":
        out.byteswap()  # the first character of each pair in the high byte
    return out


def _unpacked(regs: array) -> array:
    """Packed registers back to ST elements: the characters up to the first
    NUL (at most 82) are the string, LEN its length."""
    regs = array("H", regs)
    if sys.byteorder == "little":
        regs.byteswap()
    raw = regs.tobytes()
    out = array("H")
    for e in range(0, len(raw), STRING_CHARS):
        text = raw[e:e + STRING_CHARS].split(b"\0", 1)[0]
        out.append(len(text))
        out.extend(text)
        out.extend(bytes(STRING_CHARS - len(text)))
    return out


def string_lengths_fit(pieces: list[tuple[Slot, int, int]], values: list[int]) -> bool:
    """A string's LEN register takes 0..82 (its character count): do the
    registers ``values`` written over ``pieces`` keep every LEN they reach
    in range? A packed string has no LEN register."""
    k = 0
    for s, off, n in pieces:
        if s.value == "string" and s.string_format == "ucs2":
            for j in range(n):
                if (off + j) % STRING_WORDS == 0 and values[k + j] > STRING_CHARS:
                    return False
        k += n
    return True
