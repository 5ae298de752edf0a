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
lexer layer, a ``LineCounter`` object, the ``Token`` constructor's keyword
handling, the keyword ``UnlessCallback`` regex (memoised here per lexer and
text: it depends on nothing else), and the ``Rule`` attribute look-ups of
each reduction (precomputed into one table).
"""

from __future__ import annotations

from lark import Lark, Token
from lark.lexer import UnlessCallback
from lark.parsers.lalr_analysis import Shift

_new_str = str.__new__


class NotFastPath(Exception):
    """The text needs lark's own parser (a syntax error, or a lexer this
    loop does not model); nothing of this attempt is kept."""


class _StateLexer:
    """One state's terminals, from lark's BasicLexer for that state."""

    __slots__ = ("match", "ignore", "newline", "keyword_of", "callbacks")

    def __init__(self, basic) -> None:
        scanner = basic.scanner  # built on first use, as lark does
        if len(scanner._mres) != 1:
            raise NotFastPath("more terminals than one regex holds")
        self.match = scanner._mres[0].match
        self.ignore = basic.ignore_types
        self.newline = basic.newline_types
        # NAME -> {"bst": "BST", "Motor": "NAME", ...}: lark's UnlessCallback
        # turns a NAME spelt like a keyword into the keyword's terminal.
        self.keyword_of = {}
        self.callbacks = {}
        for name, callback in basic.callback.items():
            if isinstance(callback, UnlessCallback):
                self.keyword_of[name] = ({}, callback.scanner)
            else:
                self.callbacks[name] = callback


class FastLalr:
    """Parses with one ``Lark`` object (parser="lalr", lexer="contextual",
    a post-lexer with ``process``), giving exactly what ``lark.parse`` gives
    for a text it accepts."""

    def __init__(self, lark: Lark) -> None:
        frontend = lark.parser
        connector = frontend.lexer
        self.postlex = connector.postlexer
        contextual = connector.lexer
        shared: dict[int, _StateLexer] = {}
        self.lexers = {state: shared.setdefault(id(basic), _StateLexer(basic))
                       for state, basic in contextual.lexers.items()}
        parser = frontend.parser.parser
        table = parser.parse_table
        callbacks = parser.callbacks
        self.start_states = table.start_states
        self.end_states = table.end_states
        # state -> {symbol: (shift_to, None) or (None, (size, origin, callback))}
        self.actions: dict[int, dict[str, tuple]] = {}
        for state, row in table.states.items():
            compiled = {}
            for symbol, (action, arg) in row.items():
                if action is Shift:
                    compiled[symbol] = (arg, None)
                else:
                    compiled[symbol] = (None, (len(arg.expansion), arg.origin.name, callbacks[arg]))
            self.actions[state] = compiled
        self.token_callbacks = {k: v for k, v in callbacks.items() if isinstance(k, str)}

    def parse(self, text: str, start: str):
        actions = self.actions
        state_stack = [self.start_states[start]]
        value_stack: list = []
        end_state = self.end_states[start]
        token_callbacks = self.token_callbacks

        def feed(token: Token) -> None:
            kind = token.type
            while True:
                try:
                    shift_to, reduce = actions[state_stack[-1]][kind]
                except KeyError:
                    raise NotFastPath(kind) from None
                if shift_to is not None:
                    state_stack.append(shift_to)
                    value_stack.append(token_callbacks[kind](token) if kind in token_callbacks else token)
                    return
                size, origin, callback = reduce
                if size:
                    children = value_stack[-size:]
                    del state_stack[-size:]
                    del value_stack[-size:]
                else:
                    children = []
                value_stack.append(callback(children))
                state_stack.append(actions[state_stack[-1]][origin][0])

        last = None
        for token in self.postlex.process(self._lex(text, state_stack)):
            feed(token)
            last = token
        if last is None:
            end = Token("$END", "", 0, 1, 1)
        else:
            end = Token.new_borrow_pos("$END", "", last)
        while True:
            try:
                shift_to, reduce = actions[state_stack[-1]]["$END"]
            except KeyError:
                raise NotFastPath("$END") from None
            if shift_to is not None:
                raise NotFastPath("$END shifted")
            size, origin, callback = reduce
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

    def _lex(self, text: str, state_stack: list):
        """Lark's contextual lexer: the terminals of the parser's current
        state, tried at each position in lark's order (one regex)."""
        lexers = self.lexers
        pos = 0
        end = len(text)
        line = 1
        line_start = 0  # where the current line starts
        while pos < end:
            lexer = lexers[state_stack[-1]]
            m = lexer.match(text, pos)
            if m is None:
                raise NotFastPath("no terminal")
            kind = m.lastgroup
            value = m.group()
            start = pos
            token_line = line
            column = pos - line_start + 1
            pos = m.end()
            if kind in lexer.newline:
                newlines = value.count("\n")
                if newlines:
                    line += newlines
                    line_start = start + value.rindex("\n") + 1
            if kind in lexer.ignore:
                continue
            keyword = lexer.keyword_of.get(kind)
            if keyword is not None:
                known, scanner = keyword
                found = known.get(value)
                if found is None:
                    found = known[value] = scanner.fullmatch(value) or kind
                kind = found
            token = _new_str(Token, value)
            token.type = kind
            token.start_pos = start
            token.value = value
            token.line = token_line
            token.column = column
            token.end_line = line
            token.end_column = pos - line_start + 1
            token.end_pos = pos
            if kind in lexer.callbacks:
                token = lexer.callbacks[kind](token)
            yield token
