"""Output formatting: a format string and Params -> 16-bit characters.

Shared by STRPRINT and COMPRINT. The manual (4.3.4) restates C's printf and
adds three things: ``%b`` (binary), ``%c``/``%C`` that emit bytes from
consecutive words (little/big endian, ``precision`` bytes), and the checks
``%S`` (sum) and ``%R`` (CRC-16). Where the manual leaves a corner to C,
C99 decides it (the issue lists them; Python's ``%`` operator differs):

- a precision on an integer conversion makes the ``0`` flag ignored;
- ``+`` and space have no effect on the unsigned conversions b o u x X;
- a zero value with precision 0 prints no digits (``%#.0o`` prints ``0``);
- a negative ``*`` width means left-justify with its absolute value, a
  negative ``*`` precision counts as none;
- ``#`` has no effect on b d i u s c; ``%#x`` prefixes 0x only to non-zero
  values; ``%#o`` makes the first digit 0; ``%#g`` keeps trailing zeros.

Integer Params are 16-bit words (``l``/``L``: two words, low word first);
d and i read them signed, b o u x X unsigned. Floats come from F elements,
``s`` from ST elements. The output is characters (a ``str`` of code points
0..0xFFFF); an encoding applies only at a port.

Each format string is parsed once into a ``PrintFormat`` (``compile_print``
caches them): runs of literal text and conversions whose C99 result equals
Python's ``%`` are merged into one Python format string, so a plain format
such as the manual's example 1 costs one ``%`` operation.
"""

from __future__ import annotations

import math
import sys
from functools import lru_cache
from typing import Callable, Sequence

from .checksum import crc16, little_endian, sum16
from .formats import FLOAT_CONVERSIONS, STAR, FormatError, Spec, parse_print
from .params import Param, ParamError

MAX_PARAMS = 6


def _take(params: Sequence[Param], k: int, spec: Spec) -> Param:
    if k >= len(params):
        raise ParamError(f"too few Params: {spec.text} needs Param {k + 1}, "
                         f"but {len(params)} {'was' if len(params) == 1 else 'were'} given")
    return params[k]


def _word_getter(signed: bool, long: bool) -> Callable[[Param], int]:
    if long:
        def get(p: Param) -> int:
            v = (p.word(0) & 0xFFFF) | ((p.word(1) & 0xFFFF) << 16)
            return v - 0x100000000 if signed and v & 0x80000000 else v
    elif signed:
        def get(p: Param) -> int:
            return p.word(0)
    else:
        def get(p: Param) -> int:
            return p.word(0) & 0xFFFF
    return get


def _float_getter(p: Param) -> float:
    return p.float()


def _string_getter(p: Param) -> str:
    return p.string()


def c_integer(value: int, conv: str, flags: str, width: int | None, precision: int | None) -> str:
    """One integer conversion the C99 way (``value`` already signed or
    unsigned as the conversion reads it)."""
    mag = -value if value < 0 else value
    if conv in "diu":
        digits = str(mag)
    elif conv == "o":
        digits = f"{mag:o}"
    elif conv == "x":
        digits = f"{mag:x}"
    elif conv == "X":
        digits = f"{mag:X}"
    else:  # b
        digits = f"{mag:b}"
    if precision is not None:
        digits = "" if precision == 0 and mag == 0 else digits.rjust(precision, "0")
    prefix = ""
    if conv in "di":
        if value < 0:
            prefix = "-"
        elif "+" in flags:
            prefix = "+"
        elif " " in flags:
            prefix = " "
    if "#" in flags:
        if conv == "o" and not digits.startswith("0"):
            digits = "0" + digits
        elif conv in "xX" and mag != 0:
            prefix += "0" + conv
    return _pad(prefix, digits, flags, width, zero_ok=precision is None)


def _pad(prefix: str, body: str, flags: str, width: int | None, zero_ok: bool) -> str:
    size = len(prefix) + len(body)
    if width is None or size >= width:
        return prefix + body
    if "-" in flags:
        return prefix + body + " " * (width - size)
    if "0" in flags and zero_ok:
        return prefix + "0" * (width - size) + body
    return " " * (width - size) + prefix + body


