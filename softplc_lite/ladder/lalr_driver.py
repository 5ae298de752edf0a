"""A faster loop over a Lark LALR parser's own tables, for the load time of large programs.

Lark stays the one grammar: this module takes everything from the ``Lark``
object built from ``ladder.lark`` -- the LALR parse table, the contextual
lexer's per-state terminal regexes and keyword callbacks, the post-lexer
and the rule callbacks (the Transformer applied during the parse) -- and
only runs them with less overhead per token than lark's generic loop
(lark 1.3: ``lexer.py`` ``ContextualLexer.lex``/``BasicLexer.next_token``,
``parsers/lalr_parser_state.py`` ``ParserState.feed_token``), which costs
about 10 us a token on a 10,000-rung program. It does not report errors:
at the first token it cannot lex or shift it raises ``NotFastPath`` and the
caller parses the text again with Lark itself, so every syntax error keeps
lark's exception, position and context (softplc choice: the correct
program is the common, large case; a wrong one is parsed twice).

What lark does per token that this loop skips: a generator frame per
lexer layer (lexer, post-lexer, parser are one loop here), a second regex
match for the blanks before a token (skipped in the same match, see
``_StateLexer``), a ``LineCounter`` object, the ``Token`` constructor's
keyword handling, the keyword ``UnlessCallback`` regex (memoised here per
lexer and text: it depends on nothing else), and the ``Rule`` attribute
look-ups of each reduction (precomputed into one table, keyed by plain
str: lark names rules with Tokens, which compare through Token.__eq__).

Read from the same tables, for the cold load: the steps of a
left-recursive list rule (``_list_steps``: most tokens of a mnemonic rung
are one step, no stack traffic and, with a token action, no Token: about
2 us a token instead of 4 on the 10,000-rung boolean program), and the
one-symbol "?rule" reductions, which only change the state (lark's
``ExpandSingleChild`` returns the child), chained per (state below, state,
token kind) in ``unit_chains``.

The post-lexer is read as a table (``span_changes``: the token kinds that
open or close a span; ``dropped_inside``: the kinds dropped while a span is
open), as parser.py's LadderPostLex declares it.
"""

from __future__ import annotations

import logging
import re

from lark import Lark, Token
from lark import __version__ as LARK_VERSION

# Every internal of lark that softplc_lite reads is read here, and only here
# (the rest of the ladder package uses lark's documented API). They are
# those of lark 1.3 (pyproject.toml pins lark>=1.3,<1.4); where one is
# missing or unlike what this module expects, ``fast_parser`` gives a
# stand-in and every parse goes through lark's own parser, with the same
# results (softplc choice: slower, never wrong).
try:
    from lark.lexer import UnlessCallback
    from lark.parse_tree_builder import ExpandSingleChild
    from lark.parsers.lalr_analysis import Shift
    from lark.utils import sre_constants, sre_parse

    _ZERO_WIDTH = (sre_constants.AT, sre_constants.ASSERT, sre_constants.ASSERT_NOT)
    _REPEATS = (sre_constants.MAX_REPEAT, sre_constants.MIN_REPEAT, sre_constants.POSSESSIVE_REPEAT)
except (ImportError, AttributeError) as e:
    _MISSING: Exception | None = e
else:
    _MISSING = None

# What reading another lark's tables raises (a name moved, a table shaped otherwise).
_LARK_CHANGED = (AttributeError, KeyError, IndexError, ImportError, TypeError, ValueError, re.error)

_log = logging.getLogger(__name__)
_new_str = str.__new__


class NotFastPath(Exception):
    """The text needs lark's own parser (a syntax error, or a lexer this
    loop does not model); nothing of this attempt is kept."""


class _LarkUnlike(NotFastPath):
    """Lark's objects are not as this loop reads them: lark's own parser
    for the rest of the process."""


