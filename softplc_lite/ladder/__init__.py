"""The ladder language, its compiler and the scan engine.

Pipeline (one module per stage): parser -> validate -> compiler (fast) or
interpreter (reference) -> engine. Quick use::

    >>> from softplc_lite.ladder import run_text
    >>> engine = run_text("XIC S:1/15 MOV 42 N7:0", scans=1)
    >>> engine.table.read("N7:0")
    42
"""

from __future__ import annotations

from ..datatable import DataTable
from .ast import Program
from .clocks import RealClock, SimulatedClock
from .engine import Engine
from .errors import LadderError, ProgramErrors
from .host import Mode, ModeError
from .parser import parse_program
from .semantics import MajorFault, Settings
from .validate import check, validate


def load_text(text: str, source: str = "<program>", instructions=None) -> Program:
    """Parse and validate one program text; raises ProgramErrors/LadderError.
    ``instructions``: an InstructionSet with module (TLM) instructions."""
    if instructions is None:
        from .instructions import BUILTIN as instructions
    return validate(parse_program(text, source, instructions), instructions)


def run_text(
    text: str,
    scans: int = 1,
    *,
    executor: str = "compiled",
    settings: Settings | None = None,
    table: DataTable | None = None,
    values: dict[str, object] | None = None,
    modules=(),
) -> Engine:
    """Load a program, write ``values`` (address -> value), put it in RUN and
    run ``scans`` scans on simulated time. Returns the engine. ``modules``:
    configured plug-in modules (ladder.host.Module) whose instructions the
    program may use, attached without run options."""
    instructions = None
    if modules:
        from .instructions import InstructionSet

        instructions = InstructionSet([spec for module in modules for spec in module.instructions()])
    engine = Engine(load_text(text, instructions=instructions), table=table, settings=settings,
                    executor=executor, modules=modules)
    for addr, value in (values or {}).items():
        engine.table.write(addr, value)
    engine.set_mode(Mode.RUN)
    engine.run(scans)
    return engine


__all__ = [
    "Engine", "LadderError", "MajorFault", "Mode", "ModeError", "Program", "ProgramErrors",
    "RealClock", "Settings", "SimulatedClock", "check", "load_text", "parse_program", "run_text", "validate",
]
