"""The error every config and data file reader raises: where and what.

``LocatedError(message, path, line, column)`` reports as
``path:line:column: message`` (line and column 1-based, left out when 0).
Module configs (tlm.errors.ModuleError) and port traces
(ports.errors.PortError) derive from it; the CLI prints any of them without
a traceback.

``file_error(e, path, action)`` turns an OSError met opening, reading or
writing a user's file into a sentence ("cannot read app/softplc.toml:
permission denied"), never Python's ``[Errno 13] Permission denied: '...'``.

``shown_path(path)`` is a path as every message and the watch view show
it: printable on any output, whatever bytes the file name holds.
"""

from __future__ import annotations

import errno
import os
from typing import NamedTuple


def shown_path(path: str | bytes | os.PathLike) -> str:
    """``path`` as text that any output can print. Linux lets a file name
    hold bytes that are not UTF-8 (b"\\xff.lad"); Python gives them as
    surrogate escapes, which a UTF-8 output refuses. Such bytes are shown as
    backslash escapes (``\\xff.lad``), so the name still says which bytes
    it has; any other name is unchanged."""
    name = os.fsdecode(os.fspath(path))
    if name.isascii():
        return name
    try:
        return name.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate that is no escaped byte
        return name.encode("utf-8", "backslashreplace").decode("utf-8")


class Pos(NamedTuple):
    """A place in a source (a program file, an export): source, line,
    column, 1-based. A tuple: made for every token while parsing, so it is
    cheap to build. The ladder's and Structured Text's trees both carry it."""

    source: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.source}:{self.line}:{self.column}"


NOWHERE = Pos("<generated>", 0, 0)


class LocatedError(Exception):
    """A problem in a file: where it is and what was expected."""

    def __init__(self, message: str, path: str | None = None, line: int = 0, column: int = 0) -> None:
        self.message = message
        self.path = path
        self.line = line
        self.column = column
        super().__init__(self.report())

    def report(self) -> str:
        where = shown_path(self.path) if self.path else ""
        if self.line:
            where += f":{self.line}"
            if self.column:
                where += f":{self.column}"
        return f"{where}: {self.message}" if where else self.message


# errno -> what a person is told (a softplc_lite choice: never the C library's
# own text, which reads "Is a directory" or "[Errno 21]" in the middle of a sentence).
_WORDS = {
    errno.ENOENT: "no such file or directory",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EISDIR: "it is a directory",
    errno.ENOTDIR: "a part of the path is not a directory",
    errno.ENOSPC: "no space left on the device (disk full)",
    errno.EDQUOT: "the disk quota is used up",
    errno.EFBIG: "the file would be larger than the system allows (file too large)",
    errno.EROFS: "the file system is read-only",
    errno.EEXIST: "it already exists",
    errno.ENAMETOOLONG: "the name is too long",
    errno.ELOOP: "too many symbolic links (a link loop)",
    errno.EMFILE: "too many open files",
    errno.ENFILE: "too many open files on the system",
    errno.EBUSY: "the file is busy",
    errno.ETXTBSY: "the file is busy",
    errno.EAGAIN: "the file is busy",
    errno.EIO: "an input/output error on the device",
    errno.ENXIO: "no such device (or a FIFO nobody reads)",
    errno.ENODEV: "no such device",
    errno.EXDEV: "it is on another file system",
    errno.ENOTEMPTY: "the directory is not empty",
    errno.ENOMEM: "out of memory",
    errno.EINTR: "interrupted by a signal",
    errno.EINVAL: "the file system does not allow it",
    errno.EOPNOTSUPP: "the file system does not support it",
    errno.ESTALE: "the network file system lost the file",
}


def os_error_words(e: BaseException) -> str:
    """What went wrong, in words: 'permission denied', 'it is a directory'.
    The one place an OSError becomes words: an errno not listed is said
    generically with its number; an OSError without an errno carries
    softplc's own words (FileRefused) and keeps them; anything else is an
    unexpected error, never a Python type name."""
    if isinstance(e, FileAccessError):  # already said, maybe better than its errno says it
        return e.words
    number = getattr(e, "errno", None) if isinstance(e, OSError) else None
    if number in _WORDS:
        return _WORDS[number]
    if number is not None:
        return f"the operating system refused it (error {number})"
    if isinstance(e, OSError) and e.strerror:
        return e.strerror
    return "an unexpected error"


def describe_os_error(e: BaseException, path: str | os.PathLike | None = None) -> str:
    """``os_error_words(e)``, with the file the error concerns in
    parentheses when it is not ``path``, the file the message names (a
    save that failed on ``NAME.tmp``), nor the target of a rename onto
    ``path``."""
    words = os_error_words(e)
    if not isinstance(e, OSError) or e.filename is None:
        return words
    names = [os.fsdecode(os.fspath(n)) for n in (e.filename, e.filename2) if n is not None]
    if path is None or os.fsdecode(os.fspath(path)) not in names:  # a rename onto path: path is the one
        words += f" ({shown_path(e.filename)})"
    return words


class FileAccessError(OSError):
    """An OSError on a user's file, said as a sentence (see file_error):
    ``str(e)`` and ``e.report()`` are "cannot read PATH: permission
    denied". Still an OSError with the original's errno, strerror and
    filename, so a caller that handles OSErrors handles it."""

    def __init__(self, message: str, path: str | None, error: OSError) -> None:
        super().__init__(error.errno, error.strerror, path)
        self.message = message
        self.words = os_error_words(error)

    def report(self) -> str:
        return self.message

    def __str__(self) -> str:  # not OSError's "[Errno 13] Permission denied: '...'"
        return self.message


def file_error(e: OSError, path: str | os.PathLike[str] | None = None, action: str = "read") -> FileAccessError:
    """``e`` as 'cannot ACTION PATH: WORDS' (action: read, write, open,
    create, save...); ``path`` defaults to the file the OSError names."""
    name = os.fspath(path) if path is not None else (e.filename if e.filename is not None else "")
    name = os.fsdecode(name) if isinstance(name, bytes) else str(name)
    where = f" {shown_path(name)}" if name else ""
    return FileAccessError(f"cannot {action}{where}: {os_error_words(e)}", name or None, e)
