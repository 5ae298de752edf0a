"""Input matching: characters + a format string -> Params, or why not.

Shared by STRSCAN and COMSCAN (manual 4.3.5). The matcher reads a string of
16-bit characters from its start and reports one of:

- ``MATCHED``: the whole format matched; ``used`` characters were read
  (COMSCAN removes exactly those from its receive buffer);
- ``MISMATCH``: the input cannot match; ``used`` is the offset where it
  failed;
- ``NEED_MORE``: the input ran out before a match could be decided (COMSCAN
  waits for more; it never happens with ``final=True``, where the end of the
  text is the end of the input, as for STRSCAN's STRING).

``specs`` counts the conversion specifications matched (the CONTROL's POS).
The matcher never consumes anything itself: a caller that gets MISMATCH or
NEED_MORE keeps its input as it was ("put back"). Params are written as
their fields match, so they are staging areas until a MATCHED result.

Rules, per the manual where it speaks and C's scanf where it does not:

- whitespace in the format skips any whitespace (none included); other
  characters match literally; ``%%`` and ``%`` followed by a whitespace
  character match that one character;
- numeric and ``s`` conversions skip leading whitespace, ``c``/``C``/``n``/
  ``S``/``R`` do not;
- precision limits a field: digits for numeric conversions (a sign or ``0x``
  prefix comes on top, so ``%.3d`` on ``-1234`` reads ``-123``), characters
  for ``s`` (default 82), bytes for ``c``/``C`` (default 1); it is ignored
  for floats; width is ignored except by S and R;
- a sign is accepted on the unsigned conversions and the value wraps; values
  are stored as 16-bit words (two for ``l``/``L``, low word first), floats
  as float32, ``s`` keeps all 16 bits of each character;
- ``S`` and ``R`` compute the sum / CRC-16 of the characters read from
  offset ``width`` to ``precision`` characters before the field, and compare
  it with the next 2 characters (1 for ``%hS``), little endian;
- ``*`` suppresses assignment (no Param consumed); ``n`` stores the number
  of characters read so far.
"""

from __future__ import annotations

import re
import sys
from array import array
from functools import lru_cache
from typing import NamedTuple, Sequence

from .checksum import crc16, low_bytes, sum16
from .formats import STAR, WHITESPACE, FormatError, Spec, parse_scan
from .params import Param, ParamError

MATCHED, MISMATCH, NEED_MORE = "matched", "mismatch", "need more input"
STRING_MAX = 82


class ScanResult(NamedTuple):
    status: str
    used: int  # characters read; for MISMATCH the offset where it failed
    specs: int  # conversion specifications matched


class _Stop(Exception):
    """Raised inside the matcher: a mismatch (need=False) or the end of the
    input before a decision (need=True), at ``pos``."""

    def __init__(self, pos: int, need: bool) -> None:
        self.pos = pos
        self.need = need


_DIGITS = {
    2: frozenset("01"),
    8: frozenset("01234567"),
    10: frozenset("0123456789"),
    16: frozenset("0123456789abcdefABCDEF"),
}
_BASE = {"b": 2, "o": 8, "u": 10, "d": 10, "x": 16, "X": 16, "i": 0}


class _Scan:
    """State of one match: the input, the Params and the position."""

    __slots__ = ("data", "n", "final", "params", "k", "need_len")

    def __init__(self, data: str, final: bool, params: Sequence[Param]) -> None:
        self.data = data
        self.n = len(data)
        self.final = final
        self.params = params
        self.k = 0
        self.need_len = 0  # set by an op that stops for input it has not looked at yet

    def end(self, pos: int):
        """The input ended at ``pos`` before a decision."""
        raise _Stop(pos, not self.final)

    def param(self, spec: Spec) -> Param:
        if self.k >= len(self.params):
            raise ParamError(f"too few Params: {spec.text} needs Param {self.k + 1}, but "
                             f"{len(self.params)} {'was' if len(self.params) == 1 else 'were'} given")
        p = self.params[self.k]
        self.k += 1
        return p

    def skip_ws(self, pos: int) -> int:
        data, n = self.data, self.n
        while pos < n and data[pos] in WHITESPACE:
            pos += 1
        return pos

    def field_start(self, pos: int) -> int:
        """Skip leading whitespace before a numeric field; the field cannot
        be decided while the input ends there."""
        pos = self.skip_ws(pos)
        if pos >= self.n:
            self.end(pos)
        return pos


def _literal(text: str):
    size = len(text)

    def op(st: _Scan, pos: int) -> int:
        data = st.data
        if data.startswith(text, pos):
            return pos + size
        for j, ch in enumerate(text):
            if pos + j >= st.n:
                st.end(pos + j)
            if data[pos + j] != ch:
                raise _Stop(pos + j, False)
        return pos + size  # not reached
    return op


