"""Small instructions that need no compiler template: NOP, and SLC's END.

- NOP (no operation): passes its rung-in condition on (SLC 500
  1747-RM001, "NOP"; Logix 1756-RM003 "No Operation").
- END: SLC 500 programs end each file with an END rung (1747-RM001, "Program
  Flow Control"); a text export carries it. Here it is a no-op end marker:
  it does nothing, and a rung after it still runs (a choice: an exported
  file has nothing after END).
"""

from __future__ import annotations

from ..bound import BoundInstruction
from ..specs import InstructionSpec


def _pass(instr, access):
    return _through


def _through(c: bool) -> bool:
    return c


INSTRUCTIONS = [
    BoundInstruction(InstructionSpec("NOP", "no operation", (), False), _pass),
    BoundInstruction(InstructionSpec("END", "end of program file (no-op marker)", (), True), _pass),
]
