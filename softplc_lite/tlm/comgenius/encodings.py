"""Port encodings: 16-bit characters to bytes and back (manual 3.2.2).

COMGENIUS characters are 16-bit code units, like the ST element's. A port's
encoding (the third ``[PORTS]`` field) turns them into bytes on sending and
bytes back into them on receiving:

=============  ===============================================  ==========================================
encoding       sending a character                              receiving bytes
=============  ===============================================  ==========================================
ISO-8859-1     its low 8 bits (the upper 8 are dropped, as      one character per byte, 0..255
               the manual says: %c of any byte goes out as is)
US-ASCII       0..127 as is; anything else ``?``                0..127 as is; 128..255 U+FFFD
UTF-8          1 to 4 bytes; a surrogate pair as one code       a character per sequence; one above U+FFFF
               point; a lone surrogate ``?``                    as a surrogate pair (two 16-bit units);
                                                                a bad byte U+FFFD; an incomplete sequence
                                                                waits for the rest
UTF-16BE/LE    two bytes per 16-bit unit, surrogates included   two bytes per unit; an odd byte waits
=============  ===============================================  ==========================================

The US-ASCII and UTF-8 replacements are those of Java's encoders, which
SoftPLC's encoding names come from.
"""

from __future__ import annotations

import codecs
import functools
import re

_ASTRAL = re.compile("[\U00010000-\U0010FFFF]")
_SURROGATE = re.compile("[\ud800-\udfff]")


def _split_astral(text: str) -> str:
    """Characters above U+FFFF as UTF-16 surrogate pairs (16-bit units)."""
    if text.isascii() or not _ASTRAL.search(text):
        return text
    return _ASTRAL.sub(lambda m: _pair(ord(m.group())), text)


def _pair(cp: int) -> str:
    cp -= 0x10000
    return chr(0xD800 + (cp >> 10)) + chr(0xDC00 + (cp & 0x3FF))


class Encoding:
    """One port encoding. ``encode`` is stateless; ``decoder()`` gives a
    fresh incremental decoder per port (it keeps a split sequence)."""

    name = ""
    codec = ""
    errors = "strict"

    def encode(self, text: str) -> bytes:
        raise NotImplementedError

    def decoder(self) -> "Decoder":
        return Decoder(codecs.getincrementaldecoder(self.codec)(self.errors))


class Decoder:
    __slots__ = ("_inc",)

    def __init__(self, inc) -> None:
        self._inc = inc

    def decode(self, data: bytes) -> str:
        return _split_astral(self._inc.decode(data))

    def reset(self) -> None:
        self._inc.reset()


class Latin1(Encoding):
    name, codec = "ISO-8859-1", "latin-1"

    def encode(self, text: str) -> bytes:
        try:
            return text.encode("latin-1")
        except UnicodeEncodeError:
            return bytes(ord(c) & 0xFF for c in text)

    def decoder(self) -> "Decoder":
        return _Latin1Decoder()


class _Latin1Decoder(Decoder):
    """Stateless and the common case: skip the incremental machinery."""

    __slots__ = ()

    def __init__(self) -> None:
        pass

    # bytes.decode itself, called without a Python frame (a port's input
    # decodes at every scan while a reply arrives)
    decode = staticmethod(functools.partial(bytes.decode, encoding="latin-1"))

    def reset(self) -> None:
        pass


class Ascii(Encoding):
    name, codec, errors = "US-ASCII", "ascii", "replace"

    def encode(self, text: str) -> bytes:
        return text.encode("ascii", "replace")


class Utf8(Encoding):
    name, codec, errors = "UTF-8", "utf-8", "replace"

    def encode(self, text: str) -> bytes:
        if text.isascii():
            return text.encode("ascii")
        if _SURROGATE.search(text):
            # join surrogate pairs into code points; a lone surrogate stays and becomes "?"
            text = text.encode("utf-16-le", "surrogatepass").decode("utf-16-le", "surrogatepass")
        return text.encode("utf-8", "replace")


class Utf16(Encoding):
    errors = "surrogatepass"

    def __init__(self, name: str, codec: str) -> None:
        self.name, self.codec = name, codec

    def encode(self, text: str) -> bytes:
        return text.encode(self.codec, "surrogatepass")


ENCODINGS: dict[str, Encoding] = {e.name: e for e in (
    Latin1(), Ascii(), Utf8(), Utf16("UTF-16BE", "utf-16-be"), Utf16("UTF-16LE", "utf-16-le"),
)}


def encoding(name: str) -> Encoding:
    return ENCODINGS[name.upper()]
