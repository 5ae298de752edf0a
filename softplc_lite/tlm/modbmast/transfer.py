"""Moving data between Modbus payloads and the data table (manual 4.2:
scatter and gather).

A read reply's data is consumed by its toBlocks in order, each taking its
count; a write request's data is the concatenation of its fromBlocks (or
their ``const`` lists). Registers travel as big-endian 16-bit words and land
in data table words as they are (a register above 32767 reads as a negative
word, as on any PLC); coils and discretes travel packed, 8 to a byte, the
first in the lowest bit. A bit-format block takes or gives ``count`` bits
starting at its address's bit; an ``i2`` block 16 bits per word. Bits of a
word that a bit block does not cover are left as they are.

Blocks are bound to their data table arrays once (the files exist: the
driver references every block when it attaches), so a transfer is a few
slice operations, not one Python step per item.
"""

from __future__ import annotations

import sys
from array import array

from ...datatable import DataTable
from .config import Block

_LITTLE = sys.byteorder == "little"


class _Bound:
    """A block bound to its array: ``data[index...]`` from bit ``bit``."""

    __slots__ = ("data", "index", "bit", "bits", "words", "const", "const_words")

    def __init__(self, table: DataTable, block: Block) -> None:
        self.const = block.const
        self.const_words = block.fmt == "i2"  # a const list of words (16 coils each), or of bits
        self.bits = block.bits
        self.words = block.words
        self.data, self.index, self.bit = None, 0, 0
        if block.address is not None:
            f, index, bit = table.resolve(block.address)
            self.data, self.index, self.bit = f.data, index, bit or 0


def _words_to_int(data: array, index: int, words: int) -> int:
    """Words ``data[index:index+words]`` as one unsigned integer, word 0 lowest."""
    chunk = data[index:index + words]
    if not _LITTLE:
        chunk.byteswap()
    return int.from_bytes(chunk.tobytes(), "little")


def _int_to_words(value: int, words: int) -> array:
    out = array("h", value.to_bytes(2 * words, "little"))
    if not _LITTLE:
        out.byteswap()
    return out


class Scatter:
    """Where a read reply's data goes: the request's toBlocks."""

    def __init__(self, table: DataTable, blocks: tuple[Block, ...], bits: bool) -> None:
        self.blocks = [_Bound(table, b) for b in blocks]
        self.bits = bits

    def registers(self, payload: bytes) -> None:
        """Store big-endian registers, block after block."""
        values = array("h", payload)
        if _LITTLE:
            values.byteswap()
        offset = 0
        for b in self.blocks:
            n = b.words
            b.data[b.index:b.index + n] = values[offset:offset + n]
            offset += n

    def coils(self, payload: bytes) -> None:
        """Store packed bits (coils or discretes), block after block."""
        stream = int.from_bytes(payload, "little")
        offset = 0
        for b in self.blocks:
            n = b.bits
            chunk = (stream >> offset) & ((1 << n) - 1)
            offset += n
            if n == 16 * b.words:  # whole words (fmt i2, or a bit block of whole words)
                b.data[b.index:b.index + b.words] = _int_to_words(chunk, b.words)
                continue
            old = _words_to_int(b.data, b.index, b.words)
            mask = ((1 << n) - 1) << b.bit
            b.data[b.index:b.index + b.words] = _int_to_words((old & ~mask) | (chunk << b.bit), b.words)

    def store(self, payload: bytes) -> None:
        if self.bits:
            self.coils(payload)
        else:
            self.registers(payload)


class Gather:
    """Where a write request's data comes from: the request's fromBlocks.
    ``idle`` gives zeros (the outputs' idle state outside RUN)."""

    def __init__(self, table: DataTable, blocks: tuple[Block, ...], bits: bool) -> None:
        self.blocks = [_Bound(table, b) for b in blocks]
        self.bits = bits
        self.count = sum(b.bits if bits else b.words for b in self.blocks)

    def registers(self) -> array:
        """The registers as unsigned 16-bit values, block after block."""
        out = array("H")
        for b in self.blocks:
            if b.const is not None:
                out.extend(b.const)
            else:
                out.frombytes(b.data[b.index:b.index + b.words].tobytes())
        return out

    def coils(self) -> int:
        """The bits as one integer, the first in bit 0."""
        stream = 0
        offset = 0
        for b in self.blocks:
            n = b.bits
            if b.const is not None:
                value = 0
                width = 16 if b.const_words else 1
                for k, item in enumerate(b.const):
                    value |= item << (width * k)
            else:
                value = (_words_to_int(b.data, b.index, b.words) >> b.bit) & ((1 << n) - 1)
            stream |= value << offset
            offset += n
        return stream
