"""The rule actions of ``ladder.lark``: the Lark Transformer whose methods
build AST nodes as LALR reduces each rule (parser.py passes it to Lark, so
no parse tree is built), and the drafts it hands to parser.py, which
assembles them into a Program (mnemonic rungs are grouped into instructions
here as they are parsed, with the instruction set of the parse, and
finished there).

Positions come from tokens (see the "!" rules in the grammar). The rule
actions take lark's child list as it is (no v_args wrapper), and
``mn_token`` is ``mn_tokens`` for a token given as its fields, which
lalr_driver calls without making a Token.
"""

from __future__ import annotations

from dataclasses import dataclass

from lark import Token, Transformer, v_args

from ..datatable import AddressError, parse_address
from .ast import (
    AddressRef,
    BinOp,
    Branch,
    Call,
    Const,
    DataDecl,
    Element,
    Instruction,
    Placeholder,
    Pos,
    SymbolDecl,
    SymbolRef,
    Text,
    UnaryOp,
)
from .errors import LadderError
from .limits import (
    MAX_BRANCH_DEPTH,
    MAX_CONSTANT,
    MAX_NUMBER_DIGITS,
    MAX_RUNG_ELEMENTS,
    limit_problem,
    literal_problem,
    rung_size_message,
)

_new_tuple = tuple.__new__  # _new_tuple(Pos, (...)): a Pos without its __new__'s Python frame

# -- transformer --------------------------------------------------------------------

# The mnemonic-form branch keywords (token kinds).
BST, NXB, BND = "BST", "NXB", "BND"


class _MnemonicRun:
    """A mnemonic rung's elements, grouped as its tokens are parsed (the
    value of ``mn_tokens``): only the instruction table knows where one
    instruction's operands end, so a name that is a mnemonic starts an
    instruction and any other token is an operand of the current one.

    The first problem (an unknown instruction, an operand before any
    instruction, NXB or BND outside a branch) is kept, not raised: parser.py
    raises it when it adds the rung, after the whole text is parsed, as a
    syntax error found later comes first. Nothing after it is grouped (the
    operands are still built, for the problems they have of their own).
    ``texts``: the quoted operands, (instruction, operand index), which
    parser.py parses as expressions where the instruction takes one."""

    __slots__ = ("branches", "current", "deepest", "operands", "pos", "problem", "root", "series", "size", "texts")

    def __init__(self, pos: Pos) -> None:
        self.pos = pos  # the first token's
        self.root: list[Element] = []
        self.series = self.root  # where the next instruction or branch goes
        self.branches: list[tuple[list[Element], Branch]] = []  # (series to return to, open branch)
        self.current: Instruction | None = None
        self.operands: list | None = None  # the current instruction's, while no problem is found
        self.deepest = 0
        self.texts: list[tuple[Instruction, int]] = []
        self.problem: LadderError | None = None
        self.size = 0  # its elements (limits.MAX_RUNG_ELEMENTS), set when the rung ends

    def operand(self, operand) -> None:
        operands = self.operands
        if operands is None:
            if self.problem is None:
                self.fail(LadderError(operand.pos, "an operand with no instruction before it"))
            return
        if type(operand) is Text:
            self.texts.append((self.current, len(operands)))
        operands.append(operand)

    def fail(self, problem: LadderError) -> None:
        self.problem = problem
        self.operands = None

    def marker(self, kind: str, pos: Pos) -> None:
        if self.problem is not None:
            return
        self.current = self.operands = None
        branches = self.branches
        if kind == BST:
            branch = Branch([[]], pos)
            self.series.append(branch)
            branches.append((self.series, branch))
            self.series = branch.legs[0]
            self.deepest = max(self.deepest, len(branches))
        elif not branches:
            self.fail(LadderError(pos, f"{kind} without a BST to open the branch"))
        elif kind == NXB:
            legs = branches[-1][1].legs
            legs.append([])
            self.series = legs[-1]
        else:  # BND
            self.series, _ = branches.pop()


@dataclass
class _Comment:
    text: str
    line: int


@dataclass
class _Header:
    number: int
    name: str | None
    pos: Pos


@dataclass
class _RungDraft:
    pos: Pos
    elements: list[Element] | None = None  # neutral: already structured
    run: _MnemonicRun | None = None  # mnemonic: grouped, to be finished
    comment: str | None = None  # trailing // comment on the rung's line


