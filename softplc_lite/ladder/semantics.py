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
from ..datatable.filetypes import ITEM_BITS, LONG_MAX, LONG_MIN
from ..datatable.table import STRING_CHARS, read_string
from . import status as S
from .rounding import round_half_even

# Word-0 bit masks (signed 16-bit, see datatable.bit_mask).
EN, TT, DN = -32768, 1 << 14, 1 << 13  # timer
CU, CD, OV, UN = -32768, 1 << 14, 1 << 12, 1 << 11  # counter (DN shared)
R_EN, R_EU, R_DN, R_EM, R_ER, R_UL, R_IN, R_FD = -32768, 1 << 14, 1 << 13, 1 << 12, 1 << 11, 1 << 10, 1 << 9, 1 << 8
# A timer keeps the clock time of its last update, in ms modulo 8192, in
# bits 0..12 of word 0 (EN/TT/DN are 15/14/13), as SLC 500 timers keep a copy
# of a hardware clock in that word (1747-UM010, timer instructions). The
# stamp trails the clock by the milliseconds short of a tick, so it carries
# them to the next update.
STAMP = 0x1FFF
STAMP_MODULO = STAMP + 1


def signed32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - 0x100000000 if v & 0x80000000 else v


def signed16(v: int) -> int:
    v &= 0xFFFF
    return v - 0x10000 if v & 0x8000 else v


def signed8(v: int) -> int:
    v &= 0xFF
    return v - 0x100 if v & 0x80 else v


def signed64(v: int) -> int:
    v &= 0xFFFFFFFFFFFFFFFF
    return v - 0x10000000000000000 if v & 0x8000000000000000 else v


