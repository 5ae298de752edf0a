"""Finding, enabling and loading plug-in modules (TLMs).

Installed modules are the entry points of the group ``softplc_lite.tlms``:
the entry point's name is the module's name (``COMGENIUS``), its object a
``TLM`` subclass. A package adds one in its ``pyproject.toml``::

    [project.entry-points."softplc_lite.tlms"]
    MYTLM = "my_package.tlm:MyTLM"

softplc_lite registers COMGENIUS the same way; the engine has no special
case for it.

An app enables modules explicitly, as SoftPLC's MODULES.LST does: a file
``MODULES.LST`` in the app directory names one module a line, in any case;
``;`` starts a comment. Naming a module that is not installed is an error
that lists the installed ones; so are two modules claiming one mnemonic.

A module whose library is not installed fails at load with one line that
names the package (``_not_installed``): a ModuleNotFoundError met importing
the module, or a name of the module class's ``libraries`` (the libraries it
imports later: in a process of its own, on first use) that Python cannot
find.
"""

from __future__ import annotations

import os
import re
import shlex
import sys
from dataclasses import dataclass
from importlib.util import find_spec
from pathlib import Path
from typing import TYPE_CHECKING

from ..ladder.instructions import InstructionSet
from .api import TLM, find_file, read_module_file
from .errors import ModuleError, ModuleErrors

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

GROUP = "softplc_lite.tlms"
MODULES_FILE = "MODULES.LST"


def installed() -> dict[str, EntryPoint]:
    """Installed modules by upper-case name, in sorted order.

    Reading every installed distribution's metadata costs milliseconds, and
    a load asks several times, so the answer is kept while the import path
    and the modification times of its directories stay the same: installing
    or removing a distribution adds or removes a directory, which changes
    its parent's time (the rule Python's own import system uses for its
    directory caches)."""
    global _installed
    state = _import_path_state()
    if _installed is None or _installed[0] != state:
        from importlib.metadata import entry_points  # here: an app that enables no module never needs it (15 ms)

        found: dict[str, EntryPoint] = {}
        for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.name.upper(), e.value)):
            found.setdefault(ep.name.upper(), ep)
        _installed = (state, found)
    return dict(_installed[1])


_installed: tuple[tuple, dict[str, EntryPoint]] | None = None


def _import_path_state() -> tuple:
    state = []
    for entry in sys.path:
        try:
            state.append((entry, os.stat(entry or ".").st_mtime_ns))
        except OSError:
            state.append((entry, None))
    return tuple(state)


