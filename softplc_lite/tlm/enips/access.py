"""What the EtherNet/IP server's services (PCCC commands, CIP tag services)
see of the data table: files by type and number, their items read from one
whole scan, and writes that go through the scan and say whether they were
applied.

Two implementations: the server process's, on the network-server layer's
shared image (reads from the image a scan published, writes passed to the
scan's input point and answered once applied), and ``TableAccessOnTable``
here, on a ``DataTable`` directly, for the services' own tests and for
tools that serve a table in one process.

Items are a file's storage items as the data table keeps them
(docs/datatable.md, "Files"): signed 16-bit words for the word files (O I
S B N D A, and T C R as 3 words an element, ST as 83: ``.LEN`` then 82
UCS-2 characters), float32 values for F, signed 32-bit integers for L.
``first`` and ``count`` count items, not elements.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

from ...datatable import DataTable


@dataclass(frozen=True)
class FileInfo:
    """One data file as a client may reach it."""

    name: str  # "N7", "ST9", "O0"
    kind: str  # the type letters: "O" "I" "S" "B" "T" "C" "R" "N" "F" "ST" "A" "D" "L"
    number: int
    elements: int
    items_per_element: int  # 1; 3 for T C R; 83 for ST
    writable: bool  # a client may write some of it (``TableAccess.writable`` says which items)

    @property
    def items(self) -> int:
        return self.elements * self.items_per_element


class TableAccess(abc.ABC):
    """The data table as a request sees it."""

    @abc.abstractmethod
    def files(self) -> list[FileInfo]:
        """Every file a client may reach, in file-number order."""

    def file(self, kind: str, number: int) -> FileInfo | None:
        """The file of that type and number, or None: no such file, another
        type has that number, or it is not served."""
        for info in self.files():
            if info.number == number:
                return info if info.kind == kind else None
        return None

    def file_named(self, name: str) -> FileInfo | None:
        for info in self.files():
            if info.name == name:
                return info
        return None

    @abc.abstractmethod
    def writable(self, name: str, first: int, count: int) -> bool:
        """Whether a client may write items first..first+count-1 of file ``name``."""

    def writable_bits(self, name: str, index: int, and_mask: int, or_mask: int) -> bool:
        """Whether a masked write of item ``index`` (``write_masked``) changes
        only what a client may write: a B file's bits are opened one by one
        (a Logix app's BOOL tags), other items whole."""
        return self.writable(name, index, 1)

    @abc.abstractmethod
    async def read(self, spans: list[tuple[str, int, int]]) -> list[list]:
        """The items of each span (file name, first item, count), all from
        one and the same scan. Raises IndexError for a span past the file's end."""

    @abc.abstractmethod
    async def write(self, name: str, first: int, items: list) -> bool:
        """Write ``items`` from item ``first`` at the scan's input point;
        True once applied, False if refused there (the caller checked
        ``writable`` and the bounds before)."""

    @abc.abstractmethod
    async def write_masked(self, name: str, index: int, and_mask: int, or_mask: int) -> bool:
        """Read-modify-write of one integer item at the scan's input point:
        ``new = (old & and_mask) | or_mask`` (masks unsigned, of the item's
        width: 16 bits for a word, 8 for SI, 32 for L, 64 for LI), so the
        bits a client leaves alone keep what the scan gave them."""

    async def write_group(self, writes: list[tuple]) -> bool:
        """Several writes applied at one input point, all or none: (file
        name, first item, items), or (file name, item, and-mask, or-mask) a
        masked write; the caller checked ``writable``."""
        return all([await (self.write(*w) if len(w) == 3 else self.write_masked(*w)) for w in writes])


def file_infos(table: DataTable, writable_names: frozenset[str] = frozenset()) -> list[FileInfo]:
    """The table's files as FileInfo, ``writable`` for the names given."""
    out = []
    for f in table.files():
        per = f.ftype.words_per_element
        out.append(FileInfo(f.name, f.ftype.letter, f.number, len(f.data) // per, per, f.name in writable_names))
    return sorted(out, key=lambda i: i.number)


class TableAccessOnTable(TableAccess):
    """A ``DataTable`` served directly: reads and writes at once (one
    process, no scan between them). ``writable``: the file names clients may
    write (whole files); every file is readable."""

    def __init__(self, table: DataTable, writable: frozenset[str] | set[str] = frozenset()) -> None:
        self.table = table
        self._writable = frozenset(writable)

    def files(self) -> list[FileInfo]:
        return file_infos(self.table, self._writable)

    def writable(self, name: str, first: int, count: int) -> bool:
        info = self.file_named(name)
        return info is not None and info.writable and 0 <= first and first + count <= info.items

    async def read(self, spans: list[tuple[str, int, int]]) -> list[list]:
        out = []
        for name, first, count in spans:
            data = self.table.file(name).data
            if first < 0 or count < 0 or first + count > len(data):
                raise IndexError(f"{name}: items {first}..{first + count - 1} past its end ({len(data)} items)")
            out.append(list(data[first:first + count]))
        return out

    async def write(self, name: str, first: int, items: list) -> bool:
        if not self.writable(name, first, len(items)):
            return False
        data = self.table.file(name).data
        for k, value in enumerate(items):
            data[first + k] = value
        return True

    async def write_masked(self, name: str, index: int, and_mask: int, or_mask: int) -> bool:
        if not self.writable_bits(name, index, and_mask, or_mask):
            return False
        data = self.table.file(name).data
        if data.typecode not in "bhiq":
            return False
        bits = data.itemsize * 8
        full = (1 << bits) - 1
        new = ((data[index] & full) & and_mask | or_mask) & full
        data[index] = new - (1 << bits) if new >> (bits - 1) else new
        return True
