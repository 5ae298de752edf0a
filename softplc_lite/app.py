"""Loading a PLC app: a directory of .lad files and config, or one .lad file.

An app directory holds:

* ``*.lad``: program files (read in name order; FILE headers number them);
* ``softplc.toml``: optional app settings (see docs/engine.md);
* ``datatable.json``: optional initial data table values;
* ``MODULES.LST``: the plug-in modules (TLMs) the app enables, and their
  config files such as ``COMGENIUS.LST`` (read by the modules);
* ``.softplc/``: the retentive snapshot, kept between runs.
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from .datatable import DataTable, DataTableError, jsonio
from .errors import FileAccessError, LocatedError, shown_path
from .run_output import Display, display_names, parse_display
from .ladder.ast import Pos, Program, walk
from .ladder.errors import LadderError
from .ladder.instructions import BUILTIN, InstructionSet
from .ladder.parser import parse_program, syntax_problems
from .ladder.semantics import MAX_JSR_DEPTH, Settings
from .ladder.validate import check
from .ladder.codecache import CodeCache, apply_layout, cache_key, export_engine
from .ladder.verify import verify
from .ladder.layout import layout_problems
from .ports import claim_conflicts
from .ports.urlhandler.protocol_sim import url_problem as sim_url_problem
from .tlm.api import TLM, find_file
from .tlm.errors import ModuleError, ModuleErrors
from .tlm.registry import MODULES_FILE, configure_modules, installed, instruction_set, load_module, load_modules
from .textfile import PROGRAM, read_bytes, read_text

SETTINGS_FILE = "softplc.toml"
DATATABLE_FILE = "datatable.json"
STATE_DIR = ".softplc"
SNAPSHOT_NAME = "datatable.snap"


class AppError(Exception):
    """A problem loading an app: missing path, bad config, program errors."""

    def __init__(self, errors: list[LadderError | ModuleError] | str) -> None:
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
    source_program: Program | None  # as parsed (for fmt); None when loaded from the code cache
    datatable_json: Path | None = None
    state_dir: Path | None = None
    problems: list[LadderError] = field(default_factory=list)
    modules: list[TLM] = field(default_factory=list)  # enabled and configured
    instructions: InstructionSet = BUILTIN
    warnings: list[str] = field(default_factory=list)  # from module configs and checks
    display: Display = field(default_factory=Display)  # softplc.toml [display]: run's status line and summary
    # The code cache (ladder/codecache.py): compiled code loaded from it (None:
    # compiled at this load), its key, and the program's own warnings.
    code: dict | None = None
    cache_key: str | None = None
    program_warnings: list[str] = field(default_factory=list)
    code_cache: CodeCache | None = None
    logix: object | None = None  # a Studio 5000 export's tag directory and routines (logix/project.py)

    @property
    def name(self) -> str:
        """The app as messages name it: its directory's name (that of the
        directory it stands for when given as "." or ".."), or its file's
        stem."""
        if not self.is_dir:
            return shown_path(self.path.stem)
        name = self.path.name
        if name in ("", ".", ".."):
            name = self.path.resolve().name or str(self.path.resolve())  # "/" has no name
        return shown_path(name)

    @property
    def snapshot_path(self) -> Path | None:
        return self.state_dir / SNAPSHOT_NAME if self.state_dir else None


def lad_files(path: Path) -> list[Path]:
    """The program files of an app: every ``*.lad`` entry of the directory.
    One that cannot be a program file (a directory, a FIFO, a device, a
    dangling link) is still one: parse_files reports it by name, where
    leaving it out would leave its rungs or subroutine missing unexplained."""
    if path.is_dir():
        return sorted(path.glob("*.lad"))
    return [path]


def parse_files(files: list[Path], base: Path, instructions: InstructionSet = BUILTIN) -> tuple[Program, list[LadderError]]:
    """Parse every file. A file with a syntax error adds nothing to the
    program, but the problems after it in the file are listed too."""
    program = Program()
    errors: list[LadderError] = []
    for f in files:
        try:
            text = read_text(f, limit=PROGRAM)
        except LocatedError as e:
            errors.append(LadderError(Pos(_display(f, base), e.line, e.column), e.message))
            continue
        except FileAccessError as e:
            if f.is_dir():
                errors.append(_whole_file_error(_display(f, base), "a directory, not a program file"))
            else:
                errors.append(LadderError(Pos(_display(f, base), 1, 1), f"cannot read the file: {e.words}"))
            continue
        problems: list[LadderError] = []
        try:
            parse_program(text, _display(f, base), instructions, program=program, problems=problems)
            errors.extend(problems[:50])
        except LadderError as e:  # a syntax error: list every problem, resuming after each
            errors.extend(syntax_problems(text, _display(f, base), instructions=instructions) or [e])
    return program, errors


def _whole_file_error(source: str, message: str) -> LadderError:
    """A problem of a program file as a whole, reported as ``FILE: message``
    (no line: a directory has none); sorted with the file's others."""
    error = LadderError(Pos(source, 0, 0), message)
    error.args = (f"{source}: {message}",)
    return error


