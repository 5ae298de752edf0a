"""The tests' own layout (docs/testing.md, "Test helpers"): shared code in
the helpers package, test files independent of one another, benchmarks/
off sys.path. Checked on the files' text and syntax trees."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def _test_files() -> list[Path]:
    return sorted(TESTS.glob("test_*.py"))


def _imported(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_a_python_file_beside_the_tests_is_a_test_file_or_conftest():
    loose = [p.name for p in TESTS.glob("*.py") if not p.name.startswith("test_") and p.name != "conftest.py"]
    assert loose == [], f"move these into tests/helpers/: {loose}"


def test_no_test_file_imports_another():
    own = {p.stem for p in _test_files()}
    found = {p.name: sorted(_imported(p) & own) for p in _test_files()}
    assert {name: mods for name, mods in found.items() if mods} == {}


def test_no_test_puts_benchmarks_on_sys_path():
    # a benchmark module a test checks is loaded from its file (helpers.benchmark_modules)
    offenders = []
    for path in [*_test_files(), *sorted((TESTS / "helpers").glob("*.py")), TESTS / "conftest.py"]:
        if path == Path(__file__).resolve():
            continue
        for line in path.read_text(encoding="utf-8").splitlines():
            if ("sys.path.insert" in line or "sys.path.append" in line) and "benchmarks" in line:
                offenders.append(f"{path.name}: {line.strip()}")
    assert offenders == []