class LarkOnly:
    """Stands in for FastLalr when the loop cannot run on this lark: every
    parse is left to lark's own parser."""

    def __init__(self, why: str) -> None:
        self.why = why

    def parse(self, text: str, start: str):
        raise NotFastPath(self.why)


# Why the loop is off for the rest of the process (each thread parses with
# a FastLalr of its own: one that finds lark unlike turns them all off).
_off: str | None = None


def fast_parser(lark: Lark, token_actions: dict | None = None) -> FastLalr | LarkOnly:
    """The fast loop over ``lark``'s tables, or, when they cannot be read
    as lark 1.3 lays them out, a LarkOnly (one debug line says why)."""
    if _off is not None:
        return LarkOnly(_off)
    try:
        if _MISSING is not None:
            raise _MISSING
        return FastLalr(lark, token_actions)
    except (_LarkUnlike, *_LARK_CHANGED) as e:
        return LarkOnly(_gave_up(e))


def _gave_up(e: Exception) -> str:
    global _off
    why = f"lark {LARK_VERSION} is not laid out as this loop reads it ({e!r})"
    if _off is None:
        _log.debug("the fast parse loop is off for this process: %s; lark's own parser parses", why)
        _off = why
    return _off


class _StateLexer:
    """One parser state's terminals, from lark's BasicLexer for that state.

    Lark tries the terminals as one alternation in its order and takes the
    first that matches; an ignored terminal (blanks) is one more match. Here
    one regex does both: ``(?:(?!B)(?>I))*+`` skips, while the first
    terminal to match is the ignored one ``I`` (``B``: the terminals lark
    tries before ``I``; atomic and possessive, so nothing is given back),
    then lark's own alternation follows, unchanged.
    """

    __slots__ = ("keyword_of", "match", "newline", "skip", "skip_has_newline")

    def __init__(self, basic) -> None:
        scanner = basic.scanner  # built on first use, as lark does
        terminals = scanner.terminals
        alternation = "|".join(f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in terminals)
        flags = basic.g_regex_flags
        if (len(scanner._mres) != 1 or scanner._mres[0].pattern != alternation or scanner.use_bytes
                or scanner.re_ is not re):
            raise _LarkUnlike("a lexer unlike lark 1.3's")
        skips = []
        for i, t in enumerate(terminals):
            if t.name in basic.ignore_types:
                # Only a terminal that can start where the ignored one does
                # can match there first: the others need no look-ahead.
                ignored = _first_chars(t.pattern.to_regexp(), flags)
                before = "|".join(u.pattern.to_regexp() for u in terminals[:i]
                                  if _may_overlap(ignored, _first_chars(u.pattern.to_regexp(), flags)))
                skips.append((f"(?!{before})" if before else "") + f"(?>{t.pattern.to_regexp()})")
        skip = f"(?:{'|'.join(skips)})*+" if skips else ""
        self.match = re.compile(skip + "(?:" + alternation + ")", flags).match
        self.skip = re.compile(skip, flags).match  # the blanks at the end of a text
        self.newline = basic.newline_types
        self.skip_has_newline = bool(basic.newline_types & basic.ignore_types)
        # NAME -> ({"bst": "BST", "Motor": "NAME", ...}, keyword scanner):
        # lark's UnlessCallback turns a NAME spelt like a keyword into the keyword.
        self.keyword_of = {}
        for name, callback in basic.callback.items():
            if not isinstance(callback, UnlessCallback):
                raise _LarkUnlike("a lexer callback")
            self.keyword_of[name] = ({}, callback.scanner)


class _Lexers(dict):
    """state -> _StateLexer, each built when a parse first reaches its state
    (compiling all of them took about 50 ms of every command's start)."""

    def __init__(self, basic_lexers: dict) -> None:
        super().__init__()
        self.basic_lexers = basic_lexers
        self.shared: dict[int, _StateLexer] = {}  # lark shares one BasicLexer among states with one terminal set

    def __missing__(self, state: int) -> _StateLexer:
        basic = self.basic_lexers[state]
        lexer = self.shared.get(id(basic))
        if lexer is None:
            lexer = self.shared[id(basic)] = _StateLexer(basic)
        self[state] = lexer
        return lexer


