"""Logix's string instructions, SIZE, and compares and MOV of strings
translated into the bound instructions of ladder/instr/logix_string.py
(the rules and their 1756-RM003 sections are there).

Each operand is taken by its letter: ``s`` a string tag, ``S`` a string tag
written (its type's characters follow the operands, the capacity the
instruction keeps to), ``n`` a number or a tag's value, ``N`` a number tag
written.
"""

from __future__ import annotations

from ..ladder.ast import Const, Instruction
from ..ladder.instr.logix_string import COMPARISONS
from . import operands
from .copy import copy_run, element_run
from .operands import Operands
from .tags import PathError

PLAN = {
    "CONCAT": ("LCONCAT", "ssS"), "MID": ("LMID", "snnS"), "INSERT": ("LINSERT", "ssnS"),
    "DELETE": ("LDELETE", "snnS"), "FIND": ("LFIND", "ssnN"), "UPPER": ("LUPPER", "sS"),
    "LOWER": ("LLOWER", "sS"), "DTOS": ("LDTOS", "nS"), "RTOS": ("LRTOS", "nS"),
    "STOD": ("LSTOD", "sN"), "STOR": ("LSTOR", "sN"),
}
COMPARES = {"EQU": "EQU", "NEQ": "NEQ", "LES": "LES", "GRT": "GRT", "LEQ": "LEQ", "GEQ": "GEQ",
            "EQ": "EQU", "NE": "NEQ", "LT": "LES", "GT": "GRT", "LE": "LEQ", "GE": "GEQ"}


def translate(el, pos, rung, ctx):
    if el.mnemonic in PLAN:
        return operands.translate(el, pos, rung, ctx, _string_instruction)
    if el.mnemonic == "SIZE":
        return operands.translate(el, pos, rung, ctx, _size)
    if el.mnemonic in COMPARES:
        return operands.translate(el, pos, rung, ctx, _compare)
    return operands.translate(el, pos, rung, ctx, _move)


def _string_instruction(ops: Operands) -> list[Instruction]:
    mnemonic, letters = PLAN[ops.el.mnemonic]
    ops.count(len(letters))
    out, capacity = [], None
    for k, letter in enumerate(letters):
        if letter in "sS":
            ref, chars = ops.string(k)
            out.append(ref)
            if letter == "S":
                capacity = chars
        elif letter == "n":
            out.append(ops.value(k))
        else:
            out.append(ops.dest(k))
    if capacity is not None:
        out.append(Const(capacity, ops.pos))
    return [Instruction(mnemonic, out, ops.pos)]


def _compare(ops: Operands):
    """EQU, NEQ, LES, GRT, LEQ, GEQ (and the IEC names) of two strings;
    of numbers, rungs.py's PLAN."""
    if len(ops) != 2 or not (ops.is_string(0) or ops.is_string(1)):
        return NotImplemented
    (a, _), (b, _) = ops.string(0), ops.string(1)
    test = COMPARISONS.index(COMPARES[ops.el.mnemonic])
    return [Instruction("LSCMP", [a, b, Const(test, ops.pos)], ops.pos)]


def _move(ops: Operands):
    """MOV (MOVE) into a string: the string copied whole (as COP of one
    string, RM003 "Copy File"); any other MOV, rungs.py's PLAN."""
    if len(ops) != 2 or not ops.is_string(1):
        return NotImplemented
    dest = element_run(ops.resolve(1), ops.where(1), ops.ctx)
    source = element_run(ops.resolve(0), ops.where(0), ops.ctx)
    if source.type.kind != "string":
        raise PathError(f"expected a string to move into a string, found {source.type.name}")
    return copy_run(source, ops.where(0), dest, Const(1, ops.pos), ops.pos)


def _size(ops: Operands) -> list[Instruction]:
    """SIZE(Source, Dim, Size): the number of elements of dimension ``Dim``
    (0 the first) of the array Source (RM003, "Size In Elements (SIZE)"),
    known when the export is loaded: a MOV of that number. Source is the
    array or, as exports write it, its element (``Arr[0]``, ``Grid[0,0]``)."""
    ops.count(3)
    r = ops.resolve(0)
    if not r.dims and ops.text(0).endswith("]"):  # Arr[0], as Studio 5000 writes it: the array
        text = ops.text(0)
        depth = 0
        for k in range(len(text) - 1, -1, -1):
            depth += {"]": 1, "[": -1}.get(text[k], 0)
            if depth == 0:
                break
        r = ops.ctx.directory.resolve(text[:k], ops.ctx.scope, operands._no_index)
    dims = r.dims
    if not dims:
        raise PathError(f"expected an array, found {r.type.name}")
    dim = ops.value(1)
    if not isinstance(dim, Const) or not isinstance(dim.value, int) or not 0 <= dim.value < len(dims):
        ops.where(1)
        raise PathError(f"expected the dimension to vary as a number from 0 to {len(dims) - 1}")
    return [Instruction("MOV", [Const(dims[dim.value], ops.pos), ops.dest(2)], ops.pos)]
