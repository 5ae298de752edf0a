"""Online program edit, the engine's side: what changed between two
programs, and what an accepted edit writes into the live data table.

``program_changes(old, new)`` compares the rungs of each program file by
their canonical text (fmt.format_rung) with difflib.SequenceMatcher, so an
inserted rung is one rung added, not every later rung changed; a rung that
only moved is matched by its text and counted as moved. ``plan_edit``
checks an edit against the live data table without changing anything and
returns an EditPlan (what the table must gain and take, ``edit_writes``
for the preset rule, the module instances unchanged rungs keep);
``Engine.apply_edit`` applies it at a scan boundary (docs/engine.md,
"Online program edit").
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field

from ..datatable import DataTable, parse_address
from .ast import Pos, Program, walk
from .errors import LadderError
from .fmt import format_rung
from .layout import (data_values, instruction_writes, located, reference_module_blocks, reference_program,
                     write_data_value)


class EditRefused(Exception):
    """An edit the live data table cannot take (a file it needs exists with
    another type): nothing was changed. ``errors`` are located."""

    def __init__(self, errors: list[LadderError]) -> None:
        self.errors = errors
        super().__init__("\n".join(e.report() for e in errors))


@dataclass
class FileChanges:
    """One program file's rungs: numbers of the new program for added,
    changed and moved rungs, of the old one for removed rungs."""

    number: int
    added: list[int] = field(default_factory=list)
    removed: list[int] = field(default_factory=list)  # old rung numbers
    changed: list[int] = field(default_factory=list)
    moved: list[int] = field(default_factory=list)
    kept: dict[int, int] = field(default_factory=dict)  # old rung -> new rung, same text (moved ones too)
    status: str = "edited"  # "edited", "new" (the file is new), "deleted"

    def __bool__(self) -> bool:
        return bool(self.added or self.removed or self.changed or self.moved or self.status != "edited")

    def summary(self) -> str:
        if self.status == "new":
            return f"file {self.number}: new, {_count(len(self.added), 'rung')}"
        if self.status == "deleted":
            return f"file {self.number}: deleted ({_count(len(self.removed), 'rung')})"
        parts = []
        for label, rungs in (("added", self.added), ("removed", self.removed),
                             ("changed", self.changed), ("moved", self.moved)):
            if rungs:
                noun = ("rung " if len(rungs) == 1 else "rungs ") if not parts else ""
                was = "was " if label == "removed" else ""
                parts.append(f"{len(rungs)} {noun}{label} ({was}{_numbers(rungs)})")
        return f"file {self.number}: " + ", ".join(parts)


@dataclass
class ProgramChanges:
    """What an online edit changed, per program file (only files with a
    change are listed), plus what the data table gained (``created``, filled
    in by Engine.replace_program) and whether DATA/SYMBOL lines changed."""

    files: dict[int, FileChanges] = field(default_factory=dict)
    declarations_changed: bool = False
    created: list[str] = field(default_factory=list)  # "N10:0-N10:19", "T4:3"
    unchanged: frozenset[int] = frozenset()  # files in both programs with the same rungs

    def __bool__(self) -> bool:
        return bool(self.files or self.declarations_changed or self.created)

    def new_rung(self, file: int, old_rung: int) -> int | None:
        """Where old rung ``old_rung`` of ``file`` is in the new program when
        its text is unchanged (a breakpoint there stays); else None."""
        fc = self.files.get(file)
        if fc is None:
            return old_rung if file in self.unchanged else None
        return fc.kept.get(old_rung)

    def summary(self) -> str:
        """One line for a person: "file 2: 1 rung added (12), 1 changed (4)"."""
        parts = [fc.summary() for _, fc in sorted(self.files.items())]
        if self.declarations_changed:
            parts.append("DATA/SYMBOL lines changed")
        if self.created:
            parts.append("created " + ", ".join(self.created))
        return "; ".join(parts) if parts else "no rung changed"


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _numbers(rungs: list[int]) -> str:
    shown = ", ".join(str(r) for r in rungs[:8])
    return shown + (f", ... {len(rungs) - 8} more" if len(rungs) > 8 else "")


def rung_texts(program: Program, number: int) -> list[str]:
    return [format_rung(r) for r in program.files[number].rungs]


def program_changes(old: Program, new: Program) -> ProgramChanges:
    """The rungs added, removed, changed and moved in each program file."""
    changes = ProgramChanges()
    unchanged = set()
    for number in sorted(set(old.files) | set(new.files)):
        if number not in new.files:
            changes.files[number] = FileChanges(number, removed=list(range(len(old.files[number].rungs))),
                                                status="deleted")
            continue
        if number not in old.files:
            changes.files[number] = FileChanges(number, added=list(range(len(new.files[number].rungs))),
                                                status="new")
            continue
        fc = _file_changes(number, rung_texts(old, number), rung_texts(new, number))
        if fc:
            changes.files[number] = fc
        else:
            unchanged.add(number)
    changes.unchanged = frozenset(unchanged)
    changes.declarations_changed = (_declarations(old) != _declarations(new))
    return changes


def _declarations(program: Program) -> tuple:
    data = tuple((d.file, d.size, tuple(d.values)) for d in program.data)
    symbols = tuple(sorted((name, str(s.address)) for name, s in program.symbols.items()))
    return data, symbols


def _file_changes(number: int, old: list[str], new: list[str]) -> FileChanges:
    fc = FileChanges(number)
    matcher = difflib.SequenceMatcher(None, old, new, autojunk=False)
    removed: list[int] = []
    added: list[int] = []
    for op, i1, i2, j1, j2 in matcher.get_opcodes():
        if op == "equal":
            fc.kept.update(zip(range(i1, i2), range(j1, j2)))
        elif op == "replace":  # paired below: moved, or changed in place, or removed and added
            removed += range(i1, i2)
            added += range(j1, j2)
        elif op == "delete":
            removed += range(i1, i2)
        else:
            added += range(j1, j2)
    # a removed rung whose very text was added elsewhere only moved
    by_text: dict[str, list[int]] = {}
    for j in added:
        by_text.setdefault(new[j], []).append(j)
    still_removed = []
    for i in removed:
        places = by_text.get(old[i])
        if places:
            j = places.pop(0)
            fc.kept[i] = j
            fc.moved.append(j)
        else:
            still_removed.append(i)
    moved = set(fc.moved)
    still_added = [j for j in added if j not in moved]
    # the rest, in order: a removed rung and an added one at the same place are one rung changed
    pairs = _in_place(still_removed, still_added, matcher)
    paired_old = {i for i, _ in pairs}
    paired_new = {j for _, j in pairs}
    fc.changed = sorted(j for _, j in pairs)
    fc.removed = [i for i in still_removed if i not in paired_old]
    fc.added = [j for j in still_added if j not in paired_new]
    fc.moved.sort()
    return fc


_MAX_COMPARED = 2500  # rung pairs of one replaced block compared by text similarity, at most


def _in_place(removed: list[int], added: list[int], matcher) -> list[tuple[int, int]]:
    """Pairs (old, new) of one replace block's rungs that are one rung
    changed: in order, each new rung with the most similar old rung after
    the last one paired, when at least half their text is the same."""
    old, new = matcher.a, matcher.b
    removed_set, added_set = set(removed), set(added)
    pairs = []
    for op, i1, i2, j1, j2 in matcher.get_opcodes():
        if op != "replace":
            continue
        olds = [i for i in range(i1, i2) if i in removed_set]
        news = [j for j in range(j1, j2) if j in added_set]
        if len(olds) * len(news) > _MAX_COMPARED:  # a block rewritten wholesale: rung for rung, cheaply
            pairs += zip(olds, news)
            continue
        after = 0  # index into olds: pairs keep the rungs' order
        for j in news:
            scored = [(difflib.SequenceMatcher(None, old[i], new[j]).ratio(), k) for k, i in enumerate(olds)
                      if k >= after]
            if scored:
                ratio, k = max(scored, key=lambda rk: (rk[0], -rk[1]))
                if ratio >= 0.5:
                    pairs.append((olds[k], j))
                    after = k + 1
    return pairs


def kept_instructions(old: Program, new: Program, changes: ProgramChanges):
    """(old instruction, new instruction) of every rung whose text is
    unchanged (moved ones too): the module instances they may share."""
    for number, pfile in new.files.items():
        if number not in old.files:
            continue
        old_rungs = old.files[number].rungs
        if number in changes.files:
            pairs = changes.files[number].kept.items()
        elif number in changes.unchanged:
            pairs = ((k, k) for k in range(len(old_rungs)))
        else:
            continue
        for i, j in pairs:
            yield from zip(walk(old_rungs[i].elements), walk(pfile.rungs[j].elements))


_STATE_MEMBERS = frozenset({"ACC", "POS"})


def edit_writes(old_writes: list, new_writes: list, is_new) -> list:
    """What an accepted edit writes of the download values of instructions
    (timer/counter PRE and ACC, a control's LEN and POS): ``old_writes`` and
    ``new_writes`` are (address, value, pos) of each program, ``is_new(address)``
    says whether the edit created the element. A new element gets every
    value; an existing one its PRE/LEN when the instruction's operand
    differs from the old program's (RSLogix 5 writes an instruction's
    preset when the edit is accepted), its ACC/POS only when no instruction
    of the old program set that word (the running state is kept)."""
    before = {str(a): v for a, v, _ in old_writes}
    out = []
    for address, value, pos in new_writes:
        key = str(address)
        if is_new(address):
            out.append((address, value, pos))
        elif address.member in _STATE_MEMBERS:
            if key not in before:
                out.append((address, value, pos))
        elif before.get(key, object()) != value:
            out.append((address, value, pos))
    return out


def precompile(program: Program, settings) -> dict | None:
    """The compiled code of ``program`` in the code cache's form
    (codecache.export_file), compiled against a scratch table: what a
    background thread can do while the old program runs, so that the scan
    thread only binds it (codecache.import_file) at the scan boundary
    instead of compiling. None when some file cannot take that form (the
    scan thread then compiles)."""
    from .codecache import export_file
    from .compiler import compile_file
    from .semantics import Machine

    table = DataTable()
    reference_program(program, table)
    machine = Machine(table, settings)
    files = {}
    for number in sorted(program.files):
        compiled = compile_file(program, number, table, machine, _no_call, [True], _stand_in)
        data = export_file(compiled, program.files[number].rungs, machine, table)
        if data is None:
            return None
        files[number] = data
    return {"files": files}


def _no_call(*args) -> None:  # precompile's JSR and module instances: never run, only named
    raise AssertionError("precompiled code is bound again before it runs")


def _stand_in(ins, access):
    return _no_call


@dataclass
class EditPlan:
    """An accepted online edit, not yet applied (``plan_edit``): the
    program, what changed, the files and elements the live table has
    (``sizes``: file number -> elements), what the edit writes into it
    (address, value, pos), the instructions of unchanged rungs paired with
    their old selves (they keep their module instances), and the
    precompiled code if any. ``Engine.apply_edit`` applies it."""

    program: Program
    changes: ProgramChanges
    sizes: dict[int, int]
    writes: list
    kept: list[tuple]  # (old instruction, new instruction)
    owners: dict  # mnemonic -> module, as the engine hosts them
    code: dict | None = None

    def apply_to(self, table: DataTable) -> None:
        """Grow ``table`` to the new program and write the edit's values
        (the plan's trial showed the table takes them); ``changes.created``
        then says what the table gained."""
        reference_program(self.program, table)
        reference_module_blocks(self.program, table, self.owners)
        for address, value, _ in self.writes:
            write_data_value(table, address, value)
        self.changes.created = _created(self.sizes, table)


def plan_edit(engine, program: Program, code: dict | None = None) -> EditPlan:
    """What running ``program`` (validated) on ``engine`` from the next scan
    on, the data table kept, takes; nothing is changed. The files and
    elements it names are to be created; DATA values go into new elements
    only; instruction download values as ``edit_writes`` says; module
    instructions of unchanged rungs keep their instances. ``code``: the
    program's code from ``precompile``. Raises EditRefused when the table
    cannot take the program. Call between scans, from the scan thread (the
    plan reads the live table's layout)."""
    old = engine.program
    changes = program_changes(old, program)
    # On a table of the live one's layout: the live one is changed only when
    # everything fits (a file the program needs may exist with another type).
    trial = DataTable()
    for f in engine.table.files():
        trial.create_file(f.ftype.letter, f.number, f.size)
    problems: list[LadderError] = []
    owners = engine.module_owners
    reference_program(program, trial, problems)
    reference_module_blocks(program, trial, owners, problems)
    if problems:
        raise EditRefused(problems)
    sizes = {f.number: f.size for f in engine.table.files()}

    def is_new(address) -> bool:
        return address.element is not None and address.element >= sizes.get(address.file, 0)

    writes = [(address, value, decl.pos) for decl in program.data for address, value in data_values(decl)
              if is_new(address)]  # DATA values of new elements only: the others keep their live values
    writes += edit_writes(instruction_writes(old), instruction_writes(program), is_new)
    for address, value, pos in writes:
        with located(pos, problems):
            write_data_value(trial, address, value)
    if problems:
        raise EditRefused(problems)
    return EditPlan(program, changes, sizes, writes, list(kept_instructions(old, program, changes)), owners, code)


def build_refused(exc: Exception) -> EditRefused:
    """The refusal of an edit whose code could not be built (a bug in the
    compiler): the old code runs on, in a table that only grew."""
    problem = f"internal error building the new program: {type(exc).__name__}: {exc}"
    return EditRefused([LadderError(Pos("online edit", 0, 0), problem)])


def _created(sizes: dict[int, int], table: DataTable) -> list[str]:
    """What the table gained since ``sizes`` (file number -> elements)."""
    out = []
    for f in table.files():
        before = sizes.get(f.number)
        if before is None:
            out.append(f"{f.name} ({f.size} elements)")
        elif f.size > before:
            first = parse_address(f"{f.name}:0").with_element(before)
            last = first.with_element(f.size - 1)
            out.append(f"{first}" if f.size - before == 1 else f"{first}-{last}")
    return out