def c_float(value: float, conv: str, flags: str, width: int | None, precision: int | None) -> str:
    """One float conversion: Python's ``%`` follows C here (``#``, ``0``,
    inf and nan included), except that C99 pads an infinity or NaN with
    spaces even under the ``0`` flag (Python pads it with zeros)."""
    if "0" in flags and not math.isfinite(value):
        flags = flags.replace("0", "")
    fmt = "%" + flags + ("" if width is None else str(width)) + ("" if precision is None else f".{precision}") + conv
    return fmt % value


def c_string(text: str, flags: str, width: int | None, precision: int | None) -> str:
    if precision is not None:
        text = text[:precision]
    return _pad("", text, flags.replace("0", ""), width, zero_ok=False)


def c_bytes(p: Param, big_endian: bool, count: int) -> str:
    """``count`` bytes from the Param's words, low byte first (``c``) or
    high byte first (``C``), each as one character 0..255. The words are
    read as one run and turned into bytes in one go (%.250C is a Modbus reply)."""
    words = p.words((count + 1) >> 1)
    if big_endian != (sys.byteorder == "big"):  # array("H") holds the host's order
        words.byteswap()
    return words.tobytes()[:count].decode("latin-1")


def c_low_bytes(p: Param, count: int) -> str:
    """``count`` bytes, the low byte of each of ``count`` words (``%hc``,
    softplc's addition: a byte buffer kept one byte a word, as ladder
    handles bytes most easily)."""
    if count <= 0:
        return ""
    return bytes(w & 0xFF for w in p.words(count)).decode("latin-1")


def _python_compatible(spec: Spec) -> bool:
    """Does Python's ``%`` give the C99 result for this spec, whatever the
    value? Then the spec joins a merged Python format string."""
    c, flags = spec.conv, spec.flags
    if spec.width == STAR or spec.precision == STAR:
        return False
    if c in FLOAT_CONVERSIONS:
        return "0" not in flags  # 0: an infinity or NaN is space padded
    if c == "s":
        return "0" not in flags
    if c in "diuoxX":
        if spec.precision is not None or ("#" in flags and c in "oxX"):
            return False  # precision: 0 flag ignored / no digits for 0; #o #x differ
        if c in "ouxX" and ("+" in flags or " " in flags):
            return False
        return True
    return False


