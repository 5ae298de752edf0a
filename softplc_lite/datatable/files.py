"""Storage of one data file: a single machine-word array.

Word-based files (O I S B N T C R ST D A) keep every word in one ``array('h')``:
element ``e`` starts at word ``e * words_per_element``. F files keep float32
values in one ``array('f')``, L files 32-bit integers in one 4-byte array, SI
files 8-bit integers in one ``array('b')``, LI files 64-bit integers in one
``array('q')``. Growing extends the same array object in place,
so compiled rungs may hold a reference to ``DataFile.data`` for the life of the
table.
"""

from __future__ import annotations

import sys
from array import array

from .errors import DataTableError
from .filetypes import MAX_ELEMENTS, FileType, Storage, file_name

# An L element is 4 bytes on every platform: "i" where C int is 32-bit, else "l".
_LONG_CODE = "i" if array("i").itemsize == 4 else "l"
assert array(_LONG_CODE).itemsize == 4, "no 4-byte array typecode for L files"
assert array("q").itemsize == 8, "no 8-byte array typecode for LI files"
_TYPECODE = {Storage.WORD: "h", Storage.FLOAT: "f", Storage.LONG: _LONG_CODE,
             Storage.BYTE: "b", Storage.LONG64: "q"}


class DataFile:
    """One data file: type, number and its element storage."""

    __slots__ = ("ftype", "number", "name", "data")

    def __init__(self, ftype: FileType, number: int, elements: int = 0) -> None:
        self.ftype = ftype
        self.number = number
        self.name = file_name(ftype, number)
        self.data = array(_TYPECODE[ftype.storage])
        self.grow(elements)

    @property
    def size(self) -> int:
        """Number of elements."""
        return len(self.data) // self.ftype.words_per_element

    @property
    def is_words(self) -> bool:
        return self.ftype.storage is Storage.WORD

    def grow(self, elements: int) -> None:
        """Make the file hold at least ``elements`` elements (new ones are 0)."""
        if elements > MAX_ELEMENTS:
            raise DataTableError(
                f"{self.name} cannot hold {elements} elements: at most {MAX_ELEMENTS} per file"
            )
        missing = elements * self.ftype.words_per_element - len(self.data)
        if missing > 0:
            # frombytes() of zeros extends in place without a Python list.
            self.data.frombytes(bytes(missing * self.data.itemsize))

    def little_endian_bytes(self) -> bytes:
        """Contents in little-endian byte order, whatever the host order."""
        if sys.byteorder == "little":
            return self.data.tobytes()
        swapped = array(self.data.typecode, self.data)
        swapped.byteswap()
        return swapped.tobytes()

    def load_little_endian_bytes(self, raw: bytes) -> None:
        """Replace the contents with little-endian bytes (from a snapshot)."""
        fresh = array(self.data.typecode)
        fresh.frombytes(raw)
        if sys.byteorder != "little":
            fresh.byteswap()
        # Keep the same array object: compiled code may hold a reference.
        self.data[:] = fresh

    def __repr__(self) -> str:
        return f"<DataFile {self.name} {self.size} elements>"
