"""Stage 2b: warnings about a valid program, as RSLogix's verify gives them.

``softplc check`` (and ``run``, through ``load_app``) print these after the
program is validated; none of them stops a program from running. Each is a
LadderError located at file:line:col:

- an output bit written by OTE in more than one place ("duplicate destructive
  bit"), naming both places;
- one timer, counter or control element used by two instructions (TON TOF
  RTO CTU CTD and any instruction with a control operand; RES and the
  examining of its bits are not uses). CTU with CTD, FFL with FFU and LFL
  with LFU on one element are the documented AB pairs, not warnings;
- a rung with no output instruction (a rung of SBR or LBL alone marks a
  place, and is left alone);
- a symbol never used in the program;
- a decimal constant that a word destination cannot hold (MOV 40000 N7:0),
  by validate.constant_fits;
- an input instruction after an output instruction in series, on the rung or
  within a branch leg (outputs end a rung or leg in RSLogix 5/500); in
  neutral text a forgotten ';' joins two rungs so, and the warning says so.

Sources and choices: docs/language.md, "softplc check warnings".
"""

from __future__ import annotations

from collections import defaultdict
from typing import Iterable

from ..datatable import Address, ValueKind
from .ast import AddressRef, Branch, Const, Instruction, Program, Rung, SymbolRef, Text, leaves, walk
from .errors import LadderError
from .instructions import BUILTIN, InstructionSet, K
from .parser import parse_expression
from .symbols import SymbolIndex
from .validate import constant_fits

# Instructions that use the element they name (a RES does not: it resets it).
_ELEMENT_KINDS = (K.TIMER, K.COUNTER, K.CONTROL)
# Two instructions that share one element by design (AB: a counter counts up
# and down; a FIFO or LIFO is loaded and unloaded through one control).
_PAIRS = (frozenset({"CTU", "CTD"}), frozenset({"FFL", "FFU"}), frozenset({"LFL", "LFU"}),
          frozenset({"SQO", "SQI", "SQL"}))  # a sequencer checked by its SQI (1756-RM003)
# Instructions that only mark a place in the program: a rung of these alone
# has no output and needs none.
_MARKERS = frozenset({"SBR", "LBL"})
# Where a constant is stored as it is, so a value a word cannot hold is lost.
_STORES = frozenset({"MOV", "FLL"})


def verify(program: Program, instructions: InstructionSet = BUILTIN, parsed: Program | None = None,
           overflow: str = "clamp", shown: Iterable[str] = ()) -> list[LadderError]:
    """Every warning about ``program`` (validated and resolved), in source
    order. ``parsed`` is the same program before symbols were resolved: it
    tells which symbols the rungs use (without it, that check is skipped);
    ``shown``: names used outside the rungs (softplc.toml's [display]), which
    count as uses. ``overflow`` is the app's math setting."""
    found: list[LadderError] = []
    roles = {m: spec.output for m, spec in instructions.table.items()}  # mnemonic -> is an output
    outputs: dict[str, list[Instruction]] = defaultdict(list)
    elements: dict[str, list[Instruction]] = defaultdict(list)
    for pfile in program.files.values():
        for rung in pfile.rungs:
            has_output = False
            only_markers = True
            for ins in walk(rung.elements):
                spec = instructions.lookup(ins.mnemonic)
                if spec is None:
                    continue
                has_output = has_output or spec.output
                only_markers = only_markers and ins.mnemonic in _MARKERS
                if ins.mnemonic == "OTE" and _direct(ins.operands[0]) is not None:
                    outputs[str(ins.operands[0].address)].append(ins)
                for i, op in enumerate(ins.operands):
                    if spec.operand_at(i).kind in _ELEMENT_KINDS and _direct(op) is not None:
                        elements[str(op.address)].append(ins)
                if ins.mnemonic in _STORES:
                    found += _constant_warnings(ins, overflow)
            found += _input_after_output(rung, roles)
            if rung.elements and not has_output and not only_markers:
                found.append(LadderError(rung.pos, "rung has no output instruction: its conditions "
                                         "are evaluated and nothing is done with them"))
    for address, writers in outputs.items():
        for ins in writers[1:]:
            found.append(LadderError(ins.pos, f"OTE {address}: duplicate destructive bit, also written by "
                                     f"OTE at {writers[0].pos} (the last OTE in the scan decides)"))
    for address, users in elements.items():
        seen: dict[str, Instruction] = {}
        for ins in users:
            # A second instruction of one mnemonic, or one that is not the first's pair, shares the element.
            other = seen.get(ins.mnemonic) or next(
                (u for m, u in seen.items() if not any({m, ins.mnemonic} <= p for p in _PAIRS)), None)
            if other is not None:
                found.append(LadderError(ins.pos, f"{ins.mnemonic} {address}: {address} is also used by "
                                         f"{other.mnemonic} at {other.pos}; two instructions driving "
                                         "one element overwrite each other's status bits and values"))
            seen.setdefault(ins.mnemonic, ins)
    if parsed is not None:
        found += _unused_symbols(parsed, instructions, shown)
    return sorted(found, key=lambda e: (e.pos.source, e.pos.line, e.pos.column))