def _display(f: Path, base: Path) -> str:
    try:
        return shown_path(f.relative_to(Path.cwd()))
    except ValueError:
        return shown_path(f)


def read_settings_file(path: Path) -> dict:
    """softplc.toml as a dict ({} when the app has none); a syntax error
    names the file, line and column. A name that is there but cannot be read
    (a dangling or looping link, a directory) is reported, not taken for no
    file: the user meant settings to be read."""
    if not os.path.lexists(path):
        return {}
    try:
        text = read_text(path)
    except LocatedError as e:  # bad encoding
        raise AppError([e]) from None
    except FileAccessError as e:  # "cannot read APP/softplc.toml: permission denied"
        raise AppError(str(e)) from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        # tomllib says "... (at line 3, column 7)" or "(at end of document)": put it first, as everywhere
        m = re.search(r"\s*\(at line (\d+), column (\d+)\)$", str(e))
        message = str(e)[:m.start()] if m else re.sub(r"\s*\(at end of document\)$", "", str(e))
        line, column = (int(m.group(1)), int(m.group(2))) if m else (text.count("\n") + 1, 0)
        raise AppError([LocatedError(message, str(path), line, column)]) from None
    except ValueError:  # an integer past Python's 4,300-digit conversion limit
        m = re.search(r"[0-9_]{4000,}", text)
        line = text.count("\n", 0, m.start()) + 1 if m else 0
        raise AppError([LocatedError("a number too long to be any setting", str(path), line)]) from None
    except RecursionError:  # arrays or inline tables nested hundreds deep
        raise AppError([LocatedError("values nested too deeply for a setting", str(path),
                                     _nesting_line(text))]) from None
    doc["__text__"] = text  # for locating a bad value (load_settings); not a section
    return doc


def _nesting_line(text: str, limit: int = 100) -> int:
    """The line where brackets and braces (outside strings) first nest
    deeper than ``limit``; 0 if they never do."""
    depth, quote = 0, None
    line = 1
    for ch in text:
        if ch == "\n":
            line += 1
        elif quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
            if depth > limit:
                return line
        elif ch in "]}":
            depth -= 1
    return 0


# softplc.toml settings: section -> key -> allowed values (a tuple of choices,
# or an inclusive integer range). The ranges are what the engine can honour:
# S:8 and S:28 are 16-bit words, and the JSR nesting the engine runs without
# reaching Python's own recursion limit (docs/engine.md).
SCAN_MS_RANGE = range(0, 32768)  # also softplc run/watch --scan-ms
SETTING_RULES: dict[str, dict[str, tuple | range]] = {
    "math": {"overflow": ("clamp", "wrap"), "divide_by_zero": ("overflow", "fault")},
    "scan": {"scan_ms": SCAN_MS_RANGE, "watchdog_ms": range(1, 32768), "jsr_depth": range(1, MAX_JSR_DEPTH + 1)},
    "retentive": {"save_ms": range(0, 3_600_001)},
}


