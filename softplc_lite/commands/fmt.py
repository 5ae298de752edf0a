"""``softplc fmt``: print, check or rewrite .lad files canonically.

``fmt_command`` is the whole command (``run`` hands it the parsed options):
every PATH (a .lad file, an app directory: each of its .lad files, or
``-``: standard input) is parsed with the instructions of its app (built-in
plus the modules MODULES.LST enables) and printed by
``ladder.fmt.format_source``, which keeps every comment.

* A file fmt cannot parse, or a program ``softplc check`` refuses, is refused: every problem, as file:line:col, on
  standard error, "N problems found", exit 1; with ``--write`` nothing is
  written, not even the files that were fine.
* ``--check``: exit 1 naming each file whose text is not what fmt prints
  ("would reformat PATH"), 0 when all are; nothing else is printed.
* A Studio 5000 export (``.L5X``, ``.L5K``) is printed as the text of its
  routines (fmt_export.py), never rewritten: ``--check`` and ``--write``
  refuse one.
* ``--write``: each file that changes is replaced atomically (a temporary
  file in the same directory, then a rename; its permission bits kept).
  fmt writes UTF-8 without a BOM and LF line ends, whatever it read.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Sequence

from ..app import AppError, app_instructions, lad_files
from ..errors import LocatedError, file_error, shown_path
from ..ladder.errors import LadderError
from ..ladder.fmt import STYLES, format_source, unprintable
from ..ladder.ast import Program
from ..ladder.parser import parse_program, syntax_problems
from ..ladder.validate import check
from ..textfile import PROGRAM, decode_text, read_bytes
from .common import EXIT_ERROR, EXIT_OK
from .fmt_export import export_text, is_export

NAME = "fmt"
STDIN = "-"


def add_parser(sub) -> argparse.ArgumentParser:
    f = sub.add_parser(NAME, help="print, check or rewrite .lad programs canonically, keeping every comment",
                       description="Print each .lad file (an app directory: each of its .lad files; -: standard "
                                   "input) canonically, keeping every comment; what does not parse is refused "
                                   "(exit 1, every problem listed). See docs/language.md.")
    f.add_argument("paths", nargs="+", metavar="PATH",
                   help=".lad file, app directory, or - for standard input; a Studio 5000 export (.L5X, .L5K) "
                        "is printed as its routines' rungs, never rewritten")
    f.add_argument("--style", choices=STYLES, default="mnemonic",
                   help="mnemonic (XIC B3/0 OTE O:0/0; the default) or neutral text (XIC(B3/0)OTE(O:0/0);)")
    mode = f.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="print nothing; exit 1 naming each file that is not formatted (a CI gate)")
    mode.add_argument("--write", action="store_true",
                      help="rewrite each file that changes in place, atomically; nothing is written if a file "
                           "is refused")
    f.set_defaults(func=run)
    return f


def run(args: argparse.Namespace) -> int:
    return fmt_command(args.paths, args.style, check=args.check, write=args.write)


@dataclass
class Formatted:
    name: str  # as given (a file of an app directory: its path), "<stdin>" for -
    path: Path | None  # None for standard input
    raw: bytes  # as read
    after: str

    @property
    def changed(self) -> bool:
        return self.raw != self.after.encode("utf-8")


def _format_text(text: str, name: str, style: str, instructions) -> tuple[str | None, list]:
    """What fmt prints for ``text``, or the problems that stop it."""
    problems: list = []
    try:
        program = parse_program(text, name, instructions, problems=problems)
    except LadderError as e:
        return None, syntax_problems(text, name, instructions=instructions) or [e]
    if problems:
        return None, problems
    found = unprintable(program, style, instructions)
    if found:
        return None, found
    return format_source(program, text, style), []


def _invalid(texts: dict, instruction_sets: dict) -> list:
    """What ``softplc check`` would refuse in the programs being formatted
    (the files of one app directory together: a JSR may call a file of
    another .lad file): fmt prints only valid programs."""
    problems: list = []
    for key, files in texts.items():
        program = Program()
        for name, text in files:
            parse_program(text, name, instruction_sets[key], program=program)
        problems += check(program, instruction_sets[key])[1]
    return problems


def _sources(paths: Sequence[str], stdin: IO[bytes]) -> tuple[list[tuple[str, Path | None, bytes, Path]], list]:
    """(name, path, bytes, app directory) of every file to format, and the problems finding them."""
    found, problems = [], []
    for given in paths:
        if given == STDIN:
            found.append(("<stdin>", None, stdin.read(), Path.cwd()))
            continue
        path = Path(given)
        if not os.path.lexists(path):
            problems.append(LocatedError(f"{shown_path(given)}: no such file or directory (expected a .lad file "
                                         "or an app directory)"))
            continue
        files = lad_files(path)
        if path.is_dir() and not files:
            problems.append(LocatedError(f"{shown_path(given)}: the directory has no .lad program files"))
        for f in files:
            if f.is_dir():
                problems.append(LocatedError(f"{shown_path(f)}: a directory, not a program file"))
                continue
            try:
                found.append((str(f), f, read_bytes(f, PROGRAM), path if path.is_dir() else path.parent))
            except OSError as e:
                problems.append(LocatedError(str(e)))
    return found, problems


def _write_atomically(path: Path, text: str) -> None:
    """Replace ``path`` by ``text`` (UTF-8): a reader sees the old file or the new, never half of one."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".fmt", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        shutil.copymode(path, tmp)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def fmt_command(paths: Sequence[str], style: str = "mnemonic", check: bool = False, write: bool = False,
                stdin: IO[bytes] | None = None, stdout: IO[str] | None = None,
                stderr: IO[str] | None = None) -> int:
    """The ``softplc fmt`` command; its exit code."""
    stdin = stdin if stdin is not None else sys.stdin.buffer
    stdout = stdout if stdout is not None else sys.stdout
    stderr = stderr if stderr is not None else sys.stderr
    if style not in STYLES:
        raise ValueError(f"style must be one of {', '.join(STYLES)}")
    exports = [p for p in paths if p != STDIN and is_export(p)]  # Studio's files: printed, never rewritten
    sources, problems = _sources([p for p in paths if p == STDIN or not is_export(p)], stdin)
    results: list[Formatted] = []
    printed: list[Formatted] = []
    for given in exports:
        if check or write:
            problems.append(LocatedError(f"{shown_path(given)}: a Studio 5000 export is Studio's file: fmt "
                                         f"--{'check' if check else 'write'} takes .lad files (softplc fmt "
                                         f"{shown_path(given)} prints its routines)"))
            continue
        after, found = export_text(given)
        problems += found
        if after is not None:
            printed.append(Formatted(given, None, b"", after))
    instruction_sets: dict[Path, object] = {}
    texts: dict[Path, list[tuple[str, str]]] = {}  # app directory -> (name, text) of its files being formatted
    for name, path, raw, app_dir in sources:
        try:
            text = decode_text(raw, name)
            key = app_dir.resolve()
            if key not in instruction_sets:
                instruction_sets[key] = app_instructions(app_dir)
        except LocatedError as e:
            problems.append(e)
            continue
        except AppError as e:  # MODULES.LST names a module that is not installed
            problems.append(LocatedError(str(e)))
            continue
        after, found = _format_text(text, name, style, instruction_sets[key])
        if found:
            problems += found
            continue
        results.append(Formatted(name, path, raw, after))
        texts.setdefault(key, []).append((name, text))
    if not problems:
        problems = _invalid(texts, instruction_sets)
    results += printed
    if problems:
        for p in problems:
            print(p.report(), file=stderr)
        print(f"{len(problems)} problem{'s' if len(problems) != 1 else ''} found; nothing formatted", file=stderr)
        return EXIT_ERROR
    if check:
        changed = [r for r in results if r.changed]
        for r in changed:
            print(f"would reformat {shown_path(r.name)}", file=stderr)
        return EXIT_ERROR if changed else EXIT_OK
    if write:
        status = EXIT_OK
        for r in results:
            if r.path is None:  # standard input has nowhere to be written back: print it
                stdout.write(r.after)
            elif r.changed:
                try:
                    _write_atomically(r.path, r.after)
                except OSError as e:
                    print(file_error(e, r.path, "write").report(), file=stderr)
                    status = EXIT_ERROR
                    continue
                print(f"reformatted {shown_path(r.name)}", file=stderr)
        return status
    for k, r in enumerate(results):
        if len(results) > 1:
            stdout.write(("\n" if k else "") + f"// ==> {shown_path(r.name)} <==\n")
        stdout.write(r.after)
    return EXIT_OK
