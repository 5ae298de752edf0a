"""Find and cross-reference (softplc_lite/watch/xref.py) on the shipped
programs: which rungs read or write an address, symbol, word or file, read
and write taken from the instruction specs."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.datatable import AddressError
from softplc_lite.ladder import load_text
from softplc_lite.ladder.instructions import BUILTIN, InstructionSet, lookup
from softplc_lite.ladder.specs import K
from softplc_lite.tlm.comgenius import instructions as comgenius
from softplc_lite.tlm.modbmast import instructions as modbmast
from softplc_lite.watch.xref import IN_PLACE, Access, XrefIndex, XrefPanel, access_of

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"


def index_of(app: str) -> XrefIndex:
    loaded = load_app(PROGRAMS / app, use_cache=False)
    return XrefIndex(loaded.program, loaded.instructions)


def where(finding) -> list[tuple]:
    return [(u.file, u.rung, u.instruction, u.mnemonic, u.operand, u.access.value) for u in finding.uses]


def every_spec():
    module_specs = [v for v in vars(comgenius).values() if type(v).__name__ == "InstructionSpec"]
    return BUILTIN.all_specs() + module_specs + list(modbmast.SPECS)


# -- real programs ---------------------------------------------------------------------------


def test_motor_counter_has_one_writer_the_ctu():
    found = index_of("motor").find("C5:0")
    assert where(found) == [(2, 1, 2, "CTU", 0, "read/write")]
    assert found.writers == found.uses


def test_motor_symbol_finds_coils_and_contacts():
    found = index_of("motor").find("tripped")  # symbols without regard to case
    assert found.title == "tripped (B3/0)"
    assert where(found) == [
        (2, 0, 3, "XIO", 0, "read"),
        (2, 3, 1, "OTL", 0, "write"),
        (2, 4, 2, "OTU", 0, "write"),
        (2, 5, 0, "XIC", 0, "read"),
        (2, 6, 0, "XIC", 0, "read"),
    ]
    assert [(u.rung, u.mnemonic) for u in found.writers] == [(3, "OTL"), (4, "OTU")]


def test_a_word_finds_the_uses_of_its_bits():
    found = index_of("motor").find("B3:0")
    assert sorted({str(u.address) for u in found.uses}) == ["B3/0", "B3/1", "B3/2"]
    ons = [u for u in found.uses if u.mnemonic == "ONS"]
    assert [u.access for u in ons] == [Access.READ_WRITE, Access.READ_WRITE]  # a one-shot's storage bit
    assert index_of("motor").find("B3/1").uses == ons[:1]  # and a bit only its own


def test_timer_status_bit_in_both_spellings_and_the_timer_itself():
    x = index_of("modbus_master")
    dotted, slashed = x.find("T4:0.DN"), x.find("T4:0/DN")
    assert where(dotted) == where(slashed)
    # the TON that sets DN, the contact that reads it
    assert [(u.mnemonic, u.access.value) for u in dotted.uses][:2] == [("TON", "read/write"), ("XIC", "read")]
    assert x.find("PollTimer.DN").uses == dotted.uses
    # T4:0.ACC is a word of the timer: the TON, not the DN contact
    assert {u.mnemonic for u in x.find("T4:0.ACC").uses} == {"TON"} | {
        u.mnemonic for u in x.find("T4:0").uses if u.address.member == "ACC"}


def test_modbus_master_every_writer_of_a_counter():
    x = index_of("modbus_master")
    timeouts = x.find("Timeouts")
    assert [(u.rung, u.mnemonic, u.access) for u in timeouts.writers] == [(7, "CTU", Access.READ_WRITE)]
    reset = [u for u in x.uses if u.mnemonic == "RES"]
    for use in reset:  # a RES writes the element it names
        assert use.access is Access.WRITE
        assert use in x.find(str(use.address)).writers


def test_block_of_known_length_and_a_tlm_output_parameter():
    x = index_of("modbus_master")
    copied = x.find("N11:124")
    assert where(copied) == [(2, 5, 2, "COP", 1, "write")]
    assert copied.uses[0].span == 125 and not copied.uses[0].indirect
    assert x.find("N11:125").uses == []  # past the block
    assert where(x.find("N10:0"))[-1] == (2, 5, 2, "COP", 0, "read")
    # COMSCAN's received value: a PARAM_OUT operand of the COMGENIUS module's spec
    exception = x.find("ExceptionCode")
    assert ("COMSCAN", Access.WRITE) in [(u.mnemonic, u.access) for u in exception.uses]
    assert x.find("N7").title == "file N7"
    assert {str(u.address) for u in x.find("N7").uses} >= {"N7:0", "N7:1", "N7:20", "N7:21"}


def test_subroutine_files_and_expressions():
    x = index_of("subroutines")
    found = x.find("N7:0")
    files = {(u.file, u.mnemonic, u.access.value) for u in found.uses}
    assert (2, "ADD", "write") in files and (2, "CMP", "read") in files
    assert (3, "CPT", "read") in files and (5, "ADD", "read") in files
    assert where(x.find("F8:0")) == [(3, 1, 0, "CPT", 0, "write")]  # SBR is rung 0


# -- read and write come from the specs ----------------------------------------------------------


def test_every_destination_kind_of_every_spec_writes():
    checked = 0
    for spec in every_spec():
        for k, op in enumerate(spec.operands):
            if op.kind in (K.DEST, K.INTEGER_DEST, K.PARAM_OUT, K.RESETTABLE):
                assert access_of(spec, k) is Access.WRITE, (spec.mnemonic, op.name)
                checked += 1
            elif op.kind in (K.SOURCE, K.INT_SOURCE, K.INTEGER_SOURCE, K.EXPRESSION, K.PARAM):
                assert access_of(spec, k) is Access.READ, (spec.mnemonic, op.name)
            elif op.kind in (K.TIMER, K.COUNTER, K.CONTROL):
                assert access_of(spec, k) is Access.READ_WRITE, (spec.mnemonic, op.name)
    assert checked > 30


def test_a_changed_destination_in_the_spec_changes_the_index():
    program = load_text("XIC B3/0 MOV N7:0 N7:1\n")
    assert where(XrefIndex(program).find("N7:1")) == [(2, 0, 1, "MOV", 1, "write")]
    mov = lookup("MOV")
    assert mov.operands[1].kind is K.DEST
    changed = InstructionSet()
    changed.table["MOV"] = dataclasses.replace(mov, operands=(mov.operands[0], dataclasses.replace(
        mov.operands[1], kind=K.SOURCE)))
    assert where(XrefIndex(program, changed).find("N7:1")) == [(2, 0, 1, "MOV", 1, "read")]


def test_coils_write_contacts_read_from_the_spec_shape():
    for mnemonic, expected in (("OTE", Access.WRITE), ("OTL", Access.WRITE), ("OTU", Access.WRITE),
                               ("XIC", Access.READ), ("XIO", Access.READ), ("ONS", Access.READ_WRITE)):
        assert access_of(lookup(mnemonic), 0) is expected, mnemonic
    osr = lookup("OSR")
    assert [access_of(osr, k) for k in range(2)] == [Access.READ_WRITE, Access.WRITE]


def test_in_place_entries_name_real_operands_of_shared_kinds():
    by_mnemonic = {s.mnemonic: s for s in every_spec()}
    for (mnemonic, name), access in IN_PLACE.items():
        spec = by_mnemonic[mnemonic]
        kinds = {op.name: op.kind for op in spec.operands}
        assert name in kinds, (mnemonic, name)
        assert kinds[name] in (K.BIT, K.WORD, K.STRING, K.FILE, K.WORD_FILE), (mnemonic, name)
        assert access_of(spec, list(kinds).index(name)) is access


def test_jsr_return_parameters_are_written():
    program = load_text("JSR 3 1 N7:0 N7:1\nFILE 3 Sub\nSBR N7:5\nRET N7:6\n")
    x = XrefIndex(program)
    assert where(x.find("N7:0")) == [(2, 0, 0, "JSR", 2, "read")]
    assert where(x.find("N7:1")) == [(2, 0, 0, "JSR", 3, "write")]
    assert where(x.find("N7:5")) == [(3, 0, 0, "SBR", 0, "write")]
    assert where(x.find("N7:6")) == [(3, 1, 0, "RET", 0, "read")]


# -- indirect and indexed ------------------------------------------------------------------------


def test_indirect_and_indexed_addresses_may_touch_their_file():
    program = load_text("MOV N7:[N7:1] N[N7:2]:0\nMOV #N7:0 N9:3\n")
    x = XrefIndex(program)
    anywhere = x.find("N7:40")
    assert [(u.rung, u.operand, str(u.address), u.indirect) for u in anywhere.uses] == [
        (0, 0, "N7:[N7:1]", True), (0, 1, "N[N7:2]:0", True), (1, 0, "#N7:0", True)]
    pointer = x.find("N7:1")
    assert [(str(u.address), u.access, u.indirect) for u in pointer.uses][1] == ("N7:1", Access.READ, False)
    assert where(x.find("S:24")) == [(2, 1, 0, "MOV", 0, "read")]  # the index register
    assert [u.mnemonic for u in x.find("N9:3").uses] == ["MOV", "MOV"]  # N[N7:2]:0 may be N9 too


# -- navigation and errors ---------------------------------------------------------------------


def test_next_and_previous_wrap_and_start_at_the_selected_rung():
    found = index_of("motor").find("Tripped")
    assert found.where is None
    assert [found.next() for _ in range(6)] == [(2, 0), (2, 3), (2, 4), (2, 5), (2, 6), (2, 0)]
    assert found.previous() == (2, 6)
    found.start_at(2, 4)
    assert found.next() == (2, 4)
    found.start_at(2, 7)  # past the last: from the first
    assert found.next() == (2, 0)
    empty = index_of("motor").find("N7:0")
    assert empty.uses == [] and empty.next() is None and empty.previous() is None


@pytest.mark.parametrize("text, words", [
    ("", "expected an address"),
    ("Nope", "Nope is neither an address nor a program symbol"),
    ("Trippd", "did you mean Tripped?"),
    ("N7:[N7:1]", "expected a direct address"),
    ("T4:0.XX", "T4:0.XX"),
])
def test_bad_queries_say_what_was_expected(text, words):
    with pytest.raises(AddressError) as e:
        index_of("motor").find(text)
    assert words in str(e.value)


def test_panel_lists_uses_and_marks_the_current_one():
    found = index_of("motor").find("Tripped")
    found.next()
    found.next()
    console = Console(record=True, width=80, color_system=None)
    console.print(XrefPanel(found))
    assert console.export_text().splitlines() == [
        "find Tripped (B3/0): 5 uses, 2 writing  (2 of 5; x next, X previous)",
        "  file 2 rung 0  instruction 4 XIO  operand 1 B3/0  read",
        "▶ file 2 rung 3  instruction 2 OTL  operand 1 B3/0  write",
        "  file 2 rung 4  instruction 3 OTU  operand 1 B3/0  write",
        "  file 2 rung 5  instruction 1 XIC  operand 1 B3/0  read",
        "  file 2 rung 6  instruction 1 XIC  operand 1 B3/0  read",
    ]


def test_panel_keeps_the_current_use_in_view_and_says_when_nothing_uses_it():
    found = index_of("modbus_master").find("Busy")
    for _ in range(8):
        found.next()
    console = Console(record=True, width=60, color_system=None)
    console.print(XrefPanel(found, height=4))
    lines = console.export_text().splitlines()
    assert len(lines) == 4 and lines[0].startswith("find Busy (B3/0): 9 uses, 5 writing")
    assert any(line.startswith("▶ file 2 rung 7") for line in lines)
    assert all(len(line) <= 60 for line in lines)
    console = Console(record=True, width=60, color_system=None)
    console.print(XrefPanel(index_of("motor").find("N7:5")))
    assert console.export_text() == "find N7:5: not used in any rung\n"
