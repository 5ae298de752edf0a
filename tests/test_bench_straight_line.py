"""The straight-line baseline of benchmarks/bench_ladder.py agrees
with the engine, so the yardstick cannot rot silently. Not timed."""

from __future__ import annotations

import types

import pytest
from helpers.benchmark_modules import load

from softplc_lite.ladder import parse_program, validate

L = load("ladder_programs")
straight_line = load("straight_line")

# Shapes the generator makes rarely or never: a coil first, coils inside
# legs that have contacts, contacts after a coil, bit 15, an empty-ish leg.
SHAPES = """\
OTE B3/0
XIC I:0/17 OTL B3/15
BST XIC B3/15 OTE B3/31 NXB XIO I:1/0 OTE B3/47 BND OTE B3/63
BST OTE B3/64 NXB OTU B3/65 NXB OTL B3/66 BND
XIC B3/64 BST XIC B3/65 NXB XIO B3/66 BST XIC I:2/3 NXB XIC I:3/4 BND BND OTE B3/79 XIC B3/0
XIO B3/79 OTU B3/15 OTE B3/95
"""


def scan_both(text: str, scans: int):
    program = validate(parse_program(text, "<test>"))
    engine = L.make_engine(program)
    table = L.initial_table(L.SEED)
    baseline = straight_line.build(program, table)
    hook = L.input_hook(L.SEED)
    holder = types.SimpleNamespace(table=table)
    for _ in range(scans):
        engine.scan()
        hook(holder)
        baseline.scan()
    return engine, table, baseline, program


@pytest.mark.parametrize("text", [L.boolean_program(200, L.SEED), SHAPES], ids=["generated-200", "shapes"])
def test_baseline_tables_equal_the_engines(text):
    engine, table, baseline, program = scan_both(text, 5)
    assert engine.fault is None
    assert L.table_words(engine.table) == L.table_words(table)
    assert baseline.instructions == L.count_instructions(program)[1]


def test_baseline_reads_each_word_once_and_writes_back_once():
    _, _, baseline, _ = scan_both(L.boolean_program(200, L.SEED), 1)
    body = baseline.source.splitlines()
    loads = [line for line in body if line.startswith("    w") and "= f" in line]
    stores = [line for line in body if line.startswith("    f")]
    assert len(loads) == baseline.words_read and len(stores) == baseline.words_written
    assert sum(line.strip().startswith("def ") for line in body) == 1


def test_baseline_refuses_what_it_does_not_cover():
    program = validate(parse_program("XIC B3/0 MOV 1 N7:0\n", "<test>"))
    with pytest.raises(ValueError, match="MOV"):
        straight_line.build(program, L.initial_table(L.SEED))
