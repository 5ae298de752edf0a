"""What a format conversion reads and writes: the Params of an instruction.

COMPRINT, STRPRINT, COMSCAN and STRSCAN take up to six Param operands, each
a data table element (or, for reading, a constant). The format engine
(``printf.py``, ``scanf.py``) never touches the data table itself; it sees
each Param through this small interface, so it can be tested and measured on
plain values (``ValueParam``) and run on the data table (``TableParam``)
without change.

Each conversion locks down the kind of Param it needs (manual, conversion
tables): integer conversions take a word element (N, B, I/O, S, timer words,
...), and ``l``/``L``, ``c``/``C`` use the words that follow it in the same
file; float conversions an F element; ``s`` an ST element. A Param of another
kind, or a run of words past the end of its file, is a ``ParamError``: the
instruction sets ER (with DN) and the scan goes on.
"""

from __future__ import annotations

import enum
import math
import struct
from array import array

from ...datatable.table import STRING_CHARS, read_string, store_text, to_signed


class ParamKind(enum.Enum):
    INTEGER = "integer"
    FLOAT = "float"
    STRING = "STRING"


class ParamError(Exception):
    """A Param that cannot serve its conversion: missing, of the wrong
    kind, or running past the end of its file. ``reason`` is for people."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def float32(value: float) -> float:
    """``value`` as an F element stores it (IEEE single precision)."""
    try:
        return struct.unpack("f", struct.pack("f", value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


class Param:
    """The interface; subclasses implement the accessors their kind allows.

    Words are signed 16-bit values (-32768..32767); ``set_word`` keeps the
    low 16 bits of any integer. ``word(k)`` is the k-th word from the
    element (k = 0 is the element itself), for ``%ld`` and ``%.6c``.
    """

    kind: ParamKind
    name: str = "param"  # for messages: the address, e.g. N7:10

    def word(self, k: int = 0) -> int:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not an integer")

    def set_word(self, value: int, k: int = 0) -> None:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not an integer")

    def words(self, count: int) -> array:
        """Words 0..count-1 as unsigned 16-bit values (``%.250C`` reads 125)."""
        return array("H", [self.word(k) & 0xFFFF for k in range(count)])

    def set_words(self, words: array, k: int = 0) -> None:
        """Store a run of words from word ``k`` on (``%.250C`` fills 125)."""
        raise ParamError(f"{self.name} is a {self.kind.value} param, not an integer")

    def float(self) -> float:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not a float")

    def set_float(self, value: float) -> None:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not a float")

    def string(self) -> str:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not a STRING")

    def set_string(self, text: str) -> None:
        raise ParamError(f"{self.name} is a {self.kind.value} param, not a STRING")


class ValueParam(Param):
    """A Param over plain Python values, for tests, benchmarks and constant
    operands. An integer param is a list of words (its element and the words
    after it); writes go into that list."""

    def __init__(self, value, kind: ParamKind | None = None, name: str = "param", writable: bool = True) -> None:
        if kind is None:
            kind = (ParamKind.STRING if isinstance(value, str) else
                    ParamKind.FLOAT if isinstance(value, float) else ParamKind.INTEGER)
        if kind is ParamKind.INTEGER and not isinstance(value, list):
            value = [value]
        if kind is ParamKind.INTEGER:
            value = [to_signed(v & 0xFFFF) for v in value]
        self.kind = kind
        self.value = value
        self.name = name
        self.writable = writable

    def _check_write(self) -> None:
        if not self.writable:
            raise ParamError(f"{self.name} is a constant; a scan needs a data table element to store into")

    def word(self, k: int = 0) -> int:
        if self.kind is not ParamKind.INTEGER:
            return super().word(k)
        if k >= len(self.value):
            raise ParamError(f"{self.name}: word {k} past the end of the param ({len(self.value)} words)")
        return self.value[k]

    def set_word(self, value: int, k: int = 0) -> None:
        if self.kind is not ParamKind.INTEGER:
            return super().set_word(value, k)
        self._check_write()
        if k >= len(self.value):
            raise ParamError(f"{self.name}: word {k} past the end of the param ({len(self.value)} words)")
        self.value[k] = to_signed(value & 0xFFFF)

    def set_words(self, words: array, k: int = 0) -> None:
        if self.kind is not ParamKind.INTEGER:
            return super().set_words(words, k)
        self._check_write()
        if k + len(words) > len(self.value):
            raise ParamError(f"{self.name}: {len(words)} words from word {k} run past the end of the param "
                             f"({len(self.value)} words)")
        self.value[k:k + len(words)] = list(words)

    def float(self) -> float:
        if self.kind is not ParamKind.FLOAT:
            return super().float()
        return self.value

    def set_float(self, value: float) -> None:
        if self.kind is not ParamKind.FLOAT:
            return super().set_float(value)
        self._check_write()
        self.value = float32(value)

    def string(self) -> str:
        if self.kind is not ParamKind.STRING:
            return super().string()
        return self.value

    def set_string(self, text: str) -> None:
        if self.kind is not ParamKind.STRING:
            return super().set_string(text)
        self._check_write()
        self.value = text[:STRING_CHARS]


class TableParam(Param):
    """A Param over a data table element: ``data`` is its file's array and
    ``index`` the element's first word (an ST element's LEN word)."""

    def __init__(self, kind: ParamKind, data: array, index: int, name: str) -> None:
        self.kind = kind
        self.data = data
        self.index = index
        self.name = name

    def _at(self, k: int) -> int:
        i = self.index + k
        if i >= len(self.data):
            raise ParamError(f"{self.name}: word {k} after it is past the end of its file")
        return i

    def word(self, k: int = 0) -> int:
        if self.kind is not ParamKind.INTEGER:
            return super().word(k)
        return self.data[self._at(k)]

    def set_word(self, value: int, k: int = 0) -> None:
        if self.kind is not ParamKind.INTEGER:
            return super().set_word(value, k)
        self.data[self._at(k)] = to_signed(value & 0xFFFF)

    def words(self, count: int) -> array:
        if self.kind is not ParamKind.INTEGER or count == 0:
            return super().words(count)
        self._at(count - 1)  # past the end of the file: ParamError
        i = self.index
        return array("H", self.data[i:i + count].tobytes())  # one slice, reinterpreted unsigned

    def set_words(self, words: array, k: int = 0) -> None:
        if self.kind is not ParamKind.INTEGER:
            return super().set_words(words, k)
        i = self.index + k
        if i + len(words) > len(self.data):
            raise ParamError(f"{self.name}: {len(words)} words from it run past the end of its file")
        self.data[i:i + len(words)] = words

    def float(self) -> float:
        if self.kind is not ParamKind.FLOAT:
            return super().float()
        return self.data[self.index]

    def set_float(self, value: float) -> None:
        if self.kind is not ParamKind.FLOAT:
            return super().set_float(value)
        self.data[self.index] = float32(value)

    def string(self) -> str:
        if self.kind is not ParamKind.STRING:
            return super().string()
        return read_string(self.data, self.index)

    def set_string(self, text: str) -> None:
        if self.kind is not ParamKind.STRING:
            return super().set_string(text)
        # Every 16-bit character is kept (the manual: "all 16 bits of each
        # character"); at most 82 of them fit an ST element.
        store_text(self.data, self.index, text)
