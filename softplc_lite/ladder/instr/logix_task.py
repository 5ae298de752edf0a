"""LPER: is a Logix periodic task due? A bound object (ladder/bound.py), so
both executors run the same code. The Logix loader (logix/tasks.py) makes
each periodic task of an export a rung of program file 2:

    LBL k  XIO inhibit  LPER rate ctl next overlaps  JSR task-file  JMP k

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
"""

from __future__ import annotations

from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

SCHEDULED = 1  # bit 0 of ctl
MAX_RUNS = 100  # runs of one periodic task in one scan; periods beyond are overlaps (a softplc choice)
DINT_MAX = 2 ** 31 - 1

SPECS = [InstructionSpec("LPER", "Logix periodic task due", tuple(
    OperandSpec(n, K.ANY) for n in ("rate ms", "CTL", "next", "overlaps")), False)]


def _dint(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v & 0x80000000 else v


def _periodic(rate, ctl, nxt, overlaps, machine):
    def run(c: bool) -> bool:
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
        return True
    return run


def _bind(instr, access):
    rate, ctl, nxt, overlaps = instr.operands
    return _periodic(access.value(rate), access.location(ctl), access.location(nxt), access.location(overlaps),
                     access.machine)


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
