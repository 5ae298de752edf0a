"""LPER: is a Logix periodic task due? A bound object (ladder/bound.py), so
both executors run the same code. The Logix loader (logix/tasks.py) makes
each periodic task of an export a rung of program file 2:

    LBL k  XIO inhibit  LPER rate ctl next overlaps watchdog  JSR task-file  JMP k

so the task's programs run once for every period of the engine's clock
that has ended, at the start of the scan (docs/logix.md, "Tasks"). The
task's state is in data table items (so a retentive snapshot, a restore
and the watch view keep and show it):

- ``ctl`` (an L item): bit 0 set while the task is scheduled. A false
  rung-in (the task inhibited) clears it; the first-pass rung of file 2
  clears it, so a run, a restore or a return from PROGRAM schedules anew.
- ``next`` (an L item): the engine clock (ms, 32-bit, wrapping) at which
  the next period ends. Scheduling anew sets it one period after the
  previous scan's clock: in the first scan, a period after the engine
  entered RUN.
- ``overlaps`` (an L item): periods not run, when more than ``MAX_RUNS``
  periods ended since the task last ran (a softplc choice; the count is
  the task's overlap count, 1756-PM005 "Manage tasks", "Overlap").

Rung-out: true when a period has ended (``next`` then moves on by one
period), false otherwise.

The task's watchdog: each run of the task (from LPER's true rung-out to its
next evaluation, which follows the JSR) is timed on the wall clock, as the
engine's scan watchdog is; a run longer than ``watchdog`` ms is a major
fault (the scan watchdog's code), as a Logix task's watchdog faults
(1756-PM005; major fault type 6, code 1 in 1756-PM014).
"""

from __future__ import annotations

import time

from .. import status as S
from ..bound import BoundInstruction
from ..semantics import MajorFault
from ..specs import InstructionSpec, K, OperandSpec

SCHEDULED = 1  # bit 0 of ctl
MAX_RUNS = 100  # runs of one periodic task in one scan; periods beyond are overlaps (a softplc choice)
DINT_MAX = 2 ** 31 - 1

SPECS = [InstructionSpec("LPER", "Logix periodic task due", tuple(
    OperandSpec(n, K.ANY) for n in ("rate ms", "CTL", "next", "overlaps", "watchdog ms")), False)]
clock = time.perf_counter  # the watchdog's clock (seconds); tests count with their own


def _dint(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v & 0x80000000 else v


def _periodic(rate, ctl, nxt, overlaps, watchdog, machine):
    started = [None, None]  # the wall clock when the task's run began, and that scan's count

    def run(c: bool) -> bool:
        s = machine.s
        scan = (s[S.SCAN_COUNT_LOW], s[S.SCAN_COUNT_HIGH])
        if started[0] is not None and started[1] == scan:  # the run that LPER let in has returned
            elapsed_ms = (clock() - started[0]) * 1000
            limit = watchdog()
            if elapsed_ms > limit:
                started[0] = None
                raise MajorFault(S.FAULT_WATCHDOG, f"task watchdog: a run of the periodic task took "
                                                   f"{elapsed_ms:.1f} ms, more than its Watchdog of {limit} ms")
        started[0] = None
        cd, ci, _ = ctl()
        if not c:
            cd[ci] &= ~SCHEDULED
            return False
        period = max(int(rate()), 1)
        nd, ni, _ = nxt()
        now = machine.now_ms
        if not cd[ci] & SCHEDULED:
            cd[ci] |= SCHEDULED
            nd[ni] = _dint(now - machine.dt + period)
        late = _dint(now - nd[ni])
        if late < 0:
            return False
        due = late // period + 1
        if due > MAX_RUNS:
            skipped = due - MAX_RUNS
            od, oi, _ = overlaps()
            od[oi] = min(od[oi] + skipped, DINT_MAX)
            nd[ni] = _dint(nd[ni] + skipped * period)
        nd[ni] = _dint(nd[ni] + period)
        started[0], started[1] = clock(), scan
        return True
    return run


def _bind(instr, access):
    rate, ctl, nxt, overlaps, watchdog = instr.operands
    return _periodic(access.value(rate), access.location(ctl), access.location(nxt), access.location(overlaps),
                     access.value(watchdog), access.machine)


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