def _package(ep: EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    return f"package {dist.name}" if dist is not None else f"entry point {ep.value}"


def _requirement(ep: EntryPoint, library: str) -> str | None:
    """The requirement of the module's distribution that names ``library``
    (``pymodbus<3.17,>=3.16.1``), without its markers; None if none does."""
    dist = getattr(ep, "dist", None)
    wanted = _normal(library)
    for requirement in (dist.requires or []) if dist is not None else []:
        spec = requirement.split(";", 1)[0].strip()
        found = re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", spec)
        if found and _normal(found.group()) == wanted:
            return spec
    return None


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _not_installed(ep: EntryPoint, missing: str) -> str:
    """Why the module cannot load, the Python module ``missing`` (``pymodbus``,
    ``pymodbus.server``) not being found, in one line that names the package."""
    top = missing.split(".", 1)[0]
    if top == ep.module.split(".", 1)[0]:
        return (f"module {ep.name}: its own code ({missing}) is missing from its installation "
                f"({_package(ep)}: reinstall it)")
    requirement = _requirement(ep, top)
    pip = f"pip install {shlex.quote(requirement)}" if requirement else None
    if top == missing or find_spec(top) is None:
        return (f"module {ep.name} needs the Python package '{top}', which is not installed "
                f"({pip or 'install it into the Python that runs softplc'})")
    from importlib.metadata import packages_distributions

    have = ", ".join(f"{d} {_version(d)}" for d in packages_distributions().get(top, [])) or top
    return (f"module {ep.name} needs '{missing}', which the installed {have} does not have "
            f"({pip or 'the module may be written for another version of it'})")


def _version(dist: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(dist)
    except PackageNotFoundError:  # pragma: no cover - listed a moment ago
        return "?"


def _words(e: Exception) -> str:
    """An error of a module's own code, without Python's type names."""
    text = getattr(e, "msg", None) if isinstance(e, (ImportError, SyntaxError)) else None
    text = text or str(e)
    return f"an error in its code ({text})" if text else "an error in its code"


def _missing_library(factory: object) -> str | None:
    """The first of ``factory.libraries`` Python cannot find, if any."""
    for library in getattr(factory, "libraries", ()):
        try:
            if find_spec(library) is None:
                return library
        except ModuleNotFoundError:  # a dotted name whose package is missing
            return library
    return None


def load_module(name: str, available: dict[str, EntryPoint] | None = None, path: str | None = None,
                line: int = 0) -> TLM:
    """A new instance of the installed module ``name`` (any case); ``path``
    and ``line`` locate a problem (where MODULES.LST names the module)."""
    available = installed() if available is None else available
    ep = available.get(name.upper())
    if ep is None:
        names = ", ".join(available) or "none"
        raise ModuleError(f"no module named {name!r} is installed (installed modules: {names})", path, line)
    try:
        factory = ep.load()
    except ModuleNotFoundError as e:  # a library the module imports is not installed
        if not e.name:
            raise ModuleError(f"module {ep.name} ({_package(ep)}) failed to load: {e}", path, line) from None
        raise ModuleError(_not_installed(ep, e.name), path, line) from None
    except Exception as e:  # any other import failure of third-party code: said in words, the way to see it
        raise ModuleError(f"module {ep.name} ({_package(ep)}) failed to load: {_words(e)} "
                          f"(python -c 'import {ep.module}' shows where)", path, line) from None
    missing = _missing_library(factory)
    if missing is not None:
        raise ModuleError(_not_installed(ep, missing), path, line)
    try:
        module = factory()
    except Exception as e:
        raise ModuleError(f"module {ep.name} ({_package(ep)}) failed to start: {_words(e)}", path, line) from None
    if not isinstance(module, TLM):
        raise ModuleError(f"module {ep.name} ({_package(ep)}): {ep.value} is not a softplc_lite.tlm.TLM", path, line)
    module.name = ep.name.upper()
    return module


@dataclass(frozen=True)
class Enabled:
    name: str  # upper case
    line: int


def _read_modules_lst(app_dir: Path) -> tuple[Path | None, list[Enabled], list[ModuleError]]:
    """MODULES.LST's modules (those of its good lines) and every problem of its lines."""
    path = find_file(app_dir, MODULES_FILE)
    if path is None:
        return None, [], []
    text = read_module_file(path)
    out: list[Enabled] = []
    seen: dict[str, int] = {}
    problems: list[ModuleError] = []  # every one, not just the first (softplc check)
    for number, raw in enumerate(text.splitlines(), start=1):
        content = raw.split(";", 1)[0].strip()
        if not content:
            continue
        if len(content.split()) != 1:
            problems.append(ModuleError(f"expected one module name on the line, found {content!r}", str(path),
                                        number))
            continue
        name = content.upper()
        if name in seen:
            problems.append(ModuleError(f"module {name} is named twice (first on line {seen[name]})", str(path),
                                        number))
            continue
        seen[name] = number
        out.append(Enabled(name, number))
    return path, out, problems


def load_modules(app_dir: Path | None, configure: bool = True) -> tuple[list[TLM], list[str]]:
    """Load (and configure) the modules an app enables; returns them and the
    warnings their configs gave. ModuleError for any problem."""
    if app_dir is None:
        return [], []
    path, enabled, problems = _read_modules_lst(app_dir)  # every problem of the file, not just the first
    available = installed() if enabled else {}
    modules: list[TLM] = []
    warnings: list[str] = []
    for entry in enabled:
        if entry.name not in available:
            names = ", ".join(available) or "none"
            problems.append(ModuleError(f"module {entry.name} is not installed (installed modules: {names})",
                                        str(path), entry.line))
            continue
        try:
            modules.append(load_module(entry.name, available, str(path), entry.line))
        except ModuleError as e:
            problems.append(e)
    if problems:
        raise problems[0] if len(problems) == 1 else ModuleErrors(problems)
    instruction_set(modules)  # two modules claiming one mnemonic: an error now, not at run time
    if configure:
        warnings, problems = configure_modules(modules, app_dir)
        if problems:
            raise ModuleErrors(problems)
    return modules, warnings


def configure_modules(modules: list[TLM], app_dir: Path,
                      configured: list[TLM] | None = None) -> tuple[list[str], list[ModuleError]]:
    """Let each module read its config: the warnings, and every problem of
    every module's file (one module's bad file does not hide another's).
    ``configured``, when given, receives the modules whose config was read
    without a problem (their ports can still be checked)."""
    warnings: list[str] = []
    problems: list[ModuleError] = []
    for module in modules:
        try:
            warnings += module.configure(app_dir)
        except ModuleErrors as e:
            problems += e.problems
            continue
        except ModuleError as e:
            problems.append(e)
            continue
        if configured is not None:
            configured.append(module)
    return warnings, problems


def instruction_set(modules: list[TLM], hints: bool = False) -> InstructionSet:
    """Built-in instructions plus those of ``modules``. With ``hints``, the
    mnemonics of installed modules that are not enabled are remembered, so
    an unknown instruction can be told which module to enable."""
    extra = []
    for module in modules:
        for spec in module.instructions():
            if spec.module != module.name:
                raise ModuleError(f"module {module.name} declares {spec.mnemonic} as belonging to {spec.module}")
            extra.append(spec)
    enabled = {m.name for m in modules}

    def unavailable() -> dict[str, str]:
        found: dict[str, str] = {}
        for name in installed():
            if name in enabled:
                continue
            try:
                other = load_module(name)
                found.update({s.mnemonic: name for s in other.instructions()})
            except ModuleError:
                continue  # a broken module that is not enabled gives no hint
        return found

    try:
        return InstructionSet(extra, unavailable if hints else None)
    except ValueError as e:
        raise ModuleError(str(e)) from None
