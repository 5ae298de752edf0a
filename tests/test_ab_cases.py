"""AB-documented cases: programs whose results Allen-Bradley's manuals state,
run on both executors.

Each file in tests/data/ab_cases/ is TOML: a list of ``[[case]]`` tables with
``name``, ``source`` (the AB publication and section the expectation comes
from), ``program`` (ladder text), optional ``values`` (written before the
first scan), ``scans`` (default 1), ``settings`` (semantics.Settings
fields), ``then`` (later steps: ``values`` to write, ``scans`` to run) and
``expect`` (address -> value after the last step, as ``table.read`` gives
it; floats compare to a relative 1e-6)."""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import pytest

from softplc_lite.datatable.jsonio import dumps
from softplc_lite.ladder import Engine, Mode, Settings, load_text

CASES_DIR = Path(__file__).parent / "data" / "ab_cases"
# A citation names an AB publication: 1785-6.1, 1747-RM001, 1763-RM001, 1756-RM003, ...
PUBLICATION = re.compile(r"\b17\d\d-[A-Z0-9.]+")


def _load_cases():
    out = []
    for path in sorted(CASES_DIR.glob("*.toml")):
        with path.open("rb") as f:
            doc = tomllib.load(f)
        for k, case in enumerate(doc.get("case", [])):
            out.append(pytest.param(case, id=f"{path.stem}:{k}:{case.get('name', '?')[:40]}"))
    return out


CASES = _load_cases()


def _close(got, want) -> bool:
    if isinstance(want, float) or isinstance(got, float):
        return math.isclose(float(got), float(want), rel_tol=1e-6, abs_tol=1e-9)
    if isinstance(want, dict):
        return isinstance(got, dict) and all(k in got and _close(got[k], v) for k, v in want.items())
    return got == want


def _run(case: dict, executor: str) -> Engine:
    program = load_text(case["program"], source=case["name"])
    engine = Engine(program, settings=Settings(**case.get("settings", {})), executor=executor)
    steps = [{"values": case.get("values", {}), "scans": case.get("scans", 1)}, *case.get("then", [])]
    engine.set_mode(Mode.RUN)
    for step in steps:
        for address, value in step.get("values", {}).items():
            engine.table.write(address, value)
        engine.run(step.get("scans", 1))
    return engine


def test_the_cases_are_cited_and_complete():
    assert CASES, "no AB cases found"
    for param in CASES:
        case = param.values[0]
        missing = {"name", "source", "program", "expect"} - set(case)
        assert not missing, f"{case.get('name')}: missing {sorted(missing)}"
        assert PUBLICATION.search(case["source"]), f"{case['name']}: source names no AB publication"


@pytest.mark.parametrize("case", CASES)
def test_ab_case(case):
    tables = {}
    for executor in ("compiled", "reference"):
        engine = _run(case, executor)
        assert engine.fault is None, f"{executor}: {engine.fault}"
        got = {address: engine.table.read(address) for address in case["expect"]}
        wrong = {a: (got[a], want) for a, want in case["expect"].items() if not _close(got[a], want)}
        assert not wrong, f"{executor}: (got, expected) {wrong}  [{case['source']}]"
        tables[executor] = engine.table
    assert dumps(tables["compiled"]) == dumps(tables["reference"])
