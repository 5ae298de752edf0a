"""Small hand-written L5X exports for tests: tags, programs of RLL routines
and tasks, written in the shape Studio 5000 exports them
(programs/logix/tank_line.L5X shows a whole one)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import escape


@dataclass
class Prog:
    name: str
    routines: dict[str, list[str] | str]  # routine name -> rung texts, in order; or Structured Text, one string
    main: str | None = None  # the first routine when None
    disabled: bool = False
    tags: list[tuple[str, str]] = field(default_factory=list)  # (name, data type)


@dataclass
class Task:
    name: str
    programs: list[str]
    kind: str = "CONTINUOUS"
    rate_ms: int | None = None
    priority: int = 10
    inhibited: bool = False
    watchdog_ms: int = 500


def _tag(name: str, data_type: str) -> str:
    dims = ""
    if "[" in data_type:
        data_type, _, rest = data_type.partition("[")
        dims = f' Dimensions="{rest.rstrip("]")}"'
    return (f'<Tag Name="{name}" TagType="Base" DataType="{data_type}"{dims} Constant="false" '
            f'ExternalAccess="Read/Write"/>')


def l5x_text(tags: list[tuple[str, str]], programs: list[Prog], tasks: list[Task], name: str = "Test",
             data_types: str = "") -> str:
    """``data_types``: the export's <DataType> elements, as XML text."""
    out = ['<?xml version="1.0" encoding="UTF-8" standalone="yes"?>',
           f'<RSLogix5000Content SchemaRevision="1.0" SoftwareRevision="33.01" TargetName="{name}" '
           'TargetType="Controller" ContainsContext="false">',
           f'<Controller Use="Target" Name="{name}" ProcessorType="1756-L83E" MajorRev="33" MinorRev="11">',
           f"<DataTypes>{data_types}</DataTypes>", "<AddOnInstructionDefinitions/>", "<Tags>"]
    out += [_tag(n, t) for n, t in tags]
    out += ["</Tags>", "<Programs>"]
    for p in programs:
        main = p.main or next(iter(p.routines))
        out.append(f'<Program Name="{p.name}" TestEdits="false" MainRoutineName="{main}" '
                   f'Disabled="{str(p.disabled).lower()}" UseAsFolder="false">')
        out += ["<Tags>"] + [_tag(n, t) for n, t in p.tags] + ["</Tags>", "<Routines>"]
        for routine, rungs in p.routines.items():
            if isinstance(rungs, str):
                out += [f'<Routine Name="{routine}" Type="ST">', "<STContent>"]
                for k, line in enumerate(rungs.split("\n")):
                    out += [f'<Line Number="{k}">', f"<![CDATA[{line}]]>", "</Line>"]
                out += ["</STContent>", "</Routine>"]
                continue
            out += [f'<Routine Name="{routine}" Type="RLL">', "<RLLContent>"]
            for k, text in enumerate(rungs):
                out += [f'<Rung Number="{k}" Type="N">', "<Text>", f"<![CDATA[{text}]]>", "</Text>", "</Rung>"]
            out += ["</RLLContent>", "</Routine>"]
        out += ["</Routines>", "</Program>"]
    out += ["</Programs>", "<Tasks>"]
    for t in tasks:
        rate = f' Rate="{t.rate_ms}"' if t.rate_ms is not None else ""
        out.append(f'<Task Name="{t.name}" Type="{t.kind}"{rate} Priority="{t.priority}" Watchdog="{t.watchdog_ms}" '
                   f'DisableUpdateOutputs="false" InhibitTask="{str(t.inhibited).lower()}">')
        out += ["<ScheduledPrograms>"] + [f'<ScheduledProgram Name="{escape(p)}"/>' for p in t.programs]
        out += ["</ScheduledPrograms>", "</Task>"]
    out += ["</Tasks>", "</Controller>", "</RSLogix5000Content>", ""]
    return "\n".join(out)


def write_l5x(path: Path, tags, programs, tasks, name: str = "Test", data_types: str = "") -> Path:
    path.write_text(l5x_text(tags, programs, tasks, name, data_types), encoding="utf-8")
    return path


def export_runner(path: Path, executor: str = "compiled"):
    """A Runner of the export at ``path`` on ``executor``, from the export's
    own values, saving nothing."""
    from softplc_lite.app import load_app
    from softplc_lite.runner import RunOptions, Runner

    return Runner(load_app(path), RunOptions(executor=executor, fresh=True, save_state=False))


def read_tag(runner, path: str):
    """The value of tag ``path`` (``Tanks[1].Level``) in ``runner``'s table."""
    return runner.table.read(runner.app.program.symbols.resolve_path(path))


def write_tag(runner, path: str, value) -> None:
    runner.table.write(runner.app.program.symbols.resolve_path(path), value)
