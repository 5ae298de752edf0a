"""Logix instructions whose rules differ from the PLC-5 instruction of the
same name (a Logix export's rungs, softplc_lite/logix/), bound objects
(ladder/bound.py) as the other groups: both executors run the same object,
each reaching the operands through its own ``Access``.

The Logix translator (logix/rungs.py) gives each one its operands as data table
addresses: a TIMER, COUNTER or CONTROL operand as its three DINTs (CTL,
then PRE and ACC, or LEN and POS), from the tag layout (tags.py). Internal
mnemonics (``LTON`` ...) keep them apart from the PLC-5 instructions; the
rung's text keeps the Logix name (docs/logix.md).

Rules (1756-RM003, Logix 5000 Controllers General Instructions):

- TON: rung true: EN set; while ACC < PRE, TT set and ACC counts the
  milliseconds since the previous scan; at PRE, DN set, TT cleared, ACC held
  at PRE. Rung false: EN, TT, DN and ACC cleared ("Timer On Delay").
- TOF: rung true: EN and DN set, TT cleared, ACC cleared. Rung false with DN
  set: TT set, ACC counts; at PRE, DN and TT cleared, ACC held at PRE
  ("Timer Off Delay").
- RTO: as TON, but a false rung clears only EN and TT; ACC and DN are kept
  until RES ("Retentive Timer On").
- A negative PRE or ACC: major fault type 4, code 34 (1756-PM014), as RM003
  says for each timer.
- CTU/CTD: on a false-to-true rung, ACC up (down) by one; CU (CD) follows
  the rung; DN is ACC >= PRE; past 2,147,483,647 ACC wraps to
  -2,147,483,648 and OV is set (UN for CTD past the bottom) ("Count Up",
  "Count Down").
- DIV: with two integer sources and an integer destination, the quotient's
  fraction is cut off (truncated toward zero); with a REAL source the
  quotient is rounded into an integer destination as any store rounds
  (half to even); a zero divisor is a minor fault, type 4 code 4 ("Divide").
- RES: a TIMER's ACC, EN, TT and DN, a COUNTER's ACC, CU, CD, DN, OV and
  UN, a CONTROL's POS and status bits are cleared ("Reset").

The first scan's milliseconds: a timer counts from the scan its rung goes
true (that scan adds nothing), a softplc choice.
"""

from __future__ import annotations

from ..bound import BoundInstruction
from ..semantics import MajorFault
from ..specs import InstructionSpec, K, OperandSpec
from .logix_bits import LOGIX_NAMES as _BITS_NAMES
from .logix_data import LOGIX_NAMES as _DATA_NAMES
from .logix_fbd import LOGIX_NAMES as _FBD_NAMES
from .logix_st import LOGIX_NAMES as _ST_NAMES
from .logix_string import LOGIX_NAMES as _STRING_NAMES
from .logix_system import LOGIX_NAMES as _SYSTEM_NAMES

FAULT_NEGATIVE_TIMER = 34
DINT_MIN, DINT_MAX = -(2 ** 31), 2 ** 31 - 1

EN = -(2 ** 31)  # bit 31 of a signed 32-bit CTL
TT = 1 << 30
DN = 1 << 29
CU, CD, OV, UN = EN, 1 << 30, 1 << 28, 1 << 27
CONTROL_BITS = EN | (0xFF << 24)


def _spec(mnemonic: str, title: str, *names: str) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, K.ANY) for n in names), True)


