"""Calls of Logix's function-block instructions in Structured Text:
``TONR(MyTimer);`` (and TOFR, RTOR on an FBD_TIMER, CTUD on an
FBD_COUNTER, OSRI and OSFI on an FBD_ONESHOT) translated into the bound
instruction with their rules (ladder/instr/logix_fbd.py), its operands the
tag's items: CTL (every BOOL member a bit of it, types.py), PRE, ACC and
Status as the instruction takes them, and the first-scan flag S:FS.

The program sets the structure's inputs (``MyTimer.PRE := 500;
MyTimer.TimerEnable := Run;``) and reads its outputs (``MyTimer.DN``) as
members; the call takes the tag alone (1756-PM007, "Function Block
Instructions": ``TONR(TONR_tag);``). Logix has these instructions in
function block diagrams and Structured Text, not in ladder (1756-RM003:
"This instruction is not available in ladder diagram"), so one in a rung
is an error of the export.
"""

from __future__ import annotations

from ..ladder.ast import AddressRef, Instruction
from . import operands
from .tags import STATUS_FLAGS, PathError

# Logix name -> (the bound instruction, its tag's type, the members it takes after CTL).
CALLS = {"TONR": ("LTONR", "FBD_TIMER", ("PRE", "ACC", "Status")),
         "TOFR": ("LTOFR", "FBD_TIMER", ("PRE", "ACC", "Status")),
         "RTOR": ("LRTOR", "FBD_TIMER", ("PRE", "ACC", "Status")),
         "CTUD": ("LCTUD", "FBD_COUNTER", ("PRE", "ACC")),
         "OSRI": ("LOSRI", "FBD_ONESHOT", ()),
         "OSFI": ("LOSFI", "FBD_ONESHOT", ())}


def translate(el, pos, rung, ctx):
    mnemonic, wanted, members = CALLS[el.mnemonic]
    if ctx.language != "ST":
        ctx.problem(pos, f"rung {rung.number}: {el.mnemonic} is a function-block instruction: Logix has it in "
                         f"Structured Text and function block diagrams, not in a ladder rung (1756-RM003)")
        return None

    def build(ops):
        ops.count(1)
        r = ops.resolve(0)
        if r.address is not None or r.dims or r.type.name != wanted:
            kind = f"{r.type.name} array" if r.dims else r.type.name
            raise PathError(f"expected an {wanted} tag, found {kind}")
        text = ops.text(0)
        where = ops.where(0)
        from .rungs import _resolve_ref

        items = [_resolve_ref(f"{text}.{m}", where, ctx) for m in ("CTL", *members)]
        if mnemonic != "LCTUD":
            items.append(AddressRef(STATUS_FLAGS["S:FS"], where))
        return [Instruction(mnemonic, items, pos)]

    return operands.translate(el, pos, rung, ctx, build)
