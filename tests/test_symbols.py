"""Symbols as engineers write them: members, bits and
offsets of a symbol in both rung syntaxes, in expressions and at every place
an address is taken (--set, --print, --watch, --watch-file, --force,
--break-when, [display]); names compare without regard to case."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers.cli import softplc_here
from helpers.apps import make_app
from softplc_lite.app import load_app
from softplc_lite.datatable import DataTableError, parse_address
from softplc_lite.run_output import parse_item
from softplc_lite.errors import LocatedError
from softplc_lite.ladder import run_text
from softplc_lite.ladder.ast import SymbolDecl, address_refs
from softplc_lite.ladder.errors import ProgramErrors
from softplc_lite.ladder.instructions import InstructionSet
from softplc_lite.ladder.parser import parse_program
from softplc_lite.ladder.symbols import SymbolError, resolve_name
from softplc_lite.ladder.validate import check
from softplc_lite.runner import RunOptions, parse_assignment
from softplc_lite.watch.breakpoints import Condition
from softplc_lite.watch.forces import parse_force
from softplc_lite.watch.session import WatchOptions, WatchSession
from softplc_lite.watch.watchlist import WatchItem, read_watch_file

EXECUTORS = ("compiled", "reference")

DECLS = """SYMBOL PollTimer T4:0
SYMBOL Reply R6:3
SYMBOL Levels N7:10
SYMBOL Flags B3:2
SYMBOL Start B3/0
SYMBOL Inputs I:1
"""
SYMBOLS = {name: SymbolDecl(name, parse_address(addr)) for name, addr in (
    ("PollTimer", "T4:0"), ("Reply", "R6:3"), ("Levels", "N7:10"), ("Flags", "B3:2"), ("Start", "B3/0"),
    ("Inputs", "I:1"), ("Total", "N7:0"), ("Message", "ST9:0"))}


@pytest.mark.parametrize("text, address", [
    ("PollTimer/DN", "T4:0/DN"), ("PollTimer.DN", "T4:0/DN"), ("PollTimer.ACC", "T4:0.ACC"),
    ("polltimer.pre", "T4:0.PRE"), ("Reply/ER", "R6:3/ER"), ("Reply.POS", "R6:3.POS"), ("Flags/3", "B3:2/3"),
    ("Levels[3]", "N7:13"), ("Levels[3]/15", "N7:13/15"), ("PollTimer[2].DN", "T4:2/DN"), ("START", "B3/0"),
    ("Inputs/17", "I:1/17"), ("Reply.POS/3", "R6:3.POS/3"), ("N7:4", "N7:4"), ("B3/0", "B3/0"),
])
def test_resolve_name_gives_the_member_bit_or_offset_address(text, address):
    assert resolve_name(text, SYMBOLS) == parse_address(address)


@pytest.mark.parametrize("text, message, position", [
    ("PollTimer.XX", "PollTimer is T4:0, a timer: members EN TT DN PRE ACC", 10),
    ("PollTimer/ACC", "PollTimer is T4:0, a timer: members EN TT DN PRE ACC", 10),
    ("Reply/TT", "Reply is R6:3, a control: members EN EU DN EM ER UL IN FD LEN POS", 6),
    ("Levels.ACC", "Levels is N7:10, a word: a word has no named members", 7),
    ("Levels/16", "Levels is N7:10, a word: bit 16 is past bit 15", 7),
    ("Inputs/18", "Inputs is I:1, a word: bit 18 is past bit 17 (octal)", 7),
    ("Start/1", "Start is B3/0, a bit: it has no bits of its own", 5),
    ("Start[1]", "Start is B3/0, a bit: an [offset] applies to a symbol of a whole, direct element", 5),
    ("Message/1", "Message is ST9:0, a string: string elements have no bits", 7),
    ("Levels[9990]", "Levels[9990] is element 10000, past the last element 9999", 7),
    ("Strat", "Strat is neither an address nor a program symbol (did you mean Start?)", 0),
])
def test_a_member_the_element_lacks_is_a_clear_error_saying_where(text, message, position):
    with pytest.raises(SymbolError) as e:
        resolve_name(text, SYMBOLS)
    assert message in str(e.value)
    assert e.value.position == position


def test_one_or_two_letters_before_a_slash_are_an_address_not_a_symbol():
    # The ladder lexer reads "In/3" as an address (file type IN), so every site does.
    symbols = {"In": SymbolDecl("In", parse_address("N7:0"))}
    with pytest.raises(DataTableError, match=r"unknown file type 'IN'.*\(In/3 reads as an address: one or two "
                                             "letters and digits before '/' or ':' are one"):
        resolve_name("In/3", symbols)
    with pytest.raises(DataTableError) as e:
        resolve_name("In/3", {})  # no symbol In: the address error alone
    assert "unknown file type 'IN'" in str(e.value) and "reads as an address" not in str(e.value)
    assert resolve_name("In", symbols) == parse_address("N7:0")


PROGRAM_MNEMONIC = DECLS + """XIC Start TON PollTimer 0.01 3 0
XIC PollTimer/DN OTE Flags/3
XIC PollTimer.DN MOV PollTimer.ACC Levels[3]
XIC Flags/3 BST OTL Reply/ER NXB MOV 7 Levels NXB CPT Levels[1] "PollTimer.PRE * 2 + Levels[3] / 3" BND
"""
PROGRAM_NEUTRAL = DECLS + """XIC(Start)TON(PollTimer,0.01,3,0);
XIC(PollTimer/DN)OTE(Flags/3);
XIC(PollTimer.DN)MOV(PollTimer.ACC,Levels[3]);
XIC(Flags/3)[OTL(Reply/ER),MOV(7,Levels),CPT(Levels[1],PollTimer.PRE * 2 + Levels[3] / 3)];
"""


@pytest.mark.parametrize("executor", EXECUTORS)
@pytest.mark.parametrize("program", [PROGRAM_MNEMONIC, PROGRAM_NEUTRAL], ids=["mnemonic", "neutral"])
def test_symbol_members_work_in_both_rung_syntaxes_and_in_expressions(program, executor):
    engine = run_text(program, scans=5, executor=executor, values={"B3/0": 1})
    t = engine.table
    assert t.read("T4:0/DN") == 1 and t.read("B3:2/3") == 1 and t.read("R6:3/ER") == 1
    acc = t.read("T4:0.ACC")
    assert t.read("N7:13") == acc and t.read("N7:10") == 7
    assert t.read("N7:11") == 3 * 2 + acc // 3  # PollTimer.PRE * 2 + Levels[3] / 3
    assert t.read("N7:11") != 0


@pytest.mark.parametrize("executor", EXECUTORS)
def test_symbols_compare_without_regard_to_case(executor):
    engine = run_text("SYMBOL Start B3/0\nSYMBOL Lamp O:0/1\nXIC START OTE lamp\n", executor=executor,
                      values={"B3/0": 1})
    assert engine.table.read("O:0/1") == 1


def _errors(text: str) -> list[str]:
    _, errors = check(parse_program(text, "s.lad"))
    return [str(e) for e in errors]


def test_two_declarations_differing_only_in_case_are_a_located_error():
    with pytest.raises(Exception) as e:
        parse_program("SYMBOL Start B3/0\nSYMBOL START B3/1\n", "s.lad")
    assert str(e.value) == ("s.lad:2:8: symbol START is declared twice (first at s.lad:1:8 as Start; "
                            "symbols compare without regard to case)")


def test_the_validator_refuses_case_twins_in_a_program_built_as_a_tree():
    program = parse_program("XIC B3/0 OTE B3/1\n", "s.lad")
    program.symbols["Start"] = SymbolDecl("Start", parse_address("B3/0"))
    program.symbols["START"] = SymbolDecl("START", parse_address("B3/1"))
    _, errors = check(program)
    assert any("symbol START is declared twice (first as Start" in str(e) for e in errors)


def test_an_unknown_name_suggests_the_nearest_symbol_before_any_mnemonic():
    assert _errors("SYMBOL Start B3/0\nXIC Strat OTE O:0/0\n") == [
        "s.lad:2:5: unknown symbol 'Strat' (did you mean Start?)"]
    # No symbol close to it: a mnemonic it may be a misspelling of.
    assert _errors("SYMBOL Start B3/0\nXIC B3/1 MOV 1 N7:0 OTEE\n")[0].startswith("s.lad:2:")


def test_a_bad_member_in_a_rung_is_located_at_the_member():
    assert _errors(DECLS + "XIC PollTimer.XY OTE O:0/0\n") == [
        "s.lad:7:15: PollTimer is T4:0, a timer: members EN TT DN PRE ACC"]
    assert _errors(DECLS + 'CPT N7:0 "Levels.ACC * 2"\n') == [
        "s.lad:7:18: Levels is N7:10, a word: a word has no named members, only bits /0 to /15 (octal /0 to /17 "
        "for I and O)"]


def test_name_slash_name_in_an_expression_is_a_bit_and_the_error_says_how_to_divide():
    errors = _errors("SYMBOL Total N7:0\nSYMBOL Count N7:1\nCPT(N7:2,Total/Count);\n")
    assert len(errors) == 1 and "to divide, write Total / Count or Total | Count" in errors[0]
    assert _errors("SYMBOL Total N7:0\nSYMBOL Count N7:1\nCPT(N7:2,Total / Count);\n") == []


# -- every place an address is taken --------------------------------------------------------


@pytest.fixture
def app(tmp_path: Path) -> Path:
    return make_app(tmp_path / "sym", DECLS + "XIC Start TON PollTimer 0.01 100 0\nXIC Flags/3 OTE Reply/EN\n"
                    "XIC PollTimer/TT MOV PollTimer.ACC Levels[3]\n",
                    softplc_toml='[display]\nstatus = { "timer" = "PollTimer.ACC", "reply" = "Reply/EN" }\n'
                                 'summary = { "levels" = "#Levels 4" }\n')


def test_set_and_force_and_watch_take_symbol_members(app):
    loaded = load_app(app)
    symbols = loaded.program.symbols
    assert parse_assignment("PollTimer.PRE=5", symbols) == (parse_address("T4:0.PRE"), 5)
    assert parse_assignment("levels[2]=9", symbols) == (parse_address("N7:12"), 9)
    force = parse_force("Flags/3=1", symbols)
    assert force.address == parse_address("B3:2/3") and force.on
    assert WatchItem("PollTimer/DN", symbols).address == parse_address("T4:0/DN")
    with pytest.raises(DataTableError, match="PollTimer is T4:0, a timer: members EN TT DN PRE ACC"):
        parse_assignment("PollTimer.XX=1", symbols)


def test_display_and_break_when_take_symbol_members(app):
    loaded = load_app(app)
    assert [(i.label, str(i.address), i.count) for i in loaded.display.status + loaded.display.summary] == [
        ("timer", "T4:0.ACC", None), ("reply", "R6:3/EN", None), ("levels", "N7:10", 4)]
    with pytest.raises(DataTableError, match="Reply is R6:3, a control: members"):
        parse_item("x", "Reply.XX", "softplc.toml", loaded.program.symbols)
    cond = Condition("PollTimer.ACC + Flags/3 >= 3", loaded.program.symbols)
    assert [str(a.address) for a in address_refs(cond.node)] == ["T4:0.ACC", "B3/35"]
    with pytest.raises(DataTableError, match="--break-when: 'Strt': Strt is neither an address nor a program "
                                             r"symbol \(did you mean Start\?\)"):
        Condition("Strt = 1", loaded.program.symbols)


def test_watch_session_runs_with_symbol_members_everywhere(app):
    loaded = load_app(app)
    options = WatchOptions(run=RunOptions(sets=("Start=1", "PollTimer.PRE=1000")), watch=("PollTimer.ACC",),
                           forces=("Flags/3=1",), break_when=("PollTimer.ACC >= 5",))
    session = WatchSession(loaded, options)
    for _ in range(20):
        session.scan()
        if session.last_hit is not None:
            break
    table = session.engine.table
    assert session.last_hit is not None and table.read("T4:0.ACC") >= 5
    assert table.read("R6:3/EN") == 1  # Flags/3 forced on, so Reply/EN
    assert table.read("T4:0.PRE") == 1000


def test_watch_file_takes_symbol_members_and_locates_a_bad_one(app, tmp_path):
    symbols = load_app(app).program.symbols
    good = tmp_path / "good.watch"
    good.write_text("PollTimer/DN\n  Levels[2]  # third level\n")
    assert read_watch_file(good, symbols) == ["PollTimer/DN", "Levels[2]"]
    bad = tmp_path / "bad.watch"
    bad.write_text("N7:0\n  PollTimer.XX\n")
    with pytest.raises(LocatedError) as e:
        read_watch_file(bad, symbols)
    assert str(e.value).startswith(f"{bad}:2:13: ")
    assert "members EN TT DN PRE ACC" in str(e.value)


def test_run_print_and_set_take_symbol_members(app):
    p = softplc_here("run", str(app), "--scans", "3", "--set", "start=1", "--set", "PollTimer.PRE=500",
                     "--print", "PollTimer.PRE", "--print", "Flags/3", "--print", "N7:0")
    assert p.returncode == 0, p.stderr
    assert p.stdout.splitlines()[-3:] == ["PollTimer.PRE (T4:0.PRE) = 500", "Flags/3 (B3/35) = 0", "N7:0 = 0"]


# -- an unknown instruction that is a real AB instruction ----------------------------------------


def test_an_unknown_real_ab_instruction_says_which_processor_has_it():
    errors = _errors("XIC B3/0 BTR N7:0 N7:1\n")
    assert any("BTR (block transfer read) is a PLC-5 instruction softplc_lite does not implement" in e
               for e in errors), errors


def test_the_ab_message_follows_the_live_table_not_a_fixed_list():
    # A mnemonic the table has (a module's, here) is never "not implemented".
    from softplc_lite.ladder.specs import K, _spec

    spec = _spec("BTR", "block transfer read", True, ("source", K.WORD), ("dest", K.WORD))
    with_btr = InstructionSet(extra=[spec])
    program = parse_program("XIC B3/0 BTR N7:0 N7:1\n", "s.lad", with_btr)
    _, errors = check(program, with_btr)
    assert errors == []
    assert "does not implement" not in with_btr.hint("BTR")
    assert "SLC 500 instruction" in InstructionSet().hint("SVC")
    assert InstructionSet().hint("XIK") == " (did you mean XIO?)"


def test_every_bad_member_of_a_program_is_listed_at_once():
    from softplc_lite.ladder import load_text

    with pytest.raises(ProgramErrors) as e:
        load_text(DECLS + "XIC PollTimer.XY OTE Reply.ZZ\n")
    assert [x.message.split(":")[0] for x in e.value.errors] == ["PollTimer is T4", "Reply is R6"]


@pytest.mark.parametrize("executor", EXECUTORS)
def test_symbol_members_in_cmp_in_both_syntaxes(executor):
    program = DECLS + 'CMP "PollTimer.PRE > Levels[2]" OTE Flags/1\nCMP(PollTimer.PRE < Levels[2])OTE(Flags/2);\n'
    engine = run_text(program, executor=executor, values={"T4:0.PRE": 9, "N7:12": 4})
    assert engine.table.read("B3:2/1") == 1 and engine.table.read("B3:2/2") == 0
