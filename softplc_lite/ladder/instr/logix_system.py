"""GSV and SSV of the controller attributes a program reads from the engine
(the wall clock, the scan times, the fault bits), bound objects run by both
executors. The Logix translator (logix/system.py) gives the attribute as a
constant (``ATTRIBUTES``); an attribute held in a data table item (a task's
InhibitTask, a program's DisableFlag) is a MOV instead, and an attribute
softplc_lite does not hold is a rung not run.

Rules (1756-RM003, "Get System Value (GSV) and Set System Value (SSV)" and
its appendix "GSV/SSV objects"; the choices are softplc_lite's):

- WallClockTime.CurrentValue: microseconds since 1970-01-01 00:00 UTC, a
  LINT (or a DINT[2], low then high, as older exports write it).
  DateTime and LocalDateTime: a DINT[7] of year, month, day, hour, minute,
  second, microsecond, in UTC and in local time. SSV of any of them sets
  the clock. The clock runs with the engine's (simulated time too); until
  an SSV sets it, it starts from the host's clock when it is first read (a
  softplc choice).
- Task.LastScanTime, MaxScanTime and Program.LastScanTime, MaxScanTime, in
  microseconds: the whole scan's (S:8 and S:9, ms) for every task and
  program (a softplc choice: softplc_lite times the scan, not each
  program). An SSV of one sets it (``SSV(Task,MainTask,MaxScanTime,Zero)``
  restarts the maximum). Code 6 (WATCHDOG) is the scan watchdog, S:28 in ms,
  for PLC-5 text; a Logix task's Priority, Rate and Watchdog are the
  export's, held in the data table (logix/tasks.py), read as code 0.
- FaultLog.MinorFaultBits: bit 4 (an instruction's minor fault) while the
  minor fault words (S:10/14, S:17) hold one; MajorFaultBits: bit 4 while
  S:11 holds a major fault. An SSV with bit 4 clear clears them (the idiom
  ``SSV(FaultLog,,MinorFaultBits,Zero)``); other bits are ignored.
- GSV and SSV copy bytes: a REAL tag gets (gives) the attribute's 32 bits as
  they are, not a converted value (RM003: "the GSV ... copies the data").
"""

from __future__ import annotations

import struct
import time
from array import array
from datetime import datetime, timedelta, timezone

from .. import status as S
from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

# Attribute codes (the translator's constant operand); HELD: an attribute in the data table.
HELD = 0
WALL_CURRENT, WALL_DATETIME, WALL_LOCAL, LAST_SCAN, MAX_SCAN, WATCHDOG, MINOR_BITS, MAJOR_BITS = range(1, 9)
ATTRIBUTES = {
    ("WALLCLOCKTIME", "CURRENTVALUE"): WALL_CURRENT, ("WALLCLOCKTIME", "DATETIME"): WALL_DATETIME,
    ("WALLCLOCKTIME", "LOCALDATETIME"): WALL_LOCAL,
    ("TASK", "LASTSCANTIME"): LAST_SCAN, ("TASK", "MAXSCANTIME"): MAX_SCAN,
    ("PROGRAM", "LASTSCANTIME"): LAST_SCAN, ("PROGRAM", "MAXSCANTIME"): MAX_SCAN,
    ("FAULTLOG", "MINORFAULTBITS"): MINOR_BITS, ("FAULTLOG", "MAJORFAULTBITS"): MAJOR_BITS,
}
WORDS = {WALL_DATETIME: 7, WALL_LOCAL: 7}  # DINTs an attribute takes (the rest: one value)
SPECS = [  # a dest (source) of one item, or of several in a row, or (DateTime) one operand per DINT
    InstructionSpec("LGSV", "Logix get system value", (OperandSpec("attribute", K.ANY), OperandSpec("dest", K.ANY)),
                    True, repeat=7),
    InstructionSpec("LSSV", "Logix set system value", (OperandSpec("attribute", K.ANY),
                                                       OperandSpec("source", K.ANY)), True, repeat=7),
]
LOGIX_NAMES = {"LGSV": "GSV", "LSSV": "SSV"}
INSTRUCTION_FAULT = 1 << 4  # FaultLog's bit of an instruction (program) fault
EPOCH = datetime(1970, 1, 1, tzinfo=timezone.utc)


def _now_us(machine) -> int:
    offset = getattr(machine, "logix_wall_offset_us", None)
    if offset is None:
        offset = machine.logix_wall_offset_us = time.time_ns() // 1000 - machine.now_ms * 1000
    return offset + machine.now_ms * 1000


def _set_us(machine, us: int) -> None:
    machine.logix_wall_offset_us = us - machine.now_ms * 1000


def _fields(us: int, local: bool) -> list[int]:
    t = EPOCH + timedelta(microseconds=us)
    if local:
        t = t.astimezone()
    return [t.year, t.month, t.day, t.hour, t.minute, t.second, t.microsecond]


def _from_fields(v: list[int], local: bool) -> int:
    t = datetime(*v[:6], v[6], tzinfo=None if local else timezone.utc)
    if local:
        t = t.astimezone()
    return (t - EPOCH) // timedelta(microseconds=1)


