"""Mutants of a ladder program: one small fault each, the kind a wrong edit
makes (docs/testing.md, "Mutation testing", lists the operators and what
each catches). They are made on the parsed program (the tree ``fmt``
prints, symbols by name), so a mutant is checked by the same validator as
the app's own files, and its description reads as the source does.

A mutant keeps only the rung it changes (``rung``, None when the rung is
deleted): ``apply`` builds the whole program from the original, so the
mutants of a large program cost little memory and little to send to a
worker process.

A program file made from Structured Text gets the mutants of its text's
operators and constants instead (testing/st_mutants.py), described as the
text shows them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, Iterator

from ..ladder.ast import BinOp, Branch, Call, Const, Instruction, Placeholder, Pos, Program, Rung, UnaryOp
from ..ladder.fmt import format_instruction, format_series
from ..ladder.instructions import BUILTIN, InstructionSet
from ..ladder.specs import K
from .st_mutants import ARITHMETIC, LOGIC, st_mutants

RungKey = tuple[int, int]  # (program file number, rung index in the file)

# Each operator's name, as reports and docs call it.
CONTACT, LATCH, OUTPUT, LEG, COMPARE, CONSTANT, RUNG = (
    "contact", "latch", "output", "leg", "compare", "constant", "rung")
OPERATORS = (CONTACT, LATCH, OUTPUT, LEG, COMPARE, CONSTANT, RUNG, ARITHMETIC, LOGIC)  # the last two: ST's

_SWAPS = {"XIC": ("XIO", CONTACT), "XIO": ("XIC", CONTACT), "OTL": ("OTU", LATCH), "OTU": ("OTL", LATCH)}
# A comparison's neighbour (a choice): the operator an off-by-one or a
# slip of the pen gives, equal and not equal swapped.
_COMPARE_NEIGHBOURS = {"EQU": "NEQ", "NEQ": "EQU", "GRT": "GEQ", "GEQ": "GRT", "LES": "LEQ", "LEQ": "LES"}
_EXPRESSION_NEIGHBOURS = {"=": "<>", "<>": "=", ">": ">=", ">=": ">", "<": "<=", "<=": "<"}
# Operands whose constants are not values the logic computes with: a jump
# label, a subroutine's file, a parameter count, a time base, and the
# accumulator a timer or counter starts from.
_FIXED_KINDS = {K.LABEL, K.PROGRAM_FILE, K.PARAM_COUNT, K.TIMEBASE}
_FIXED_NAMES = {"accum"}


@dataclass(frozen=True)
class Spelling:
    """How mutant descriptions write a program file's instructions: as its
    source does (mnemonic text, addresses and symbols), or a Logix app's
    way (neutral text, tag paths, Logix's instruction names), as the watch
    view names them (watch/naming.py)."""

    style: str = "mnemonic"
    name_of: Callable | None = None
    operators: dict | None = None
    mnemonic_of: Callable | None = None

    def instruction(self, ins: Instruction) -> str:
        return format_instruction(ins, self.style, self.name_of, self.operators, self.mnemonic_of)

    def series(self, elements) -> str:
        return format_series(elements, self.style, name_of=self.name_of, operators=self.operators,
                             mnemonic_of=self.mnemonic_of)


AS_WRITTEN = Spelling()


@dataclass(frozen=True)
class Mutant:
    index: int  # its place in the generation order (the order of reports)
    operator: str
    key: RungKey  # the rung of the original program it changes
    pos: Pos  # where the change is
    description: str  # e.g. "XIC Start -> XIO Start"
    rung: Rung | None  # the changed rung; None: the rung is deleted

    @property
    def where(self) -> str:
        return f"{self.pos.source}:{self.pos.line}"

    def apply(self, program: Program) -> Program:
        """``program`` (the original) with this mutant's change."""
        number, index = self.key
        pfile = program.files[number]
        rungs = list(pfile.rungs)
        if self.rung is None:
            del rungs[index]
        else:
            rungs[index] = self.rung
        files = dict(program.files)
        files[number] = dataclasses.replace(pfile, rungs=rungs)
        return Program(files, program.data, program.symbols)


def mutants(program: Program, instructions: InstructionSet = BUILTIN,
            spelling: Callable[[int], Spelling | None] | None = None) -> list[Mutant]:
    """Every mutant of a parsed program, in file, rung and element order;
    ``spelling(file number)``: how its descriptions write the file's
    instructions (as written when None), None for a file to leave alone."""
    found: list[Mutant] = []
    for number in sorted(program.files):
        pfile = program.files[number]
        spell = spelling(number) if spelling is not None else AS_WRITTEN
        if spell is None:  # a file the program made itself: nothing its author wrote, or could change
            continue
        if pfile.listing is not None:  # Structured Text: its operators and constants, as the text shows them
            for index, m in st_mutants(pfile, instructions):
                found.append(Mutant(len(found), m.operator, (number, index), m.pos, m.description, m.rung))
            continue
        rungs = pfile.rungs
        for index, rung in enumerate(rungs):
            for operator, description, pos, elements in _series(rung.elements, instructions, spell):
                found.append(Mutant(len(found), operator, (number, index), pos, description,
                                    Rung(elements, rung.comment, rung.pos)))
            if rung.elements and not _deletion_changes_nothing(rungs, index):
                found.append(Mutant(len(found), RUNG, (number, index), rung.pos,
                                    f"rung deleted: {spell.series(rung.elements)}", None))
    return found


def _deletion_changes_nothing(rungs, index: int) -> bool:
    """A lone SBR without parameters (it receives nothing), or a lone RET
    without parameters ending its file (the file's end returns the same):
    deleting it makes a mutant no test could catch, which would only lower
    the score."""
    elements = rungs[index].elements
    if len(elements) != 1 or not isinstance(elements[0], Instruction) or elements[0].operands:
        return False
    return elements[0].mnemonic == "SBR" or (elements[0].mnemonic == "RET" and index == len(rungs) - 1)


def _series(elements, instructions, spell: Spelling = AS_WRITTEN) -> Iterator[tuple[str, str, Pos, list]]:
    """(operator, description, position, the series changed) for each
    single change of a series, branches included."""
    elements = list(elements)
    for i, el in enumerate(elements):
        before, after = elements[:i], elements[i + 1:]
        if isinstance(el, Branch):
            legs = [list(leg) for leg in el.legs]
            if len(legs) >= 2:
                for j, leg in enumerate(legs):
                    rest = legs[:j] + legs[j + 1:]
                    # a branch of one leg is that leg in series
                    middle = [Branch(rest, el.pos)] if len(rest) > 1 else rest[0]
                    pos = leg[0].pos if leg else el.pos
                    text = spell.series(leg) or "(empty)"
                    yield LEG, f"branch leg {j + 1} of {len(legs)} removed: {text}", pos, before + middle + after
            for j, leg in enumerate(legs):
                for operator, description, pos, changed in _series(leg, instructions, spell):
                    new_legs = legs[:j] + [changed] + legs[j + 1:]
                    yield operator, description, pos, before + [Branch(new_legs, el.pos)] + after
        else:
            for operator, new in _instruction(el, instructions):
                old = spell.instruction(el)
                if new is None:
                    yield operator, f"{old} removed", el.pos, before + after
                else:
                    yield operator, f"{old} -> {spell.instruction(new)}", el.pos, before + [new] + after


def _instruction(ins: Instruction, instructions) -> Iterator[tuple[str, Instruction | None]]:
    mnemonic = ins.mnemonic.upper()
    operands = list(ins.operands)
    if mnemonic in _SWAPS:
        other, operator = _SWAPS[mnemonic]
        yield operator, Instruction(other, operands, ins.pos)
    if mnemonic == "OTE":
        yield OUTPUT, None
    if mnemonic in _COMPARE_NEIGHBOURS:
        yield COMPARE, Instruction(_COMPARE_NEIGHBOURS[mnemonic], operands, ins.pos)
    spec = instructions.lookup(mnemonic)
    if spec is None:
        return
    for k, operand in enumerate(operands):
        if k >= spec.max_operands:
            break
        o = spec.operand_at(k)
        if o.kind in _FIXED_KINDS or o.name in _FIXED_NAMES:
            continue
        for operator, new in _operand(operand):
            yield operator, Instruction(ins.mnemonic, operands[:k] + [new] + operands[k + 1:], ins.pos)


def _operand(node) -> Iterator[tuple[str, object]]:
    """Each single change of an operand or expression: an integer constant
    one more and one less, an expression's comparison moved to its neighbour."""
    if isinstance(node, Const):
        if not isinstance(node, Placeholder) and type(node.value) is int:
            for delta in (1, -1):
                yield CONSTANT, Const(node.value + delta, node.pos, hex=node.hex)
    elif isinstance(node, BinOp):
        if node.op in _EXPRESSION_NEIGHBOURS:
            yield COMPARE, BinOp(_EXPRESSION_NEIGHBOURS[node.op], node.left, node.right, node.pos)
        for operator, new in _operand(node.left):
            yield operator, BinOp(node.op, new, node.right, node.pos)
        for operator, new in _operand(node.right):
            yield operator, BinOp(node.op, node.left, new, node.pos)
    elif isinstance(node, UnaryOp):
        for operator, new in _operand(node.operand):
            yield operator, UnaryOp(node.op, new, node.pos)
    elif isinstance(node, Call):
        for operator, new in _operand(node.arg):
            yield operator, Call(node.func, new, node.pos)
