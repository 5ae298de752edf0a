"""Instruction semantics shared by the compiled path and the reference
interpreter: the run-time machine (status file, settings, elapsed time,
faults) and the kernels of instructions with more than a line of logic
(timers, counters, math stores with PLC flags, strings, file moves).

Both executors call these kernels with ``(array, index)`` pairs; they differ
in how they find those pairs (bound once vs resolved every time) and in how
they evaluate rungs, branches, contacts and control flow. docs/instructions.md
says which AB manual each rule follows.
"""

from __future__ import annotations

import math
from array import array
from dataclasses import dataclass

from ..datatable import DataTable
from ..datatable.filetypes import Storage
from ..datatable.table import STRING_CHARS, read_string
from . import status as S

# Word-0 bit masks (signed 16-bit, see datatable.bit_mask).
EN, TT, DN = -32768, 1 << 14, 1 << 13  # timer
CU, CD, OV, UN = -32768, 1 << 14, 1 << 12, 1 << 11  # counter (DN shared)
R_EN, R_EU, R_DN, R_EM, R_ER, R_UL, R_IN, R_FD = -32768, 1 << 14, 1 << 13, 1 << 12, 1 << 11, 1 << 10, 1 << 9, 1 << 8
# Timers keep the milliseconds not yet counted (less than one time-base tick)
# in bits 0..9 of word 0, as PLC-5 timers keep internal state in that word.
FRACTION = 0x3FF


def signed16(v: int) -> int:
    v &= 0xFFFF
    return v - 0x10000 if v & 0x8000 else v


# The deepest JSR nesting a jsr_depth setting may ask for: deep enough for any
# real program, shallow enough that the engine reaches fault 30 long before
# Python's recursion limit (tests/test_hardening.py runs it at this depth).
MAX_JSR_DEPTH = 64


@dataclass
class Settings:
    """App settings (``softplc.toml``), with PLC-5 defaults."""

    overflow: str = "clamp"  # "clamp" (PLC-5) or "wrap" (keep the low 16 bits, SLC 500 style)
    divide_by_zero: str = "overflow"  # "overflow" (minor fault, result clamped) or "fault" (major)
    watchdog_ms: int = S.DEFAULT_WATCHDOG_MS
    scan_ms: int = 10  # simulated time per scan
    jsr_depth: int = 32
    save_ms: int = 100  # [retentive] save_ms: wall-clock ms between retentive snapshot saves


class MajorFault(Exception):
    """A run-time error that faults the processor. The engine records code,
    file, rung and instruction in the status file and says it in words."""

    def __init__(self, code: int, message: str) -> None:
        self.code = code
        self.message = message
        self.file: int | None = None
        self.rung: int | None = None
        self.instruction: str | None = None
        super().__init__(message)

    def __str__(self) -> str:
        where = ""
        if self.file is not None:
            where = f"program file {self.file}, rung {self.rung}"
            if self.instruction:
                where += f", {self.instruction}"
            where += ": "
        return f"major fault {self.code}: {where}{self.message}"