class PrintFormat:
    """A compiled print format: call ``render(params)``."""

    def __init__(self, text: str) -> None:
        self.text = text
        items = parse_print(text)
        self.items = items
        self.params_used = 0
        # ops: str literal, or (python_format, [(param index, getter)]), or a
        # general op callable(out, params) for the rest.
        self.ops: list = []
        k = 0
        chunk: list[str] = []
        getters: list[tuple[int, Callable]] = []

        def flush() -> None:
            if chunk:
                fmt = "".join(chunk)
                self.ops.append((fmt, tuple(getters)) if getters else fmt % ())
                chunk.clear()
                getters.clear()

        for item in items:
            if isinstance(item, str):
                chunk.append(item.replace("%", "%%"))
                continue
            spec = item
            if _python_compatible(spec):
                conv = "d" if spec.conv in "iu" else spec.conv
                chunk.append("%" + spec.flags + ("" if spec.width is None else str(spec.width))
                             + ("" if spec.precision is None else f".{spec.precision}") + conv)
                getters.append((k, self._getter(spec)))
                k += 1
                continue
            flush()
            op, used = self._general(spec, k)
            self.ops.append(op)
            k += used
        flush()
        self.params_used = k

    @staticmethod
    def _getter(spec: Spec) -> Callable[[Param], object]:
        c = spec.conv
        if c in FLOAT_CONVERSIONS:
            return _float_getter
        if c == "s":
            return _string_getter
        return _word_getter(c in "di", spec.long)

    def _general(self, spec: Spec, k: int):
        """An op for a spec Python's ``%`` cannot do: returns (op, params used)."""
        c = spec.conv
        first = k
        star_w, star_p = spec.width == STAR, spec.precision == STAR
        used = int(star_w) + int(star_p) + (0 if c in "%SR" else 1)

        def sizes(params) -> tuple[str, int | None, int | None, int]:
            flags, width, precision, j = spec.flags, spec.width, spec.precision, first
            if star_w:
                width = _take(params, j, spec).word(0)
                j += 1
                if width < 0:
                    # For S and R the width is a start offset, not a field
                    # width: a negative one starts at the beginning.
                    flags, width = (flags, 0) if c in "SR" else (flags + "-", -width)
            if star_p:
                precision = _take(params, j, spec).word(0)
                j += 1
                if precision < 0:
                    precision = None
            return flags, width, precision, j

        if c in "SR":
            def check(out: list, params) -> None:
                flags, width, precision, _ = sizes(params)
                done = "".join(out)
                start = width or 0
                end = len(done) - (1 if precision is None else precision) + 1
                chars = done[start:end] if end > start else ""
                if c == "R":
                    out.append(little_endian(crc16(chars, 0xFFFF if "#" in flags else 0)))
                else:
                    one = spec.length in ("h", "H")
                    out.append(little_endian(sum16(chars, "#" in flags, one), 1 if one else 2))
            return check, used

        if c == "%":
            def percent(out: list, params) -> None:
                flags, width, _, _ = sizes(params)
                out.append(_pad("", "%", flags, width, zero_ok=False))
            return percent, used

        getter = self._getter(spec) if c not in "cC" else None
        one_a_word = spec.byte_per_word

        def convert(out: list, params) -> None:
            flags, width, precision, j = sizes(params)
            p = _take(params, j, spec)
            if c in "cC":
                count = 1 if precision is None else precision
                data = c_low_bytes(p, count) if one_a_word else c_bytes(p, c == "C", count)
                out.append(_pad("", data, flags.replace("0", ""), width, zero_ok=False))
            elif c in FLOAT_CONVERSIONS:
                out.append(c_float(getter(p), c, flags, width, precision))
            elif c == "s":
                out.append(c_string(getter(p), flags, width, precision))
            else:
                out.append(c_integer(getter(p), c, flags, width, precision))
        return convert, used

    def render(self, params: Sequence[Param], limit: int | None = None) -> str:
        """The output characters. Raises ParamError (too few Params, a Param
        of the wrong kind, words past the end of a file). With ``limit``
        (the size of what the output goes to), rendering stops once the
        output is longer: the result is then ``limit + 1`` characters, enough
        to tell it does not fit, and no conversion after that is built."""
        if limit is not None and len(params) < self.params_used:
            self.render(params)  # too few Params: the same ParamError as without a limit
        out: list[str] = []
        append = out.append
        size, counted = 0, 0
        for op in self.ops:
            if limit is not None:
                while counted < len(out):
                    size += len(out[counted])
                    counted += 1
                if size > limit:
                    return "".join(out)[:limit + 1]
            if op.__class__ is str:
                append(op)
            elif op.__class__ is tuple:
                fmt, getters = op
                try:
                    append(fmt % tuple([get(params[k]) for k, get in getters]))
                except IndexError:
                    k = next(k for k, _ in getters if k >= len(params))
                    spec = [s for s in self.items if isinstance(s, Spec)]
                    raise ParamError(f"too few Params: the format needs Param {k + 1}, "
                                     f"but {len(params)} {'was' if len(params) == 1 else 'were'} given "
                                     f"({' '.join(s.text for s in spec)})") from None
            else:
                op(out, params)
        text = "".join(out)
        return text if limit is None else text[:limit + 1]


@lru_cache(maxsize=4096)
def compile_print(text: str) -> PrintFormat:
    """The compiled format for ``text`` (parsed once); FormatError if bad."""
    return PrintFormat(text)


def format_text(text: str, params: Sequence[Param]) -> str:
    """Format ``params`` with the format string ``text`` (for tests and docs)."""
    return compile_print(text).render(params)


__all__ = ["MAX_PARAMS", "FormatError", "PrintFormat", "c_float", "c_integer", "compile_print", "format_text"]
