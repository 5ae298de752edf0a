"""The memory the runtime and its server process share: the data table
image clients read, and the server's counters.

The scan publishes the mapped words at its output point; the server copies
what a request asks for. A sequence number around each publication (a
seqlock) lets the server tell a copy taken while the scan was writing from
a whole one, so a client never sees half a scan: the scan never waits for
the server, the server retries its copy (a few microseconds) instead.

Layout of the file (native byte order: both processes run on this machine)::

    0     u64   sequence: odd while the scan is writing
    8     u32 x COUNTERS   the server's counters (status.py); only the server writes them
    ...   the image: each region's words at the offset the Layout gave it

The file lives in /dev/shm where there is one (memory, not disk) and is
unlinked as soon as both processes have it open.
"""

from __future__ import annotations

import mmap
import os
import struct
import tempfile
from array import array

from .status import COUNTERS

SEQUENCE = struct.Struct("=Q")
COUNTER_ARRAY = struct.Struct(f"={COUNTERS}I")
IMAGE_START = SEQUENCE.size + COUNTER_ARRAY.size


class SharedImage:
    def __init__(self, path: str, size: int, create: bool) -> None:
        self.path = path
        self.size = max(size, IMAGE_START)
        if create:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o600)
            os.ftruncate(fd, self.size)
        else:
            fd = os.open(path, os.O_RDWR)
        try:
            self.mm = mmap.mmap(fd, self.size)
        finally:
            os.close(fd)
        self._sequence = 0

    @classmethod
    def create(cls, image_bytes: int) -> "SharedImage":
        directory = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
        fd, path = tempfile.mkstemp(prefix="softplc-modbtcps-", dir=directory)
        os.close(fd)
        os.unlink(path)  # mkstemp chose a free name; O_EXCL makes it ours again
        return cls(path, IMAGE_START + image_bytes, create=True)

    @classmethod
    def attach(cls, path: str, size: int) -> "SharedImage":
        return cls(path, size, create=False)

    def unlink(self) -> None:
        try:
            os.unlink(self.path)
        except OSError:
            pass

    def close(self) -> None:
        try:
            self.mm.close()
        except (BufferError, ValueError):
            pass

    # -- the scan's side ----------------------------------------------------------------------
    def begin(self) -> None:
        self._sequence += 1  # odd: writing
        SEQUENCE.pack_into(self.mm, 0, self._sequence)

    def put(self, offset: int, words: array) -> None:
        """Copy ``words`` (a slice of a data file's array) into the image."""
        start = IMAGE_START + offset
        self.mm[start:start + len(words) * words.itemsize] = words

    def end(self) -> None:
        self._sequence += 1  # even: whole
        SEQUENCE.pack_into(self.mm, 0, self._sequence)

    def counters(self) -> tuple[int, ...]:
        return COUNTER_ARRAY.unpack_from(self.mm, SEQUENCE.size)

    # -- the server's side --------------------------------------------------------------------
    def read(self, spans: list[tuple[int, int]]) -> list[bytes] | None:
        """The bytes of each (offset, length) span of the image, all from one
        publication; None if the scan was writing (the caller tries again)."""
        mm = self.mm
        before = SEQUENCE.unpack_from(mm, 0)[0]
        if before & 1:
            return None
        out = [mm[IMAGE_START + offset:IMAGE_START + offset + length] for offset, length in spans]
        if SEQUENCE.unpack_from(mm, 0)[0] != before:
            return None
        return out

    def add(self, counter: int, n: int = 1) -> None:
        offset = SEQUENCE.size + 4 * counter
        value = struct.unpack_from("=I", self.mm, offset)[0]
        struct.pack_into("=I", self.mm, offset, (value + n) & 0xFFFFFFFF)

    def set(self, counter: int, value: int) -> None:
        struct.pack_into("=I", self.mm, SEQUENCE.size + 4 * counter, value & 0xFFFFFFFF)
