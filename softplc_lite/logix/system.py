"""GSV(Class, Instance, Attribute, Dest) and SSV(Class, Instance,
Attribute, Source): the class and attribute are names in the rung, known
when the export is loaded (1756-RM003, "Get System Value (GSV) and Set
System Value (SSV)").

- An attribute the data table holds (the tag directory's ``objects``: a
  task's InhibitTask and OverlapCount, a program's DisableFlag; tasks.py) is
  read from it (GSV) or written into it (SSV): LGSV/LSSV code 0. The instance ``THIS`` of a Program
  is the program the rung is in. A task's Priority, Rate and Watchdog (µs) are the export's; an SSV
  of one is a rung not run (a softplc choice: the schedule is made at load).
- An attribute read from the engine (the wall clock, the scan times, the
  fault bits: ladder/instr/logix_system.py) is an LGSV or LSSV.
- Any other (Module.EntryStatus, Controller, Axis ...): the rung is not run,
  with a warning naming the class and attribute.
"""

from __future__ import annotations

from ..ladder.ast import AddressRef, Const, Instruction
from ..ladder.instr.logix_system import ATTRIBUTES, HELD, WALL_CURRENT, WORDS
from . import operands
from .copy import element_run
from .operands import Operands, Skip
from .tags import PathError

FIXED = ("PRIORITY", "RATE", "WATCHDOG")  # a task's schedule: read, not changed


def translate(el, pos, rung, ctx):
    return operands.translate(el, pos, rung, ctx, _build)


def _build(ops: Operands) -> list[Instruction]:
    ops.count(4)
    get = ops.el.mnemonic == "GSV"
    cls, instance, attribute = (ops.text(k).upper() for k in range(3))
    if cls == "PROGRAM" and instance == "THIS" and ops.ctx.scope:
        instance = ops.ctx.scope.upper()
    held = ops.ctx.directory.objects.get((cls, instance, attribute))
    if not get and cls == "TASK" and attribute in FIXED:
        raise Skip(f"SSV of Task.{ops.text(2)} is not applied by softplc_lite: a task's schedule is the export's "
                   f"(GSV reads it)")
    code = HELD if held is not None else ATTRIBUTES.get((cls, attribute))
    if code is None:
        raise Skip(f"{ops.text(0)}.{ops.text(2)} is not an attribute softplc_lite holds (it has WallClockTime "
                   f"CurrentValue, DateTime, LocalDateTime; Task and Program LastScanTime, MaxScanTime; Task "
                   f"Priority, Rate, Watchdog, InhibitTask, OverlapCount; Program DisableFlag; FaultLog "
                   f"MinorFaultBits, "
                   f"MajorFaultBits)")
    r = ops.resolve(3)
    where = ops.where(3)
    if r.type.kind != "atomic" or r.type.name == "BOOL":
        raise PathError(f"expected a DINT{' or LINT' if code == WALL_CURRENT else ''}, found {r.type.name}")
    need = WORDS.get(code, 1)
    name = "LGSV" if get else "LSSV"
    if need > 1 and r.address is not None and r.path and not r.dims:  # DateTime.Year: a structure's DINTs
        members = _members_from(r, need)
        if members is not None:
            head = ops.text(3)[:ops.text(3).rfind(".") + 1]
            refs = [AddressRef(rungs_resolve(ops, head + m, where).address, where) for m in members]
            return [Instruction(name, [Const(code, ops.pos)] + refs, ops.pos)]
    run = element_run(r, where, ops.ctx)
    address, _, end = run.leaves[()]
    if code == WALL_CURRENT and address.type_letter == "L":
        need = 2
    if isinstance(address.element, int) and end - address.element < need:
        raise PathError(f"{ops.el.mnemonic} of {ops.text(0)}.{ops.text(2)} takes {need} DINTs: expected an "
                        f"array with {need} elements from here, or a structure with {need} DINT members from here")
    extra = [AddressRef(held, ops.pos)] if held is not None else []
    return [Instruction(name, [Const(code, ops.pos), AddressRef(address, where)] + extra, ops.pos)]


def _members_from(r, need: int) -> list[str] | None:
    """The names of ``need`` DINT members of the structure holding the
    member ``r`` names, from that member on (Logix copies a DateTime's seven
    DINTs into them, in order), or None."""
    t = r.declared.type
    for key in r.path[:-1]:
        t = t.member(key).type
    names = [m for m in t.members if not m.hidden and m.host is None]
    at = next((k for k, m in enumerate(names) if m.name.upper() == r.path[-1]), None)
    run = names[at:at + need] if at is not None else []
    if len(run) < need or any(m.type.name != "DINT" or m.dim for m in run):
        return None
    return [m.name for m in run]


def rungs_resolve(ops: Operands, text: str, where):
    from . import rungs

    return rungs._resolve(text, where, ops.ctx)
