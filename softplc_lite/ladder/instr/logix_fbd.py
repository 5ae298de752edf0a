"""Logix's function-block instructions that Structured Text calls on a tag
of their own structure: the timers TONR, TOFR and RTOR (FBD_TIMER), the
counter CTUD (FBD_COUNTER) and the one-shots OSRI and OSFI (FBD_ONESHOT),
bound objects (ladder/bound.py) as the other groups: both executors run
the same object.

logix/fbd.py translates ``TONR(MyTimer);`` into ``LTONR`` with the tag's
items as operands: its hidden CTL DINT (every BOOL member is a bit of it,
logix/types.py lays them out from ``TIMER_BITS`` ...), then PRE, ACC and
Status, and the first-scan flag S:FS. Logix has these in function block
diagrams and Structured Text only, not in ladder.

Rules (1756-RM003, Logix 5000 Controllers General Instructions, chapter
"Timer and Counter Instructions" (TONR, TOFR, RTOR, CTUD) and "One Shot
Rising with Input (OSRI)", "One Shot Falling with Input (OSFI)"):

- In Structured Text EnableIn is always set and the instruction executes:
  EnableIn and EnableOut are set each time it runs (EnableOut cleared while
  PRE is invalid).
- The time base is 1 ms: ACC adds the milliseconds since the previous
  scan. TONR: TimerEnable set: EN; while ACC < PRE, TT and ACC counts; at
  PRE, DN, TT cleared, ACC held at PRE. TimerEnable cleared: EN, TT, DN
  cleared, ACC 0. RTOR: as TONR, but TimerEnable cleared clears only EN
  and TT (ACC and DN kept). TOFR: TimerEnable set: EN and DN, TT cleared,
  ACC 0; TimerEnable cleared with DN set: TT, ACC counts; at PRE, DN and
  TT cleared.
- Reset set: EN, TT and DN cleared, ACC 0 (TOFR: ACC = PRE); the timer
  does not time while Reset is set.
- PRE < 0 is invalid: Status.0 (InstructFault) and Status.1 (PresetInv)
  set, the timer does not execute; no controller fault (RM003: "This is not
  a minor or major controller error").
- The first scan after going to run: TONR clears EN, TT, DN and ACC; RTOR
  clears EN, TT, DN and keeps ACC (RM003's "Instruction first scan").
- CTUD counts up by one when CUEnable goes from cleared to set, down by one
  when CDEnable does; both in one run: up first, then down. CU and CD
  follow CUEnable and CDEnable; DN is ACC >= PRE; past 2,147,483,647 ACC
  wraps to -2,147,483,648 and OV is set (UN for the other way). Reset: CU,
  CD, DN, OV, UN cleared, ACC 0.
- OSRI: OutputBit set for one run when InputBit goes from cleared to set;
  OSFI when it goes from set to cleared. The first scan takes InputBit as
  it is (no edge on that scan).

Choices of ours (docs/logix.md): the scan a timer starts timing adds
nothing (as LTON); CTUD's edges are taken against the CUEnable and CDEnable
of its previous run, kept in CTL bits no member names, also while Reset is
set (so releasing Reset with CUEnable held does not count); OV and UN are
cleared when the count comes back past zero, as the ladder's CTU and CTD
do; TOFR and CTUD do nothing special at the first scan.
"""

from __future__ import annotations

from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec

DINT_MIN, DINT_MAX = -(2 ** 31), 2 ** 31 - 1

# Each structure's BOOL members, bit k of its CTL for the k-th name (logix/types.py lays them out).
TIMER_BITS = ("EnableIn", "TimerEnable", "Reset", "EnableOut", "EN", "TT", "DN")
COUNTER_BITS = ("EnableIn", "CUEnable", "CDEnable", "Reset", "EnableOut", "CU", "CD", "DN", "OV", "UN")
ONESHOT_BITS = ("EnableIn", "InputBit", "EnableOut", "OutputBit")
STATUS_BITS = (("InstructFault", 0), ("PresetInv", 1))  # of Status (RM003: Status.0, Status.1)
MEMORY, MEMORY_2 = 16, 17  # CTL bits no member names: CTUD's CUEnable and CDEnable, a one-shot's InputBit


T_IN, T_ENABLE, T_RESET, T_OUT, T_EN, T_TT, T_DN = (1 << k for k in range(len(TIMER_BITS)))
C_IN, C_UP, C_DOWN, C_RESET, C_OUT, C_CU, C_CD, C_DN, C_OV, C_UN = (1 << k for k in range(len(COUNTER_BITS)))
O_IN, O_INPUT, O_OUT, O_OUTPUT = (1 << k for k in range(len(ONESHOT_BITS)))
MEM, MEM_2 = 1 << MEMORY, 1 << MEMORY_2
FAULT_BITS = 0b11  # InstructFault | PresetInv


def _spec(mnemonic: str, title: str, *names: str) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, K.ANY) for n in names), True)