def _whitespace(st: _Scan, pos: int) -> int:
    return st.skip_ws(pos)


def _one_char(ch: str):
    def op(st: _Scan, pos: int) -> int:
        if pos >= st.n:
            st.end(pos)
        if st.data[pos] != ch:
            raise _Stop(pos, False)
        return pos + 1
    return op


def _integer(spec: Spec):
    base0 = _BASE[spec.conv]
    limit = spec.precision  # digits, None: no limit
    bits = 32 if spec.long else 16
    store = not spec.suppressed

    def op(st: _Scan, pos: int) -> int:
        data, n = st.data, st.n
        pos = st.field_start(pos)
        negative = False
        if data[pos] in "+-":
            negative = data[pos] == "-"
            pos += 1
            if pos >= n:
                st.end(pos)
        base = base0
        if base in (0, 16) and data[pos] == "0":
            # 0x prefix (x, i) or a leading 0 for octal (i); decide on the next character.
            if pos + 1 >= n:
                if not st.final:
                    st.end(pos + 1)
            elif data[pos + 1] in "xX":
                if pos + 2 >= n and not st.final:
                    st.end(pos + 2)
                if pos + 2 < n and data[pos + 2] in _DIGITS[16]:
                    pos += 2
                    base = 16
            if base == 0:
                base = 8
        elif base == 0:
            base = 10
        digits_ok = _DIGITS[base]
        start = pos
        while pos < n and data[pos] in digits_ok and (limit is None or pos - start < limit):
            pos += 1
        count = pos - start
        if count == 0:
            if pos >= n:
                st.end(pos)
            raise _Stop(pos, False)
        if pos >= n and (limit is None or count < limit) and not st.final:
            st.end(pos)  # more digits may follow
        value = int(data[start:pos], base)
        if negative:
            value = -value
        if store:
            p = st.param(spec)
            p.set_word(value & 0xFFFF, 0)
            if bits == 32:
                p.set_word((value >> 16) & 0xFFFF, 1)
        return pos
    return op


def _float_end(data: str, pos: int, n: int) -> int:
    """End of the longest float prefix at ``pos`` (strtod's syntax), or pos."""
    j = pos
    if j < n and data[j] in "+-":
        j += 1
    word = data[j:j + 8].lower()
    for special in ("infinity", "inf", "nan"):
        if word.startswith(special):
            return j + len(special)
    digits = 0
    while j < n and data[j].isascii() and data[j].isdigit():
        j += 1
        digits += 1
    if j < n and data[j] == ".":
        j += 1
        while j < n and data[j].isascii() and data[j].isdigit():
            j += 1
            digits += 1
    if digits == 0:
        return pos
    if j < n and data[j] in "eE":
        k = j + 1
        if k < n and data[k] in "+-":
            k += 1
        e = k
        while k < n and data[k].isascii() and data[k].isdigit():
            k += 1
        if k > e:
            j = k
    return j


# Input that more characters could still turn into a longer float: a whole
# number so far ("1.5"), or one cut short ("-", ".", "1e", "1e+", "in", "na").
_FLOAT_PREFIX = re.compile(
    r"[+-]?(?:\d*\.?\d*|(?:\d+\.?\d*|\.\d+)e[+-]?\d*"
    r"|i(?:n(?:f(?:i(?:n(?:i(?:ty?)?)?)?)?)?)?|n(?:an?)?)",
    re.IGNORECASE | re.ASCII)


def _float(spec: Spec):
    store = not spec.suppressed

    def op(st: _Scan, pos: int) -> int:
        data, n = st.data, st.n
        pos = st.field_start(pos)
        if not st.final and _FLOAT_PREFIX.fullmatch(data, pos):
            st.end(n)  # the number may go on, or has not yet begun
        end = _float_end(data, pos, n)
        if end == pos:
            raise _Stop(pos, False)
        value = float(data[pos:end])
        if store:
            st.param(spec).set_float(value)
        return end
    return op


def _string(spec: Spec):
    limit = min(spec.precision if spec.precision is not None else STRING_MAX, STRING_MAX)
    store = not spec.suppressed

    def op(st: _Scan, pos: int) -> int:
        data, n = st.data, st.n
        pos = st.skip_ws(pos)
        start = pos
        while pos < n and pos - start < limit and data[pos] not in WHITESPACE:
            pos += 1
        if pos >= n and pos - start < limit and (not st.final or pos == start):
            st.end(pos)  # the field is not known to be complete
        if limit == 0:
            pos = start
        if store:
            st.param(spec).set_string(data[start:pos])
        return pos
    return op