def _input_after_output(rung: Rung, roles: dict[str, bool]) -> list[LadderError]:
    """The first input instruction of ``rung`` that an output instruction
    precedes in series (on the rung, or inside a branch leg, or after a
    branch one of whose legs ends in an output); outputs in parallel legs,
    each last in its leg, are the way to have several. ``roles``: mnemonic
    -> whether it is an output instruction (unknown ones are skipped)."""
    first: list[tuple[Instruction, Instruction]] = []

    def series(elements, before: Instruction | None) -> Instruction | None:
        # ``before``: the last output on the path into ``elements``; returns the same after them.
        for el in elements:
            if first:
                return before
            if isinstance(el, Branch):
                after = [series(leg, before) for leg in el.legs]
                before = next((o for o in after if o is not None), None)
                continue
            output = roles.get(el.mnemonic)
            if output:
                before = el
            elif output is not None and before is not None:
                first.append((el, before))
        return before

    series(rung.elements, None)
    if not first:
        return []
    ins, output = first[0]
    message = (f"{ins.mnemonic} after {output.mnemonic} at {output.pos} in series: an output instruction "
               "ends its rung or branch leg")
    spans = ins.pos.line != output.pos.line
    head = rung.elements[0]
    sor = spans and (head.pos.line, head.pos.column) != (rung.pos.line, rung.pos.column)
    if spans and not sor:
        # Only a neutral-text rung runs on over lines without SOR ... EOR.
        message += (f" (a ';' missing after the {output.mnemonic} on line {output.pos.line} "
                    "would join two rungs into this one)")
    elif not spans:
        message += (" (if two rungs were meant, end the first: ';' in neutral text, "
                    "a new line in mnemonic form)")
    return [LadderError(ins.pos, message)]


def _direct(op) -> Address | None:
    if isinstance(op, AddressRef) and op.address.is_direct:
        return op.address
    return None


def _constant_warnings(ins: Instruction, overflow: str) -> list[LadderError]:
    """MOV 40000 N7:0: the constant cannot be stored as written."""
    if len(ins.operands) < 2:
        return []
    source, dest = ins.operands[0], ins.operands[1]
    if not isinstance(source, Const) or not isinstance(dest, AddressRef) or dest.address.kind is not ValueKind.WORD:
        return []
    problem = constant_fits(source, dest.address, overflow)
    if problem is None:
        return []
    return [LadderError(source.pos, f"{ins.mnemonic} {source.value} {dest.address}: {problem} "
                        "(a decimal constant is its value; write 0x.... for a 16-bit pattern)")]


def _unused_symbols(parsed: Program, instructions: InstructionSet, shown: Iterable[str]) -> list[LadderError]:
    names = SymbolIndex(parsed.symbols)
    used = {decl.name for text in shown if (decl := names.declaration(text)) is not None}
    for pfile in parsed.files.values():
        for rung in pfile.rungs:
            for ins in walk(rung.elements):
                spec = instructions.lookup(ins.mnemonic)
                quoted = spec is not None and any(o.kind is K.EXPRESSION for o in spec.operands)
                for ref in _symbol_refs(ins.operands, quoted):
                    decl = names.declaration(ref.name)
                    if decl is not None:
                        used.add(decl.name)
    return [LadderError(decl.pos, f"symbol {decl.name} ({decl.address}) is never used in the program")
            for decl in parsed.symbols.values() if decl.name not in used]


def _symbol_refs(operands: Iterable, quoted: bool) -> Iterable[SymbolRef]:
    """The symbols of operands; ``quoted``: a Text operand is an expression
    (CPT, CMP) that only the validator parses."""
    for op in operands:
        for leaf in leaves(op):
            if isinstance(leaf, SymbolRef):
                yield leaf
            elif isinstance(leaf, Text) and quoted:
                try:
                    tree = parse_expression(leaf.value, leaf.pos)
                except LadderError:
                    continue
                yield from (x for x in leaves(tree) if isinstance(x, SymbolRef))

