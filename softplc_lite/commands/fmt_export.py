"""``softplc fmt EXPORT``: a Studio 5000 export's routines printed as text,
never the export rewritten (docs/logix.md, "fmt and an export").

The export is Studio 5000's file: its layout, its data and what it holds
beside the rungs are Studio's to write, so fmt neither rewrites nor checks
the layout of an export (``--write`` and ``--check`` refuse one, a choice).
What it prints is each program's RLL and ST routines in the routine forms
of an L5K export (1756-RM084, "Logix 5000 Controllers Import/Export":
``ROUTINE`` blocks of ``RC:`` rung comments and ``N:`` rungs, one rung a
line, its neutral text as the export has it, tag names, ``?`` operands and
all, its surrounding blanks trimmed; ``ST_ROUTINE`` blocks of the routine's
lines as written, each after a ``'``). A routine in another language (FBD,
SFC) is named with what it is. An export softplc check refuses is refused the same way, every
problem at once.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import LocatedError, shown_path
from ..ladder.errors import LadderError
from ..logix.model import ExportError, Project
from ..logix.project import build_program

SUFFIXES = (".l5x", ".l5k")
LANGUAGES = {"FBD": "Function Block Diagram", "SFC": "Sequential Function Chart"}


def is_export(path: str) -> bool:
    p = Path(path)
    return p.suffix.lower() in SUFFIXES and not p.is_dir()


def export_text(path: str) -> tuple[str | None, list]:
    """What fmt prints for the export at ``path``, or the problems that stop it."""
    from ..logix.load import read_export

    p = Path(path)
    if not p.exists():
        return None, [LocatedError(f"{shown_path(path)}: no such export file")]
    try:
        project = read_export(p, shown_path(path))
    except ExportError as e:
        return None, [LadderError(q.pos, q.message) for q in e.problems]
    except OSError as e:
        return None, [LocatedError(f"{shown_path(path)}: cannot read it: {e.strerror or e}")]
    made = build_program(project)
    if made.problems:
        return None, [LadderError(q.pos, q.message) for q in sorted(made.problems, key=lambda q: (q.pos.line,
                                                                                                   q.pos.column))]
    return routines_text(project), []


def routines_text(project: Project) -> str:
    out: list[str] = []
    for prog in project.programs:
        out.append(f"PROGRAM {prog.name}")
        for routine in prog.routines:
            if routine.kind == "ST" and not routine.encoded:
                out.append(f"    ST_ROUTINE {routine.name}")
                out += [f"        '{line.text.rstrip()}" for line in routine.lines]
                out.append("    END_ST_ROUTINE")
                continue
            out.append(f"    ROUTINE {routine.name}")
            if routine.kind != "RLL":
                out.append(f"        // {LANGUAGES.get(routine.kind, routine.kind)}: fmt prints RLL and ST routines")
            elif routine.encoded:
                out.append("        // source-protected: its rungs cannot be read")
            for rung in routine.rungs if routine.kind == "RLL" else ():
                if rung.comment:
                    out.append(f'        RC: "{_escaped(rung.comment)}";')
                text = " ".join(rung.text.split("\n")).strip()
                out.append(f"        N: {text if text.endswith(';') else text + ';'}")
            out.append("    END_ROUTINE")
        out.append("END_PROGRAM")
    return "".join(line + "\n" for line in out)


def _escaped(text: str) -> str:
    """A comment as an L5K string: ``$`` escapes as in IEC 61131-3 string
    literals (``$$``, ``$"``, ``$N`` a line break, ``$T`` a tab)."""
    text = text.replace("\r\n", "\n").strip("\n")
    return text.replace("$", "$$").replace('"', '$"').replace("\n", "$N").replace("\t", "$T")
