"""Reading the text files a user hands softplc: program, config, data.

Every reader goes through :func:`read_text` (or :func:`decode_text` for
bytes it read itself), so every file kind gives the same answer:

* a byte-order mark is honoured, as Windows editors write one: UTF-8 with a
  BOM (Notepad's "UTF-8 with BOM"), UTF-16 LE or BE with a BOM (Notepad's
  "Unicode" / "Unicode big endian"); the BOM itself is dropped, so line and
  column numbers count the characters after it;
* without a BOM a file is UTF-8; bytes that are not give a
  :class:`LocatedError` naming the file, the line and column of the first
  bad byte and what was expected, never a ``UnicodeDecodeError`` (a reader
  of DOS-era files may ask for a ``fallback`` codec instead, latin-1);
* an OSError becomes errors.FileAccessError, still an OSError, whose
  text is a sentence: "cannot read PATH: permission denied".
"""

from __future__ import annotations

import codecs
import os

from .errors import LocatedError, file_error

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


def read_bytes(path: str | os.PathLike[str]) -> bytes:
    """The file's bytes; an OSError as errors.FileAccessError ('cannot read PATH: ...')."""
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise file_error(e, path) from None


def read_text(path: str | os.PathLike[str], fallback: str | None = None) -> str:
    """The file's text (see decode_text); LocatedError for bad encoding,
    FileAccessError (an OSError said in words) when it cannot be read."""
    return decode_text(read_bytes(path), os.fspath(path), fallback)
