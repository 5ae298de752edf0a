"""Retentive snapshots: the whole data table on disk, saved atomically.

File format (little-endian throughout)::

    header  "SPLCSNAP"  u16 version=1  u16 reserved  u32 file count  u64 body length
    body    per file:  2s type letter(s)  u16 number  u32 elements  <data bytes>
    trailer u32 CRC-32 of header+body   "SPLCEND!"

The data bytes are the file's array items, little-endian: 2 bytes a word
(every word file, D and A included), 4 a float (F) or a long (L), 1 an SI
item, 8 an LI item. The L, D, A, SI and LI files came later under the same
version, so every older snapshot loads; an older softplc refuses a snapshot
holding one as an unknown file type.

A short file, a wrong length, a bad CRC or a missing trailer is reported as
:class:`SnapshotError`; nothing half-read is ever returned. So is a path
that is not a regular file (a FIFO, a device, a dangling or looping link)
or a file over the snapshot limit (textfile.SNAPSHOT): it is refused before
anything is read.

:func:`save` writes ``NAME.tmp``, fsyncs it, hard-links the current snapshot
to ``NAME.prev`` (the previous good one), renames the temp file over ``NAME``
and fsyncs the directory. At every instant ``NAME`` is either the complete
old snapshot or the complete new one, so a process killed during a save
leaves a loadable snapshot.

A running PLC saves with :func:`write` instead (softplc_lite/retentive.py):
the bytes :func:`encode` made between two scans, to ``NAME`` through the same
temp file and rename, without fsync for the frequent saves (a killed process
does not lose the page cache); the durable ones are then fsynced and become
``NAME.prev`` (:func:`make_durable`): the newest snapshot known to be on
disk, for after a power loss. :func:`remove_stale` deletes the temp files a killed
process left. A write that fails (a full disk, a file size limit) removes
its own temp file: nothing partial is left behind.
"""

from __future__ import annotations

import errno
import os
import stat
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import FileAccessError, file_error
from ..textfile import SNAPSHOT, read_bytes
from .errors import DataTableError, SnapshotError
from .filetypes import FILE_TYPES, MAX_ELEMENTS
from .table import DataTable

MAGIC = b"SPLCSNAP"
TRAILER_MAGIC = b"SPLCEND!"
VERSION = 1
_HEADER = struct.Struct("<8sHHIQ")
_FILE = struct.Struct("<2sHI")
_TRAILER = struct.Struct("<I8s")


def encode(table: DataTable) -> bytes:
    parts: list[bytes] = []
    files = table.files()
    for f in files:
        parts.append(_FILE.pack(f.ftype.letter.encode("ascii").ljust(2), f.number, f.size))
        parts.append(f.little_endian_bytes())
    body = b"".join(parts)
    header = _HEADER.pack(MAGIC, VERSION, 0, len(files), len(body))
    crc = zlib.crc32(body, zlib.crc32(header))
    return header + body + _TRAILER.pack(crc, TRAILER_MAGIC)