def _chars(spec: Spec):
    fixed = 1 if spec.precision is None else spec.precision
    star = spec.precision == STAR
    # Words hold the bytes little endian (c) or big endian (C), whatever
    # the host's own order: array("h") uses the native one.
    swap = (spec.conv == "C") != (sys.byteorder == "big")
    store = not spec.suppressed
    one_a_word = spec.byte_per_word

    def op(st: _Scan, pos: int) -> int:
        count = fixed
        if star:
            count = st.param(spec).word(0)
            if count < 0:
                raise ParamError(f"{spec.text}: the byte count Param is {count}, below 0")
        end = pos + count
        if end > st.n:
            if not star:
                st.need_len = end  # nothing of the field is read before it is all there
            st.end(st.n)
        if store:
            raw = low_bytes(st.data[pos:end])
            if one_a_word:
                words = array("h", list(raw))
            else:
                if count & 1:
                    raw += b"\0"
                words = array("h", raw)
                if swap:
                    words.byteswap()
            st.param(spec).set_words(words)
        return end
    return op


def _check(spec: Spec):
    start = spec.width or 0
    back = 1 if spec.precision is None else spec.precision
    one = spec.conv == "S" and spec.length in ("h", "H")
    size = 1 if one else 2
    negate_or_preload = "#" in spec.flags

    def op(st: _Scan, pos: int) -> int:
        if pos + size > st.n:
            st.end(st.n)
        end = pos - back + 1
        chars = st.data[start:end] if end > start else ""
        if spec.conv == "R":
            want = crc16(chars, 0xFFFF if negate_or_preload else 0)
        else:
            want = sum16(chars, negate_or_preload, one)
        got = low_bytes(st.data[pos:pos + size])
        if int.from_bytes(got, "little") != want:
            raise _Stop(pos, False)
        return pos + size
    return op


def _count(spec: Spec):
    store = not spec.suppressed

    def op(st: _Scan, pos: int) -> int:
        if store:
            st.param(spec).set_word(pos & 0xFFFF, 0)
        return pos
    return op


class ScanFormat:
    """A compiled scan format: call ``match(text, params, final)``."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.items = parse_scan(text)
        self.ops: list[tuple[object, bool]] = []  # (op, counts as a conversion spec)
        for item in self.items:
            if isinstance(item, str):
                self.ops.append((_literal(item), False))
            elif item.conv == "ws":
                self.ops.append((_whitespace, False))
            elif item.conv == "char":
                self.ops.append((_one_char(item.flags), False))
            elif item.conv in "bdiouxX":
                self.ops.append((_integer(item), True))
            elif item.conv in "eEfgG":
                self.ops.append((_float(item), True))
            elif item.conv == "s":
                self.ops.append((_string(item), True))
            elif item.conv in "cC":
                self.ops.append((_chars(item), True))
            elif item.conv in "SR":
                self.ops.append((_check(item), True))
            elif item.conv == "n":
                self.ops.append((_count(item), True))
            else:  # parse_scan lets no other conversion through
                raise FormatError(item.offset, f"unsupported conversion {item.text!r}")

    def match(self, data: str, params: Sequence[Param] = (), final: bool = False) -> ScanResult:
        """Match ``data`` from its start. Raises ParamError for a missing
        Param or one of the wrong kind."""
        return self.match_counted(data, params, final)[0]

    def match_counted(self, data: str, params: Sequence[Param] = (),
                      final: bool = False) -> tuple[ScanResult, int, int]:
        """``match``, how many Params it took (read or wrote) and, for a
        NEED_MORE, the input length below which it stays NEED_MORE (0 when
        unknown). With no Param taken the result depended on ``data`` and
        ``final`` alone and the match changed nothing, so COMSCAN need not
        repeat it on the same input; nor, while shorter than that length, on
        input that only grew at its end (what the stopped field reads first
        is not there yet, and the fields before it read only the old input)."""
        st = _Scan(data, final, params)
        pos = 0
        specs = 0
        try:
            for op, is_spec in self.ops:
                pos = op(st, pos)
                if is_spec:
                    specs += 1
        except _Stop as stop:
            if stop.need:
                return ScanResult(NEED_MORE, stop.pos, specs), st.k, st.need_len
            return ScanResult(MISMATCH, stop.pos, specs), st.k, 0
        return ScanResult(MATCHED, pos, specs), st.k, 0


@lru_cache(maxsize=4096)
def compile_scan(text: str) -> ScanFormat:
    """The compiled format for ``text`` (parsed once); FormatError if bad."""
    return ScanFormat(text)


def scan_text(fmt: str, data: str, params: Sequence[Param] = (), final: bool = True) -> ScanResult:
    """Match ``data`` against the format string ``fmt`` (tests and docs)."""
    return compile_scan(fmt).match(data, params, final)
