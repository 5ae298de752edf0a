"""The fast parse loop (lalr_driver.py) gives exactly what Lark's
own parser gives over the same grammar: the same AST with the same
positions for every shipped program, the benchmark programs and thousands
of damaged copies of them, and the same errors (message, file:line:col,
lark's context) for every text it refuses. Not timed."""

from __future__ import annotations

import inspect
import random
from pathlib import Path

import pytest
from helpers.benchmark_modules import load

from softplc_lite.ladder import lalr_driver, parser
from softplc_lite.ladder.ast import Pos
from softplc_lite.ladder.errors import LadderError
from softplc_lite.ladder.lalr_driver import FastLalr, NotFastPath
from softplc_lite.ladder.parser import parse_expression, parse_program, syntax_problems

ROOT = Path(__file__).resolve().parent.parent
ladder_programs = load("ladder_programs")

PROGRAMS = sorted([*ROOT.glob("programs/**/*.lad"), *ROOT.glob("tests/data/**/*.lad")])


def dump(node) -> str:
    """A node with every constructor field and its position, recursively
    (``==`` on AST nodes ignores positions; this does not)."""
    if isinstance(node, (list, tuple)) and not hasattr(node, "_fields"):
        return "[" + ",".join(dump(x) for x in node) + "]"
    if isinstance(node, dict):
        return "{" + ",".join(f"{k!r}:{dump(v)}" for k, v in node.items()) + "}"
    if type(node).__module__.startswith("softplc_lite") and not isinstance(node, type):
        names = list(inspect.signature(type(node)).parameters)
        if hasattr(node, "pos") and "pos" not in names:
            names.append("pos")
        return f"{type(node).__name__}(" + ",".join(f"{n}={dump(getattr(node, n))}" for n in names) + ")"
    return repr(node)


class _LarkOnly:
    def parse(self, text, start):
        raise NotFastPath("this test parses with Lark's own loop")


@pytest.fixture
def lark_only(monkeypatch):
    """Within the fixture, every parse goes through Lark's own parser."""

    def use_lark():
        monkeypatch.setattr(parser, "_fast_parser", lambda: _LarkOnly())

    return use_lark


def outcome(text: str, source: str) -> str:
    try:
        result = dump(parse_program(text, source))
    except LadderError as e:
        result = f"error {e.pos} {e.message} {e.context!r}"
    problems = syntax_problems(text, source)
    return result + " | " + " ; ".join(f"{e.pos} {e.message} {e.context!r}" for e in problems)


def damaged(text: str, rnd: random.Random) -> str:
    pieces = list("()[];,:/.\n \"#+-*|=<>0123456789ABNXIOTCSE") + [
        "BST ", "NXB ", "BND ", "SOR ", "EOR ", "MOD ", "1e999 ", "0x", "\r\n", "//", "XIC ", "CPT ", "\t", "\f"]
    for _ in range(rnd.randint(1, 3)):
        i = rnd.randrange(len(text) + 1)
        choice = rnd.random()
        if choice < 0.4:
            text = text[:i] + text[i + 1:]
        elif choice < 0.8:
            text = text[:i] + rnd.choice(pieces) + text[i:]
        else:
            text = text[:i] + text[min(len(text), i + rnd.randint(1, 20)):]
    return text


def corpus() -> list[tuple[str, str]]:
    texts = [(str(p.relative_to(ROOT)), p.read_text()) for p in PROGRAMS]
    texts.append(("boolean", ladder_programs.boolean_program(80)))
    texts.append(("mixed", ladder_programs.mixed_program(80)))
    texts += [("blank", ""), ("blanks", " \t\n\n  "), ("no newline", "XIC B3/0 OTE B3/1"),
              ("tail blanks", "XIC B3/0 OTE B3/1\n   "), ("crlf", "XIC B3/0\r\nOTE B3/1\r\n")]
    return texts


