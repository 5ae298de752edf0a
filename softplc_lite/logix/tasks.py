"""An export's tasks made into program files: program file 2 runs the
periodic tasks that are due, then the continuous task's programs; each
periodic task is a program file of its own that calls its programs' main
routines. docs/logix.md ("Tasks") says it for users; the rules:

- The continuous task's programs run in their scheduled order, one rung
  each, ``XIO(task inhibit) XIO(program disable) JSR(main routine)``
  (1756-PM005, "Manage tasks": a task's programs run in the order they are
  scheduled). An export without a task (a program or routine export) runs
  each program's main routine, or its only routine.
- A periodic task is a rung at the start of file 2, in priority order (1
  highest, then the export's order): ``LBL k XIO(task inhibit)
  LPER(rate, ctl, next, overlaps, watchdog) JSR(task file) JMP(k)``. LPER
  (ladder/instr/logix_task.py) is true once for each period of the engine's
  clock that has ended since the task last ran, so the task runs as many
  times as periods have passed, before the continuous task's rungs (a
  softplc choice: Logix interrupts the continuous task when the period
  ends, PM005 "Manage tasks"; softplc_lite's scan is not interrupted). A
  run longer than the task's Watchdog is a major fault.
- Every program has a disable bit, every task an inhibit bit, in the data
  table, set from the export (``Disabled="true"``, ``InhibitTask="true"``)
  and settable while running: PM005's "Inhibit a program" and "Inhibit a
  task". The directory's ``objects`` names them, with each periodic
  task's overlap count, as GSV/SSV attributes: (``PROGRAM``, name,
  ``DISABLEFLAG``), (``TASK``, name, ``INHIBITTASK``), (``TASK``, name,
  ``OVERLAPCOUNT``).
- An event task is not run: softplc_lite raises none of the events that
  trigger one; a warning names it.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..datatable import Address
from ..ladder.ast import MAIN_FILE, AddressRef, Const, Instruction, Pos, ProgramFile, Rung
from . import model
from .initial import ValueWriter
from .tags import STATUS_FLAGS, WORD_BITS, TagDirectory


@dataclass
class Periodic:
    task: model.Task
    rate: int  # ms
    inhibit: Address
    ctl: Address
    next: Address
    overlaps: Address


class Schedule:
    """The tasks' and programs' state laid out in the data table (at
    construction, before the routines are translated, so that their GSV and
    SSV find the attributes), and the program files that run them
    (``files``)."""

    def __init__(self, project: model.Project, directory: TagDirectory, writer: ValueWriter,
                 warnings: list[model.Problem]) -> None:
        self.project = project
        self.warnings = warnings
        self.disable: dict[str, Address] = {}
        self.inhibit: dict[str, Address] = {}
        self.periodic: list[Periodic] = []
        objects = directory.objects
        for prog in project.programs:
            self.disable[prog.name.upper()] = bit = _bit(directory, writer, prog.disabled)
            objects[("PROGRAM", prog.name.upper(), "DISABLEFLAG")] = bit
        for order, task in enumerate(project.tasks):
            kind = task.kind.upper()
            if kind == "EVENT":
                warnings.append(model.Problem(task.pos, f"event task {task.name}: not run: softplc_lite raises no "
                                                        f"event to trigger it (an input, a consumed tag, an axis, "
                                                        f"an EVENT instruction); its programs "
                                                        f"({', '.join(task.programs) or 'none'}) do not run"))
                continue
            if kind not in ("CONTINUOUS", "PERIODIC"):
                warnings.append(model.Problem(task.pos, f"task {task.name} of type {task.kind}: not run"))
                continue
            self.inhibit[task.name.upper()] = bit = _bit(directory, writer, task.inhibited)
            objects[("TASK", task.name.upper(), "INHIBITTASK")] = bit
            if kind == "PERIODIC":
                rate = task.rate_ms or 0
                if rate <= 0:
                    warnings.append(model.Problem(task.pos, f"periodic task {task.name} has no Rate: not run"))
                    continue
                if rate != int(rate):
                    warnings.append(model.Problem(task.pos, f"periodic task {task.name}: Rate {rate:g} ms runs "
                                                            f"every {max(round(rate), 1)} ms (softplc_lite's "
                                                            f"clock counts whole milliseconds)"))
                ctl, nxt, overlaps = (_item(directory) for _ in range(3))
                objects[("TASK", task.name.upper(), "OVERLAPCOUNT")] = overlaps
                self.periodic.append(Periodic(task, max(round(rate), 1), bit, ctl, nxt, overlaps))
        self.periodic.sort(key=lambda p: p.task.priority)  # stable: equal priorities keep the export's order
        # what GSV reads of each task's schedule (1756-RM003, GSV/SSV objects, TASK: Rate and Watchdog
        # in microseconds); logix/system.py does not let SSV change them
        for task in project.tasks:
            if ("TASK", task.name.upper(), "INHIBITTASK") not in objects:
                continue
            for attribute, value in (("PRIORITY", task.priority), ("WATCHDOG", round(task.watchdog_ms * 1000)),
                                     ("RATE", round((task.rate_ms or 0) * 1000))):
                leaf = directory.alloc.one("L")
                writer.put(leaf, 0, value)
                objects[("TASK", task.name.upper(), attribute)] = Address("L", leaf.file, leaf.first, None, None)

    def files(self, routine_files: dict[tuple[str, str], int], first_file: int) -> dict[int, ProgramFile]:
        """Program file 2 and a file for each periodic task (numbered from
        ``first_file``)."""
        project = self.project
        where = Pos(project.source, 0, 0)
        files: dict[int, ProgramFile] = {}
        main: list[Rung] = []
        for p in self.periodic:
            pos = p.task.pos if p.task.pos.line else where
            scheduled = Address(p.ctl.type_letter, p.ctl.file, p.ctl.element, None, 0)
            main.append(Rung([_ins("XIC", pos, STATUS_FLAGS["S:FS"]), _ins("OTU", pos, scheduled)],
                             f"periodic task {p.task.name}: scheduled anew at the first scan", pos))
        for label, p in enumerate(self.periodic):
            pos = p.task.pos if p.task.pos.line else where
            number = first_file + label
            files[number] = ProgramFile(number, f"task {p.task.name}", self._program_rungs(
                p.task.programs, routine_files, None), pos)
            main.append(Rung([Instruction("LBL", [Const(label, pos)], pos), _ins("XIO", pos, p.inhibit),
                              Instruction("LPER", [Const(p.rate, pos), AddressRef(p.ctl, pos),
                                                   AddressRef(p.next, pos), AddressRef(p.overlaps, pos),
                                                   Const(max(round(p.task.watchdog_ms), 1), pos)], pos),
                              Instruction("JSR", [Const(number, pos)], pos),
                              Instruction("JMP", [Const(label, pos)], pos)],
                             f"periodic task {p.task.name}: every {p.rate} ms, priority {p.task.priority}", pos))
        if project.tasks:
            for task in project.tasks:
                if task.kind.upper() == "CONTINUOUS":
                    main += self._program_rungs(task.programs, routine_files, self.inhibit[task.name.upper()])
        else:
            main += self._program_rungs([p.name for p in project.programs], routine_files, None)
        files[MAIN_FILE] = ProgramFile(MAIN_FILE, "continuous task", main)
        return files

    def _program_rungs(self, names: list[str], routine_files, task_inhibit: Address | None) -> list[Rung]:
        programs = {p.name.upper(): p for p in self.project.programs}
        rungs = []
        for name in names:
            prog = programs.get(name.upper())
            if prog is None:
                continue
            main = prog.main_routine or (prog.routines[0].name if len(prog.routines) == 1 else None)
            file_number = routine_files.get((prog.name.upper(), (main or "").upper()))
            if file_number is None:
                self.warnings.append(model.Problem(prog.pos, f"program {prog.name} has no main routine: not run"))
                continue
            pos = prog.pos if prog.pos.line else Pos(self.project.source, 0, 0)
            tests = [] if task_inhibit is None else [_ins("XIO", pos, task_inhibit)]
            tests.append(_ins("XIO", pos, self.disable[prog.name.upper()]))
            rungs.append(Rung(tests + [Instruction("JSR", [Const(file_number, pos)], pos)],
                              f"program {prog.name}", pos))
        return rungs


def _ins(mnemonic: str, pos: Pos, address: Address) -> Instruction:
    return Instruction(mnemonic, [AddressRef(address, pos)], pos)


def _bit(directory: TagDirectory, writer: ValueWriter, value: bool) -> Address:
    leaf = directory.alloc.one("B")
    if value:
        writer.put(leaf, 0, 1)
    return Address("B", leaf.file, leaf.first // WORD_BITS, None, leaf.first % WORD_BITS)


def _item(directory: TagDirectory) -> Address:
    leaf = directory.alloc.one("L")
    return Address("L", leaf.file, leaf.first, None, None)
