"""Loading a PLC app: a directory of .lad files and config, or one .lad file.

An app directory holds:

* ``*.lad``: program files (read in name order; FILE headers number them);
* ``softplc.toml``: optional app settings (see docs/engine.md);
* ``datatable.json``: optional initial data table values;
* module config files such as ``MODULES.LST`` and ``COMGENIUS.LST``
  (read by the plug-in modules);
* ``.softplc/``: the retentive snapshot, kept between runs.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from .ladder.ast import Pos, Program
from .ladder.errors import LadderError
from .ladder.parser import parse_program, syntax_problems
from .ladder.semantics import Settings
from .ladder.validate import check

SETTINGS_FILE = "softplc.toml"
DATATABLE_FILE = "datatable.json"
STATE_DIR = ".softplc"
SNAPSHOT_NAME = "datatable.snap"


class AppError(Exception):
    """A problem loading an app: missing path, bad config, program errors."""

    def __init__(self, errors: list[LadderError] | str) -> None:
        self.errors = errors if isinstance(errors, list) else []
        text = errors if isinstance(errors, str) else "\n".join(e.report() for e in errors)
        super().__init__(text)


@dataclass
class App:
    path: Path
    is_dir: bool
    lad_files: list[Path]
    program: Program  # validated
    settings: Settings
    source_program: Program  # as parsed (for fmt)
    datatable_json: Path | None = None
    state_dir: Path | None = None
    problems: list[LadderError] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.path.stem if not self.is_dir else self.path.name

    @property
    def snapshot_path(self) -> Path | None:
        return self.state_dir / SNAPSHOT_NAME if self.state_dir else None


def lad_files(path: Path) -> list[Path]:
    if path.is_dir():
        return sorted(p for p in path.glob("*.lad") if p.is_file())
    return [path]


def parse_files(files: list[Path], base: Path) -> tuple[Program, list[LadderError]]:
    """Parse every file. A file with a syntax error adds nothing to the
    program, but the problems after it in the file are listed too."""
    program = Program()
    errors: list[LadderError] = []
    for f in files:
        try:
            text = f.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            errors.append(LadderError(Pos(str(f), 1, 1), f"cannot read: {e}"))
            continue
        try:
            parse_program(text, _display(f, base), program=program)
        except LadderError as e:
            errors.extend(syntax_problems(text, _display(f, base)) or [e])
    return program, errors


def _display(f: Path, base: Path) -> str:
    try:
        return str(f.relative_to(Path.cwd()))
    except ValueError:
        return str(f)


def load_settings(path: Path) -> Settings:
    settings = Settings()
    if not path.exists():
        return settings
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise AppError(f"{path}: {e}") from None
    allowed = {
        "math": {"overflow": ("clamp", "wrap"), "divide_by_zero": ("overflow", "fault")},
        "scan": {"scan_ms": int, "watchdog_ms": int, "jsr_depth": int},
    }
    known = {f.name for f in fields(Settings)}
    for section, values in doc.items():
        if section not in allowed or not isinstance(values, dict):
            raise AppError(f"{path}: unknown section [{section}] (expected {', '.join(f'[{s}]' for s in allowed)})")
        for key, value in values.items():
            rule = allowed[section].get(key)
            if rule is None or key not in known:
                raise AppError(f"{path}: [{section}] has no setting {key!r} "
                               f"(settings: {', '.join(allowed[section])})")
            if isinstance(rule, tuple):
                if value not in rule:
                    raise AppError(f"{path}: [{section}] {key} = {value!r}; expected one of "
                                   f"{', '.join(repr(r) for r in rule)}")
            elif not isinstance(value, int) or isinstance(value, bool) or value < (0 if key == "scan_ms" else 1):
                raise AppError(f"{path}: [{section}] {key} = {value!r}; expected a positive integer")
            setattr(settings, key, value)
    return settings


def load_app(path: str | Path, state_dir: str | Path | None = None) -> App:
    """Parse, validate and configure an app; AppError lists every problem."""
    path = Path(path)
    if not path.exists():
        raise AppError(f"{path}: no such app directory or .lad file")
    is_dir = path.is_dir()
    files = lad_files(path)
    if is_dir and not files:
        raise AppError(f"{path}: the app directory has no .lad program files")
    if not is_dir and path.suffix.lower() != ".lad":
        raise AppError(f"{path}: expected an app directory or a .lad file")
    parsed, errors = parse_files(files, path)
    resolved, problems = check(parsed)
    errors += problems
    if errors:
        raise AppError(sorted(errors, key=lambda e: (e.pos.source, e.pos.line, e.pos.column)))
    settings = load_settings(path / SETTINGS_FILE) if is_dir else Settings()
    table_json = path / DATATABLE_FILE if is_dir and (path / DATATABLE_FILE).exists() else None
    if state_dir is not None:
        state = Path(state_dir)
    else:
        state = path / STATE_DIR if is_dir else None
    return App(path, is_dir, files, resolved, settings, parsed, table_json, state)
