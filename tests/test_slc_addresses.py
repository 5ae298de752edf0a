"""SLC 500 I/O addresses I:e.s/b and O:e.s (slot.word/bit) beside PLC-5's
octal I:012/17: parsing, the canonical text of each form, the word they
name in the I/O files, fmt round trips and both rung syntaxes on both
executors (docs/datatable.md, "SLC I/O addresses")."""

from __future__ import annotations

import pytest

from softplc_lite.cli import main
from softplc_lite.datatable import AddressError, parse_address
from softplc_lite.datatable.address import SLC_SLOT_WORDS
from softplc_lite.ladder import load_text, run_text
from softplc_lite.ladder.fmt import format_program
from softplc_lite.ladder.parser import parse_program

EXECUTORS = ("compiled", "reference")


@pytest.mark.parametrize("text, word, bit", [
    ("I:1.0/3", 32, 3),
    ("I:2.1/3", 65, 3),  # 1747-6.1 appendix B's example: input 3, slot 2, word 1
    ("O:5.1", 161, None),
    ("O:30.31/15", 30 * 32 + 31, 15),
    ("I:0.0/0", 0, 0),
    ("I:7.0/8", 224, 8),  # decimal bits: 8 and 9 are bits, not octal errors
])
def test_slc_form_names_word_32_times_slot_plus_word(text, word, bit):
    a = parse_address(text)
    assert (a.element, a.bit) == (word, bit)
    assert str(a) == text and parse_address(str(a)) == a


@pytest.mark.parametrize("slc, plc5", [("I:1.0/3", "I:40/3"), ("O:2.1/15", "O:101/17"), ("I:0.2", "I:2")])
def test_an_slc_address_and_its_plc5_alias_are_the_same_address(slc, plc5):
    a, b = parse_address(slc), parse_address(plc5)
    assert a == b and hash(a) == hash(b)
    assert str(a) == slc and str(b) == plc5  # each prints in the form it was written in


def test_plc5_octal_forms_are_unchanged():
    a = parse_address("I:012/17")
    assert (a.element, a.bit, str(a)) == (10, 15, "I:12/17")
    assert parse_address("I:3/5").element == 3  # no word number: PLC-5's octal word 3


@pytest.mark.parametrize("text, message", [
    ("I:31.0", "slot 31 out of range 0..30"),
    (f"I:1.{SLC_SLOT_WORDS}", f"word number {SLC_SLOT_WORDS} out of range 0..{SLC_SLOT_WORDS - 1}"),
    ("O:1.0/16", "bit number 16 out of range 0..15"),
    ("I:1./3", "expected a word number"),
    ("N7:1.0", "elements have no members"),
    ("I:1.0.DN", "unexpected '.'"),
])
def test_bad_slc_addresses_say_what_is_wrong(text, message):
    with pytest.raises(AddressError, match=message.replace(".", r"\.")):
        parse_address(text)


MNEMONIC = "XIC I:1.0/3 XIO I:12/17 BST OTE O:2.1/15 NXB OTE O:3/5 BND\nCOP #I:1.0 #N7:0 2\nMOV I:3.2 N7:5\n"
NEUTRAL = "XIC(I:1.0/3)XIO(I:12/17)[OTE(O:2.1/15),OTE(O:3/5)];\nCOP(#I:1.0,#N7:0,2);\nMOV(I:3.2,N7:5);\n"


@pytest.mark.parametrize("style, text", [("mnemonic", MNEMONIC), ("neutral", NEUTRAL)])
def test_fmt_prints_slc_and_plc5_addresses_back_as_written(style, text):
    assert format_program(parse_program(text), style) == text


def test_softplc_fmt_round_trip(tmp_path, capsys):
    path = tmp_path / "slc.lad"
    path.write_text(MNEMONIC)
    assert main(["fmt", str(path)]) == 0
    assert capsys.readouterr().out == MNEMONIC


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("text", [MNEMONIC, NEUTRAL])
def test_both_forms_run_in_both_syntaxes(executor, text):
    values = {"I:1.0/3": 1, "I:1.1": 1234, "I:3.2": -7}
    t = run_text(text, 1, executor=executor, values=values).table
    assert t.read("O:2.1/15") == 1 and t.read("O:101/17") == 1  # the same bit in both forms
    assert t.read("O:3/5") == 1  # PLC-5 octal word 3 (slot 3 word 0)
    assert (t.read("N7:0"), t.read("N7:1")) == (8, 1234)  # slot 1 words 0 and 1 (bit 3 = 8)
    assert t.read("N7:5") == -7


def test_tables_agree_between_executors_with_slc_addresses():
    values = {"I:1.0/3": 1, "I:1.1": 1234, "I:3.2": -7}
    a, b = (run_text(MNEMONIC, 2, executor=ex, values=values).table for ex in EXECUTORS)
    assert a == b


def test_the_io_file_grows_to_the_slot_words_a_program_names():
    program = load_text("XIC I:30.31/0 OTE O:30.0/0\n")
    from softplc_lite.ladder import Engine

    engine = Engine(program)
    assert engine.table.file("I1").size == 30 * 32 + 32
    assert engine.table.file("O0").size >= 30 * 32 + 1


def test_softplc_address_prints_the_slc_form(capsys):
    assert main(["address", "I:1.0/3", "O:2.1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "address\tcanonical\tkind\taccess"
    assert out[1].split("\t")[:3] == ["I:1.0/3", "I:1.0/3", "bit"]
    assert out[2].split("\t")[:3] == ["O:2.1", "O:2.1", "word"]


def test_a_decimal_bit_in_the_plc5_form_suggests_the_slc_form():
    with pytest.raises(AddressError, match=r"octal.*SLC address names the slot and word, decimal: I:1\.0/8"):
        parse_address("I:1/8")


def test_a_file_operand_keeps_its_slc_form_through_validation():
    program = load_text("COP #I:1.0 #N7:0 2\n")
    source = program.main.rungs[0].elements[0].operands[0].address
    assert str(source) == "I:1.0" and not source.indexed


def test_display_blocks_of_slc_and_octal_io_words():
    from softplc_lite.datatable import DataTable
    from softplc_lite.run_output import parse_item

    t = DataTable()
    t.reference("I:2.1")
    for k, v in enumerate((5, 6)):
        t.write(f"I:2.{k}", v)
    t.write("I:17", 7)
    t.write("I:20", 8)
    assert parse_item("slot 2", "#I:2.0 2", "softplc.toml").read(t) == "5 6"
    assert parse_item("octal", "#I:17 2", "softplc.toml").read(t) == "7 8"  # I:17 then I:20 (octal)
    with pytest.raises(Exception, match="a block is"):
        parse_item("bad", "#T4:0.ACC 2", "softplc.toml")


@pytest.mark.parametrize("executor", EXECUTORS)
def test_data_values_of_an_io_file_fill_consecutive_words(executor):
    """DATA O0 10 = ...: value k goes to word k (O:0..O:11 octal), not to the text "O0:k"."""
    t = run_text("DATA O0 10 = 1 2 3 4 5 6 7 8 9 10\n", 1, executor=executor).table
    assert [t.read(f"O:{k:o}") for k in range(10)] == list(range(1, 11))
    assert t.read("O:0.9") == 10  # SLC form of the same word