def _get(code: int, machine) -> list[int]:
    s = machine.s
    if code == WALL_CURRENT:
        return [_now_us(machine)]
    if code in (WALL_DATETIME, WALL_LOCAL):
        return _fields(_now_us(machine), code == WALL_LOCAL)
    if code == LAST_SCAN:
        return [s[S.LAST_SCAN_MS] * 1000]
    if code == MAX_SCAN:
        return [s[S.MAX_SCAN_MS] * 1000]
    if code == WATCHDOG:
        return [s[S.WATCHDOG_MS]]
    if code == MINOR_BITS:
        return [INSTRUCTION_FAULT if s[S.MINOR_FAULT_BITS] or s[S.PLC5_MINOR_FAULT_BITS] & (1 << 14) else 0]
    return [INSTRUCTION_FAULT if s[S.MAJOR_FAULT_BITS] else 0]


def _held(instr, access, get: bool):
    """Code 0: an attribute held in the data table, the third operand (a
    bit, as a program's DisableFlag, or a word), read into a DINT (GSV) or
    written from one (SSV: a bit set when the value is not 0)."""
    tag = access.location(instr.operands[1])
    held = access.location(instr.operands[2])

    def run(c: bool) -> bool:
        if c:
            (td, ti, _), (hd, hi, bit) = tag(), held()
            if get:
                td[ti] = hd[hi] if bit is None else (hd[hi] >> bit) & 1
            elif bit is None:
                hd[hi] = td[ti]
            else:
                mask = 1 << bit if bit < 15 or hd.itemsize > 2 else -32768
                hd[hi] = (hd[hi] | mask) if td[ti] else (hd[hi] & ~mask)
        return c
    return run


def _bind_get(instr, access):
    code = instr.operands[0].value
    if code == HELD:
        return _held(instr, access, True)
    if len(instr.operands) > 2:  # one operand per value (a structure's DINT members)
        dests = [access.location(op) for op in instr.operands[1:]]
        machine = access.machine

        def each(c: bool) -> bool:
            if c:
                for get, v in zip(dests, _get(code, machine)):
                    d, i, _ = get()
                    d[i] = v
            return c
        return each
    dest = access.location(instr.operands[1])
    machine = access.machine

    def run(c: bool) -> bool:
        if c:
            values = _get(code, machine)
            d, i, _ = dest()
            if code == WALL_CURRENT and d.itemsize == 4:  # a DINT[2]: low, high
                v = values[0]
                values = [(v & 0xFFFFFFFF) - ((v & 0x80000000) << 1), v >> 32]
            if d.typecode == "f":  # a REAL destination gets the DINT's bytes, as GSV copies them
                values = list(struct.unpack(f"{len(values)}f", struct.pack(f"{len(values)}i", *(
                    (v & 0xFFFFFFFF) - ((v & 0x80000000) << 1) for v in values))))
            if i + len(values) > len(d):
                values = values[:len(d) - i]
            d[i:i + len(values)] = type(d)(d.typecode, values)
        return c
    return run


def _bind_set(instr, access):
    code = instr.operands[0].value
    if code == HELD:
        return _held(instr, access, False)
    sources = [access.location(op) for op in instr.operands[1:]]
    machine = access.machine

    def run(c: bool) -> bool:
        if c:
            d, i, _ = sources[0]()
            if d.typecode == "f":  # a REAL source gives its bytes
                d, i = array("i", struct.pack("f", d[i])), 0
            if len(sources) > 1:  # one operand per value: gathered in a row
                values = []
                for get in sources:
                    sd, si, _ = get()
                    values.append(sd[si])
                d, i = array("q", values), 0
            s = machine.s
            if code == WALL_CURRENT:
                _set_us(machine, d[i] if d.itemsize == 8 else (d[i] & 0xFFFFFFFF) | (d[i + 1] << 32))
            elif code in (WALL_DATETIME, WALL_LOCAL):
                try:
                    _set_us(machine, _from_fields(list(d[i:i + 7]), code == WALL_LOCAL))
                except (ValueError, OverflowError):
                    pass  # no such date: the clock is left as it is (a softplc choice)
            elif code in (LAST_SCAN, MAX_SCAN):
                s[S.LAST_SCAN_MS if code == LAST_SCAN else S.MAX_SCAN_MS] = min(d[i] // 1000, 32767)
            elif code == WATCHDOG:
                s[S.WATCHDOG_MS] = max(0, min(d[i], 32767))
            elif code == MINOR_BITS and not d[i] & INSTRUCTION_FAULT:
                s[S.MINOR_FAULT_BITS] = 0
                s[S.PLC5_MINOR_FAULT_BITS] &= ~(1 << 14)
            elif code == MAJOR_BITS and not d[i] & INSTRUCTION_FAULT:
                s[S.MAJOR_FAULT_BITS] = 0
        return c
    return run


INSTRUCTIONS = [BoundInstruction(SPECS[0], _bind_get), BoundInstruction(SPECS[1], _bind_set)]