class Machine:
    """What instructions see at run time besides their operands."""

    def __init__(self, table: DataTable, settings: Settings | None = None) -> None:
        self.table = table
        self.settings = settings or Settings()
        table.reference("S:127")
        self.s = table.file("S2").data
        self.dt = 0  # milliseconds since the previous scan
        self.file = 0  # program file and rung being scanned (for faults)
        self.rung = 0
        self.clamp = self.settings.overflow == "clamp"

    # -- status file --------------------------------------------------------------
    def flags(self, carry: bool, overflow: bool, zero: bool, sign: bool) -> None:
        s = self.s
        s[0] = (s[0] & ~0xF) | carry | (overflow << 1) | (zero << 2) | (sign << 3)

    def minor(self, bit: int, code: int) -> None:
        s = self.s
        s[S.MINOR_FAULT_BITS] |= 1 << bit
        s[S.MINOR_FAULT_CODE] = code
        s[S.MINOR_FAULT_FILE] = self.file
        s[S.MINOR_FAULT_RUNG] = self.rung

    # -- storing numbers ------------------------------------------------------------
    def store(self, value: int | float, d: array, i: int, carry: bool = False) -> None:
        """Store a math result the PLC-5 way: float destinations take float32;
        integer destinations round floats (half away from zero), and out of
        range values set overflow (S:0/1, minor fault) and are clamped or
        wrapped per the app setting. Sets S:0 carry/overflow/zero/sign."""
        if d.typecode == "f":
            v = float(value)
            over = False
            if math.isfinite(v) and abs(v) > 3.4028234663852886e38:
                v = math.copysign(math.inf, v)
                over = True
            d[i] = v
            stored = d[i]
            # A result that is not a finite float32 (too large, division by zero, NaN) is an overflow.
            if over or not math.isfinite(stored):
                self.minor(S.MINOR_OVERFLOW_BIT, S.MINOR_CODE_OVERFLOW)
                over = True
            self.flags(False, over, stored == 0, stored < 0)
            return
        over = False
        if isinstance(value, float):
            if math.isnan(value):
                value, over = 0, True
            elif math.isinf(value):
                # No low 16 bits to keep: the extreme of its sign whatever the overflow setting.
                value, over = (32767 if value > 0 else -32768), True
            else:
                value = int(math.floor(abs(value) + 0.5)) * (1 if value >= 0 else -1)
        if not -32768 <= value <= 32767:
            over = True
            value = (32767 if value > 0 else -32768) if self.clamp else signed16(value)
        if over:
            self.minor(S.MINOR_OVERFLOW_BIT, S.MINOR_CODE_OVERFLOW)
        d[i] = value
        self.flags(carry, over, value == 0, value < 0)

    # -- word fast paths (compiled code only) ---------------------------------------------
    # The compiler calls these when it can prove at load time that every
    # operand and the destination are 16-bit words: no float cases to test.
    # Out of range, they hand over to the general kernel, so the result and
    # the flags are those of store(); the differential test holds them to it.
    def store_word(self, v: int, d: array, i: int) -> None:
        if -32768 <= v <= 32767:
            d[i] = v
            s = self.s
            s[0] = (s[0] & -16) | ((v == 0) << 2) | ((v < 0) << 3)
        else:
            self.store(v, d, i)

    def add_words(self, a: int, b: int, d: array, i: int) -> None:
        v = a + b
        if -32768 <= v <= 32767:
            d[i] = v
            s = self.s
            s[0] = (s[0] & -16) | ((a & 0xFFFF) + (b & 0xFFFF) > 0xFFFF) | ((v == 0) << 2) | ((v < 0) << 3)
        else:
            self.add(a, b, d, i)

    def sub_words(self, a: int, b: int, d: array, i: int) -> None:
        v = a - b
        if -32768 <= v <= 32767:
            d[i] = v
            s = self.s
            s[0] = (s[0] & -16) | ((a & 0xFFFF) < (b & 0xFFFF)) | ((v == 0) << 2) | ((v < 0) << 3)
        else:
            self.sub(a, b, d, i)

    def div_zero(self, a: int | float) -> int | float:
        """Division by zero: a major fault, or overflow with the largest result."""
        if self.settings.divide_by_zero == "fault":
            raise MajorFault(S.FAULT_DIV_ZERO, "division by zero")
        self.minor(S.MINOR_DIV_ZERO_BIT, S.MINOR_CODE_DIV_ZERO)
        # Infinity with the dividend's sign: store() sets overflow and stores
        # 32767/-32768 (in both overflow modes) or +-inf in a float.
        return math.copysign(math.inf, a) if a != 0 else math.inf

    # -- math kernels -----------------------------------------------------------------------
    def add(self, a, b, d: array, i: int) -> None:
        carry = False
        if isinstance(a, int) and isinstance(b, int):
            carry = (a & 0xFFFF) + (b & 0xFFFF) > 0xFFFF
        self.store(a + b, d, i, carry)

    def sub(self, a, b, d: array, i: int) -> None:
        carry = False
        if isinstance(a, int) and isinstance(b, int):
            carry = (a & 0xFFFF) < (b & 0xFFFF)  # borrow
        self.store(a - b, d, i, carry)

    def div(self, a, b, d: array, i: int) -> None:
        self.store(self.divide(a, b), d, i)

    def divide(self, a, b):
        """PLC-5 division: integer operands give a rounded result."""
        if b == 0:
            return self.div_zero(a)
        if isinstance(a, int) and isinstance(b, int):
            q = abs(a) * 2 + abs(b)
            q //= 2 * abs(b)
            return q if (a >= 0) == (b >= 0) else -q
        return a / b

    def mod(self, a, b, d: array, i: int) -> None:
        self.store(self.modulo(a, b), d, i)

    def modulo(self, a, b):
        """Remainder with the sign of the dividend (C-style, as AB MOD)."""
        if b == 0:
            return self.div_zero(a)
        if isinstance(a, int) and isinstance(b, int):
            r = abs(a) % abs(b)
            return r if a >= 0 else -r
        try:
            return math.fmod(a, b)
        except ValueError:  # fmod(inf, b): no remainder
            return math.nan

    def sqr(self, v, d: array, i: int) -> None:
        self.store(math.sqrt(abs(v)), d, i)

    def logic(self, value: int, d: array, i: int) -> None:
        """Bitwise results: always 16 bits, never overflow. (signed16 and
        flags written out: a ladder CRC loop runs this for every byte.)"""
        value &= 0xFFFF
        if value > 0x7FFF:
            value -= 0x10000
        d[i] = value
        s = self.s
        s[0] = (s[0] & -16) | ((value == 0) << 2) | ((value < 0) << 3)

    def clear(self, d: array, i: int) -> None:
        d[i] = 0
        s = self.s
        s[0] = (s[0] & -16) | 4  # Z

    def power(self, a, b):
        try:
            r = float(a) ** float(b)
        except (OverflowError, ZeroDivisionError):
            return math.inf
        except ValueError:
            return math.nan
        # a negative base with a fractional exponent has no real result (Python gives a complex)
        return r if isinstance(r, float) else math.nan

    # -- timers and counters ------------------------------------------------------------------
    def _check_timer(self, d: array, i: int) -> None:
        if d[i + 1] < 0 or d[i + 2] < 0:
            raise MajorFault(S.FAULT_NEGATIVE_TIMER,
                             f"negative timer preset or accumulator (PRE={d[i + 1]}, ACC={d[i + 2]})")

    def _accumulate(self, d: array, i: int, w: int, base_ms: int) -> int:
        """Add this scan's time to ACC; returns word 0 with the new fraction."""
        total = (w & FRACTION) + self.dt
        ticks, rest = divmod(total, base_ms)
        acc = d[i + 2] + ticks
        pre = d[i + 1]
        if acc >= pre:
            acc, rest = pre if d[i + 2] <= pre else d[i + 2], 0
        d[i + 2] = acc
        return (w & ~FRACTION) | rest

    def ton(self, d: array, i: int, c: bool, base_ms: int) -> None:
        self._check_timer(d, i)
        w = d[i]
        if c:
            # DN is ACC >= PRE, evaluated each scan: a done timer whose preset is
            # raised times on again (it does not test its own DN bit).
            if w & EN and d[i + 2] < d[i + 1]:
                w = self._accumulate(d, i, w, base_ms)
            # The scan the rung goes true starts the timer; time counts from the next one.
            w |= EN
            if d[i + 2] >= d[i + 1]:
                w = (w | DN) & ~TT & ~FRACTION
            else:
                w = (w | TT) & ~DN
        else:
            w &= ~(EN | TT | DN | FRACTION)
            d[i + 2] = 0
        d[i] = w

    def tof(self, d: array, i: int, c: bool, base_ms: int) -> None:
        self._check_timer(d, i)
        w = d[i]
        if c:
            w = (w | EN | DN) & ~TT & ~FRACTION
            d[i + 2] = 0
        else:
            if w & DN:
                if w & TT:
                    w = self._accumulate(d, i, w, base_ms)
                w = (w | TT) & ~EN
                if d[i + 2] >= d[i + 1]:
                    w &= ~(DN | TT | FRACTION)
            else:
                w &= ~(EN | TT)
        d[i] = w

    def rto(self, d: array, i: int, c: bool, base_ms: int) -> None:
        self._check_timer(d, i)
        w = d[i]
        if c:
            if w & EN and d[i + 2] < d[i + 1]:
                w = self._accumulate(d, i, w, base_ms)
            w |= EN
            if d[i + 2] >= d[i + 1]:
                w = (w | DN) & ~TT & ~FRACTION
            else:
                w = (w | TT) & ~DN
        else:
            w &= ~(EN | TT)  # ACC and DN are retained until RES
        d[i] = w

    def ctu(self, d: array, i: int, c: bool) -> None:
        w = d[i]
        if c and not w & CU:
            acc = d[i + 2] + 1
            if acc > 32767:
                acc = -32768
                w = (w | OV) if not w & UN else (w & ~UN)
            d[i + 2] = acc
        w = (w | CU) if c else (w & ~CU)
        d[i] = (w | DN) if d[i + 2] >= d[i + 1] else (w & ~DN)

    def ctd(self, d: array, i: int, c: bool) -> None:
        w = d[i]
        if c and not w & CD:
            acc = d[i + 2] - 1
            if acc < -32768:
                acc = 32767
                w = (w | UN) if not w & OV else (w & ~OV)
            d[i + 2] = acc
        w = (w | CD) if c else (w & ~CD)
        d[i] = (w | DN) if d[i + 2] >= d[i + 1] else (w & ~DN)

    def res(self, d: array, i: int) -> None:
        """RES: timers and counters clear ACC and their status bits; a
        control clears POS and its status bits (LEN stays)."""
        d[i] = 0
        d[i + 2] = 0

    # -- files ------------------------------------------------------------------------------
    def cop(self, sd: array, si: int, dd: array, di: int, n: int) -> None:
        # Overlapping copies behave like memmove, as on the PLC (source first read whole).
        if sd.typecode == dd.typecode:
            dd[di:di + n] = sd[si:si + n]
            return
        # F <-> word file: PLC-5 COP copies memory without conversion. n counts
        # destination units; the source gives the same number of bytes (a float
        # is two words, low word first).
        nbytes = n * dd.itemsize
        m = -(-nbytes // sd.itemsize)
        if si + m > len(sd):
            raise MajorFault(S.FAULT_BLOCK_RANGE, f"{m} source elements from index {si} run past the end "
                             f"of the file ({len(sd)})")
        dd[di:di + n] = array(dd.typecode, sd[si:si + m].tobytes()[:nbytes])

    def fll(self, value, dd: array, di: int, n: int) -> None:
        if dd.typecode == "f":
            dd[di:di + n] = array("f", [float(value)]) * n
        else:
            if isinstance(value, float):
                if math.isnan(value):
                    value = 0  # no integer value (as store())
                elif math.isinf(value):
                    value = 32767 if value > 0 else -32768
                else:
                    value = int(math.floor(abs(value) + 0.5)) * (1 if value >= 0 else -1)
            value = max(-32768, min(32767, value)) if self.clamp else signed16(value)
            dd[di:di + n] = array("h", [value]) * n

    def btd(self, src: int, sbit: int, d: array, i: int, dbit: int, length: int) -> None:
        length = min(length, 16 - sbit, 16 - dbit)
        mask = (1 << length) - 1
        field = (src >> sbit) & mask
        d[i] = signed16((d[i] & ~(mask << dbit)) | (field << dbit))

    # -- strings (ST elements: LEN word then 82 code units) ------------------------------------------
    def _string_error(self) -> None:
        self.minor(S.MINOR_STRING_BIT, S.MINOR_CODE_STRING)

    def _put_string(self, text: str, d: array, i: int) -> None:
        if len(text) > STRING_CHARS:
            self._string_error()
            text = text[:STRING_CHARS]
        units = [ord(c) for c in text] + [0] * (STRING_CHARS - len(text))
        d[i] = len(text)
        d[i + 1:i + 1 + STRING_CHARS] = array("h", [signed16(u) for u in units])

    def aci(self, sd: array, si: int, d: array, di: int) -> None:
        """String to integer: leading spaces, optional sign, digits."""
        text = read_string(sd, si).lstrip(" ")
        digits = ""
        for k, ch in enumerate(text):
            if ch.isdigit() and ch.isascii() or (k == 0 and ch in "+-"):
                digits += ch
            else:
                break
        if digits in ("", "+", "-"):
            self._string_error()
            value = 0
        else:
            value = int(digits)
        self.store(value, d, di)

    def aic(self, value: int, d: array, i: int) -> None:
        self._put_string(str(value), d, i)

    def acn(self, ad: array, ai: int, bd: array, bi: int, d: array, di: int) -> None:
        self._put_string(read_string(ad, ai) + read_string(bd, bi), d, di)

    def aex(self, sd: array, si: int, index: int, count: int, d: array, di: int) -> None:
        """Extract ``count`` characters starting at 1-based ``index``."""
        text = read_string(sd, si)
        if index < 1 or count < 0 or index + count - 1 > len(text):
            self._string_error()
            return
        self._put_string(text[index - 1:index - 1 + count], d, di)

    def asc(self, sd: array, si: int, index: int, qd: array, qi: int, d: array, di: int) -> None:
        """Search for a string from 1-based ``index``; result is the 1-based
        position, or 0 (with the string minor fault) when not found."""
        text = read_string(sd, si)
        if index < 1 or index > max(len(text), 1):
            self._string_error()
            d[di] = 0
            return
        found = text.find(read_string(qd, qi), index - 1)
        if found < 0:
            self._string_error()
            d[di] = 0
        else:
            d[di] = found + 1

    def asr(self, ad: array, ai: int, bd: array, bi: int) -> bool:
        return read_string(ad, ai) == read_string(bd, bi)


def source_units(count: int, src_ftype, dest_ftype) -> int:
    """COP between a float file and a word file copies memory: the number
    of source array units holding as many bytes as ``count`` destination units."""
    sb, db = (4 if f.storage is Storage.FLOAT else 2 for f in (src_ftype, dest_ftype))
    return count if sb == db else -(-count * db // sb)


def lim(low, test, high) -> bool:
    """LIM: inside [low, high], or outside (high, low) when low > high."""
    if low <= high:
        return low <= test <= high
    return test >= low or test <= high


BASE_MS = {1.0: 1000, 0.01: 10, 0.001: 1}  # 0.001: MicroLogix 1100's 1 ms time base
