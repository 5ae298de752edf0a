"""Reading the files a user hands softplc (program, config, data, traces)
and its own state files (the retentive snapshot, the code cache).

Every reader goes through :func:`read_text` or :func:`read_bytes` (or
:func:`decode_text` for text it has as bytes), so every file kind gives the
same answer:

* a byte-order mark is honoured, as Windows editors write one: UTF-8 with a
  BOM (Notepad's "UTF-8 with BOM"), UTF-16 LE or BE with a BOM (Notepad's
  "Unicode" / "Unicode big endian"); the BOM itself is dropped, so line and
  column numbers count the characters after it;
* without a BOM a file is UTF-8; bytes that are not give a
  :class:`LocatedError` naming the file, the line and column of the first
  bad byte and what was expected, never a ``UnicodeDecodeError`` (a reader
  of DOS-era files may ask for a ``fallback`` codec instead, latin-1);
* an OSError becomes errors.FileAccessError, still an OSError, whose
  text is a sentence: "cannot read PATH: permission denied" (a link to
  nothing: "cannot read PATH: a symbolic link to TARGET, which does not
  exist");
* only a regular file is read, and no more than its kind's :class:`Limit`
  (docs/cli.md, "Input file limits"): a FIFO, a device (a link to
  ``/dev/zero``), a socket or a directory is refused without waiting or
  reading ("cannot read PATH: not a regular file (a FIFO)"), and so is a
  file over the limit ("cannot read PATH: 20 GiB, over the 16 MiB limit
  for a program file"), before any of it is read. At most limit + 1 bytes
  are ever read, so a file that grows while it is read is refused too.
  The refusal is a :class:`FileRefused`, a FileAccessError.
"""

from __future__ import annotations

import codecs
import errno
import os
import stat
from dataclasses import dataclass

from .errors import FileAccessError, LocatedError, file_error, shown_path


@dataclass(frozen=True)
class Limit:
    """The most softplc reads of one kind of file: ``size`` bytes, and
    ``what`` the kind is, for the message ("a program file")."""

    what: str
    size: int


MiB = 1 << 20
# The caps of docs/cli.md, "Input file limits" (softplc_lite choices; the reasons are there).
PROGRAM = Limit("a program file", 16 * MiB)
CONFIG = Limit("a settings or config file", 1 * MiB)
DATA_JSON = Limit("a data table JSON file", 64 * MiB)
SNAPSHOT = Limit("a snapshot", 256 * MiB)
TRACE = Limit("a port trace", 64 * MiB)
WATCH_FILE = Limit("a watch file", 1 * MiB)
CODE_CACHE = Limit("a code cache", 256 * MiB)


class FileRefused(FileAccessError):
    """A file not read because of what it is (not a regular file) or its
    size (over its kind's Limit); ``str(e)`` is "cannot read PATH: WHY"."""

    def __init__(self, path: str, why: str, too_large: bool = False) -> None:
        super().__init__(f"cannot read {shown_path(path)}: {why}", path, OSError(None, why))
        self.too_large = too_large  # else: not a regular file


def size_text(n: float) -> str:
    """``n`` bytes the way a person reads it: 512 bytes, 1.5 KiB, 16 MiB, 20 GiB."""
    if n < 1024:
        return f"{int(n)} byte{'s' if n != 1 else ''}"
    for unit in ("KiB", "MiB", "GiB", "TiB"):
        n /= 1024
        if round(n, 1) < 1024 or unit == "TiB":
            break
    return f"{n:.1f}".removesuffix(".0") + f" {unit}"


_NOT_REGULAR = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _refusal(path: str, st: os.stat_result, limit: Limit) -> FileAccessError | None:
    """Why a file with status ``st`` is not read, or None."""
    if stat.S_ISDIR(st.st_mode):
        return file_error(IsADirectoryError(errno.EISDIR, "Is a directory"), path)
    if not stat.S_ISREG(st.st_mode):
        kind = next((name for test, name in _NOT_REGULAR if test(st.st_mode)), "a special file")
        return FileRefused(path, f"not a regular file ({kind})")
    if st.st_size > limit.size:
        size, cap = size_text(st.st_size), size_text(limit.size)
        if size == cap:  # just over: "256 MiB, over the 256 MiB limit" would say nothing
            size = f"{st.st_size:,} bytes"
        return FileRefused(path, f"{size}, over the {cap} limit for {limit.what}", too_large=True)
    return None