def decode(raw: bytes, source: str = "<snapshot>") -> DataTable:
    def bad(reason: str) -> SnapshotError:
        return SnapshotError(f"{source}: not a usable snapshot: {reason}")

    if len(raw) < _HEADER.size + _TRAILER.size:
        raise bad(f"only {len(raw)} bytes (truncated)")
    magic, version, _, count, body_len = _HEADER.unpack_from(raw, 0)
    if magic != MAGIC:
        raise bad("wrong magic number (not a softplc snapshot)")
    if version != VERSION:
        raise bad(f"format version {version}, this softplc reads version {VERSION}")
    expected = _HEADER.size + body_len + _TRAILER.size
    if len(raw) != expected:
        raise bad(f"{len(raw)} bytes where the header promises {expected} (truncated or padded)")
    crc, end_magic = _TRAILER.unpack_from(raw, _HEADER.size + body_len)
    if end_magic != TRAILER_MAGIC:
        raise bad("missing end marker")
    actual = zlib.crc32(raw[_HEADER.size:_HEADER.size + body_len], zlib.crc32(raw[:_HEADER.size]))
    if crc != actual:
        raise bad(f"checksum mismatch (stored {crc:08x}, computed {actual:08x}): corrupted")
    table = DataTable(defaults=False)
    pos = _HEADER.size
    end = _HEADER.size + body_len
    seen: set[int] = set()
    try:
        for _ in range(count):
            letters, number, elements = _FILE.unpack_from(raw, pos)
            pos += _FILE.size
            ftype = FILE_TYPES.get(letters.decode("ascii").strip())
            if ftype is None:
                raise bad(f"unknown file type {letters!r}")
            if elements > MAX_ELEMENTS:
                raise bad(f"{ftype.letter}{number} claims {elements} elements (at most {MAX_ELEMENTS})")
            if number in seen:
                raise bad(f"file number {number} appears twice")
            seen.add(number)
            f = table.create_file(ftype.letter, number, 0)
            nbytes = elements * ftype.words_per_element * f.data.itemsize
            if pos + nbytes > end:
                raise bad(f"{f.name} runs past the end of the body")
            f.load_little_endian_bytes(raw[pos:pos + nbytes])
            pos += nbytes
    except (struct.error, UnicodeDecodeError, DataTableError) as e:
        if isinstance(e, SnapshotError):
            raise
        raise bad(str(e)) from None
    if pos != end:
        raise bad(f"{end - pos} stray bytes after the last file")
    return table


def save(table: DataTable, path: str | os.PathLike[str]) -> None:
    """Write ``table`` to ``path`` atomically, keeping the old one as .prev."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    prev = path.with_name(path.name + ".prev")
    _write_tmp(encode(table), tmp, durable=True)  # removed again if it fails
    if path.exists():
        # A hard link, not a rename: NAME must never be missing, even for an
        # instant, or a kill right then would leave no current snapshot.
        _link_as(path, prev)
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def write(data: bytes, path: str | os.PathLike[str], durable: bool) -> None:
    """Put encoded snapshot bytes at ``path`` atomically: ``NAME.tmp``, then
    a rename over ``NAME``, so ``NAME`` is always a complete snapshot.
    Creates the directory when missing. Not durable: no fsync, and
    ``NAME.prev`` is left alone (it stays the last durable snapshot).
    Durable: then :func:`make_durable`. Raises OSError; a failed write leaves
    ``NAME`` and ``NAME.prev`` as they were, and no ``NAME.tmp``."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        _write_tmp(data, tmp, False)
    except FileNotFoundError:
        path.parent.mkdir(parents=True, exist_ok=True)
        _write_tmp(data, tmp, False)
    try:
        os.replace(tmp, path)
    except OSError:
        _remove(tmp)
        raise
    if durable:
        make_durable(path)


def make_durable(path: str | os.PathLike[str]) -> None:
    """Put the snapshot now at ``path`` on disk: fsync it, make ``NAME.prev``
    a hard link to it, fsync the directory. Only then does ``NAME.prev`` name
    it, so after a power loss ``NAME.prev`` holds a whole snapshot whatever
    happened to later writes of ``NAME`` that were not made durable. (The
    rename comes before the fsync, so a save's rename, all a killed process
    needs, never waits for the disk.)"""
    path = Path(path)
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # never waits, whatever took the name since the rename
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    _link_as(path, path.with_name(path.name + ".prev"))
    _fsync_dir(path.parent)


def remove_stale(path: str | os.PathLike[str]) -> list[Path]:
    """Delete ``NAME.tmp`` and ``NAME.prev.tmp`` (what a process killed in
    the middle of a save leaves); the ones removed. Never raises: a file
    that cannot be removed is left for the next save to overwrite."""
    path = Path(path)
    removed = []
    for stale in (path.with_name(path.name + ".tmp"), path.with_name(path.name + ".prev.tmp")):
        try:
            stale.unlink()
        except OSError:
            continue
        removed.append(stale)
    return removed


