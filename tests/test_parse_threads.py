"""Two threads parse at once (the online reloader parses on a thread of
its own): each parse keeps its own source name, offsets, problems and
instruction set."""

from __future__ import annotations

import inspect
import sys
import threading

from softplc_lite.ladder import LadderError
from softplc_lite.ladder.ast import Pos
from softplc_lite.ladder.parser import parse_expression, parse_program, syntax_problems


def _mnemonic(rungs: int) -> str:
    return "".join(f"XIC B3:{i % 50}/{i % 16} CPT N7:{i % 40} \"N7:{(i + 1) % 40} + {i}\"\n" for i in range(rungs))


def _neutral(rungs: int) -> str:
    return "".join(f"[XIC(I:0/{i % 16}),XIO(B9:{i % 7}/{i % 16})]OTE(O:0/{i % 16});\n" for i in range(rungs))


def _with_problems(rungs: int) -> str:
    return "".join(f"XIC B3:{i}/99 OTE Z{i}\n" if i % 10 == 0 else f"XIC B3:0/{i % 16} OTL B3:1/{i % 16}\n"
                   for i in range(rungs))


def _dump(node) -> str:
    """A node with its fields and position, recursively (``==`` and repr
    of AST nodes leave positions out)."""
    if isinstance(node, (list, tuple)) and not hasattr(node, "_fields"):
        return "[" + ",".join(_dump(x) for x in node) + "]"
    if isinstance(node, dict):
        return "{" + ",".join(f"{k!r}:{_dump(v)}" for k, v in node.items()) + "}"
    if isinstance(node, LadderError):
        return f"error {node.pos} {node.message}"
    if type(node).__module__.startswith("softplc_lite") and not isinstance(node, type):
        names = list(inspect.signature(type(node)).parameters)
        if hasattr(node, "pos") and "pos" not in names:
            names.append("pos")
        return f"{type(node).__name__}(" + ",".join(f"{n}={_dump(getattr(node, n))}" for n in names) + ")"
    return repr(node)


def _summary(run) -> str:
    try:
        return _dump(run())
    except LadderError as e:
        return _dump(e)


JOBS = {
    "mnemonic": lambda: parse_program(_mnemonic(600), "a.lad"),
    "neutral": lambda: parse_program(_neutral(600), "b.lad", line_offset=7),
    "problems": lambda: syntax_problems(_with_problems(600), "c.lad"),
    "expression": lambda: [parse_expression(f"N7:{i} * (N7:{i + 1} - {i})", Pos("d.lad", 3, 9)) for i in range(400)],
}


def test_two_threads_parse_different_programs_at_once_and_get_each_right():
    expected = {name: _summary(job) for name, job in JOBS.items()}  # one at a time, on this thread
    assert "a.lad" in expected["mnemonic"] and "b.lad" in expected["neutral"] and "c.lad" in expected["problems"]
    got: dict[str, list[str]] = {name: [] for name in JOBS}
    start = threading.Barrier(len(JOBS))

    def worker(name: str) -> None:
        start.wait(10)
        for _ in range(3):
            got[name].append(_summary(JOBS[name]))

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)  # threads switch often: every parse is interleaved with the others
    try:
        threads = [threading.Thread(target=worker, args=(name,), daemon=True) for name in JOBS]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
    finally:
        sys.setswitchinterval(interval)
    assert not any(t.is_alive() for t in threads)
    for name in JOBS:
        assert got[name] == [expected[name]] * 3, name
