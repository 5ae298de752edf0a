"""PID: the PLC-5 PID instruction with its integer control block.

``PID block pv tieback cv``: a 23-word control block in a word file (N),
the process variable (0..4095), the tieback (0..4095, or 0: the output of a
hand/auto station, used in manual mode) and the control output (0..4095).
docs/instructions.md ("## PID") has the word table, the equations and the
AB section each rule comes from; the ones we chose are marked there.

The PID works in counts: error, integral, bias and output are all in the
0..4095 range of a 12-bit analog module. With setpoint scaling (word 0
bit 5) the setpoint and dead band are in engineering units (Smin..Smax)
and are turned into counts; words 14 and 15 show the PV and the error in
those units. The block keeps what the PID remembers between updates in its
internal words 17..22 (the integral, the last derivative input, the last
error's sign and the clock time of the last update), so a snapshot or a
retentive save carries the loop's state with the rest of the data table.
"""

from __future__ import annotations

import math
import struct
from array import array

from ..bound import BoundInstruction, block, file_references
from ..rounding import round_half_even
from ..specs import K, _spec

BLOCK_WORDS = 23
FULL_SCALE = 4095  # counts: PV, tieback, bias, output (12-bit analog)

# Word 0: the control bits the program sets ...
PE = 1 << 0  # equation: 0 independent gains, 1 ISA (dependent) gains
MO = 1 << 1  # mode: 0 automatic, 1 manual (output follows the tieback)
CA = 1 << 2  # control action: 0 E = SP - PV, 1 E = PV - SP
OL = 1 << 3  # output limiting to words 11/12
SWM = 1 << 4  # set output: the output is word 10 (% of 4095)
SC = 1 << 5  # setpoint scaling: SP and DB in Smin..Smax units
DO = 1 << 6  # derivative of: 0 PV, 1 error
TM = 1 << 12  # softplc (a bit PLC-5 reserves): timed, the PID updates itself every word 13
# ... and the status bits the instruction sets.
EWD = 1 << 8  # error within dead band
OLH = 1 << 9  # output alarm, upper limit
OLL = 1 << 10  # output alarm, lower limit
SPOR = 1 << 11  # setpoint out of range
DN = 1 << 13  # the loop was computed on this scan
EN = -32768  # bit 15: follows the rung
_STATUS = EWD | OLH | OLL | SPOR

# Word offsets in the block.
SP, GAIN_P, GAIN_I, GAIN_D, BIAS, SMAX, SMIN, DEADBAND = 2, 3, 4, 5, 6, 7, 8, 9
SETOUT, LMAX, LMIN, UPDATE, SCALED_PV, SCALED_ERR, OUT_PCT = 10, 11, 12, 13, 14, 15, 16
INTEGRAL, PREV_INPUT, STATE = 17, 19, 21  # internal: float32, float32, uint32

# STATE (words 21-22): bits 0-1 the sign of the last error (0: no update yet),
# bits 2..31 the engine clock (ms) of the last update, modulo 2**30 (12 days).
_NO_SAMPLE, _POSITIVE, _NEGATIVE, _ZERO = 0, 1, 2, 3
_STAMP_MODULO = 1 << 30


_FLOAT32_MAX = 3.4028234663852886e38


def _get_float(d: array, i: int) -> float:
    return struct.unpack("<f", struct.pack("<hh", d[i], d[i + 1]))[0]


def _get_state_float(d: array, i: int) -> float | None:
    """An internal float (the integral, the last derivative input), or None
    when the words do not hold a finite number: the program wrote them (Table
    Q says "do not write"); the PID then starts that term again."""
    v = _get_float(d, i)
    return v if math.isfinite(v) else None


def _put_float(d: array, i: int, v: float) -> None:
    v = max(-_FLOAT32_MAX, min(_FLOAT32_MAX, v))  # float32 range (NaN cannot reach here)
    d[i], d[i + 1] = struct.unpack("<hh", struct.pack("<f", v))


def _get_state(d: array, i: int) -> tuple[int, int]:
    (v,) = struct.unpack("<I", struct.pack("<hh", d[i], d[i + 1]))
    return v & 3, v >> 2


def _put_state(d: array, i: int, sign: int, now_ms: int) -> None:
    d[i], d[i + 1] = struct.unpack("<hh", struct.pack("<I", ((now_ms % _STAMP_MODULO) << 2) | sign))


def _round(v: float) -> int:
    """Into a 16-bit word, rounded as every float stored into a word
    (rounding.round_half_even), then clamped."""
    return max(-32768, min(32767, round_half_even(v)))


def _clamp(v, lo, hi):
    return lo if v < lo else hi if v > hi else v


def _sign_code(err: float) -> int:
    return _POSITIVE if err > 0 else _NEGATIVE if err < 0 else _ZERO


def gains(d: array, i: int, w0: int) -> tuple[float, float, float]:
    """(Kp, Ki per second, Kd in seconds) from words 3..5 (hundredths).
    ISA: Kc, Ti in minutes per repeat, Td in minutes, turned into the
    independent form (Kp = Kc, Ki = Kc / 60 Ti, Kd = 60 Kc Td)."""
    a, b, c = d[i + GAIN_P] / 100, d[i + GAIN_I] / 100, d[i + GAIN_D] / 100
    if not w0 & PE:
        return a, b, c
    return a, (a / (60 * b) if b > 0 else 0.0), a * 60 * c