SPECS = [
    _spec("LTON", "Logix timer on delay", "CTL", "PRE", "ACC"),
    _spec("LTOF", "Logix timer off delay", "CTL", "PRE", "ACC"),
    _spec("LRTO", "Logix retentive timer on", "CTL", "PRE", "ACC"),
    _spec("LCTU", "Logix count up", "CTL", "PRE", "ACC"),
    _spec("LCTD", "Logix count down", "CTL", "PRE", "ACC"),
    _spec("LRES", "Logix reset", "CTL", "ACC or POS"),
    _spec("LDIV", "Logix divide", "source A", "source B", "dest"),
    _spec("LFLT", "Logix run-time fault", "code"),
    InstructionSpec("LIDX", "Logix array index", (OperandSpec("dest", K.ANY), OperandSpec("offset", K.ANY),
                                                  OperandSpec("term", K.ANY)), False, repeat=3 * 8),
]
# The Logix name each shows as (the watch view, fmt, messages); LIDX is no Logix instruction: it
# computes an index Logix computes inside the instruction that uses it.
LOGIX_NAMES = {s.mnemonic: s.mnemonic[1:] for s in SPECS if s.mnemonic not in ("LIDX", "LFLT")}
FAULT_JSR_PARAMETERS = 31  # major fault type 4 code 31, invalid JSR parameter (1756-PM014)
# What LFLT says, by code: a rung Logix lets load but faults on when it runs.
RUN_TIME_FAULTS = {FAULT_JSR_PARAMETERS: "JSR parameters that do not match the routine's SBR or RET: major fault "
                                         "type 4, code 31 (invalid JSR parameter)"}
LOGIX_NAMES.update(_DATA_NAMES, **_STRING_NAMES, **_SYSTEM_NAMES, **_BITS_NAMES, **_ST_NAMES, **_FBD_NAMES)
FAULT_SUBSCRIPT = 20  # major fault type 4 code 20: an array subscript out of range (1756-PM014)


def _timer(kind: str, ctl, pre, acc, machine):
    def run(c: bool) -> bool:
        cd, ci, _ = ctl()
        pd, pi, _ = pre()
        ad, ai, _ = acc()
        w, p, a = cd[ci], pd[pi], ad[ai]
        if p < 0 or a < 0:
            raise _negative(p, a)
        if kind == "TOF":
            if c:
                w = (w | EN | DN) & ~TT
                a = 0
            else:
                w &= ~EN
                if w & DN:
                    if w & TT:
                        a = min(a + machine.dt, DINT_MAX)
                    w |= TT
                    if a >= p:
                        w &= ~(DN | TT)
                        a = p
        elif c:
            w |= EN
            if a >= p:  # done (or ACC written past PRE): held where it is
                w = (w | DN) & ~TT
            else:
                if w & TT:
                    a = min(a + machine.dt, DINT_MAX)
                w |= TT
                if a >= p:
                    w = (w | DN) & ~TT
                    a = p
        elif kind == "RTO":
            w &= ~(EN | TT)
        else:
            w &= ~(EN | TT | DN)
            a = 0
        cd[ci] = w
        ad[ai] = a
        return c
    return run


def _negative(p: int, a: int) -> MajorFault:
    return MajorFault(FAULT_NEGATIVE_TIMER, f"timer with a negative {'PRE' if p < 0 else 'ACC'} "
                                            f"({p if p < 0 else a}): major fault type 4, code 34")


def _ton_fixed(cd, ci, pd, pi, ad, ai, machine):
    """TON on three items resolved at load (the common case): the same rules
    as ``_timer``'s, with its steady states (false and reset, done) cheap."""
    held = EN | DN

    def run(c: bool) -> bool:
        w, p, a = cd[ci], pd[pi], ad[ai]
        if p < 0 or a < 0:
            raise _negative(p, a)
        if c:
            if a >= p:
                if w & (held | TT) != held:
                    cd[ci] = (w | held) & ~TT
                return c
            if w & TT:
                a = a + machine.dt
            w |= EN | TT
            if a >= p:
                w = (w | DN) & ~TT
                a = p
            cd[ci] = w
            ad[ai] = a
        elif w & (EN | TT | DN) or a:
            cd[ci] = w & ~(EN | TT | DN)
            ad[ai] = 0
        return c
    return run


def _counter(up: bool, ctl, pre, acc):
    step = _count_step(up)

    def run(c: bool) -> bool:
        cd, ci, _ = ctl()
        pd, pi, _ = pre()
        ad, ai, _ = acc()
        return step(c, cd, ci, pd, pi, ad, ai)
    return run


def _counter_fixed(up: bool, cd, ci, pd, pi, ad, ai):
    """CTU/CTD on three items resolved at load: a rung held as it was and a
    DN already right cost a few reads."""
    step = _count_step(up)
    edge = CU if up else CD

    def run(c: bool) -> bool:
        w = cd[ci]
        if (c and w & edge) or (not c and not w & edge):  # no edge: only DN to keep right
            if (ad[ai] >= pd[pi]) == bool(w & DN):
                return c
        return step(c, cd, ci, pd, pi, ad, ai)
    return run