def test_the_fast_loop_parses_every_program_without_lark(monkeypatch):
    # Otherwise the comparisons below would compare Lark with itself.
    assert isinstance(parser._fast_parser(), FastLalr)
    lark = parser._ast_parser()
    monkeypatch.setattr(lark, "parse", lambda *a, **k: pytest.fail("parsed by Lark"))
    for name, text in corpus():
        parse_program(text, name, problems=[])


@pytest.mark.parametrize("seed", range(2))
def test_the_fast_loop_and_lark_give_the_same_programs_and_errors(lark_only, seed):
    rnd = random.Random(seed)
    texts = corpus() if seed == 0 else []
    for name, text in corpus():
        texts += [(f"{name}#{seed}.{k}", damaged(text, rnd)) for k in range(6)]
    fast = [outcome(text, name) for name, text in texts]
    lark_only()
    slow = [outcome(text, name) for name, text in texts]
    for (name, _), a, b in zip(texts, fast, slow):
        assert a == b, name


@pytest.mark.parametrize("text", ["N7:0 + 5", "1e999", "(N7:1", "SQR(N7:0) ** 2", "-0x10", "NOT N7:0 AND 3",
                                  "FOO(1)", "5 MOD 3", "5 mod3", "N7:0 ", "", "  ", "N7:0 +", "Timer/DN = 1"])
def test_expressions_too(lark_only, text):
    def parsed():
        try:
            return dump(parse_expression(text, Pos("e.lad", 3, 7)))
        except LadderError as e:
            return f"error {e.pos} {e.message} {e.context!r}"

    fast = parsed()
    lark_only()
    assert fast == parsed()


def test_a_syntax_error_is_lark_s_with_every_problem_found_before_it_once():
    # The fast loop gives up at the ";" and Lark parses the text again: the
    # problems the first try found are not listed twice.
    text = "MOV 1e999 N7:0\nXIC B3/0 OTE B3/1 ;\n"
    problems = syntax_problems(text, "t.lad")
    assert [(p.pos.line, p.pos.column) for p in problems] == [(1, 5), (2, 19)]
    assert "out of range" in problems[0].message and "unexpected ';'" in problems[1].message
    assert problems[1].context and "^" in problems[1].context


def test_a_mnemonic_rung_skips_limit_problem_only_when_nothing_can_be_over_a_limit():
    # parser._finish tells limit_problem's work is needed from the branch
    # depth and the expressions it saw; at and past each limit it is asked.
    from softplc_lite.ladder.instructions import BUILTIN
    from softplc_lite.ladder.limits import (
        MAX_BRANCH_DEPTH,
        MAX_EXPRESSION_DEPTH,
        limit_problem,
    )

    def grouped(text):
        run = parser._parse_tree(text + "\n", "t.lad", "start", instructions=BUILTIN)[0].run
        return parser._finish(run, BUILTIN)

    def nested(depth):
        return "XIC B3/0 " + "BST XIC B3/1 NXB " * depth + "OTE B3/2 " + "BND " * depth

    for depth in (0, 1, MAX_BRANCH_DEPTH - 1, MAX_BRANCH_DEPTH):
        elements, check = grouped(nested(depth))
        assert not check and limit_problem(elements) is None
    elements, check = grouped(nested(MAX_BRANCH_DEPTH + 1))
    assert check and "branches nested" in limit_problem(elements)[1]
    # An expression (CPT's, parsed by parse_expression, which refuses one
    # past MAX_EXPRESSION_DEPTH itself) is always handed to limit_problem.
    elements, check = grouped('CPT N7:0 "' + "ABS(" * MAX_EXPRESSION_DEPTH + "N7:1" + ")" * MAX_EXPRESSION_DEPTH + '"')
    assert check and limit_problem(elements) is None
    for name, text in corpus():
        for line in text.splitlines():
            result = grouped_or_none(line)
            assert result is None or result[1] or limit_problem(result[0]) is None, (name, line)