def _setting_line(text: str, section: str, key: str | None = None) -> int:
    """The line of ``[section]`` (or of ``key`` inside it) in a TOML text, 0
    when not found: tomllib gives no positions for valid documents."""
    current = ""  # keys before any [section] header
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("[") and "]" in stripped:
            current = stripped[1:stripped.index("]")].strip().strip('"')
            if key is None and current == section:
                return number
            continue
        if key is not None and current == section and "=" in stripped:
            if stripped.split("=", 1)[0].strip().strip('"') == key:
                return number
    return 0


def load_settings(path: Path, doc: dict | None = None) -> Settings:
    """The engine settings of softplc.toml (``doc``: the file already read).
    Every problem is listed, each with the file and line."""
    settings = Settings()
    if doc is None:
        doc = read_settings_file(path)
    text = doc.get("__text__", "")
    problems: list[LocatedError] = []

    def problem(message: str, section: str, key: str | None = None) -> None:
        problems.append(LocatedError(message, str(path), _setting_line(text, section, key)))

    known = {f.name for f in fields(Settings)}
    for section, values in doc.items():
        if section in ("display", "__text__"):  # [display] is read by load_display, once the symbols are known
            continue
        if not isinstance(values, dict):  # a key before any [section]
            home = next((f" (under [{name}]?)" for name, keys in SETTING_RULES.items() if section in keys), "")
            problems.append(LocatedError(f"{section} = ... is outside any section{home}; settings go under "
                                         f"{', '.join(f'[{s}]' for s in SETTING_RULES)}", str(path),
                                         _setting_line(text, "", section)))
            continue
        if section not in SETTING_RULES:
            problem(f"unknown section [{section}] (expected "
                    f"{', '.join(f'[{s}]' for s in [*SETTING_RULES, 'display'])})", section)
            continue
        for key, value in values.items():
            rule = SETTING_RULES[section].get(key)
            if rule is None or key not in known:
                problem(f"[{section}] has no setting {key!r} (settings: {', '.join(SETTING_RULES[section])})",
                        section, key)
            elif isinstance(rule, tuple):
                if value not in rule:
                    problem(f"[{section}] {key} = {_short(value)}; expected one of "
                            f"{', '.join(repr(r) for r in rule)}", section, key)
            elif not isinstance(value, int) or isinstance(value, bool) or value not in rule:
                problem(f"[{section}] {key} = {_short(value)}; expected an integer from "
                        f"{rule.start} to {rule.stop - 1}", section, key)
            else:
                setattr(settings, key, value)
    if problems:
        raise AppError(problems)
    return settings


def _short(value: object) -> str:
    """A config value for a message, never thousands of characters long."""
    text = repr(value) if not isinstance(value, int) or abs(value) < 10 ** 30 else f"<{value.bit_length()}-bit integer>"
    return text if len(text) <= 60 else text[:57] + "..."


def load_display(path: Path, symbols=None, doc: dict | None = None) -> Display:
    """The ``[display]`` section of softplc.toml (see run_output.py)."""
    if doc is None:
        doc = read_settings_file(path)
    if "display" not in doc:
        return Display()
    try:
        return parse_display(doc["display"], str(path), symbols)
    except DataTableError as e:
        message = str(e).removeprefix(f"{path}: ")
        raise AppError([LocatedError(message, str(path), _display_line(doc.get("__text__", ""), message))]) from None


def _display_line(text: str, message: str) -> int:
    """The line of [display] that a parse_display message is about: the
    first line of the section naming its label, else the section's header."""
    m = re.match(r"\[display\] (?:has )?(.+?) = ", message)
    label = m.group(1) if m else None
    header = _setting_line(text, "display")
    if label and header:
        for number, line in enumerate(text.splitlines()[header:], header + 1):
            if line.lstrip().startswith("["):
                break
            if label in line:
                return number
    return header


def display_problems(display: Display, table, path: Path, doc: dict) -> list[LocatedError]:
    """[display] values that the table a run starts with cannot show (an
    element past its file's end): located in softplc.toml."""
    text = doc.get("__text__", "")
    found = []
    for kind in ("status", "summary"):
        for item in getattr(display, kind):
            try:
                item.read(table)
            except DataTableError as e:
                found.append(LocatedError(f"[display] {kind} {item.label!r}: {e}", str(path),
                                          _setting_line(text, "display", kind) or _setting_line(text, "display")))
    return found


