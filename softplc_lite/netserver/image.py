"""The memory the runtime and its server process share: the data table
image clients read, and the server's counters (counters.py).

The scan publishes the mapped words at its output point; the server copies
what a request asks for. A sequence number around each publication (a
seqlock) lets the server tell a copy taken while the scan was writing from
a whole one, so a client never sees half a scan: the scan never waits for
the server, the server retries its copy (a few microseconds) instead.

Layout of the file (native byte order: both processes run on this machine)::

    0     u64   sequence: odd while the scan is writing
    8     u32 x COUNTERS   the server's counters (counters.py); only the server writes them
    ...   the image: each region's words at the offset the protocol's map gave it

The memory is a file in /dev/shm where there is one (memory, not disk),
named ``softplc-NAME-PID-RANDOM`` after the protocol's server (``Segments``:
``softplc-modbtcps-...``) and the runtime that made it, and unlinked as soon as it is open: the server process gets the open file
itself (its descriptor), never the name. A runtime killed in the
microseconds between creating and unlinking it leaves the file behind; the
next runtime that creates one of that name removes every such file whose runtime is gone
(``remove_stale``): named after a process that no longer exists, and locked
by no one (its maker holds a lock on it while it has a name).
"""

from __future__ import annotations

import fcntl
import mmap
import os
import re
import secrets
import struct
import tempfile
from array import array

from .counters import COUNTERS

SEQUENCE = struct.Struct("=Q")
COUNTER_ARRAY = struct.Struct(f"={COUNTERS}I")
IMAGE_START = SEQUENCE.size + COUNTER_ARRAY.size


def segment_directory() -> str:
    return "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else tempfile.gettempdir()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: another user's process, alive
        return True
    return True


class Segments:
    """The files of one protocol's images, ``softplc-NAME-PID-RANDOM``."""

    def __init__(self, name: str) -> None:
        self.PREFIX = f"softplc-{name}-"
        self._name = re.compile(re.escape(self.PREFIX) + r"(\d+)-[0-9a-f]+$")

    segment_directory = staticmethod(segment_directory)

    def remove_stale(self, directory: str | None = None) -> list[str]:
        """Remove the segments runtimes killed while they had a name left
        behind; the names removed. A segment is removed only when the process
        it is named after no longer exists and no one holds its lock: a live
        runtime's (another test's, a user's running PLC's) is never touched."""
        directory = directory or segment_directory()
        removed = []
        try:
            names = os.listdir(directory)
        except OSError:
            return removed
        for name in names:
            m = self._name.match(name)
            if m is None or int(m.group(1)) == os.getpid() or _alive(int(m.group(1))):
                continue
            path = os.path.join(directory, name)
            try:
                fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
            except OSError:
                continue
            try:
                if os.fstat(fd).st_uid != os.geteuid():
                    continue
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # held by its maker while it has a name
                os.unlink(path)
                removed.append(name)
            except OSError:
                continue
            finally:
                os.close(fd)
        return removed

    def create_named(self, size: int, directory: str | None = None) -> tuple[int, str]:
        """A new segment of ``size`` bytes, named after this process and locked:
        (its descriptor, its path)."""
        directory = directory or segment_directory()
        while True:
            path = os.path.join(directory, f"{self.PREFIX}{os.getpid()}-{secrets.token_hex(6)}")
            try:
                fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
                break
            except FileExistsError:
                continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            os.ftruncate(fd, size)
        except BaseException:
            os.close(fd)
            os.unlink(path)
            raise
        return fd, path

    def create_image(self, image_bytes: int) -> "SharedImage":
        """A new image; its file is gone from the directory when this returns."""
        directory = segment_directory()
        self.remove_stale(directory)
        size = max(IMAGE_START + image_bytes, IMAGE_START)
        fd, path = self.create_named(size, directory)
        try:
            os.unlink(path)
        except FileNotFoundError:  # removed by another runtime's clean-up meanwhile: the open file serves
            pass
        try:
            return SharedImage(fd, size)
        except BaseException:
            os.close(fd)
            raise


class SharedImage:
    def __init__(self, fd: int, size: int) -> None:
        """Map the segment open on ``fd`` (kept open: the server process gets a copy of it)."""
        self.fd = fd
        self.size = max(size, IMAGE_START)
        self.mm = mmap.mmap(fd, self.size)
        self._sequence = 0

    @classmethod
    def attach(cls, fd: int, size: int) -> "SharedImage":
        return cls(fd, size)

    def close(self) -> None:
        try:
            self.mm.close()
        except (BufferError, ValueError):
            pass
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1

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
    def sequence(self) -> int:
        """The publication's sequence number: odd while the scan writes; a
        new even number once per scan (a server that follows the scans, as
        OPC UA's subscriptions do, looks here first)."""
        return SEQUENCE.unpack_from(self.mm, 0)[0]

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