class FastLalr:
    """Parses with one ``Lark`` object (parser="lalr", lexer="contextual",
    a post-lexer declaring ``span_changes`` and ``dropped_inside``), giving
    exactly what ``lark.parse`` gives for a text it accepts. Construction
    raises a NotFastPath for a ``Lark`` set up otherwise, or whatever
    reading another lark's objects raises: ``fast_parser`` takes either."""

    def __init__(self, lark: Lark, token_actions: dict | None = None) -> None:
        self.off: str | None = None  # why lark's own parser parses instead, once it must
        frontend = lark.parser
        connector = frontend.lexer
        postlex = connector.postlexer
        self.span_changes = dict(postlex.span_changes)
        self.dropped_inside = postlex.dropped_inside
        self.span_count = 1 + max((i for i, _ in self.span_changes.values()), default=0)
        self.lexers = _Lexers(connector.lexer.lexers)
        parser = frontend.parser.parser
        table = parser.parse_table
        callbacks = parser.callbacks
        if any(isinstance(k, str) for k in callbacks):
            raise _LarkUnlike("terminal callbacks")
        self.start_states = table.start_states
        self.end_states = table.end_states
        # state -> {symbol: (shift_to, None) or (None, (size, origin, callback))}
        self.actions: dict[int, dict[str, tuple]] = {}
        reductions: dict = {}  # rule -> its one (size, origin, callback)
        for state, row in table.states.items():
            compiled = {}
            for symbol, (action, arg) in row.items():
                if action is Shift:
                    compiled[str(symbol)] = (arg, None)
                else:
                    if arg not in reductions:
                        callback = callbacks[arg]
                        if len(arg.expansion) == 1 and type(callback) is ExpandSingleChild:
                            callback = None  # a "?rule" of one symbol gives that symbol's value: nothing to do
                        reductions[arg] = (len(arg.expansion), str(arg.origin.name), callback)
                    compiled[str(symbol)] = (None, reductions[arg])
            self.actions[state] = compiled
        # (state below, state, token kind) -> the state after the one-symbol
        # reductions that follow, one after the other (an expression operand
        # goes up about ten levels of precedence that way)
        self.unit_chains: dict[tuple[int, int, str], int] = {}
        self.list_steps = _list_steps(self.actions, reductions, token_actions or {},
                                      set(self.span_changes) | set(self.dropped_inside))

    def parse(self, text: str, start: str):
        """What ``lark.parse(text, start=start)`` gives, or NotFastPath. A
        failure to read lark's objects (a state's lexer is built on first
        use) turns this loop off for the rest of the process."""
        if self.off is not None or _off is not None:
            self.off = self.off or _off
            raise NotFastPath(self.off)
        try:
            return self._parse(text, start)
        except NotFastPath as e:
            if not isinstance(e, _LarkUnlike):
                raise
            self.off = _gave_up(e)
        except _LARK_CHANGED as e:
            self.off = _gave_up(e)
        raise NotFastPath(self.off)

    def _parse(self, text: str, start: str):
        """Lark's contextual lexer, post-lexer and LALR parser as one loop."""
        actions = self.actions
        list_steps = self.list_steps
        unit_chains = self.unit_chains
        lexers = self.lexers
        span_changes = self.span_changes
        dropped_inside = self.dropped_inside
        spans = [False] * self.span_count
        state = self.start_states[start]
        lex_state = state  # whose terminals lex the next token: lark lexes it before it reduces
        expected = None  # after a list step: the actions of the state lark would be in
        state_stack = [state]
        value_stack: list = []
        push_state = state_stack.append
        push_value = value_stack.append
        pos = 0
        end = len(text)
        line = 1
        line_start = 0  # where the current line starts
        while pos < end:
            lexer = lexers[lex_state]
            m = lexer.match(text, pos)
            if m is None:
                blanks = lexer.skip(text, pos)
                if blanks is not None and blanks.end() == end:
                    if lexer.skip_has_newline:
                        line, line_start = _count_lines(text, pos, end, line, line_start)
                    break
                raise NotFastPath("no terminal")
            kind = m.lastgroup
            value = m.group(kind)
            skipped_from = pos
            pos = m.end()
            start_pos = pos - len(value)
            if lexer.skip_has_newline and start_pos != skipped_from:
                line, line_start = _count_lines(text, skipped_from, start_pos, line, line_start)
            token_line = line
            column = start_pos - line_start + 1
            if kind in lexer.newline and "\n" in value:
                line, line_start = _count_lines(text, start_pos, pos, line, line_start)
            keyword = lexer.keyword_of.get(kind)
            if keyword is not None:
                known, scanner = keyword
                found = known.get(value)
                if found is None:
                    found = known[value] = scanner.fullmatch(value) or kind
                kind = found
            steps = list_steps.get(state)
            if steps is not None:  # the next step of a list, most tokens of a mnemonic rung
                step = steps.get(kind)  # (never a kind the post-lexer reads)
                if step is not None:
                    if expected is not None and kind not in expected:
                        raise NotFastPath(kind)
                    lex_state, expected, token_action, units, list_callback = step
                    if token_action is not None:
                        value_stack[-1] = token_action(value_stack[-1], kind, value, token_line, column)
                    else:
                        token = _token(kind, value, start_pos, token_line, column, line, pos - line_start + 1, pos)
                        value_stack[-1] = list_callback([value_stack[-1], _reduced(units, token)])
                    continue
            # the post-lexer
            change = span_changes.get(kind)
            if change is not None:
                spans[change[0]] = change[1]
            elif kind in dropped_inside and True in spans:
                continue
            if expected is not None and kind not in expected:
                raise NotFastPath(kind)  # where lark, one token later than this loop, finds the error
            token = _token(kind, value, start_pos, token_line, column, line, pos - line_start + 1, pos)
            # the parser: reduce while the table says so, then shift, or
            # take one step of a left-recursive list (see _list_steps)
            row = actions[state]
            while True:
                action = row.get(kind)
                if action is None:
                    raise NotFastPath(kind)
                shift_to, reduce = action
                if shift_to is not None:
                    break
                size, origin, callback = reduce
                if callback is None:  # the value stays; only the state changes
                    key = (state_stack[-2], state, kind)
                    state = unit_chains.get(key)
                    if state is None:
                        state = unit_chains[key] = self._after_units(*key)
                    state_stack[-1] = state
                    row = actions[state]
                    continue
                if size:
                    children = value_stack[-size:]
                    del state_stack[-size:]
                    del value_stack[-size:]
                else:
                    children = []
                push_value(callback(children))
                state = actions[state_stack[-1]][origin][0]
                push_state(state)
                row = actions[state]
            steps = list_steps.get(state)
            if steps is not None and kind in steps:  # the first step of a list
                lex_state, expected, token_action, units, list_callback = steps[kind]
                if token_action is not None:
                    value_stack[-1] = token_action(value_stack[-1], kind, value, token_line, column)
                else:
                    value_stack[-1] = list_callback([value_stack[-1], _reduced(units, token)])
                continue
            state = lex_state = shift_to
            expected = None
            push_state(state)
            push_value(token)
        if expected is not None and "$END" not in expected:
            raise NotFastPath("$END")
        return self._end(state_stack, value_stack, self.end_states[start])

    def _after_units(self, below: int, state: int, kind: str) -> int:
        """The state after the one-symbol reductions in a row that ``kind``
        calls for in ``state``, over ``below``: each replaces the top state
        only, so nothing else decides where they end."""
        actions = self.actions
        while True:
            action = actions[state].get(kind)
            if action is None or action[0] is not None or action[1][2] is not None:
                return state
            state = actions[below][action[1][1]][0]

    def _end(self, state_stack: list, value_stack: list, end_state: int):
        """Lark's "$END": reduce until the start rule is complete (no rule
        action sees the $END token itself)."""
        actions = self.actions
        while True:
            action = actions[state_stack[-1]].get("$END")
            if action is None or action[0] is not None:
                raise NotFastPath("$END")
            size, origin, callback = action[1]
            if callback is None:
                state_stack[-1] = actions[state_stack[-2]][origin][0]
                if state_stack[-1] == end_state:
                    return value_stack[-1]
                continue
            if size:
                children = value_stack[-size:]
                del state_stack[-size:]
                del value_stack[-size:]
            else:
                children = []
            value_stack.append(callback(children))
            state_stack.append(actions[state_stack[-1]][origin][0])
            if state_stack[-1] == end_state:
                return value_stack[-1]