def load_app(path: str | Path, state_dir: str | Path | None = None, use_cache: bool = True,
             program: Program | None = None, program_key: str | None = None) -> App:
    """Parse, validate and configure an app; AppError lists every problem.
    With ``use_cache``, a program loaded before comes from the code cache in
    the state directory (ladder/codecache.py; check passes False).
    ``program``: a parsed program checked in place of the app's .lad files,
    the rest of the app (modules, settings, data) kept (mutation testing);
    the code cache is then used only with ``program_key``, a text that
    names that program among those loaded with the same state directory."""
    path = Path(path)
    if path.suffix.lower() in (".l5x", ".l5k") and not path.is_dir():
        return _load_export_app(path, state_dir, program)
    if program is not None:  # the cache is keyed by the files: it needs the program's own key
        use_cache = use_cache and program_key is not None
    if not path.exists():
        raise AppError(f"{shown_path(path)}: no such app directory or .lad file")
    is_dir = path.is_dir()
    files = lad_files(path)
    if is_dir and not files:
        raise AppError(f"{shown_path(path)}: the app directory has no .lad program files")
    if not is_dir and path.suffix.lower() != ".lad":
        raise AppError(f"{shown_path(path)}: expected an app directory or a .lad file")
    module_dir = path if is_dir else path.parent
    try:
        modules, _ = load_modules(module_dir, configure=False)
        instructions = instruction_set(modules, hints=True)
    except ModuleError as e:  # MODULES.LST: without the instruction set the program cannot be checked
        problems = list(e.problems) if isinstance(e, ModuleErrors) else [e]
        raise AppError(problems + _settings_problems(path / SETTINGS_FILE if is_dir else None)) from None
    # Every problem at once: the modules' config files, then the program's.
    configured: list[TLM] = []
    warnings, config_problems = configure_modules(modules, module_dir, configured)
    claims = [c for m in configured for c in m.port_claims()]  # a module whose config is bad has none
    if not config_problems:  # a conflict with a port of a bad config may be only a consequence
        config_problems = [ModuleError(c) for c in claim_conflicts(claims)]
    config_problems += [ModuleError(f"{c.where}: {c.module} port {c.number}: {problem}") for c in claims
                        if c.url.lower().startswith("sim://") and (problem := sim_url_problem(c.url))]
    warnings += _unused_configs(module_dir, modules)
    state = Path(state_dir) if state_dir is not None else (path / STATE_DIR if is_dir else None)
    cache = CodeCache(state) if use_cache and state is not None and not config_problems else None
    key = cached = None
    if cache is not None:
        try:
            parts = _cache_parts(files, path, modules)
            if program is not None:
                parts.append(("substituted program", program_key.encode("utf-8")))
            key = cache_key(parts)
        except OSError:  # a file the parse below reports, in words
            cache = None
        else:
            cached = cache.load(key)
            if cache.problem is not None:  # damaged, or not a file: the program is loaded from its text
                warnings.append(cache.problem)
    if cached is not None:
        # Loaded before from these very files: the validated program, its
        # warnings and compiled code (ladder/codecache.py), no parse or check.
        resolved, program_warnings, code = cached
        parsed, errors = None, []
        table = DataTable()
        try:
            apply_layout(table, code["layout"])  # the table check validates [display] and datatable.json against
        except Exception:  # not what a cache holds after all: load from the text
            cached = None
    if cached is None:
        parsed, errors = (program, []) if program is not None else parse_files(files, path, instructions)
        resolved, problems = check(parsed, instructions)
        errors += problems
        code = None
    if not errors and cached is None:
        # What run would refuse when it builds the table (N9 beside ST9, a
        # DATA string that is not UCS-2): check reports it first, located.
        table, layout = layout_problems(resolved, modules)
        errors += layout
    settings_problems: list = []
    settings, display = Settings(), Display()
    settings_doc = None
    if is_dir:
        try:
            settings_doc = read_settings_file(path / SETTINGS_FILE)
            settings = load_settings(path / SETTINGS_FILE, settings_doc)
            if not errors and not config_problems:  # else its addresses may only be missing as a consequence
                display = load_display(path / SETTINGS_FILE, resolved.symbols, settings_doc)
                settings_problems += display_problems(display, table, path / SETTINGS_FILE, settings_doc)
        except AppError as e:
            settings_problems += e.errors or [LocatedError(str(e))]
    table_json = path / DATATABLE_FILE if is_dir and os.path.lexists(path / DATATABLE_FILE) else None
    if table_json is not None and not errors:
        try:  # what a run without a snapshot loads: check it as well
            jsonio.load_file(table, str(table_json))
        except DataTableError as e:
            settings_problems.append(LocatedError(str(e)))
    if errors or config_problems or settings_problems:
        raise AppError(config_problems + settings_problems
                       + sorted(errors, key=lambda e: (e.pos.source, e.pos.line, e.pos.column)))
    if cached is None:
        program_warnings = [w.report() for w in _module_checks(resolved, modules)]
        # RSLogix-style verify (duplicate OTE, shared timers, rungs without output, unused symbols): warnings
        shown = display_names(settings_doc.get("display")) if is_dir and isinstance(settings_doc, dict) else set()
        program_warnings += [w.report() for w in verify(resolved, instructions, parsed, settings.overflow, shown)]
    warnings += program_warnings
    app = App(path, is_dir, files, resolved, settings, parsed, table_json, state,
              modules=modules, instructions=instructions, warnings=warnings, display=display)
    app.code, app.cache_key, app.program_warnings = code, key, program_warnings
    app.code_cache = cache
    return app


