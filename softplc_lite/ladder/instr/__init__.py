"""Built-in instructions written as bound objects (see ladder/bound.py),
one module per group. Each group module lists its ``INSTRUCTIONS``
(BoundInstruction); this package collects them for the instruction
table, the compiler, the interpreter and the engine.

To add a group: write the module, add it to ``_GROUPS`` below, document
its instructions in docs/instructions.md with their AB citation.
"""

from __future__ import annotations

from importlib import import_module

from ..bound import BoundInstruction

# Group modules, in the order docs/instructions.md lists them.
_GROUPS = ("misc", "mathfn", "convert", "pid", "shift", "sequencer", "filemath", "logix", "logix_task", "logix_aoi",
           "logix_data", "logix_string", "logix_system", "logix_bits", "logix_st",
           "logix_fbd")


def _collect() -> dict[str, BoundInstruction]:
    table: dict[str, BoundInstruction] = {}
    for name in _GROUPS:
        for bi in import_module(f"{__name__}.{name}").INSTRUCTIONS:
            if bi.spec.mnemonic in table:
                raise ValueError(f"{bi.spec.mnemonic} is declared twice (in {name})")
            table[bi.spec.mnemonic] = bi
    return table


BOUND: dict[str, BoundInstruction] = _collect()
