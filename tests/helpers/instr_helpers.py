"""Shared by the tests of the bound instruction groups (ladder/instr/): a
one-scan rung pulse and the S:0 flags as letters. (Their ``engine`` and
``run`` fixtures are in conftest.py.)"""

from __future__ import annotations

from softplc_lite.ladder import Engine

EXECUTORS = ("compiled", "reference")


def pulse(e: Engine, bit: str = "B3/0") -> Engine:
    """One false-to-true transition: a scan true, then a scan false."""
    e.table.write(bit, 1)
    e.scan()
    e.table.write(bit, 0)
    e.scan()
    return e


def flags(e) -> str:
    """S:0 arithmetic flags as letters: C carry, V overflow, Z zero, S sign."""
    s0 = e.table.read("S:0")
    return "".join(name for bit, name in enumerate("CVZS") if s0 >> bit & 1)

