"""The import rules of docs/architecture.md, read from its ``layers`` table:
a module imports its own unit and lower layers only; units of one layer are
independent; every module belongs to a unit of the table."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "softplc_lite"
MAP = ROOT / "docs" / "architecture.md"


def layers(text: str) -> dict[str, int]:
    """unit (a dotted module or package name) -> its layer, from the page's
    fenced ``layers`` block."""
    block = re.search(r"```layers\n(.*?)```", text, re.S)
    assert block, "docs/architecture.md has no ```layers block"
    table: dict[str, int] = {}
    for line in block.group(1).splitlines():
        number, *units = line.split()
        for unit in units:
            assert unit not in table, f"{unit} is in two layers"
            table[unit] = int(number)
    return table


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(source: str, module: str, is_package: bool) -> list[tuple[str, int]]:
    """(imported module, line) for every import in ``source``, relative ones
    made absolute; ``from X import name`` counts as X.name (a submodule, or a
    name of X: the unit is the same either way)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".") if is_package else module.split(".")[:-1]
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found += [(f"{target}.{alias.name}", node.lineno) for alias in node.names]
    return found


def unit_of(name: str, table: dict[str, int]) -> str | None:
    parts = name.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in table:
            return ".".join(parts[:n])
    return None


def violations(table: dict[str, int], sources: dict[str, tuple[str, bool]]) -> list[str]:
    """Every import against the table's rules; ``sources``: module -> (text,
    is a package)."""
    problems = []
    for module, (text, is_package) in sorted(sources.items()):
        own = unit_of(module, table)
        if own is None:
            if module != "softplc_lite":
                problems.append(f"{module}: in no layer of docs/architecture.md")
            continue
        for target, line in imports(text, module, is_package):
            if not target.startswith("softplc_lite.") or target.split(".")[1] == "__version__":
                continue  # another package, or the version in the package's own __init__
            other = unit_of(target, table)
            if other is None or other == own:
                continue  # a name of the root package, or its own unit
            if table[other] > table[own]:
                problems.append(f"{module}:{line}: imports {target} (layer {table[other]}), above its "
                                f"own layer {table[own]} ({own})")
            elif table[other] == table[own]:
                problems.append(f"{module}:{line}: imports {target}: {other} and {own} are in the same "
                                f"layer ({table[own]}), which keeps its units independent")
    return problems


def package_sources() -> dict[str, tuple[str, bool]]:
    return {module_name(path): (path.read_text(encoding="utf-8"), path.name == "__init__.py")
            for path in PACKAGE.rglob("*.py")}


def test_no_module_imports_a_layer_above_its_own():
    assert violations(layers(MAP.read_text(encoding="utf-8")), package_sources()) == []


def test_every_unit_of_the_table_exists():
    for unit in layers(MAP.read_text(encoding="utf-8")):
        path = ROOT / unit.replace(".", "/")
        assert path.is_dir() or path.with_suffix(".py").is_file(), f"{unit} is in the table but not in the package"


def test_the_rules_catch_an_upward_import_a_sideways_one_and_a_module_of_no_layer():
    table = {"softplc_lite.low": 0, "softplc_lite.left": 1, "softplc_lite.right": 1, "softplc_lite.top": 2}
    sources = {
        "softplc_lite.low.core": ("def f():\n    from ..top import view\n", False),  # lazy, relative, upward
        "softplc_lite.left": ("from softplc_lite.right import x\nfrom . import __version__\n", True),
        "softplc_lite.top.cmd": ("import softplc_lite.low.core\nfrom ..left import y\nimport os\n", False),
        "softplc_lite.stray": ("", False),
    }
    assert violations(table, sources) == [
        "softplc_lite.left:1: imports softplc_lite.right.x: softplc_lite.right and softplc_lite.left are in "
        "the same layer (1), which keeps its units independent",
        "softplc_lite.low.core:2: imports softplc_lite.top.view (layer 2), above its own layer 0 "
        "(softplc_lite.low)",
        "softplc_lite.stray: in no layer of docs/architecture.md",
    ]