SPECS = [
    _spec("LTONR", "Logix timer on delay with reset", "CTL", "PRE", "ACC", "Status", "first scan"),
    _spec("LTOFR", "Logix timer off delay with reset", "CTL", "PRE", "ACC", "Status", "first scan"),
    _spec("LRTOR", "Logix retentive timer on with reset", "CTL", "PRE", "ACC", "Status", "first scan"),
    _spec("LCTUD", "Logix count up/down", "CTL", "PRE", "ACC"),
    _spec("LOSRI", "Logix one shot rising with input", "CTL", "first scan"),
    _spec("LOSFI", "Logix one shot falling with input", "CTL", "first scan"),
]
LOGIX_NAMES = {s.mnemonic: s.mnemonic[1:] for s in SPECS}


def _bit(get):
    def read() -> bool:
        d, i, bit = get()
        return bool(d[i] >> bit & 1) if bit is not None else bool(d[i])
    return read


def _timer(kind: str, ctl, pre, acc, status, first, machine):
    def run(c: bool) -> bool:
        if not c:
            return c
        cd, ci, _ = ctl()
        pd, pi, _ = pre()
        ad, ai, _ = acc()
        sd, si, _ = status()
        w, p, a = cd[ci], pd[pi], ad[ai]
        if first() and kind != "TOF":
            w &= ~(T_EN | T_TT | T_DN)
            if kind == "TON":
                a = 0
        w |= T_IN
        if w & T_RESET:
            w = (w | T_OUT) & ~(T_EN | T_TT | T_DN)
            a = p if kind == "TOF" else 0
            sd[si] &= ~FAULT_BITS
        elif p < 0:
            w &= ~T_OUT
            sd[si] |= FAULT_BITS
        else:
            sd[si] &= ~FAULT_BITS
            w |= T_OUT
            if kind == "TOF":
                if w & T_ENABLE:
                    w = (w | T_EN | T_DN) & ~T_TT
                    a = 0
                else:
                    w &= ~T_EN
                    if w & T_DN:
                        if w & T_TT:
                            a = min(a + machine.dt, DINT_MAX)
                        w |= T_TT
                        if a >= p:
                            w &= ~(T_DN | T_TT)
                            a = p
            elif w & T_ENABLE:
                w |= T_EN
                if a >= p:  # done (or ACC written past PRE): held where it is
                    w = (w | T_DN) & ~T_TT
                else:
                    if w & T_TT:
                        a = min(a + machine.dt, DINT_MAX)
                    w |= T_TT
                    if a >= p:
                        w = (w | T_DN) & ~T_TT
                        a = p
            elif kind == "RTO":
                w &= ~(T_EN | T_TT)
            else:
                w &= ~(T_EN | T_TT | T_DN)
                a = 0
        cd[ci] = w
        ad[ai] = a
        return c
    return run


def _counter(ctl, pre, acc):
    def run(c: bool) -> bool:
        if not c:
            return c
        cd, ci, _ = ctl()
        pd, pi, _ = pre()
        ad, ai, _ = acc()
        w, p, a = cd[ci], pd[pi], ad[ai]
        up, down = bool(w & C_UP), bool(w & C_DOWN)
        if w & C_RESET:
            w &= ~(C_CU | C_CD | C_DN | C_OV | C_UN)
            a = 0
        else:
            if up and not w & MEM:
                if a == DINT_MAX:
                    a, w = DINT_MIN, w | C_OV
                else:
                    a += 1
                    if a == 0 and w & C_UN:
                        w &= ~C_UN
            if down and not w & MEM_2:
                if a == DINT_MIN:
                    a, w = DINT_MAX, w | C_UN
                else:
                    a -= 1
                    if a == -1 and w & C_OV:
                        w &= ~C_OV
            w = (w | C_CU) if up else (w & ~C_CU)
            w = (w | C_CD) if down else (w & ~C_CD)
            w = (w | C_DN) if a >= p else (w & ~C_DN)
        w = (w | MEM) if up else (w & ~MEM)
        w = (w | MEM_2) if down else (w & ~MEM_2)
        cd[ci] = w | C_IN | C_OUT
        ad[ai] = a
        return c
    return run


def _oneshot(rising: bool, ctl, first):
    def run(c: bool) -> bool:
        if not c:
            return c
        cd, ci, _ = ctl()
        w = cd[ci]
        now = bool(w & O_INPUT)
        before = now if first() else bool(w & MEM)
        fired = (now and not before) if rising else (before and not now)
        w = (w | O_OUTPUT) if fired else (w & ~O_OUTPUT)
        w = (w | MEM) if now else (w & ~MEM)
        cd[ci] = w | O_IN | O_OUT
        return c
    return run


def _bind(instr, access):
    m = instr.mnemonic
    ops = instr.operands
    if m == "LCTUD":
        return _counter(*(access.location(op) for op in ops))
    if m in ("LOSRI", "LOSFI"):
        return _oneshot(m == "LOSRI", access.location(ops[0]), _bit(access.location(ops[1])))
    ctl, pre, acc, status = (access.location(op) for op in ops[:4])
    return _timer(m[1:4], ctl, pre, acc, status, _bit(access.location(ops[4])), access.machine)


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
