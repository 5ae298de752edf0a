"""A Logix export (model.Project) made into a ladder program the engine
runs: its tags laid out over the data table (tags.py) with their initial
values as DATA declarations, each RLL routine a program file, and the
continuous task a main file that calls each scheduled program's main
routine in order. docs/logix.md says it for users; the rules:

- Program file 2 runs the tasks (tasks.py): the periodic tasks that are
  due, then the continuous task, one rung a scheduled program, a JSR to its
  main routine; an inhibited program or task is not run.
- Each routine is a program file from 3 up, in the export's order, then a
  file for each periodic task; JSR names a routine of its own program.
- An event task, a routine in ST, FBD or SFC, and an instruction
  softplc_lite does not run yet are not run: each is a warning at its place
  (``softplc check`` lists them; a run says them before scan 0), and a rung
  holding such an instruction is kept as an empty rung. Wrong exports (an
  unknown tag, a path that does not fit its type, bad rung text) are errors.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..datatable import DataTable
from ..ladder.ast import (MAIN_FILE, Const, DataDecl, Instruction, Listing, Program, ProgramFile, Rung, instructions_of,
                          walk)
from ..ladder.instr.logix import FAULT_JSR_PARAMETERS
from ..ladder.subroutine_check import subroutine_shape
from . import model
from .aoi import AoiCalls, add_types
from .initial import ValueWriter, apply_initial, data_files
from .modules import declare_module_tags
from .languages import routine_rungs
from .rungs import RoutineContext
from .subroutines import Subroutines
from .tags import TagDirectory, TagSymbols
from .tasks import Schedule
from .types import TypeSystem

NOT_RUN_KINDS = {"ST": "Structured Text", "FBD": "Function Block Diagram", "SFC": "Sequential Function Chart"}


@dataclass
class LogixProgram:
    """The ladder program of an export (not yet validated), its tag
    directory, and what was found: ``problems`` stop a load, ``warnings``
    name what is not run."""

    program: Program
    directory: TagDirectory
    problems: list[model.Problem] = field(default_factory=list)
    warnings: list[model.Problem] = field(default_factory=list)
    routine_files: dict[tuple[str, str], int] = field(default_factory=dict)  # (program, routine) -> file
    # RLL rungs of the export: how many, how many were made into ladder rungs that run, how many are
    # kept as a NOP (a warning says why), how many have errors (benchmarks/logix_corpus.py counts them)
    rungs: dict[str, int] = field(default_factory=lambda: {"total": 0, "run": 0, "not run": 0, "errors": 0})
    # ST statements, counted alike
    statements: dict[str, int] = field(default_factory=lambda: {"total": 0, "run": 0, "not run": 0, "errors": 0})


def build_program(project: model.Project) -> LogixProgram:
    types = TypeSystem()
    add_types(types, project.data_types, project.add_on_instructions)
    table = DataTable()
    directory = TagDirectory(table, types)
    result = LogixProgram(Program(symbols=TagSymbols(directory)), directory)
    problems, warnings = result.problems, result.warnings
    problems += types.problems
    for tag in project.tags:
        directory.declare(tag)
    declare_module_tags(project, directory, problems, warnings)
    for prog in project.programs:
        for tag in prog.tags:
            directory.declare(tag, prog.name)
    problems += directory.problems
    warnings += directory.warnings
    warnings += types.warnings

    writer = ValueWriter()
    aois = AoiCalls(project, directory, types)
    for scope in directory.scopes.values():
        for declared in scope.values():
            aois.defaults(declared, writer, problems)
            apply_initial(declared, writer, problems)
    schedule = Schedule(project, directory, writer, warnings)

    number = MAIN_FILE + 1
    for prog in project.programs:
        routines = {}
        for routine in prog.routines:
            routines[routine.name.upper()] = number
            result.routine_files[(prog.name.upper(), routine.name.upper())] = number
            number += 1
        not_passed: set[int] = set()  # routines whose SBR or RET has a parameter not passed
        calls = Subroutines(prog, directory)
        for routine in prog.routines:
            file_number = routines[routine.name.upper()]
            rungs, listing = _routine_rungs(routine, prog, directory, routines, project.source, problems, warnings,
                                            result, not_passed, file_number, aois, calls)
            result.program.files[file_number] = ProgramFile(file_number, f"{prog.name}.{routine.name}", rungs,
                                                            routine.pos, listing)
        _calls_not_run(prog, routines, result.program.files, not_passed, warnings, result.rungs)
    aois.check_uncalled(project.source, problems, warnings)
    made = aois.files(number)
    result.program.files.update(made)
    number += len(made)
    result.program.files.update(schedule.files(result.routine_files, number))
    _mismatched_calls(result.program, warnings)
    for letter, file, values in data_files(writer, table):
        result.program.data.append(DataDecl(f"{letter}{file}", len(values), values))
    written = {d.file for d in result.program.data}
    for f in table.files():  # every file the tags take exists in the engine's table, written or not
        if f.number >= 10 and f.name not in written:
            result.program.data.append(DataDecl(f.name, len(f.data) // f.ftype.words_per_element, []))
    return result


def _routine_rungs(routine, prog, directory, routines, source, problems, warnings, result, not_passed,
                   file_number, aois=None, calls=None) -> tuple[list[Rung], Listing | None]:
    if routine.kind not in ("RLL", "ST"):
        kind = NOT_RUN_KINDS.get(routine.kind, routine.kind)
        warnings.append(model.Problem(routine.pos, f"routine {prog.name}.{routine.name} is {kind}: not yet run "
                                                   f"by softplc_lite"))
        return [], None
    ctx = RoutineContext(directory, prog.name, routines, source, f"{prog.name}.{routine.name}")
    ctx.aoi = aois
    ctx.calls, ctx.name = calls, routine.name
    rungs, listing = routine_rungs(routine, ctx, result.rungs, result.statements)
    problems += ctx.problems
    warnings += ctx.warnings
    if ctx.parameters_not_run:
        not_passed.add(file_number)
    return rungs, listing


def _calls_not_run(prog, routines, files, not_passed, warnings, counts) -> None:
    """A JSR with parameters to a routine whose SBR or RET is not run (a
    parameter softplc_lite does not pass) is not run either: the call and
    the subroutine are said together, never half run."""
    if not not_passed:
        return
    names = {routines[r.name.upper()]: r.name for r in prog.routines}
    for number in routines.values():
        rungs = files[number].rungs
        for k, rung in enumerate(rungs):
            for ins in walk(rung.elements):
                if ins.mnemonic == "JSR" and len(ins.operands) > 1 and ins.operands[0].value in not_passed:
                    warnings.append(model.Problem(ins.pos, f"routine {prog.name}.{names[number]}: JSR to "
                                                           f"{names[ins.operands[0].value]}: its SBR or RET has a "
                                                           f"parameter not passed; the rung is not run"))
                    rungs[k] = Rung([Instruction("NOP", [], rung.pos)], rung.comment, rung.pos)
                    counts["run"] -= 1
                    counts["not run"] += 1
                    break


def _mismatched_calls(program: Program, warnings: list) -> None:
    """A JSR whose parameters do not match its routine's SBR or RETs loads
    in Logix and faults when it runs (major fault type 4, code 31: 1756-
    PM014): such a JSR becomes LFLT 31, said as a warning, instead of the
    load-time error the ladder gives a PLC-5 program."""
    shapes: dict[int, tuple] = {}

    def shape(number: int):
        if number not in shapes:
            sbr, rets = subroutine_shape(program, number) if number in program.files else (None, [])
            shapes[number] = (len(sbr.operands) if sbr is not None else 0, [len(r.operands) for r in rets])
        return shapes[number]

    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in instructions_of(rung.elements):
                if ins.mnemonic != "JSR" or not ins.operands or not isinstance(ins.operands[0], Const):
                    continue
                ops = ins.operands
                count = ops[1].value if len(ops) > 1 and isinstance(ops[1], Const) else 0
                returns = len(ops) - 2 - count if len(ops) > 1 else 0
                received, rets = shape(ops[0].value)
                if received == count and (not returns or (rets and all(n == returns for n in rets))):
                    continue
                target = program.files.get(ops[0].value)
                ins.mnemonic, ins.operands = "LFLT", [Const(FAULT_JSR_PARAMETERS, ins.pos)]
                warnings.append(model.Problem(ins.pos, f"JSR to {target.name if target else ops[0].value}: its "
                                                       f"parameters do not match the routine's SBR or RET; the rung "
                                                       f"faults when it runs (major fault type 4, code 31), as Logix "
                                                       f"does"))
