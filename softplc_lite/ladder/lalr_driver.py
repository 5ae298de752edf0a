"""A faster loop over a Lark LALR parser's own tables (issue 17, "Load").

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

The post-lexer is read as a table (``span_changes``: the token kinds that
open or close a span; ``dropped_inside``: the kinds dropped while a span is
open), as parser.py's LadderPostLex declares it.
"""

from __future__ import annotations

import re

from lark import Lark, Token
from lark.lexer import UnlessCallback
from lark.parsers.lalr_analysis import Shift

_new_str = str.__new__


class NotFastPath(Exception):
    """The text needs lark's own parser (a syntax error, or a lexer this
    loop does not model); nothing of this attempt is kept."""


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
            raise NotFastPath("a lexer unlike lark 1.3's")
        skips = []
        for i, t in enumerate(terminals):
            if t.name in basic.ignore_types:
                before = "|".join(u.pattern.to_regexp() for u in terminals[:i])
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
                raise NotFastPath("a lexer callback")
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
    raises NotFastPath for a ``Lark`` set up otherwise."""

    def __init__(self, lark: Lark) -> None:
        frontend = lark.parser
        connector = frontend.lexer
        postlex = connector.postlexer
        self.span_changes = dict(postlex.span_changes)
        self.dropped_inside = postlex.dropped_inside
        self.lexers = _Lexers(connector.lexer.lexers)
        parser = frontend.parser.parser
        table = parser.parse_table
        callbacks = parser.callbacks
        if any(isinstance(k, str) for k in callbacks):
            raise NotFastPath("terminal callbacks")
        self.start_states = table.start_states
        self.end_states = table.end_states
        # state -> {symbol: (shift_to, None) or (None, (size, origin, callback))}
        self.actions: dict[int, dict[str, tuple]] = {}
        for state, row in table.states.items():
            compiled = {}
            for symbol, (action, arg) in row.items():
                if action is Shift:
                    compiled[str(symbol)] = (arg, None)
                else:
                    compiled[str(symbol)] = (None, (len(arg.expansion), str(arg.origin.name), callbacks[arg]))
            self.actions[state] = compiled

    def parse(self, text: str, start: str):
        """Lark's contextual lexer, post-lexer and LALR parser as one loop."""
        actions = self.actions
        lexers = self.lexers
        span_changes = self.span_changes
        dropped_inside = self.dropped_inside
        spans = [False] * (1 + max((i for i, _ in span_changes.values()), default=0))
        state = self.start_states[start]
        state_stack = [state]
        value_stack: list = []
        push_state = state_stack.append
        push_value = value_stack.append
        pos = 0
        end = len(text)
        line = 1
        line_start = 0  # where the current line starts
        token = None
        while pos < end:
            lexer = lexers[state]
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
            # the post-lexer
            change = span_changes.get(kind)
            if change is not None:
                spans[change[0]] = change[1]
            elif kind in dropped_inside and True in spans:
                continue
            token = _new_str(Token, value)
            token.type = kind
            token.start_pos = start_pos
            token.value = value
            token.line = token_line
            token.column = column
            token.end_line = line
            token.end_column = pos - line_start + 1
            token.end_pos = pos
            # the parser: reduce while the table says so, then shift
            row = actions[state]
            while True:
                action = row.get(kind)
                if action is None:
                    raise NotFastPath(kind)
                shift_to, reduce = action
                if shift_to is not None:
                    break
                size, origin, callback = reduce
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
            state = shift_to
            push_state(state)
            push_value(token)
        return self._end(token, state_stack, value_stack, self.end_states[start])

    def _end(self, last: Token | None, state_stack: list, value_stack: list, end_state: int):
        """Lark's "$END": reduce until the start rule is complete."""
        end = Token("$END", "", 0, 1, 1) if last is None else Token.new_borrow_pos("$END", "", last)
        actions = self.actions
        while True:
            action = actions[state_stack[-1]].get(end.type)
            if action is None or action[0] is not None:
                raise NotFastPath("$END")
            size, origin, callback = action[1]
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


def _count_lines(text: str, begin: int, stop: int, line: int, line_start: int) -> tuple[int, int]:
    """The line and line start after text[begin:stop], as lark's LineCounter."""
    newlines = text.count("\n", begin, stop)
    if newlines:
        return line + newlines, text.rindex("\n", begin, stop) + 1
    return line, line_start