def grouped_or_none(line: str):
    """_finish's answer for a one-line mnemonic rung; None for any other line
    (a line of a multi-line rung, a directive, one with a problem)."""
    from softplc_lite.ladder.instructions import BUILTIN

    try:
        drafts = [i for i in parser._parse_tree(line + "\n", "t.lad", "start", instructions=BUILTIN)
                  if getattr(i, "run", None)]
        return parser._finish(drafts[0].run, BUILTIN) if drafts else None
    except LadderError:
        return None


@pytest.mark.parametrize("text", ["XIC B3/: ;\n", "XIC B3/:\n;\n", "XIC B3/: B3/x\n", "SOR XIC B3/: ; EOR\n",
                                  "XIC B3/: (\n", "XIC B3/0 B3/: ) OTE B3/1\n", "XIC B3/:", "XIC Timer/DN B3/: [\n",
                                  "MOV 1e999 ;\n", "MOV 1e999", "MOV 5 N7:0 (\n", "TON T4:0 0x10 -5 +3 1.5e3 .5\n",
                                  "MOV 0x1FFFFFFFFF N7:0 ]\n", "MOV 5\n", "SOR MOV 5 EOR 6\n"])
def test_a_rule_action_s_error_just_before_a_syntax_error(lark_only, text):
    # The fast loop reduces a mnemonic rung's list one token before lark
    # does, so a bad address is refused before the syntax error after it is
    # seen: lark, parsing again, says which one it meets first.
    fast = outcome(text, "t.lad")
    lark_only()
    assert fast == outcome(text, "t.lad")


def test_the_list_steps_come_from_the_tables():
    steps = parser._fast_parser().list_steps
    assert steps, "mn_tokens' list steps"
    kinds = set().union(*steps.values())
    assert kinds == {"NAME", "ADDRESS", "SYMBOL_MEMBER", "STRING", "BST", "NXB", "BND", "INT", "FLOAT", "HEX"}
    for by_kind in steps.values():  # a number is reduced to signed_number on the way
        assert all((step[2] is None) == (kind in ("INT", "FLOAT", "HEX")) for kind, step in by_kind.items())


@pytest.mark.parametrize(("regexp", "chars"), [
    (r"[ \t\f]+", " \t\f"), (r"(?i:bst)", "Bb"), (r"(?:\r?\n)+", "\r\n"), (r'"([^"\\\n]|\\.)*"', '"'),
    (r"\/\/[^\n]*", "/"), (r"([0-9]+\.[0-9]*|\.[0-9]+)|[0-9]+[eE][0-9]+", ".0123456789"), (r"(?:<>|<=|=)", "<="),
    (r"#?[A-C]{1,2}", "#ABC"), (r"(?>x)y", "x"), (r"(?=a)b", "b"),
    (r"a?", None), (r".x", None), (r"[^a]", None), (r"\sx", None), (r"[\u0100-\u0400]", None), (r"(?i:\u00e9)", None)])
def test_the_characters_a_terminal_can_start_with(regexp, chars):
    # Too many is safe (a look-ahead kept that was not needed), too few not.
    found = lalr_driver._first_chars(regexp, 0)
    assert found == (None if chars is None else frozenset(chars))


def test_the_blanks_need_no_look_ahead_in_this_grammar():
    # No terminal of ladder.lark starts with a blank, so the skip of blanks
    # before a token is a plain repetition (the look-ahead cost ~0.4 us a token).
    parse_program("XIC B3/0 OTE B3/1\n")
    for lexer in parser._fast_parser().lexers.values():
        assert "(?!" not in lexer.skip.__self__.pattern


def test_the_unit_chains_end_where_the_reductions_one_by_one_do():
    fast = parser._fast_parser()
    parse_expression("SQR(N7:0) ** 2 + -N7:1 * 3 < 4", Pos("e.lad", 1, 1))
    assert fast.unit_chains
    for (below, state, kind), end in fast.unit_chains.items():
        action = fast.actions[state][kind]
        while action[0] is None and action[1][2] is None:  # a one-symbol reduction lark's callback would undo
            state = fast.actions[below][action[1][1]][0]
            action = fast.actions[state].get(kind, (0, None))
        assert state == end