def _list_steps(actions: dict[int, dict[str, tuple]], reductions: dict, token_actions: dict,
                post_lexer_kinds: set[str]) -> dict:
    """state -> {token kind: step} for each left-recursive list rule
    ``x: x? y`` given a token action (parser.py gives mn_tokens'): in a
    state reached by ``x``, a token K shifts to a state whose every action
    is to reduce, and the reductions end with ``x: x y``, which returns to
    the state reached by ``x``. The loop does that shift and those
    reductions as one step, with no stack traffic. A step is

    (state after the shift, the next token's allowed kinds, token action,
    reductions, list callback).

    For ``y`` the token itself the token action gets (list so far, kind,
    text, line, column), no Token, and does what the rule's callback does
    with [list so far, Token]; its result replaces the list on the stack.
    Otherwise (a number: ``y`` is signed_number, reduced from INT) the
    one-symbol reductions' callbacks (None: the value stays) and then the
    list callback are called on a Token, as by lark. This is the classic
    "default reduction": the token after K, which lark reads (in the state
    after the shift) before it reduces, is checked against the kinds every
    state on the way reduces on before it is used. Kinds the post-lexer
    reads are left to the general loop."""
    reached_by: dict[int, str] = {}
    for row in actions.values():
        for symbol, (shift_to, _reduce) in row.items():
            if shift_to is not None:
                reached_by[shift_to] = symbol
    nonterminals = {origin for _size, origin, _callback in reductions.values()}
    found: dict[int, dict[str, tuple]] = {}
    for state, row in actions.items():
        list_rule = reached_by.get(state)
        if list_rule not in token_actions:
            continue
        for kind, (shift_to, _reduce) in row.items():
            if shift_to is None or kind in nonterminals or kind in post_lexer_kinds:
                continue
            units: list = []
            allowed = set(actions[shift_to])
            current = shift_to
            while len(units) < 8:
                after = set(actions[current].values())
                if len(after) != 1:
                    break
                (to, reduce), = after
                if to is not None:
                    break
                size, origin, callback = reduce
                if size == 2 and origin == list_rule and _left_recursive(reductions, reduce):
                    if units:
                        step = (shift_to, frozenset(allowed), None, tuple(units), callback)
                    else:
                        step = (shift_to, actions[shift_to], token_actions[list_rule], None, None)
                    found.setdefault(state, {})[kind] = step
                    break
                goto = actions[state].get(origin)
                if size != 1 or goto is None or goto[0] is None:
                    break
                units.append(callback)
                current = goto[0]
                allowed &= set(actions[current])
    return found