def _count_step(up: bool):
    edge = CU if up else CD

    def step(c, cd, ci, pd, pi, ad, ai) -> bool:
        w, p, a = cd[ci], pd[pi], ad[ai]
        if c and not w & edge:
            if up:
                if a == DINT_MAX:
                    a, w = DINT_MIN, w | OV
                else:
                    a += 1
                    if a == 0 and w & UN:
                        w &= ~UN
            else:
                if a == DINT_MIN:
                    a, w = DINT_MAX, w | UN
                else:
                    a -= 1
                    if a == -1 and w & OV:
                        w &= ~OV
        w = (w | edge) if c else (w & ~edge)
        w = (w | DN) if a >= p else (w & ~DN)
        cd[ci] = w
        ad[ai] = a
        return c
    return step


def _reset(ctl, acc):
    def run(c: bool) -> bool:
        if c:
            cd, ci, _ = ctl()
            ad, ai, _ = acc()
            cd[ci] = cd[ci] & ~CONTROL_BITS
            ad[ai] = 0
        return c
    return run


def _divide(a, b, dest, machine):
    def run(c: bool) -> bool:
        if c:
            x, y = a(), b()
            d, i, _ = dest()
            if y == 0:
                machine.store(machine.div_zero(x), d, i)
            elif isinstance(x, int) and isinstance(y, int) and d.typecode != "f":
                q = abs(x) // abs(y)
                machine.store(q if (x < 0) == (y < 0) else -q, d, i)
            else:
                machine.store(x / y, d, i)
        return c
    return run


def _index(instr, access):
    """LIDX dest offset (expression size stride)...: dest = offset + the sum
    of each expression times its stride, whatever the rung (the index of an
    operand is taken where the instruction is, true rung or false); an
    expression outside 0..size-1 is major fault 20."""
    ops = instr.operands
    dest = access.location(ops[0])
    offset = ops[1].value
    terms = [(access.expression(ops[k]), ops[k + 1].value, ops[k + 2].value) for k in range(2, len(ops), 3)]

    def run(c: bool) -> bool:
        v = offset
        for get, size, stride in terms:
            k = get()
            if not isinstance(k, int):
                k = int(k)
            if not 0 <= k < size:
                raise MajorFault(FAULT_SUBSCRIPT, f"array subscript {k} outside 0..{size - 1}: major fault type 4, "
                                                  f"code 20")
            v += k * stride
        d, i, _ = dest()
        d[i] = v
        return c
    return run


def _fault(instr, access):
    """LFLT code: a true rung is the major fault ``code`` (RUN_TIME_FAULTS
    says it); a false rung passes."""
    code = instr.operands[0].value
    message = RUN_TIME_FAULTS.get(code, f"major fault {code}")

    def run(c: bool) -> bool:
        if c:
            raise MajorFault(code, message)
        return c
    return run


def _bind(instr, access):
    m = instr.mnemonic
    machine = access.machine
    if m == "LFLT":
        return _fault(instr, access)
    if m == "LIDX":
        return _index(instr, access)
    if m == "LDIV":
        a, b, dest = instr.operands
        return _divide(access.value(a), access.value(b), access.location(dest), machine)
    fixed = [access.fixed(op) for op in instr.operands]
    if m == "LTON" and all(f is not None for f in fixed):
        (cd, ci, _), (pd, pi, _), (ad, ai, _) = fixed
        return _ton_fixed(cd, ci, pd, pi, ad, ai, machine)
    ops = [access.location(op) for op in instr.operands]
    if m in ("LTON", "LTOF", "LRTO"):
        return _timer(m[1:], *ops, machine)
    if m in ("LCTU", "LCTD"):
        if all(f is not None for f in fixed):
            (cd, ci, _), (pd, pi, _), (ad, ai, _) = fixed
            return _counter_fixed(m == "LCTU", cd, ci, pd, pi, ad, ai)
        return _counter(m == "LCTU", *ops)
    return _reset(*ops)


INSTRUCTIONS = [BoundInstruction(spec, _bind) for spec in SPECS]
