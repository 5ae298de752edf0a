"""A Logix export (model.Project) made into a ladder program the engine
runs: its tags laid out over the data table (tags.py) with their initial
values as DATA declarations, each RLL routine a program file, and the
continuous task a main file that calls each scheduled program's main
routine in order. docs/logix.md says it for users; the rules:

- Program file 2 is the continuous task: one rung a scheduled program, a
  JSR to its main routine, in the task's order (1756-PM005, "Tasks,
  programs and routines": the programs of a task run in the order they are
  scheduled). An inhibited program's rung is left out, as an inhibited
  program is not scanned. An export without a task (a program or routine
  export) runs each program's main routine, or its only routine.
- Each routine is a program file from 3 up, in the export's order; JSR
  names a routine of its own program.
- A periodic or event task, a routine in ST, FBD or SFC, and an instruction
  softplc_lite does not run yet are not run: each is a warning at its place
  (``softplc check`` lists them; a run says them before scan 0), and a rung
  holding such an instruction is kept as an empty rung. Wrong exports (an
  unknown tag, a path that does not fit its type, bad rung text) are errors.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..datatable import DataTable
from ..ladder.ast import MAIN_FILE, Const, DataDecl, Instruction, Pos, Program, ProgramFile, Rung
from . import model
from .initial import ValueWriter, apply_initial, data_files
from .modules import declare_module_tags
from .rungs import RoutineContext, translate_rung
from .tags import TagDirectory, TagSymbols
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


def build_program(project: model.Project) -> LogixProgram:
    types = TypeSystem()
    types.add_data_types(project.data_types)
    table = DataTable()
    directory = TagDirectory(table, types)
    result = LogixProgram(Program(symbols=TagSymbols(directory)), directory)
    problems, warnings = result.problems, result.warnings
    problems += types.problems
    for aoi in project.add_on_instructions:
        warnings.append(model.Problem(aoi.pos, f"Add-On Instruction {aoi.name}: not yet run by softplc_lite"))
    for tag in project.tags:
        directory.declare(tag)
    declare_module_tags(project, directory, problems, warnings)
    for prog in project.programs:
        for tag in prog.tags:
            directory.declare(tag, prog.name)
    problems += directory.problems
    warnings += directory.warnings

    writer = ValueWriter()
    for scope in directory.scopes.values():
        for declared in scope.values():
            apply_initial(declared, writer, problems)

    number = MAIN_FILE + 1
    for prog in project.programs:
        routines = {}
        for routine in prog.routines:
            routines[routine.name.upper()] = number
            result.routine_files[(prog.name.upper(), routine.name.upper())] = number
            number += 1
        for routine in prog.routines:
            file_number = routines[routine.name.upper()]
            rungs = _routine_rungs(routine, prog, directory, routines, project.source, problems, warnings,
                                   result.rungs)
            result.program.files[file_number] = ProgramFile(file_number, f"{prog.name}.{routine.name}", rungs,
                                                            routine.pos)
    result.program.files[MAIN_FILE] = ProgramFile(MAIN_FILE, "continuous task",
                                                  _task_rungs(project, result, warnings))
    for letter, file, values in data_files(writer, table):
        result.program.data.append(DataDecl(f"{letter}{file}", len(values), values))
    written = {d.file for d in result.program.data}
    for f in table.files():  # every file the tags take exists in the engine's table, written or not
        if f.number >= 10 and f.name not in written:
            result.program.data.append(DataDecl(f.name, len(f.data) // f.ftype.words_per_element, []))
    return result


def _routine_rungs(routine, prog, directory, routines, source, problems, warnings, counts) -> list[Rung]:
    if routine.kind != "RLL":
        kind = NOT_RUN_KINDS.get(routine.kind, routine.kind)
        warnings.append(model.Problem(routine.pos, f"routine {prog.name}.{routine.name} is {kind}: not yet run "
                                                   f"by softplc_lite"))
        return []
    ctx = RoutineContext(directory, prog.name, routines, source, f"{prog.name}.{routine.name}")
    rungs = []
    for rung in routine.rungs:
        translated = translate_rung(rung, ctx)
        counts["total"] += 1
        if translated is None:  # its problems are errors: the program does not run
            translated = Rung([Instruction("NOP", [], rung.pos)], rung.comment, rung.pos)
            counts["errors"] += 1
        else:
            counts["not run" if ctx.skip else "run"] += 1
        rungs.append(translated)
    problems += ctx.problems
    warnings += ctx.warnings
    return rungs


def _task_rungs(project: model.Project, result: LogixProgram, warnings) -> list[Rung]:
    programs = {p.name.upper(): p for p in project.programs}
    continuous = [t for t in project.tasks if t.kind.upper() == "CONTINUOUS" and not t.inhibited]
    for t in project.tasks:
        if t.kind.upper() != "CONTINUOUS":
            warnings.append(model.Problem(t.pos, f"{t.kind.lower()} task {t.name}: not yet scheduled by "
                                                 f"softplc_lite; its programs ({', '.join(t.programs) or 'none'}) "
                                                 f"do not run"))
    if project.tasks:
        names = [n for t in continuous for n in t.programs]
    else:
        names = [p.name for p in project.programs]
    rungs = []
    for name in names:
        prog = programs.get(name.upper())
        if prog is None or prog.disabled:
            continue
        main = prog.main_routine or (prog.routines[0].name if len(prog.routines) == 1 else None)
        file_number = result.routine_files.get((prog.name.upper(), (main or "").upper()))
        if file_number is None:
            warnings.append(model.Problem(prog.pos, f"program {prog.name} has no main routine: not run"))
            continue
        pos = prog.pos if prog.pos.line else Pos(project.source, 0, 0)
        rungs.append(Rung([Instruction("JSR", [Const(file_number, pos)], pos)], f"program {prog.name}", pos))
    return rungs