def in_deadband(err: float, band: float, w0: int, last_sign: int) -> bool:
    """Zero-crossing dead band: within +-band only once the error has
    reached zero or changed sign, and until it leaves the band."""
    if band <= 0 or abs(err) > band:
        return False
    if w0 & EWD:
        return True
    return err == 0 or (last_sign == _POSITIVE and err < 0) or (last_sign == _NEGATIVE and err > 0)


def compute(d: array, i: int, w0: int, last_sign: int, dt: float, pv: int | float, tieback: int | float,
            cd: array, ci: int) -> tuple[int, int]:
    """One loop update: writes words 14..20 and the control output
    ``cd[ci]``; returns word 0 (status bits set) and the error's sign code."""
    alarms_before = w0 & (OLH | OLL)
    w0 &= ~_STATUS
    pv = _clamp(pv, 0, FULL_SCALE)
    sp = d[i + SP]
    if w0 & SC:
        smax, smin = d[i + SMAX], d[i + SMIN]
        if smax == smin:  # no span to scale by: nothing to compute
            return w0 | SPOR, last_sign
        lo, hi = min(smin, smax), max(smin, smax)
        per_count = (smax - smin) / FULL_SCALE  # engineering units per count
        sp_used = _clamp(sp, lo, hi)
        sp_counts = (sp_used - smin) / per_count
        band = abs(d[i + DEADBAND] / per_count)
        d[i + SCALED_PV] = _round(smin + pv * per_count)
    else:
        per_count = 1.0
        sp_used = _clamp(sp, 0, FULL_SCALE)
        sp_counts = sp_used
        band = d[i + DEADBAND]
        d[i + SCALED_PV] = _round(pv)
    if sp_used != sp:
        w0 |= SPOR
    sign = -1 if w0 & CA else 1
    err = sign * (sp_counts - pv)
    d[i + SCALED_ERR] = _round(err * per_count)
    kp, ki, kd = gains(d, i, w0)
    # Derivative of the error, or of the PV with the error's sign (the
    # error's slope with the setpoint held), so a setpoint step gives no kick.
    d_input = err if w0 & DO else -sign * pv
    last_input = _get_state_float(d, i + PREV_INPUT)
    derivative = 0.0 if last_sign == _NO_SAMPLE or last_input is None else kd * (d_input - last_input) / dt
    integral = _get_state_float(d, i + INTEGRAL) or 0.0
    proportional = kp * err
    bias = d[i + BIAS]
    alarm_hi, alarm_lo = d[i + LMAX] * FULL_SCALE / 100, d[i + LMIN] * FULL_SCALE / 100
    lo, hi = (alarm_lo, alarm_hi) if w0 & OL else (0, FULL_SCALE)
    hold = False
    if w0 & (MO | SWM):
        # Manual (tieback) wins over set output. The integral is
        # back-calculated so that automatic starts from this output.
        raw = _clamp(tieback, 0, FULL_SCALE) if w0 & MO else d[i + SETOUT] * FULL_SCALE / 100
        out = _clamp(raw, lo, hi)
        integral = out - proportional - bias
    elif in_deadband(err, band, w0, last_sign):
        # The output does not change while in the dead band, nor do its alarms.
        w0 |= EWD | alarms_before
        hold = True
        raw = out = 0.0
    else:
        step = ki * err * dt
        raw = proportional + integral + step + derivative + bias
        # Anti-reset windup: no integration further past a limit.
        if (raw > hi and step > 0) or (raw < lo and step < 0):
            raw -= step
            step = 0.0
        integral += step
        out = _clamp(raw, lo, hi)
    if not hold:
        if raw > alarm_hi:
            w0 |= OLH
        if raw < alarm_lo:
            w0 |= OLL
        cv = _round(out)
        cd[ci] = cv
        d[i + OUT_PCT] = _round(cv * 100 / FULL_SCALE)
    _put_float(d, i + INTEGRAL, integral)
    _put_float(d, i + PREV_INPUT, d_input)
    return w0, _sign_code(err)


def _bind(instr, access):
    ops = instr.operands
    get_block = access.location(ops[0])
    get_pv, get_tieback = access.value(ops[1]), access.value(ops[2])
    get_cv = access.location(ops[3])
    machine = access.machine
    what = str(ops[0].address)

    def run(c: bool) -> bool:
        d, i, _ = get_block()
        block(d, i, BLOCK_WORDS, what)
        w0 = d[i]
        if not c:
            d[i] = w0 & ~(EN | DN)  # the output and the loop's memory stay as they are
            return False
        last_sign, stamp = _get_state(d, i + STATE)
        update_ms = max(d[i + UPDATE], 1) * 10  # word 13: hundredths of a second
        now = machine.now_ms
        if w0 & TM and last_sign != _NO_SAMPLE:
            elapsed = (now - stamp) % _STAMP_MODULO
            if elapsed < update_ms:
                d[i] = (w0 | EN) & ~DN
                return True
            # Updates keep their period; one missed (a long scan) is not made up.
            now -= (elapsed - update_ms) % update_ms
        cd, ci, _ = get_cv()
        w0, sign = compute(d, i, w0 | EN | DN, last_sign, update_ms / 1000, get_pv(), get_tieback(), cd, ci)
        d[i] = w0
        _put_state(d, i + STATE, sign, now)
        return True

    return run


def _references(instr):
    return file_references(instr, 0, BLOCK_WORDS)


SPEC = _spec("PID", "proportional integral derivative (integer control block)", True, ("control_block", K.WORD),
             ("process_variable", K.WORD), ("tieback", K.INT_SOURCE), ("control_output", K.WORD))

INSTRUCTIONS = [BoundInstruction(SPEC, _bind, _references)]