def _load_export_app(path: Path, state_dir: str | Path | None, program: Program | None = None) -> App:
    """A Studio 5000 export (.L5X, .L5K) as an app (logix/, docs/logix.md):
    its ladder program checked as any program is, Logix's integer overflow
    (wrap, 1756-RM003), no state directory unless --state names one. What
    it holds that is not run is said in its warnings. ``program``: a
    program made from the export's (a mutant) checked in its place, over
    the export's tags. An export is one file, so its one module is found
    beside it: ``<stem>.ENIPS.XML`` serves its tags over EtherNet/IP
    (docs/logix.md, "EtherNet/IP: Logix tags")."""
    from .logix.load import load_export
    from .logix.model import ExportError

    if not path.exists():
        raise AppError(f"{shown_path(path)}: no such export file")
    try:
        made = load_export(path, shown_path(path))
    except ExportError as e:
        raise AppError([LadderError(p.pos, p.message) for p in e.problems]) from None
    except OSError as e:
        raise AppError(f"{shown_path(path)}: cannot read it: {e.strerror or e}") from None
    if program is not None:
        made.program = program
    resolved, errors = check(made.program)
    if not errors:
        _, layout = layout_problems(resolved, [])
        errors += layout
    if errors:
        # an Add-On Instruction's logic is a file for each call (logix/aoi.py): a problem in it is said once
        said: set[str] = set()
        raise AppError([e for e in errors if not (e.report() in said or said.add(e.report()))])
    # a mutant is checked over the export's tags, and serves no client
    modules, warnings = _export_modules(path, made) if program is None else ([], [])
    app = App(path, False, [path], resolved, Settings(overflow="wrap"), made.program,
              state_dir=Path(state_dir) if state_dir is not None else None,
              warnings=warnings + [str(w) for w in made.warnings], modules=modules)
    app.logix = made
    return app


EXPORT_ENIPS = ".ENIPS.XML"
EXPORT_SERVERS = (("ENIPS", EXPORT_ENIPS), ("OPCUAS", ".OPCUAS.XML"))  # a server module, its config beside an export


def _export_modules(path: Path, made) -> tuple[list[TLM], list[str]]:
    """ENIPS configured from ``<stem>.ENIPS.XML`` beside the export, and
    OPCUAS from ``<stem>.OPCUAS.XML`` (any case); each absent, no module."""
    modules: list[TLM] = []
    warnings: list[str] = []
    for name, suffix in EXPORT_SERVERS:
        config = find_file(path.parent, path.stem + suffix)
        if config is None:
            continue
        try:
            module = load_module(name)
            # each program's name as spelled: its routines' files are named PROGRAM.ROUTINE
            programs = list(dict.fromkeys(made.program.files[n].name.split(".")[0]
                                          for n in made.routine_files.values()))
            warnings += module.configure_export(config, shown_path(path.stem), made.directory, programs)
        except ModuleErrors as e:
            raise AppError(list(e.problems)) from None
        except ModuleError as e:
            raise AppError([e]) from None
        modules.append(module)
    return modules, warnings