def _write_tmp(data: bytes, tmp: Path, durable: bool) -> None:
    """Write ``data`` to the temp file ``tmp`` (a new regular file: whatever
    else is found under its name, a FIFO, a device or a link, is removed,
    never opened through or waited on); on any failure, such as a full
    disk, the temp file is removed and the error raised."""
    fd = _open_tmp(tmp)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
        if durable:
            os.fsync(fd)
    except BaseException:
        os.close(fd)
        _remove(tmp)
        raise
    os.close(fd)


_TMP_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_NONBLOCK | os.O_NOCTTY | getattr(os, "O_NOFOLLOW", 0)


def _open_tmp(tmp: Path) -> int:
    """A file descriptor for writing ``tmp`` from its start, a regular file."""
    try:
        fd = os.open(tmp, _TMP_FLAGS | os.O_TRUNC, 0o644)
    except OSError as e:
        if e.errno not in (errno.ELOOP, errno.ENXIO):  # a link (O_NOFOLLOW), a FIFO nobody reads: removed below
            raise
        fd = None
    if fd is not None:
        if stat.S_ISREG(os.fstat(fd).st_mode):
            return fd
        os.close(fd)  # a FIFO someone reads, a device: not written through
    tmp.unlink()
    return os.open(tmp, _TMP_FLAGS | os.O_EXCL, 0o644)


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:  # gone already, or the directory is unwritable: the next start's remove_stale tries again
        pass


def _link_as(path: Path, name: Path) -> None:
    """Make ``name`` another name of ``path``'s file, atomically (through
    ``name.tmp``): ``name`` is never missing or partial."""
    link_tmp = name.with_name(name.name + ".tmp")
    link_tmp.unlink(missing_ok=True)
    os.link(path, link_tmp)
    os.replace(link_tmp, name)


def _fsync_dir(directory: Path) -> None:
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def load_into(table: DataTable, path: str | os.PathLike[str]) -> None:
    """Replace ``table``'s contents with the snapshot at ``path``, keeping
    its array objects (compiled rungs hold references to them)."""
    table.assign(load(path))


def load(path: str | os.PathLike[str]) -> DataTable:
    """Read one snapshot file; raise SnapshotError if it is missing or bad
    (not a regular file, over the snapshot limit: textfile.read_bytes)."""
    try:
        raw = read_bytes(path, SNAPSHOT)
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: not a regular file (a FIFO)"
        if e.errno == errno.ENOENT and os.path.islink(path):
            raise SnapshotError(f"{path}: a symbolic link to {os.readlink(path)}, which does not exist") from None
        if e.errno == errno.ENOENT:
            raise SnapshotError(f"{path}: no snapshot") from None
        raise SnapshotError(e.report() if isinstance(e, FileAccessError) else file_error(e, path).report()) from None
    return decode(raw, str(path))


@dataclass
class Restored:
    """What :func:`restore` found: the table (None when there was no
    snapshot at all), which file it came from, and problems to report."""

    table: DataTable | None
    source: Path | None
    problems: list[str] = field(default_factory=list)


def restore(path: str | os.PathLike[str]) -> Restored:
    """Load the snapshot at ``path``; if it is corrupt, report that and fall
    back to ``path.prev``. Raises SnapshotError only when a snapshot exists
    but neither it nor the previous one is usable."""
    path = Path(path)
    prev = path.with_name(path.name + ".prev")
    # lexists: a dangling or looping link is a snapshot that cannot be read, said so, not no snapshot.
    if not os.path.lexists(path) and not os.path.lexists(prev):
        return Restored(None, None)
    problems: list[str] = []
    for candidate in (path, prev):
        if not os.path.lexists(candidate):
            continue
        try:
            return Restored(load(candidate), candidate, problems)
        except SnapshotError as e:
            problems.append(str(e))
    raise SnapshotError("; ".join(problems) + "; no usable snapshot")
