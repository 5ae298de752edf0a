"""Stage 1: program text -> typed AST (``Program``).

The grammar is ``ladder.lark`` (LALR, contextual lexer). A small post-lexer
lets neutral-text rungs and SOR...EOR rungs span lines. Mnemonic rungs are
parsed as flat token runs, grouped into instructions as they are parsed
(``parse_actions._MnemonicRun``) and finished here (``_finish``), because
only the instruction table knows where one instruction's operands end: a
name that is a known mnemonic starts a new instruction, any other name is a
symbol operand.

The rule actions (the Transformer applied during the parse) are in
``parse_actions.py``; ``lalr_driver.py`` runs this Lark parser's own tables
with less overhead a token (a 10,000-rung program parses about 2.5x
faster), and a text it cannot parse (a syntax error) is parsed again by
Lark itself for Lark's error.

Threads: the rule actions hold the state of the parse under way (its
source name and offsets, its problem list, its instruction set), so each
thread parses with a parser of its own (``_ast_parser``), built on its
first parse (about 6 ms from the cached tables). The online reloader
parses on a thread of its own while the scan thread may parse too.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from types import MappingProxyType

from lark import Lark, Token
from lark.exceptions import UnexpectedInput, VisitError

from ..gcpause import gc_paused
from ..usercache import cached_file
from .ast import (
    MAIN_FILE,
    DataDecl,
    Element,
    Instruction,
    Operand,
    Pos,
    Program,
    ProgramFile,
    Rung,
    SymbolDecl,
)
from .errors import LadderError
from .lalr_driver import FastLalr, LarkOnly, NotFastPath, fast_parser
from .limits import (
    MAX_BRANCH_DEPTH,
    MAX_EXPRESSION_DEPTH,
    MAX_RUNG_ELEMENTS,
    expression_depth,
    expression_size,
    limit_problem,
    nesting_problem,
    rung_size_message,
)
from .parse_actions import (
    _Comment,
    _Header,
    _MnemonicRun,
    _RungDraft,
    _ToAst,
)
from .syntax_errors import syntax_error

# -- the post-lexer ---------------------------------------------------------------


class LadderPostLex:
    """Drop newlines and comments inside multi-line rungs.

    A neutral-text rung opens at its first "(" or "[" and closes at ";"; a
    mnemonic rung may be wrapped in SOR ... EOR. Inside either, line ends
    carry no meaning (and comments inside a rung are not rung comments).

    Written as a table (``span_changes``, ``dropped_inside``) that both
    ``process`` (lark's post-lexer interface) and lalr_driver's loop read.
    """

    always_accept = ("_NL", "COMMENT")
    # token kind -> (which span, open?): 0 a neutral-text rung, 1 SOR...EOR
    span_changes = MappingProxyType({"LPAR": (0, True), "LSQB": (0, True), "SEMICOLON": (0, False),
                                     "SOR": (1, True), "EOR": (1, False)})
    dropped_inside = frozenset(("_NL", "COMMENT"))

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        spans = [False, False]
        for tok in stream:
            kind = tok.type
            change = self.span_changes.get(kind)
            if change is not None:
                spans[change[0]] = change[1]
            elif kind in self.dropped_inside and True in spans:
                continue
            yield tok


# This thread's parser and its fast loop ("lark", "fast"), see the module docstring.
_per_thread = threading.local()


def _ast_parser() -> Lark:
    """This thread's grammar with the AST built during the parse: Lark calls
    ``_ToAst``'s methods as LALR reduces each rule, so no parse tree is built
    and walked a second time (that halved the load of a 10,000-rung
    program). Positions come from tokens (see the "!" rules in the grammar);
    the source name and line offset of each parse are ``_ToAst.context``."""
    try:
        return _per_thread.lark
    except AttributeError:
        lark = _per_thread.lark = _lark(_ToAst())
        return lark


def _lark(transformer) -> Lark:
    """The grammar's LALR parser. Building its tables takes about 60 ms,
    a third of a short ``softplc check``; lark keeps them in the user's
    cache (usercache.py) and loads them in a tenth of that when the grammar,
    lark and Python are unchanged (lark checks a digest of all three and of
    the options, the file's path among them)."""

    # lark loads the file only when its digest matches, and rebuilds and
    # rewrites it otherwise (cut short, made for another version, or being
    # written by another softplc starting at the same moment).
    cached = cached_file(f"ladder-parser-{sys.version_info[0]}.{sys.version_info[1]}.lark")
    return Lark.open_from_package("softplc_lite.ladder", "ladder.lark", parser="lalr", lexer="contextual",
                                  postlex=LadderPostLex(), propagate_positions=False, maybe_placeholders=False,
                                  start=["start", "expr"], transformer=transformer,
                                  cache=False if cached is None else str(cached))


# -- errors ---------------------------------------------------------------------------

def _parse_tree(text: str, source: str, start: str, line_offset: int = 0, column_offset: int = 0,
                problems: list[LadderError] | None = None, instructions=None):
    parser = _ast_parser()
    builder = parser.options.transformer
    # an expression parse happens inside a program parse
    saved = builder.context, builder.problems, builder.addresses, builder.instructions, builder.mnemonics
    sizes = builder.size, builder.size_limit
    builder.context = (source, line_offset, column_offset)
    builder.problems = problems
    builder.new_parse(counted=start == "start")
    if start == "start":
        if instructions is None:
            from .instructions import BUILTIN as instructions
        builder.addresses = {}
        builder.instructions = instructions
        builder.mnemonics = {}
    try:
        result = _parse_fast_or_lark(parser, text, start, problems)
        if isinstance(result, Token):  # a bare number as a whole expression: in this parse's context
            result = builder._atomize(result)
    except UnexpectedInput as e:
        raise syntax_error(e, text, source, line_offset, column_offset) from None
    except VisitError as e:
        if isinstance(e.orig_exc, LadderError):
            raise e.orig_exc from None
        raise
    finally:
        builder.context, builder.problems, builder.addresses, builder.instructions, builder.mnemonics = saved
        builder.size, builder.size_limit = sizes
    return result


def _fast_parser() -> FastLalr | LarkOnly:
    """lalr_driver's loop over this thread's grammar tables, or a LarkOnly
    where this lark's objects are not laid out as that loop reads them."""
    try:
        return _per_thread.fast
    except AttributeError:
        lark = _ast_parser()
        fast = _per_thread.fast = fast_parser(lark, token_actions={"mn_tokens": lark.options.transformer.mn_token})
        return fast


def _parse_fast_or_lark(parser: Lark, text: str, start: str, problems: list[LadderError] | None):
    """The same parse as ``parser.parse``, by lalr_driver's faster loop over
    the same tables; a text that loop cannot take (a syntax error) is parsed
    again by lark itself, for lark's error, after undoing what the first try
    added to ``problems``. So is one where a rule action refuses something
    (a bad address): the loop reduces a list one token earlier than lark,
    so lark may find a syntax error first."""
    found = len(problems) if problems is not None else 0
    try:
        return _fast_parser().parse(text, start)
    except (NotFastPath, LadderError):
        if problems is not None:
            del problems[found:]
        parser.options.transformer.new_parse(counted=start == "start")
        return parser.parse(text, start=start)


def parse_expression(text: str, pos: Pos) -> Operand:
    """Parse a CPT/CMP expression given as a quoted mnemonic operand; errors
    point into the original file (``pos`` is where the text starts)."""
    tree = _parse_tree(text, pos.source, "expr", pos.line - 1, pos.column)
    levels = expression_depth(tree)
    if levels > MAX_EXPRESSION_DEPTH:  # the same limit as in a rung (a --break-when condition, too)
        raise LadderError(getattr(tree, "pos", pos), f"expression nested {levels} levels deep; the limit is "
                          f"{MAX_EXPRESSION_DEPTH} (split it over several CPT instructions)")
    return tree


# -- assembling the program ------------------------------------------------------------


@gc_paused
def parse_program(
    text: str,
    source: str = "<program>",
    instructions=None,
    program: Program | None = None,
    line_offset: int = 0,
    problems: list[LadderError] | None = None,
) -> Program:
    """Parse one .lad text into ``program`` (a new one by default).

    ``instructions`` (an InstructionSet) tells instruction names from symbol
    names in mnemonic rungs: by default the built-in instructions; an app
    passes the set that includes its modules' (TLM) instructions.

    The first problem is raised as a LadderError, unless ``problems`` is a
    list: then every problem short of a syntax error (a bad address or
    number, an unknown instruction, a rung past the limits...) is added to
    it and the parse goes on, so one parse finds them all; a syntax error is
    still raised (syntax_problems resumes after it).
    """
    if instructions is None:
        from .instructions import BUILTIN as instructions
    if text and not text.endswith("\n"):
        text += "\n"
    nested = nesting_problem(text)  # before the parser holds millions of "(" on its stack
    if nested is not None:
        offset, message = nested
        raise LadderError(Pos(source, text.count("\n", 0, offset) + 1 + line_offset,
                              offset - text.rfind("\n", 0, offset)), message)
    items = _parse_tree(text, source, "start", line_offset, problems=problems, instructions=instructions)
    program = program if program is not None else Program()
    current: ProgramFile | None = None
    comments: list[_Comment] = []
    declared = {d.name.upper(): d for d in program.symbols.values()}  # other files' symbols too

    def file_for_rungs(pos: Pos) -> ProgramFile:
        nonlocal current
        if current is None:
            current = _add_file(program, MAIN_FILE, None, Pos(source, pos.line, 1))
        return current

    def add(item) -> None:
        nonlocal current
        if isinstance(item, _Header):
            current = _add_file(program, item.number, item.name, item.pos)
        elif isinstance(item, DataDecl):
            program.data.append(item)
        elif isinstance(item, SymbolDecl):
            # Symbols compare without regard to case (docs/language.md), so
            # Start and START are one name declared twice.
            first = declared.get(item.name.upper())
            if first is not None:
                spelt = "" if first.name == item.name else f" as {first.name}"
                raise LadderError(item.pos, f"symbol {item.name} is declared twice "
                                  f"(first at {first.pos}{spelt}; symbols compare without regard to case)")
            program.symbols[item.name] = declared[item.name.upper()] = item
        elif isinstance(item, _RungDraft):
            rung_comment = _comment_above(comments, item.pos.line)
            if item.comment:
                rung_comment = f"{rung_comment}\n{item.comment}" if rung_comment else item.comment
            if item.elements is not None:
                elements, check_limits = item.elements, True
            else:
                elements, check_limits = _finish(item.run, instructions)
            problem = limit_problem(elements) if check_limits else None
            if problem is not None:
                raise LadderError(problem[0].pos, problem[1])
            file_for_rungs(item.pos).rungs.append(Rung(elements, rung_comment, item.pos))

    for item in items:
        if isinstance(item, _Comment):
            comments.append(item)
            continue
        if problems is None:
            add(item)
        else:
            try:
                add(item)
            except LadderError as e:
                problems.append(e)
        comments = []
    if problems:
        problems.sort(key=lambda e: (e.pos.line, e.pos.column))
    return program


def syntax_problems(text: str, source: str, limit: int = 50, instructions=None) -> list[LadderError]:
    """Every problem ``parse_program`` finds in a file, in source order, not
    just the first, so that ``check`` lists them all. After a problem,
    parsing resumes on the next line; the lines before a syntax error are
    parsed on their own too, because the problems found only after the
    parse (an unknown instruction) would otherwise be hidden behind it.
    Resuming inside a rung that spans lines can report a problem that is
    only a consequence of the one before, as compilers do."""
    lines = text.splitlines(keepends=True)
    found: list[LadderError] = []

    def scan(start: int, end: int, cut: bool) -> None:
        # lines[start:end]; ``cut``: the range ends where a later problem is,
        # so a rung may be cut short there (not a problem of its own).
        while start < end and len(found) < limit:
            problems: list[LadderError] = []
            try:
                parse_program("".join(lines[start:end]), source, instructions, program=Program(), line_offset=start,
                              problems=problems)
                found.extend(problems)
                return
            except LadderError as e:  # a syntax error: what came before it is parsed on its own
                line = e.pos.line
                if cut and e.message.startswith("unexpected end of file"):
                    end -= 1  # a rung cut short at the range's end: check the range without it
                    continue
                if line <= start or line > end:
                    return
                if line - 1 > start:
                    scan(start, line - 1, True)
                found.append(e)
                start = line

    scan(0, len(lines), False)
    return found[:limit]


def _add_file(program: Program, number: int, name: str | None, pos: Pos) -> ProgramFile:
    if not 2 <= number <= 999:
        raise LadderError(pos, f"program file number {number} out of range: the main file is 2, "
                          "subroutine files are 3..999")
    if number in program.files:
        raise LadderError(pos, f"program file {number} is defined twice (first at {program.files[number].pos})")
    f = program.files[number] = ProgramFile(number, name, [], pos)
    return f


def _comment_above(comments: list[_Comment], rung_line: int) -> str | None:
    """The comment lines that end on the line just above the rung."""
    lines: list[str] = []
    expected = rung_line - 1
    for c in reversed(comments):
        if c.line != expected:
            break
        lines.append(c.text)
        expected -= 1
    return "\n".join(reversed(lines)) if lines else None


def _finish(run: _MnemonicRun, instructions) -> tuple[list[Element], bool]:
    """A mnemonic rung's elements, grouped while it was parsed (see
    _MnemonicRun), with its quoted expressions parsed; and whether
    limit_problem must look at them (branches nested deeper than its
    limit, or an expression: nothing else in a mnemonic rung can be over a
    limit). Its first problem is raised here, in the order of its tokens."""
    expression = False
    size = run.size
    for instruction, index in run.texts:
        if _takes_expression(instruction, index, instructions):
            # CPT "N7:1 + 5": the quoted text is an expression; parse it
            # so both rung syntaxes give the same tree.
            operands = instruction.operands
            text = operands[index]
            operands[index] = parse_expression(text.value, text.pos)
            expression = True
            size += expression_size(operands[index]) - 1  # its elements, as neutral text counts them
            if size > MAX_RUNG_ELEMENTS:
                raise LadderError(text.pos, rung_size_message())
    if run.problem is not None:
        raise run.problem
    if run.branches:
        raise LadderError(run.branches[-1][1].pos, "BST without a matching BND (unclosed branch)")
    return run.root, expression or run.deepest > MAX_BRANCH_DEPTH


def _takes_expression(instr: Instruction, index: int, instructions) -> bool:
    from .instructions import K

    spec = instructions.lookup(instr.mnemonic)
    return spec is not None and index < len(spec.operands) and spec.operands[index].kind is K.EXPRESSION
