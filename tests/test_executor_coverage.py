"""Every instruction has both executors' implementations: a compiler
template (ladder/templates.py) or a bound object (ladder/instr/) for the
compiled path, and a rule of the reference interpreter (RULES), so no
instruction runs on one executor alone and the differential test can hold
each to the other."""

from __future__ import annotations

from softplc_lite.ladder.instr import BOUND
from softplc_lite.ladder.instructions import BUILTIN
from softplc_lite.ladder.interpreter import RULES
from softplc_lite.ladder.templates import TEMPLATES


def test_every_builtin_instruction_has_a_compiled_implementation():
    missing = [m for m in BUILTIN.table if m not in TEMPLATES and m not in BOUND]
    assert missing == []


def test_every_builtin_instruction_has_an_interpreter_rule():
    missing = [m for m in BUILTIN.table if m not in RULES]
    assert missing == []


def test_no_implementation_is_left_without_an_instruction():
    """A template or rule for a mnemonic the instruction set does not know
    would be dead code, or a misspelt registration."""
    known = set(BUILTIN.table)
    assert set(TEMPLATES) - known == set()
    assert set(RULES) - known == set()
    assert set(BOUND) <= known


def test_a_mnemonic_has_one_compiled_implementation():
    assert set(TEMPLATES) & set(BOUND) == set()