def _dangling(path: str) -> FileAccessError | None:
    """A link at ``path`` whose target does not exist, said so ("cannot
    read PATH: a symbolic link to TARGET, which does not exist"), or None:
    "no such file" would deny the name the user sees in a listing. Still
    ENOENT, so a reader of an optional file that asks for its errno treats
    it as missing only if it means to."""
    try:
        target = os.readlink(path)
    except OSError:  # not a link (a missing file), or gone meanwhile
        return None
    why = f"a symbolic link to {shown_path(target)}, which does not exist"
    error = FileAccessError(f"cannot read {shown_path(path)}: {why}", path, OSError(errno.ENOENT, why))
    error.words = why
    return error


# BOM -> codec; UTF-8's first (a UTF-16 LE BOM is a prefix of no UTF-8 BOM, but keep the longest first).
BOMS = ((codecs.BOM_UTF8, "utf-8"), (codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be"))


def _located(raw: bytes, start: int, message: str, path: str) -> LocatedError:
    """The line and column (in characters) of byte ``start`` of UTF-8 ``raw``."""
    text = raw[:start].decode("utf-8", "replace")
    line = text.count("\n") + 1
    column = len(text) - (text.rfind("\n") + 1) + 1
    return LocatedError(message, path, line, column)


def decode_text(raw: bytes, path: str, fallback: str | None = None) -> str:
    """``raw`` as text, by its BOM (dropped) or else as UTF-8 (``fallback``,
    e.g. "latin-1", for bytes that are not UTF-8); LocatedError at the first
    byte that cannot be decoded."""
    for bom, codec in BOMS:
        if raw.startswith(bom):
            body = raw[len(bom):]
            try:
                return body.decode(codec)
            except UnicodeDecodeError as e:
                if codec == "utf-8":
                    raise _located(body, e.start, f"byte 0x{body[e.start]:02x} is not UTF-8 text (the file "
                                   "starts with a UTF-8 byte-order mark, so it must be UTF-8)", path) from None
                unit = body[: e.start // 2 * 2].decode(codec, "replace")
                line = unit.count("\n") + 1
                column = len(unit) - (unit.rfind("\n") + 1) + 1
                what = ("the file ends in half a character" if e.start + 2 > len(body)
                        else "an unpaired UTF-16 surrogate")
                raise LocatedError(f"{what} (the file starts with a {codec.upper()} byte-order mark, "
                                   "so it must be UTF-16 throughout)", path, line, column) from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as e:
        if fallback is not None:
            return raw.decode(fallback)
        raise _located(raw, e.start, f"byte 0x{raw[e.start]:02x} is not UTF-8 text (save the file as UTF-8, "
                       "or as UTF-16 with a byte-order mark)", path) from None


def read_bytes(path: str | os.PathLike[str], limit: Limit = CONFIG) -> bytes:
    """The bytes of the regular file at ``path``, at most ``limit.size``
    of them; an OSError as errors.FileAccessError ('cannot read PATH:
    ...'), a file that is not regular or is too large as FileRefused.

    The path's status is looked at before it is opened (a device is never
    opened), it is opened without blocking (a FIFO made after that look
    does not hang the open) and the opened file's own status is checked
    again; then at most limit.size + 1 bytes are read."""
    name = os.fspath(path)
    name = os.fsdecode(name) if isinstance(name, bytes) else name
    try:
        refused = _refusal(name, os.stat(name), limit)
        if refused is not None:
            raise refused
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | getattr(os, "O_CLOEXEC", 0))
    except FileAccessError:
        raise
    except OSError as e:
        raise (_dangling(name) if e.errno == errno.ENOENT else None) or file_error(e, name) from None
    try:
        st = os.fstat(fd)
        refused = _refusal(name, st, limit)
        if refused is not None:
            raise refused
        parts: list[bytes] = []
        total = 0
        while total <= limit.size:  # the size fstat gave in one read, then until the end or the limit
            chunk = os.read(fd, min(limit.size + 1 - total, max(st.st_size + 1 - total, 1 << 16)))
            if not chunk:
                break
            parts.append(chunk)
            total += len(chunk)
    except FileAccessError:
        raise
    except OSError as e:
        raise file_error(e, name) from None
    finally:
        os.close(fd)
    if total > limit.size:
        raise FileRefused(name, f"more than {size_text(limit.size)} (it grew while being read), over the limit "
                                f"for {limit.what}", too_large=True)
    return b"".join(parts)


def read_text(path: str | os.PathLike[str], fallback: str | None = None, limit: Limit = CONFIG) -> str:
    """The file's text (see decode_text), read as read_bytes does with
    ``limit``; LocatedError for bad encoding, FileAccessError (an OSError
    said in words) when it cannot or may not be read."""
    return decode_text(read_bytes(path, limit), os.fspath(path), fallback)