# An integer item's range and wrap by its array's itemsize: an SI (1), a
# word (2), an L (4) or an LI (8) element, the same rules at each width.
INT_ITEMS = {1: (-128, 127, signed8), 2: (-32768, 32767, signed16), 4: (LONG_MIN, LONG_MAX, signed32),
             8: (-(2 ** 63), 2 ** 63 - 1, signed64)}


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
        self.now_ms = 0  # the engine's clock at this scan (timers measure from it)
        self.file = 0  # program file and rung being scanned (for faults)
        self.rung = 0
        self.clamp = self.settings.overflow == "clamp"

    # -- status file --------------------------------------------------------------
    def flags(self, carry: bool, overflow: bool, zero: bool, sign: bool) -> None:
        s = self.s
        s[0] = (s[0] & ~0xF) | carry | (overflow << 1) | (zero << 2) | (sign << 3)

    def minor(self, bit: int, code: int, word: int = S.MINOR_FAULT_BITS) -> None:
        s = self.s
        s[word] |= 1 << bit if bit < 15 else -32768
        s[S.MINOR_FAULT_CODE] = code
        s[S.MINOR_FAULT_FILE] = self.file
        s[S.MINOR_FAULT_RUNG] = self.rung

    def overflow_fault(self) -> None:
        """Math overflow: PLC-5's minor fault bit S:10/14 and code 1 in S:102."""
        self.minor(S.MINOR_OVERFLOW_BIT, S.MINOR_CODE_OVERFLOW, S.PLC5_MINOR_FAULT_BITS)

    # -- storing numbers ------------------------------------------------------------
    def store(self, value: int | float, d: array, i: int, carry: bool = False) -> None:
        """Store a math result the PLC-5 way: float destinations take float32;
        integer destinations round floats to the nearest integer, a half to
        the even one (rounding.round_half_even), and out of range values set
        overflow (S:0/1, minor fault) and are clamped or wrapped per the app
        setting. Sets S:0 carry/overflow/zero/sign."""
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
                self.overflow_fault()
                over = True
            self.flags(False, over, stored == 0, stored < 0)
            return
        over = False
        # A 16-bit word, or a 32-bit L element (1747-RM001/1763-RM001 L file
        # range), an 8-bit SI or a 64-bit LI one (Logix SINT, LINT: 1756-RM003).
        # (Plain assignments for a word, not a lookup: store() runs for most math.)
        if d.itemsize == 2:
            lo, hi, wrap = -32768, 32767, signed16
        else:
            lo, hi, wrap = INT_ITEMS[d.itemsize]
        if isinstance(value, float):
            if math.isnan(value):
                value, over = 0, True
            elif math.isinf(value):
                # No low bits to keep: the extreme of its sign whatever the overflow setting.
                value, over = (hi if value > 0 else lo), True
            else:
                value = round_half_even(value)
        if not lo <= value <= hi:
            over = True
            value = (hi if value > 0 else lo) if self.clamp else wrap(value)
        if over:
            self.overflow_fault()
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
            mask = 0xFFFF if d.itemsize == 2 else (1 << 8 * d.itemsize) - 1  # the carry out of the item's top bit
            carry = (a & mask) + (b & mask) > mask
        self.store(a + b, d, i, carry)

    def sub(self, a, b, d: array, i: int) -> None:
        carry = False
        if isinstance(a, int) and isinstance(b, int):
            mask = 0xFFFF if d.itemsize == 2 else (1 << 8 * d.itemsize) - 1
            carry = (a & mask) < (b & mask)  # borrow
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

    def divide_truncated(self, a, b):
        """Logix division of integers: the quotient truncated toward zero
        (1756-RM003, "Divide (DIV)"); a float operand divides as ``/``."""
        if b == 0:
            return self.div_zero(a)
        if isinstance(a, int) and isinstance(b, int):
            q = abs(a) // abs(b)
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

    def neg(self, v, d: array, i: int) -> None:
        """NEG: dest = -source. Carry is set unless the source is 0 or the
        result overflows (-(-32768)), as SLC 500 / MicroLogix NEG say."""
        lowest = INT_ITEMS[d.itemsize][0] if d.typecode != "f" else None
        carry = isinstance(v, int) and v != 0 and v != lowest
        self.store(-v, d, i, carry)

    def sqr(self, v, d: array, i: int) -> None:
        self.store(math.sqrt(abs(v)), d, i)

    def logic(self, value: int, d: array, i: int) -> None:
        """Bitwise results: as wide as the destination (16 bits, 32 in an L
        file), never overflow: bits above the destination are dropped.
        (signed16 and flags written out: a ladder CRC loop runs this for
        every byte.)"""
        if d.itemsize == 2:
            value &= 0xFFFF
            if value > 0x7FFF:
                value -= 0x10000
        else:
            value = INT_ITEMS[d.itemsize][2](value)
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

    def _stamp(self, w: int) -> int:
        """Word 0 with the stamp set to now: nothing counted yet from here."""
        return (w & ~STAMP) | (self.now_ms & STAMP)

    def _accumulate(self, d: array, i: int, w: int, base_ms: int) -> int:
        """Add the time since this timer's own last update to ACC (not the
        scan's: a timer evaluated twice in a scan adds nothing the second
        time, one skipped for a scan adds both); returns word 0 with the new
        stamp. Time more than 8192 ms old is lost (STAMP_MODULO)."""
        elapsed = (self.now_ms - (w & STAMP)) % STAMP_MODULO
        ticks, rest = divmod(elapsed, base_ms)
        acc = d[i + 2] + ticks
        pre = d[i + 1]
        if acc >= pre:
            acc, rest = pre if d[i + 2] <= pre else d[i + 2], 0
        d[i + 2] = acc
        return (w & ~STAMP) | ((self.now_ms - rest) & STAMP)

    def ton(self, d: array, i: int, c: bool, base_ms: int) -> None:
        # _check_timer, _accumulate and _stamp written out: one call per TON
        # (a quarter of a mixed program's scan was these calls).
        pre = d[i + 1]
        acc = d[i + 2]
        if pre < 0 or acc < 0:
            self._check_timer(d, i)
        w = d[i]
        if c:
            now = self.now_ms
            # DN is ACC >= PRE, evaluated each scan: a done timer whose preset is
            # raised times on again (it does not test its own DN bit).
            if w & EN and acc < pre:
                ticks, rest = divmod((now - (w & STAMP)) % STAMP_MODULO, base_ms)
                acc += ticks
                if acc >= pre:
                    acc, rest = pre, 0
                d[i + 2] = acc
                w = (w & ~STAMP) | ((now - rest) & STAMP) | EN
            else:
                # The evaluation that enables the timer starts it: time counts from here.
                w = (w & ~STAMP) | (now & STAMP) | EN
            if acc >= pre:
                w = (((w | DN) & ~STAMP) | (now & STAMP)) & ~TT
            else:
                w = (w | TT) & ~DN
        else:
            w &= ~(EN | TT | DN | STAMP)
            if acc:
                d[i + 2] = 0
        d[i] = w

    def tof(self, d: array, i: int, c: bool, base_ms: int) -> None:
        self._check_timer(d, i)
        w = d[i]
        if c:
            w = self._stamp(w | EN | DN) & ~TT
            d[i + 2] = 0
        else:
            if w & DN:
                # The first false evaluation starts the delay; time counts from it.
                w = self._accumulate(d, i, w, base_ms) if w & TT else self._stamp(w)
                w = (w | TT) & ~EN
                if d[i + 2] >= d[i + 1]:
                    w &= ~(DN | TT | STAMP)
            else:
                w &= ~(EN | TT)
        d[i] = w

    def rto(self, d: array, i: int, c: bool, base_ms: int) -> None:
        self._check_timer(d, i)
        w = d[i]
        if c:
            if w & EN and d[i + 2] < d[i + 1]:
                w = self._accumulate(d, i, w, base_ms)
            elif not w & EN:
                # Timing resumes: the bits hold the part of a tick counted before the pause.
                w = (w & ~STAMP) | ((self.now_ms - (w & STAMP)) & STAMP)
            else:
                w = self._stamp(w)
            w |= EN
            if d[i + 2] >= d[i + 1]:
                w = self._stamp(w | DN) & ~TT
            else:
                w = (w | TT) & ~DN
        else:
            if w & EN:
                # Paused: keep the milliseconds short of a tick, counted up to the
                # previous scan (this one's time is not timed), for when it resumes.
                rest = (self.now_ms - self.dt - (w & STAMP)) % STAMP_MODULO
                w = (w & ~STAMP) | (rest if rest < base_ms else 0)
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
        # F or L <-> word file: COP copies memory without conversion. n counts
        # destination units; the source gives the same number of bytes (a float
        # or a long is two words, low word first). An F <-> L copy is 1:1.
        nbytes = n * dd.itemsize
        m = -(-nbytes // sd.itemsize)
        if si + m > len(sd):
            raise MajorFault(S.FAULT_BLOCK_RANGE, f"{m} source elements from index {si} run past the end "
                             f"of the file ({len(sd)})")
        dd[di:di + n] = array(dd.typecode, sd[si:si + m].tobytes()[:nbytes])

    def fll(self, value, dd: array, di: int, n: int) -> None:
        if dd.typecode == "f":
            dd[di:di + n] = array("f", [float(value)]) * n
        elif dd.itemsize != 2:  # an L, SI or LI file: its range, the same rules as words
            lo, hi, wrap = INT_ITEMS[dd.itemsize]
            if isinstance(value, float):
                if math.isnan(value):
                    value = 0
                elif math.isinf(value):
                    value = hi if value > 0 else lo
                else:
                    value = round_half_even(value)
            value = max(lo, min(hi, value)) if self.clamp else wrap(value)
            dd[di:di + n] = array(dd.typecode, [value]) * n
        else:
            if isinstance(value, float):
                if math.isnan(value):
                    value = 0  # no integer value (as store())
                elif math.isinf(value):
                    value = 32767 if value > 0 else -32768
                else:
                    value = round_half_even(value)
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
        """String to integer, as SLC 500 ACI: skip to the first digit; a + or -
        right before it gives the sign; digits and commas (ignored) follow up
        to the first other character. No digit: nothing is stored (the string
        error). Out of range of a word: overflow, 32767 (-32768 below) and
        the string error, whatever the overflow setting."""
        text = read_string(sd, si)
        first = next((k for k, ch in enumerate(text) if "0" <= ch <= "9"), None)
        if first is None:
            self._string_error()
            return
        end = first
        while end < len(text) and ("0" <= text[end] <= "9" or text[end] == ","):
            end += 1
        value = int(text[first:end].replace(",", ""))
        if first > 0 and text[first - 1] == "-":
            value = -value
        if d.typecode != "f" and not -32768 <= value <= 32767:
            self._string_error()
            self.overflow_fault()
            d[di] = value = 32767 if value > 0 else -32768
            self.flags(False, True, False, value < 0)
            return
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

    def asc(self, qd: array, qi: int, index: int, sd: array, si: int, d: array, di: int) -> None:
        """String search, AB operand order: look for the source string ``q``
        in the String Search string ``s`` from 1-based ``index``; result is the
        1-based position, or 0 when it is not there. An empty source, or an
        index below 1 or past the end of ``s``: the string error, result
        unchanged."""
        wanted, text = read_string(qd, qi), read_string(sd, si)
        if not wanted or index < 1 or index > len(text):
            self._string_error()
            return
        d[di] = text.find(wanted, index - 1) + 1

    def asr(self, ad: array, ai: int, bd: array, bi: int) -> bool:
        return read_string(ad, ai) == read_string(bd, bi)


def source_units(count: int, src_ftype, dest_ftype) -> int:
    """COP between a float file and a word file copies memory: the number
    of source array units holding as many bytes as ``count`` destination units."""
    sb, db = (ITEM_BITS[f.storage] // 8 for f in (src_ftype, dest_ftype))
    return count if sb == db else -(-count * db // sb)


def lim(low, test, high) -> bool:
    """LIM: inside [low, high], or outside (high, low) when low > high."""
    if low <= high:
        return low <= test <= high
    return test >= low or test <= high


BASE_MS = {1.0: 1000, 0.01: 10, 0.001: 1}  # 0.001: MicroLogix 1100's 1 ms time base