def _settings_problems(path: Path | None) -> list:
    """Every problem of softplc.toml on its own (when the program cannot be checked)."""
    if path is None:
        return []
    try:
        load_settings(path, read_settings_file(path))
    except AppError as e:
        return e.errors or [LocatedError(str(e))]
    return []


def _cache_parts(files: list[Path], path: Path, modules) -> list[tuple[str, bytes]]:
    """What an app's compiled code depends on, for its code cache key: every
    program file, the settings file, and each enabled module with its
    version and config file. A file is named as messages name it (from the
    current directory): the cached tree's positions hold that name."""
    base = path if path.is_dir() else path.parent
    parts = [(_display(f, base), read_bytes(f, PROGRAM)) for f in files]
    settings = base / SETTINGS_FILE
    parts.append((SETTINGS_FILE, read_bytes(settings) if os.path.lexists(settings) else b""))
    for m in modules:
        config = base / m.config_file if getattr(m, "config_file", None) else None
        parts.append((f"module {m.name} {getattr(m, 'version', '')} {type(m).__module__}",
                      read_bytes(config) if config is not None and config.exists() else b""))
    return parts


def save_code_cache(app: App, engine) -> None:
    """After a run's engine is built from a freshly checked program: keep its
    compiled code for the next load (nothing if it came from the cache)."""
    if app.code_cache is None or app.code is not None or app.cache_key is None:
        return
    code = export_engine(engine)
    if code is not None:
        app.code_cache.save(app.cache_key, app.program, app.program_warnings, code)


def app_instructions(path: Path) -> InstructionSet:
    """The instruction set of the app at ``path`` (a directory, or the
    directory of a .lad file): built-in plus its enabled modules'. Module
    configs are not read (for fmt)."""
    try:
        modules, _ = load_modules(path if path.is_dir() else path.parent, configure=False)
        return instruction_set(modules, hints=True)
    except ModuleError as e:
        raise AppError(e.report()) from None


def _module_checks(program: Program, modules: list[TLM]) -> list[LadderError]:
    """Each module's warnings about its own instructions (softplc check)."""
    owner = {spec.mnemonic: m for m in modules for spec in m.instructions()}
    found: list[LadderError] = []
    for pfile in program.files.values():
        for rung in pfile.rungs:
            for ins in walk(rung.elements):
                module = owner.get(ins.mnemonic)
                if module is not None:
                    found += module.check(ins)
    return sorted(found, key=lambda e: (e.pos.source, e.pos.line, e.pos.column))


# The files of an app directory that are softplc's own, never a module's config.
_OWN_FILES = {name.upper() for name in (MODULES_FILE, SETTINGS_FILE, DATATABLE_FILE)}


def _maybe_config_files(app_dir: Path) -> bool:
    """Whether ``app_dir`` holds any entry that could be a module's config file."""
    try:
        return any(not p.name.upper().endswith(".LAD") and p.name.upper() not in _OWN_FILES and not p.is_dir()
                   for p in app_dir.iterdir())
    except OSError:
        return True  # the modules' own lookups meet the error and say it


def _unused_configs(app_dir: Path, modules: list[TLM]) -> list[str]:
    """A module config file in the app directory whose module MODULES.LST
    does not enable: likely a forgotten line."""
    enabled = {m.name for m in modules}
    out: list[str] = []
    if not _maybe_config_files(app_dir):
        return out  # spares loading every installed module's code to learn its config file's name
    for name in installed():
        if name in enabled:
            continue
        try:
            config = load_module(name).config_file
        except ModuleError:
            continue
        found = find_file(app_dir, config) if config else None
        if found is not None:
            out.append(f"{found}: {name} is not enabled (add {name} to MODULES.LST), so this file is not read")
    return out
