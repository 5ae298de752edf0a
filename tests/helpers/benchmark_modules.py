"""Modules of ``benchmarks/`` that tests check (the programs the ladder
benchmark generates, its straight-line baseline), loaded from their files.

``benchmarks/`` does not go on ``sys.path``: its scripts' module names
(``_common``, ``ladder_programs``...) would then be importable by any test,
and a test would depend on the order the run imported them in. A module is
loaded once per process, under ``benchmarks.NAME``."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def load(name: str) -> ModuleType:
    """``benchmarks/NAME.py`` as a module (registered in ``sys.modules``,
    which dataclasses need to resolve the module's annotations)."""
    key = f"benchmarks.{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, BENCHMARKS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[key]
            raise
    return sys.modules[key]
