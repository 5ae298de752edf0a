"""Shared by the tests of the bound instruction groups (ladder/instr/): a
one-scan rung pulse. (Their ``engine`` fixture is in conftest.py.)"""

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