def _token(kind: str, value: str, start_pos: int, line: int, column: int, end_line: int, end_column: int,
           end_pos: int) -> Token:
    """lark's Token, without its constructor's keyword handling."""
    token = _new_str(Token, value)
    token.type = kind
    token.start_pos = start_pos
    token.value = value
    token.line = line
    token.column = column
    token.end_line = end_line
    token.end_column = end_column
    token.end_pos = end_pos
    return token


def _reduced(units: tuple, token: Token):
    """The value of one-symbol reductions over a token, as lark's loop gives it."""
    value = token
    for callback in units:
        if callback is not None:
            value = callback([value])
    return value


def _left_recursive(reductions: dict, reduce: tuple) -> bool:
    rule = next(r for r, compiled in reductions.items() if compiled is reduce)
    return str(rule.expansion[0].name) == reduce[1]


def _count_lines(text: str, begin: int, stop: int, line: int, line_start: int) -> tuple[int, int]:
    """The line and line start after text[begin:stop], as lark's LineCounter."""
    newlines = text.count("\n", begin, stop)
    if newlines:
        return line + newlines, text.rindex("\n", begin, stop) + 1
    return line, line_start


# -- the characters a terminal can start with -------------------------------------
# Read from the regex's parse by Python's own regex parser (the one lark's
# get_regexp_width uses). None stands for "any character, or cannot tell":
# the answer may be too large, never too small.