def _number(tok: Token) -> int | float:
    """A numeric token's value; _NumberRangeError for one no element can hold
    (checked on the text first: Python converts at most 4,300 digits)."""
    text = str(tok)
    if tok.type in ("HEX", "INT") and len(text) > MAX_NUMBER_DIGITS:
        raise _NumberRangeError(f"{text[:12]}... ({len(text)} {'characters' if tok.type == 'HEX' else 'digits'})")
    value: int | float = int(text, 16) if tok.type == "HEX" else int(text) if tok.type == "INT" else float(text)
    if not abs(value) <= MAX_CONSTANT:  # also catches inf from 1e999
        raise _NumberRangeError(text if len(text) <= 30 else f"{text[:12]}... ({len(text)} characters)")
    return value


class _NumberRangeError(Exception):
    def __init__(self, shown: str) -> None:
        self.shown = shown


_CALLS = ("SQR", "ABS", "NEG", "FRD", "TOD", "LN", "LOG", "SIN", "COS", "TAN", "ASN", "ACS", "ATN", "DEG", "RAD")


def _tokens(items, *kinds):
    return [t for t in items if isinstance(t, Token) and t.type in kinds]


class _ToAst(Transformer):
    """Parse-tree rules to AST nodes, called by Lark during the LALR parse.

    One instance serves every parse of one thread (parser.py gives each
    thread a parser of its own: the attributes below are the state of the
    parse under way); ``context`` holds the current parse's source name and
    offsets (an expression inside a quoted mnemonic operand is parsed on
    its own and its positions shifted into the file).
    """

    def __init__(self) -> None:
        super().__init__()
        self.context = ("<program>", 0, 0)
        # Where problems found while building nodes go when the caller lists
        # every problem (syntax_problems): a placeholder node stands in for
        # the bad one and the parse goes on. None: the first one is raised.
        self.problems: list[LadderError] | None = None
        # Address text -> Address within one parse: a program names the same
        # addresses many times (more distinct ones than parse_address's cache holds)
        self.addresses: dict[str, object] = {}
        # The instruction set of the program being parsed (an InstructionSet:
        # the built-in instructions and its app's modules'), and name ->
        # mnemonic, or "" for a name that is none, within one parse.
        self.instructions = None
        self.mnemonics: dict[str, str] = {}
        # The elements of the current line item (a rung, a DATA line) so
        # far, against size_limit (MAX_RUNG_ELEMENTS; none in an expression
        # parse: parser._finish counts a quoted one into its rung). Reset
        # by ``lines``. The first element past the limit ends the parse as
        # a syntax error does (parsing resumes on the next line): the rest
        # of a huge rung is never read into memory.
        self.size = 0
        self.size_limit = MAX_RUNG_ELEMENTS

    def new_parse(self, counted: bool) -> None:
        """Start counting elements afresh (each parse, and lark's parse
        again after the fast loop gave up)."""
        self.size = 0
        self.size_limit = MAX_RUNG_ELEMENTS if counted else 1 << 62

    def _grow(self, pos_of) -> None:
        """Count one element (``pos_of``: its token or node); past the
        limit, raise the size problem there."""
        self.size += 1
        if self.size > self.size_limit:
            raise LadderError(self._pos(pos_of), rung_size_message())

    def _fail(self, error: LadderError, placeholder):
        if self.problems is None:
            raise error
        self.problems.append(error)
        return placeholder

    def _num(self, tok: Token) -> int | float:
        try:
            return _number(tok)
        except _NumberRangeError as e:
            return self._fail(LadderError(self._pos(tok), f"number {e.shown} is out of range: no data table "
                                          f"element holds a value beyond +-{MAX_CONSTANT:.8g}"), 0)

    def _pos(self, item) -> Pos:
        """The position of a token, or of an AST node already built."""
        if not isinstance(item, Token):
            return item.pos
        return self._token_pos(item)

    def _token_pos(self, tok: Token) -> Pos:
        source, line_offset, column_offset = self.context
        if not (line_offset or column_offset):  # a whole file
            return _new_tuple(Pos, (source, tok.line, tok.column))
        line = tok.line
        return _new_tuple(Pos, (source, line + line_offset, tok.column + column_offset if line == 1 else tok.column))

    def _small_int(self, tok: Token, what: str) -> int:
        """A file number or element count; one too long to be either is
        refused here, before Python is asked to convert thousands of digits."""
        text = str(tok)
        if len(text) > 9:
            return self._fail(LadderError(self._pos(tok), f"{what} {text[:12]}... ({len(text)} digits) is out of range"),
                              None)
        return int(text)

    # operands ------------------------------------------------------------------
    def _address(self, tok: Token) -> AddressRef:
        # a plain str key: a Token compares with lark's own __eq__
        return self._address_at(str(tok), self._token_pos(tok))

    def _address_at(self, text: str, pos: Pos) -> AddressRef:
        address = self.addresses.get(text)
        if address is not None:  # this text parsed before in this program: one shared Address
            return AddressRef(address, pos)
        try:
            address = self.addresses[text] = parse_address(text)
            return AddressRef(address, pos)
        except AddressError as e:
            return self._fail(LadderError(Pos(pos.source, pos.line, pos.column + e.position), e.reason),
                              Placeholder(0, pos))

    # The rules below take lark's child list as it is: a v_args wrapper
    # costs three calls a reduction, and most are reduced once a token.
    def address(self, children):
        self._grow(children[0])
        return self._address(children[0])

    def symbol(self, children):
        tok = children[0]
        self._grow(tok)
        return SymbolRef(str(tok), self._token_pos(tok))

    def signed_number(self, children):
        return self._const(children[0])

    def negative_number(self, children):
        sign, tok = children
        const = self._const(tok)
        # -0x10 is the number -16: only an unsigned hex constant is a bit pattern
        return Const(-const.value, self._pos(sign)) if str(sign) == "-" else Const(const.value, self._pos(sign), hex=const.hex)

    def _const(self, tok: Token) -> Const:
        self._grow(tok)
        return Const(self._num(tok), self._token_pos(tok), hex=tok.type == "HEX")

    def call(self, children):
        name, arg = children
        arg = self._atomize(arg)
        self._grow(name)
        func = str(name).upper()
        if func not in _CALLS:
            return self._fail(LadderError(self._pos(name), f"unknown function {name}() in an expression; "
                                          f"functions are {' '.join(_CALLS)}"), Placeholder(0, self._pos(name)))
        return Call(func, arg, self._pos(name))

    def negate(self, children):
        sign, operand = children
        operand = self._atomize(operand)
        if str(sign) == "+":
            return operand
        if isinstance(operand, Const):
            return Const(-operand.value, self._pos(sign))
        return UnaryOp("NEG", operand, self._pos(sign))

    def bit_not(self, children):
        keyword, operand = children
        operand = self._atomize(operand)
        self._grow(keyword)
        return UnaryOp("NOT", operand, self._pos(keyword))

    def binop(self, children):
        left, op, right = children
        operator = str(op).upper()
        if operator == "/":
            operator = "|"  # PLC-5 writes division as |
        left = self._atomize(left)
        self._grow(op)
        return BinOp(operator, left, self._atomize(right), left.pos)

    def _atomize(self, item):
        if isinstance(item, Token) and item.type in ("INT", "FLOAT", "HEX"):
            return self._const(item)
        return item

    # neutral text -----------------------------------------------------------------
    def nt_instruction(self, items):
        name = items[0]
        self._grow(name)
        operands = [self._atomize(i) for i in items[1:]]
        return Instruction(str(name).upper(), operands, self._pos(name))

    def nt_branch(self, items):
        legs = [i for i in items if not isinstance(i, Token)]
        self.size += len(legs)  # "[", each ",", "]": one each, with the one below
        self._grow(items[0])
        return Branch(legs, self._pos(items[0]))

    def nt_series(self, items):
        return list(items)

    def neutral_rung(self, items):
        series = items[0]
        comment = _tokens(items, "COMMENT")
        at = series[0] if series else items[1]  # an empty rung: its ";"
        return _RungDraft(self._pos(at), elements=series, comment=comment[0][2:].strip() if comment else None)

    # mnemonic --------------------------------------------------------------------------
    def mn_tokens(self, children):
        """A mnemonic rung's tokens, grouped left to right (one call a
        token): [token] or [run so far, token]."""
        if len(children) == 1:
            tok = children[0]
            run = _MnemonicRun(self._pos(tok))
        else:
            run, tok = children
        if isinstance(tok, Token):
            return self.mn_token(run, tok.type, tok.value, tok.line, tok.column)
        run.operand(tok)  # a signed number, already a Const
        return run

    def mn_token(self, run: _MnemonicRun, kind: str, text: str, line: int, column: int) -> _MnemonicRun:
        """``mn_tokens`` for a token, given as its fields: lalr_driver calls
        it so for most tokens of a rung, without making a Token."""
        source, line_offset, column_offset = self.context
        if line_offset or column_offset:
            line, column = line + line_offset, column + column_offset if line == 1 else column
        pos = _new_tuple(Pos, (source, line, column))
        self.size += 1
        if self.size > self.size_limit:
            raise _deepest_first(run, LadderError(pos, rung_size_message()))
        if kind == "ADDRESS":
            address = self.addresses.get(text)
            operand = self._address_at(text, pos) if address is None else AddressRef(address, pos)
            operands = run.operands
            if operands is not None:  # the common case, without a call
                operands.append(operand)
            else:
                run.operand(operand)
        elif kind == "NAME":
            mnemonic = self.mnemonics.get(text)
            if mnemonic is None:
                mnemonic = self.mnemonics[text] = text.upper() if self.instructions.is_mnemonic(text) else ""
            if mnemonic:
                if run.problem is None:  # a new instruction, which keeps the list it is given
                    run.operands = operands = []
                    run.current = instruction = Instruction(mnemonic, operands, pos)
                    run.series.append(instruction)
            elif run.current is None and run.problem is None:
                run.fail(LadderError(pos, f"unknown instruction {text!r}{self.instructions.hint(text)}"))
            else:
                run.operand(SymbolRef(text, pos))
        elif kind == "SYMBOL_MEMBER":  # PollTimer/DN: never a mnemonic, so an operand at once
            run.operand(SymbolRef(text, pos))
        elif kind == "STRING":
            problem = literal_problem(text)
            if problem is None:
                run.operand(Text(_unquote(text), pos))
            elif run.problem is None:
                run.fail(LadderError(pos, problem))
        else:  # BST, NXB, BND
            run.marker(kind, pos)
        return run

    def mnemonic_rung(self, items):
        # [run, COMMENT?, _NL] or ["SOR", run?, "EOR", COMMENT?, _NL]
        first = items[0]
        if type(first) is _MnemonicRun:
            first.size = self.size
            if len(items) == 2:  # no comment: most rungs
                return _RungDraft(first.pos, run=first)
            run = first
        else:  # SOR
            run = items[1] if type(items[1]) is _MnemonicRun else _MnemonicRun(self._pos(first))
            run.size = self.size
        comment = _tokens(items, "COMMENT")
        return _RungDraft(run.pos if run is first else self._pos(first), run=run,
                          comment=comment[0][2:].strip() if comment else None)

    # directives and comments -------------------------------------------------------------
    @v_args(inline=True)
    def comment(self, tok):
        return _Comment(str(tok)[2:].strip(), self._pos(tok).line)

    def file_header(self, items):
        number = _tokens(items, "INT")[0]
        name = _tokens(items, "NAME")
        number = self._small_int(number, "program file number")
        return None if number is None else _Header(number, str(name[0]) if name else None, self._pos(items[0]))

    def data_decl(self, items):
        name, size = _tokens(items, "NAME", "INT")[:2]
        values = []
        for v in items[3:]:
            if isinstance(v, Token):
                if v.type == "STRING":
                    problem = literal_problem(str(v))
                    if problem is not None:
                        return self._fail(LadderError(self._pos(v), f"DATA {name}: {problem}"), None)
                    values.append(_unquote(str(v)))
            elif v.hex and 0x8000 <= v.value <= 0xFFFF and str(name)[:1].upper() in ("N", "B", "O", "I", "S"):
                values.append(v.value - 0x10000)  # a hex bit pattern for a 16-bit word file: 0xFFFF is -1
            else:
                values.append(v.value)
        size = self._small_int(size, f"DATA {name}: size")
        return None if size is None else DataDecl(str(name).upper(), size, values, self._pos(items[0]))

    @v_args(inline=True)
    def symbol_decl(self, name, addr, *_comment_nl):
        ref = self._address(addr)
        return SymbolDecl(str(name), ref.address, self._pos(name)) if isinstance(ref, AddressRef) else None

    def lines(self, children):
        """[], [line], [lines so far] or [lines so far, line] (the newline
        between is filtered out): one list grown left to right. A line is
        an item, or None for a header or declaration already reported."""
        self.size = 0
        if not children:
            return []
        if len(children) == 2:
            lines, line = children
            lines.append(line)
            return lines
        first = children[0]
        return first if isinstance(first, list) else [first]

    def start(self, items):
        return items[0] if items else []


def _deepest_first(run: _MnemonicRun, problem: LadderError) -> LadderError:
    """A rung past the size limit may have had branches nested past their
    limit before that point: the earlier problem is the one reported."""
    if run.deepest > MAX_BRANCH_DEPTH and run.problem is None:
        deep = limit_problem(run.root)
        if deep is not None and deep[0].pos < problem.pos:
            return LadderError(deep[0].pos, deep[1])
    return problem


def _unquote(text: str) -> str:
    body = text[1:-1]
    return body.replace('\\"', '"').replace("\\\\", "\\")
