"""What the scan engine needs of a plug-in module, and the modes it tells it.

The engine hosts modules without knowing any: it sees each one through
:class:`Module`, the whole of what it calls. ``softplc_lite.tlm`` builds
its module base class (``tlm.api.TLM``) on this one and adds what only the
loader, ``softplc check`` and the watch view use (configuration, port
claims, warnings). Run policy (which ``--port`` override goes to which
module, the ``--record`` recorder) is decided above the engine, by the
runner, and handed in as each module's attach options.

A module's life with one engine:

1. ``instructions()`` and ``references(instr)`` at load: the mnemonics it
   owns, and what its instructions reach beyond their operands;
2. ``attach(engine, options)`` once, before the first scan;
3. ``bind(engine, instr, access)`` once per instruction it owns (by
   default ``instance(engine, instr)``): the callable the executors run each
   scan with the rung-in condition, returning the rung-out condition;
4. ``on_input`` / ``on_output`` every scan at the input and output points,
   ``on_mode`` on each mode change (only those a module overrides are
   called: :func:`overrides`);
5. ``close()`` when the run ends.
"""

from __future__ import annotations

import enum
from typing import TYPE_CHECKING, Callable, Mapping

if TYPE_CHECKING:  # pragma: no cover - types only
    from .ast import Instruction
    from .bound import Access
    from .engine import Engine


class Mode(enum.Enum):
    PROGRAM = 0
    RUN = 1
    TEST = 2
    FAULTED = 3


# Which mode changes an operator may ask for (FAULTED is entered by faults).
TRANSITIONS = {
    Mode.PROGRAM: {Mode.RUN, Mode.TEST},
    Mode.RUN: {Mode.PROGRAM, Mode.TEST},
    Mode.TEST: {Mode.PROGRAM, Mode.RUN},
    Mode.FAULTED: {Mode.PROGRAM},  # clearing the fault
}


class ModeError(Exception):
    pass


Instance = Callable[[bool], bool]  # rung-in condition -> rung-out condition


class Module:
    """A plug-in module as the engine sees it. Every method has a default
    that does nothing, so a module overrides only what it uses."""

    name: str = ""
    config_file: str | None = None  # named in what ``softplc check`` reports about the module

    def instructions(self) -> list:
        """The module's instructions (ladder.specs.InstructionSpec)."""
        return []

    def references(self, instr: "Instruction") -> list:
        """Data table addresses one of the module's instructions reaches
        beyond its operands (the last word of a block operand), so that the
        engine grows those files as it does for COP."""
        return []

    def config_references(self) -> list:
        """Addresses the module's configuration makes exist in the data table
        when it attaches (MODBMAST's data blocks). ``softplc check`` builds the
        table a run would start with from these and references()."""
        return []

    def attach(self, engine: "Engine", options: Mapping[str, object]) -> list[str]:
        """An engine takes the module (before its first scan); return warnings."""
        return []

    def instance(self, engine: "Engine", instr: "Instruction") -> Instance:
        """The run-time callable of one of the module's instructions."""
        raise NotImplementedError(f"module {self.name} cannot run {instr.mnemonic}")

    def bind(self, engine: "Engine", instr: "Instruction", access: "Access") -> Instance:
        """The callable of one of the module's instructions for the executor
        that binds it: ``access`` (ladder.bound.Access) is how that executor
        reaches operands, as a built-in bound instruction's ``bind(instr,
        access)`` gets it. A module whose instances read their operands
        through it runs under the executor differential test like a built-in
        instruction. By default: ``instance(engine, instr)``."""
        return self.instance(engine, instr)

    # driver hooks: the engine calls only those a module overrides
    def on_input(self, engine: "Engine") -> None:
        pass

    def on_output(self, engine: "Engine", outputs_enabled: bool) -> None:
        pass

    def on_mode(self, engine: "Engine", old: Mode, new: Mode) -> None:
        pass

    def close(self) -> None:
        pass


def overrides(module: object, hook: str) -> bool:
    """Does ``module`` implement ``hook`` (so the engine must call it)?"""
    implementation = getattr(type(module), hook, None)
    return implementation is not None and implementation is not getattr(Module, hook)