_MOST_CHARS = 512  # a larger class counts as "any character"


def _first_chars(regexp: str, flags: int) -> frozenset[str] | None:
    """The characters a match of ``regexp`` can start with (lark allows
    no terminal to match the empty string)."""
    chars, can_be_empty = _first(sre_parse.parse(regexp, flags), bool(flags & sre_constants.SRE_FLAG_IGNORECASE))
    return None if chars is None or can_be_empty else frozenset(chars)


def _may_overlap(a: frozenset[str] | None, b: frozenset[str] | None) -> bool:
    return a is None or b is None or not a.isdisjoint(b)


def _first(items, ignore_case: bool) -> tuple[set[str] | None, bool]:
    """(first characters or None, can the sequence ``items`` match nothing)."""
    found: set[str] = set()
    for op, arg in items:
        if op in _ZERO_WIDTH:
            continue
        if op is sre_constants.LITERAL:
            chars, can_be_empty = {chr(arg)}, False
        elif op is sre_constants.IN:
            chars, can_be_empty = _class_chars(arg), False
        elif op is sre_constants.SUBPATTERN:
            _group, add_flags, del_flags, pattern = arg
            case = sre_constants.SRE_FLAG_IGNORECASE
            chars, can_be_empty = _first(pattern, (ignore_case or bool(add_flags & case)) and not del_flags & case)
        elif op is sre_constants.ATOMIC_GROUP:
            chars, can_be_empty = _first(arg, ignore_case)
        elif op is sre_constants.BRANCH:
            chars, can_be_empty = set(), False
            for alternative in arg[1]:
                more, empty = _first(alternative, ignore_case)
                if more is None:
                    return None, True
                chars |= more
                can_be_empty = can_be_empty or empty
        elif op in _REPEATS:
            least, _most, pattern = arg
            chars, can_be_empty = _first(pattern, ignore_case)
            can_be_empty = can_be_empty or least == 0
        else:  # ANY, NOT_LITERAL, a group reference...
            return None, True
        if chars is None:
            return None, True
        if ignore_case and op in (sre_constants.LITERAL, sre_constants.IN):
            if not all(c.isascii() for c in chars):
                return None, True
            chars = chars | {c.lower() for c in chars} | {c.upper() for c in chars}
        found |= chars
        if not can_be_empty:
            return found, False
    return found, True


def _class_chars(items) -> set[str] | None:
    """The characters of a class [...]; None for a negated one, a category
    (\\s, \\w ...) or a large range."""
    chars: set[str] = set()
    for op, arg in items:
        if op is sre_constants.LITERAL:
            chars.add(chr(arg))
        elif op is sre_constants.RANGE and arg[1] - arg[0] < _MOST_CHARS:
            chars.update(chr(c) for c in range(arg[0], arg[1] + 1))
        else:
            return None
    return chars
