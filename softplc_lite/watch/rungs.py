"""Rungs drawn as an online ladder editor draws them: rails, contacts,
coils, boxes and branches, each operand with its current value, and power
flow in colour (power.py says what is energized).

A rung at 64 columns (I:0/0 forced, a timer timing)::

       Rung 0
        Run the timer while Start is held and B3/1 or not B3/2.
    | Start                                                        |
    | I:0/0    B3/1                          +-TON---------------+ |
    |--] [---+-] [--+------------------------|T4:0 base 0.01     |-|
    |  1 F   |  0   |                        |EN TT . PRE 5 ACC 3| |
    |        | B3/2 |                        +-------------------+ |
    |        +-]/[--+                                              |
    |           0                                                  |

* the header line: ``>`` when selected, ``*`` with a breakpoint, the rung
  number; then the rung comment (dim), reflowed to the width (blank lines
  separate paragraphs), and a red ``! ...`` line per address fault;
* a contact or coil has its symbol (if the program declares one; a bit of
  a named element is named after it, ``Reply/DN``) and its address above
  it, its bit value (and ``F`` when forced) below it;
* every other instruction is a box: the mnemonic in its top border, then
  its operands (``ADDR=value``, ``Symbol(ADDR)=value``, constants with the
  operand's name; compares, math and moves as formulas,
  ``N7:0=5 + 1 -> N7:1=6``), then, for a timer, counter or control
  element, its status bits (set ones by name, clear ones ``.``) and words
  (``EN DN . . LEN 255 POS 2``), live from the table;
* branches are legs stacked between ``+`` connectors; output instructions
  (the rung's tail of outputs) sit against the right rail;
* a rung wider than the space wraps between elements: the wire ends with
  ``>>`` at the right and the next row starts with ``>>``; a branch too wide
  for a row wraps inside its legs the same way, and a box's contents wrap
  inside the box. Nothing is cut off;
* a branch nested deeper than MAX_DEPTH levels, or left too few columns
  for its legs (MIN_LEG), is one ``BST`` box saying what it holds
  (``2 legs, 12 levels, 13 instructions``), with its power;
* colour: energized wires, true instructions and energized outputs bold
  green, faults bold red, ``F`` yellow. Plain text shows values, not power.

Layout works on blocks: lines of (text, style) runs, all one width, with
the row the rung wire runs through (``wire``), composed side by side
(series) and stacked (branches, wrapped rows). Laying out a rung takes
time linear in its size (times the nesting depth drawn, at most
MAX_DEPTH), and a long rung is laid out only as far as it is drawn (see
``_Layout``).
"""

from __future__ import annotations

import copy
import io
import itertools
import json
from collections.abc import Callable, Iterable, Mapping

from rich.cells import cell_len
from rich.console import Console, ConsoleOptions, RenderResult
from rich.segment import Segment
from rich.style import Style
from rich.text import Text

from ..datatable import Address, DataTable, ValueKind
from ..ladder.ast import (
    AddressRef,
    Branch,
    Const,
    Element,
    Instruction,
    ProgramFile,
    Rung,
    address_refs,
)
from ..ladder.ast import Text as TextOperand
from ..ladder.fmt import format_expression
from ..ladder.instructions import BUILTIN, InstructionSet, K
from .power import READ_FAILURES, Power, rung_power

ENERGIZED = Style(color="green", bold=True)  # wires with power, true instructions, energized outputs
FAULT = Style(color="red", bold=True)  # an address that does not resolve
FORCED = Style(color="yellow", bold=True)
COMMENT = Style(dim=True)
HEADER = Style(bold=True)
SELECTED = Style(bold=True, reverse=True)
BREAKPOINT = Style(color="red", bold=True)

BOX_MAX = 34  # widest box interior, in cells
STRING_MAX = 24  # longest string value shown (quotes included)
CONTINUED = ">>"
COMMENT_INDENT = 4

_GLYPHS = {"XIC": "] [", "XIO": "]/[", "OTE": "( )", "OTL": "(L)", "OTU": "(U)", "ONS": "[ONS]"}
_COMPARE = {"EQU": "==", "NEQ": "<>", "LES": "<", "LEQ": "<=", "GRT": ">", "GEQ": ">="}
_INFIX = {"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/", "MOD": "MOD", "AND": "AND", "OR": "OR", "XOR": "XOR"}
_MOVES = {"MOV", "NEG", "ABS", "SQR", "NOT", "ACI", "AIC"}  # source -> dest
_LIVE_PRESETS = {"TON": (2, 3), "TOF": (2, 3), "RTO": (2, 3), "CTU": (1, 2), "CTD": (1, 2)}  # shown from the table
_STATUS_BITS = {"T": ("EN", "TT", "DN"), "C": ("CU", "CD", "DN", "OV", "UN"), "R": ("EN", "DN", "ER", "EM")}
_STRUCTS = (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL)

Run = tuple[str, "Style | None"]
Line = list  # of Runs, and of Lines: composing blocks nests their lines instead of copying them


# -- blocks -------------------------------------------------------------------------------


class _Block:
    """Lines, each ``width`` cells: a line is a list of runs (text, style)
    and of lines (a block's lines go into the lines of the block around it
    as they are, so composing costs a few items a line, not a copy of every
    run: ``_runs`` flattens them); ``wire`` is the row the rung wire
    enters by, ``exit`` the row it leaves by (lower than ``wire`` only for a
    series wrapped inside a branch leg); ``out`` whether the wire leaving
    it has power."""

    __slots__ = ("exit", "lines", "out", "width", "wire")

    def __init__(self, lines: list[Line], wire: int, width: int, out: bool, exit: int | None = None) -> None:
        self.lines = lines
        self.wire = wire
        self.exit = wire if exit is None else exit
        self.width = width
        self.out = out


def _power_style(on: bool) -> Style | None:
    return ENERGIZED if on else None


def _wire(n: int, on: bool) -> Run:
    return ("-" * n, _power_style(on))


def _blank(n: int) -> Run:
    return (" " * n, None)


def _runs(line: Line) -> Iterable[Run]:
    """A line's runs in order, its nested lines flattened (no recursion)."""
    stack = [iter(line)]
    while stack:
        for item in stack[-1]:
            if isinstance(item, list):
                stack.append(iter(item))
                break
            yield item
        else:
            stack.pop()


def _width(line: Line) -> int:
    return sum(cell_len(text) for text, _ in _runs(line))


def _centered(line: Line, width: int) -> Line:
    free = width - _width(line)
    return [_blank(free // 2), *line, _blank(free - free // 2)]


def _wire_block(width: int, on: bool) -> _Block:
    return _Block([[_wire(width, on)]], 0, width, on)


def _side_by_side(blocks: list[_Block]) -> _Block:
    """A series: blocks next to each other, their wire rows lined up."""
    above = max(b.wire for b in blocks)
    below = max(len(b.lines) - b.wire - 1 for b in blocks)
    lines: list[Line] = [[] for _ in range(above + 1 + below)]
    for b in blocks:
        top = above - b.wire
        for r, line in enumerate(lines):
            k = r - top
            line.append(b.lines[k] if 0 <= k < len(b.lines) else _blank(b.width))
    return _Block(lines, above, sum(b.width for b in blocks), blocks[-1].out)


def _with_edges(block: _Block, left: tuple[str, str, Style | None] | None,
                right: tuple[str, str, Style | None] | None) -> _Block:
    """Add a column at either side: (text on the row the wire enters by
    (left) or leaves by (right), text on the others, style of the first)."""
    def run(edge, r: int, wire_row: int) -> list[Run]:
        if edge is None:
            return []
        return [(edge[0], edge[2])] if r == wire_row else [(edge[1], None)]

    lines = [[*run(left, r, block.wire), line, *run(right, r, block.exit)] for r, line in enumerate(block.lines)]
    extra = sum(cell_len(e[0]) for e in (left, right) if e is not None)
    return _Block(lines, block.wire, block.width + extra, block.out, block.exit)


def _stacked(blocks: list[_Block]) -> _Block:
    """Rows under each other (padded to the widest: only a row holding an
    element wider than the others' width is wider): the wire enters by the
    first row and leaves by the last."""
    width = max(b.width for b in blocks)
    last = blocks[-1]
    lines = []
    for b in blocks:
        for r, line in enumerate(b.lines):
            if b.width < width:  # the wire leaving the last row goes on to the right
                line = [line, _wire(width - b.width, b.out) if b is last and r == b.exit else _blank(width - b.width)]
            lines.append(line)
    exit = len(lines) - len(last.lines) + last.exit
    return _Block(lines, blocks[0].wire, width, last.out, exit)


# -- what the view needs to know ---------------------------------------------------------------


class _SymbolNames:
    """Address -> symbol name; a bit or word of a named element is named
    after it (``Reply/DN`` for R6:1/DN when Reply is R6:1)."""

    def __init__(self, symbols: Mapping[str, object] | None) -> None:
        self.by_address: dict[str, str] = {}
        for name, target in (symbols or {}).items():
            address = getattr(target, "address", target)
            self.by_address.setdefault(str(address), name)

    def name(self, address: Address) -> str | None:
        if not self.by_address or not address.is_direct:
            return None
        text = str(address)
        found = self.by_address.get(text)
        if found is not None or (address.bit is None and address.member is None) or address.element is None:
            return found
        element = str(Address(address.type_letter, address.file, address.element))
        owner = self.by_address.get(element)
        if owner is not None and text.startswith(element):
            return owner + text[len(element):]
        return None


class _Context:
    """What drawing one rung needs: values, power, names, forces, specs."""

    def __init__(self, table: DataTable, power: Power, names: _SymbolNames, forced,
                 instructions: InstructionSet, tli_status: bool) -> None:
        self.table = table
        self.power = power
        self.names = names
        self.forced = forced
        self.instructions = instructions
        self.tli_status = tli_status

    def state(self, element: Element):
        return self.power.get(element)

    def value(self, address: Address) -> Run:
        try:
            return (_value_text(self.table.read(address)), None)
        except READ_FAILURES:
            return ("?", FAULT)

    def is_output(self, element: Element) -> bool:
        """An output instruction, or a branch whose every leg ends in one
        (looked at without recursion, whatever the nesting)."""
        stack = [element]
        while stack:
            el = stack.pop()
            if isinstance(el, Branch):
                for leg in el.legs:
                    if not leg:
                        return False
                    stack.append(leg[-1])
            else:
                spec = self.instructions.lookup(el.mnemonic)
                if spec is not None and not spec.output:
                    return False
        return True


def _value_text(value) -> str:
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, float):
        return f"{value:.7g}"
    if isinstance(value, str):
        text = json.dumps(value)
        return text if len(text) <= STRING_MAX else text[:STRING_MAX - 4] + '..."'
    return str(value)


# -- contacts and coils -----------------------------------------------------------------------


def _bit_cell(ins: Instruction, ctx: _Context) -> _Block:
    glyph = _GLYPHS[ins.mnemonic]
    state = ctx.state(ins)
    p_in, p_out = (state.power_in, state.power_out) if state else (False, False)
    operand = ins.operands[0] if ins.operands else None
    rows_above: list[Line] = []
    value: Line = []
    if isinstance(operand, AddressRef):
        address = operand.address
        name = ctx.names.name(address)
        if name:
            rows_above.append([(name, None)])
        rows_above.append([(str(address), None)])
        value = [ctx.value(address)]
        if str(address) in ctx.forced:
            value += [(" F", FORCED)]
    if state is not None and state.fault:
        glyph_style = FAULT
    else:
        glyph_style = _power_style(state is not None and state.is_true)
    width = max(cell_len(glyph), *(_width(r) for r in rows_above), _width(value)) + 2
    left = (width - cell_len(glyph)) // 2
    wire = [_wire(left, p_in), (glyph, glyph_style), _wire(width - left - cell_len(glyph), p_out)]
    lines = [_centered(r, width) for r in rows_above] + [wire] + [_centered(value, width)]
    return _Block(lines, len(rows_above), width, p_out)


# -- boxes --------------------------------------------------------------------------------------


def _box_cell(ins: Instruction, budget: int, ctx: _Context) -> _Block:
    state = ctx.state(ins)
    p_in, p_out = (state.power_in, state.power_out) if state else (False, False)
    title_style = FAULT if state is not None and state.fault else _power_style(state is not None and state.is_true)
    return _box(ins.mnemonic, title_style, _box_items(ins, ctx), budget, p_in, p_out)


def _box(title: str, title_style: Style | None, groups: list[list[Line]], budget: int, p_in: bool,
         p_out: bool) -> _Block:
    """A box with ``title`` in its top border and ``groups`` flowed inside,
    at most ``budget`` wide (BOX_MAX inside) unless its title needs more."""
    least = cell_len(title) + 2
    lines = _flow(groups, max(least, min(BOX_MAX, budget - 4))) or [[]]
    inner = max(least, *(_width(line) for line in lines))
    top = [_blank(1), ("+-", None), (title, title_style), ("-" * (inner - cell_len(title) - 1) + "+", None), _blank(1)]
    body = []
    for k, line in enumerate(lines):
        left, right = (_wire(1, p_in), _wire(1, p_out)) if k == 0 else (_blank(1), _blank(1))
        body.append([left, ("|", None), *line, _blank(inner - _width(line)), ("|", None), right])
    bottom = [_blank(1), ("+" + "-" * inner + "+", None), _blank(1)]
    return _Block([top, *body, bottom], 1, inner + 4, p_out)


def _box_items(ins: Instruction, ctx: _Context) -> list[list[Line]]:
    """The box's contents: groups of items, each group starting a line.
    Compares, math and moves read as formulas (``N7:0=5 + 1 -> N7:1=6``);
    other instructions list their operands, constants with their names."""
    m, ops = ins.mnemonic, ins.operands
    spec = ctx.instructions.lookup(m)
    specs = spec.operands if spec else ()

    def item(i: int, labelled: bool = True) -> Line:
        name = specs[i].name if i < len(specs) and labelled else None
        return _operand_item(ops[i], name, specs[i].kind if i < len(specs) else None, ctx)

    if m in _COMPARE and len(ops) == 2:
        main = [item(0, False), _prefixed(_COMPARE[m], item(1, False))]
    elif m == "LIM" and len(ops) == 3:
        main = [item(0, False), _prefixed("<=", item(1, False)), _prefixed("<=", item(2, False))]
    elif m in _INFIX and len(ops) == 3:
        main = [item(0, False), _prefixed(_INFIX[m], item(1, False)), _prefixed("->", item(2))]
    elif m in _MOVES and len(ops) == 2:
        main = [item(0, False), _prefixed("->", item(1))]
    elif m == "CPT" and len(ops) == 2:
        formula, *reads = _expression_items(ops[1], ctx)
        return [[formula, _prefixed("->", item(0))], reads]
    elif m == "CMP" and len(ops) == 1:
        formula, *reads = _expression_items(ops[0], ctx)
        return [[formula], reads]
    else:
        skip = _LIVE_PRESETS.get(m, ())
        main = [item(i) for i in range(len(ops)) if i not in skip]
    groups = [main]
    if spec is None or spec.module is None or ctx.tli_status:
        for op in ops:
            if isinstance(op, AddressRef) and op.address.kind in _STRUCTS:
                groups.append([_struct_status(op.address, ctx)])
    return groups


def _prefixed(text: str, item: Line) -> Line:
    return [(text + " ", None), *item]


def _operand_item(op, name: str | None, kind: K | None, ctx: _Context) -> Line:
    label = name if name and not name.startswith("param") and name not in ("dest", "result") else None
    if isinstance(op, Const):
        text = repr(op.value) if isinstance(op.value, float) else str(op.value)
        return [(f"{label} {text}" if label else text, None)]
    if isinstance(op, TextOperand):
        return [(json.dumps(op.value), None)]
    if not isinstance(op, AddressRef):  # an expression (CMP, CPT)
        return [run for k, it in enumerate(_expression_items(op, ctx)) for run in ([_blank(1)] if k else []) + it]
    address = op.address
    if kind in (K.FILE, K.FILE_SOURCE):
        return [("#" + str(address), None)]
    name_text = ctx.names.name(address)
    shown = f"{name_text}({address})" if name_text else str(address)
    if address.kind in _STRUCTS:
        return [(shown, None)]
    line: Line = [(shown + "=", None), ctx.value(address)]
    if str(address) in ctx.forced:
        line.append((" F", FORCED))
    return line


def _expression_items(node, ctx: _Context) -> list[Line]:
    """The expression's text, then each address it reads with its value."""
    items: list[Line] = [[(format_expression(node), None)]]
    seen = set()
    for ref in address_refs(node):
        text = str(ref.address)
        if text not in seen:
            seen.add(text)
            items.append([(text + "=", None), ctx.value(ref.address)])
    return items


def _struct_status(address: Address, ctx: _Context) -> Line:
    """``EN DN . . LEN 255 POS 2``: status bits (clear ones as dots), then words."""
    try:
        members = ctx.table.read(address)
    except READ_FAILURES:
        return [("?", FAULT)]
    line: Line = []
    for bit in _STATUS_BITS.get(address.type_letter, ()):
        on = bool(members.get(bit))
        line += [(bit if on else ".", ENERGIZED if on else None), _blank(1)]
    words = (f"{w.name} {members[w.name]}" for w in address.ftype.word_members)
    line.append((" ".join(words), None))
    return line


def _flow(groups: list[list[Line]], width: int) -> list[Line]:
    """Items into lines of at most ``width`` cells, one space apart; each
    group starts a new line; an item wider than a line is split."""
    lines: list[Line] = []
    for group in groups:
        line: Line = []
        used = 0
        for item in group:
            w = _width(item)
            if w > width:
                if line:
                    lines.append(line)
                line, used = [], 0
                lines.extend(_chunks(item, width))
                continue
            if line and used + 1 + w > width:
                lines.append(line)
                line, used = [], 0
            if line:
                line.append(_blank(1))
                used += 1
            line.extend(item)
            used += w
        if line:
            lines.append(line)
    return lines


def _chunks(item: Line, width: int) -> list[Line]:
    """An item too wide for a line, cut into lines, after a space when
    there is one."""
    chars = [(ch, style) for text, style in item for ch in text]
    out = []
    at, n = 0, len(chars)
    while at < n:
        cut = min(n - at, width)
        if cut < n - at:
            space = max((k for k in range(1, cut) if chars[at + k][0] == " "), default=None)
            cut = space + 1 if space is not None else cut
        out.append(_merged(chars[at:at + cut]))
        at += cut
    return out


def _merged(chars: list[Run]) -> Line:
    line: Line = []
    for ch, style in chars:
        if line and line[-1][1] is style:
            line[-1] = (line[-1][0] + ch, style)
        else:
            line.append((ch, style))
    return line


# -- series, branches, rows ----------------------------------------------------------------------
#
# A series is laid out at a budget (the columns it may take): side by side
# when its elements fit, else wrapped into rows, its too-wide elements laid
# out again narrower. Deciding that needs the elements' widths at a budget,
# and a branch's width needs its legs' (a budget 4 narrower), and so on down.
# Building every candidate block to measure it would lay a subtree out
# again at every level above it that wraps: twice per level, exponential in
# the nesting depth. So _Layout measures first (widths only, memoized per
# element and budget) and builds each element's block once, at the budget
# its series chose. Branches nested deeper than MAX_DEPTH, or left fewer
# than MIN_LEG columns a leg, are drawn as one box that sums them up, so the
# drawn depth, and with it the work per element, is bounded.

MAX_DEPTH = 32  # branch levels drawn; deeper branches are summed up in a box
MIN_LEG = 16  # columns a branch's legs need at least; with fewer it is summed up in a box


class _Layout:
    """The blocks of one rung: measure (``width``) and build (``block``)
    elements; ``level`` is the number of branches around an element."""

    def __init__(self, ctx: _Context, elements: list[Element]) -> None:
        self.ctx = ctx
        self.elements = elements
        self._widths: dict[tuple[int, int], int] = {}
        self._cells: dict[tuple[int, int], _Block] = {}
        self._sizes: dict[int, tuple[int, int]] | None = None

    # -- measuring
    def width(self, el: Element, budget: int, level: int) -> int:
        key = (id(el), budget)
        w = self._widths.get(key)
        if w is None:
            if self._drawn(el, budget, level):
                w = 4 + max(self._leg_plan(leg, budget - 4, level + 1)[0] for leg in el.legs)
            else:
                w = self._cell(el, budget, level).width
            self._widths[key] = w
        return w

    def _drawn(self, el: Element, budget: int, level: int) -> bool:
        """A branch drawn as legs (else a single cell: an instruction, or a
        branch summed up)."""
        return isinstance(el, Branch) and bool(el.legs) and level < MAX_DEPTH and budget - 4 >= MIN_LEG

    def _leg_plan(self, leg: list[Element], budget: int, level: int) -> tuple[int, list[int], bool]:
        """(width, each element's budget, wrapped) of a branch leg."""
        if not leg:
            return 2, [], False
        widths = [self.width(el, budget, level) for el in leg]
        if sum(widths) <= budget:
            return sum(widths), [budget] * len(leg), False
        budgets, widths = self._narrowed(leg, widths, budget, budget - 2, 0, level)
        return _rows_width(widths, budget - 2, 0) + 2, budgets, True

    def _narrowed(self, elements: list[Element], widths: list[int], budget: int, width: int, rail: int,
                  level: int) -> tuple[list[int], list[int]]:
        """A series that does not fit rows of ``width``: its elements wider
        than a row between ``>>`` markers are laid out that narrow."""
        budgets = [budget] * len(elements)
        if sum(widths) > width - 2 * rail:
            narrow = width - 2 * len(CONTINUED)
            widths = list(widths)
            for k, el in enumerate(elements):
                if widths[k] > narrow:
                    budgets[k], widths[k] = narrow, self.width(el, narrow, level)
        return budgets, widths

    # -- building
    def block(self, el: Element, budget: int, level: int) -> _Block:
        if self._drawn(el, budget, level):
            return self._branch(el, budget, level)
        return self._cell(el, budget, level)

    def _cell(self, el: Element, budget: int, level: int) -> _Block:
        """An instruction's block, or a branch summed up; kept, as measuring
        builds them."""
        bit = isinstance(el, Instruction) and el.mnemonic in _GLYPHS and len(el.operands) == 1
        key = (id(el), -1 if bit else budget)
        cell = self._cells.get(key)
        if cell is None:
            if bit:
                cell = _bit_cell(el, self.ctx)
            elif isinstance(el, Branch):
                cell = self._summary(el, budget)
            else:
                cell = _box_cell(el, budget, self.ctx)
            self._cells[key] = cell
        return cell

    def _summary(self, branch: Branch, budget: int) -> _Block:
        """A branch too deep for the width (or for MAX_DEPTH): a box saying
        what it holds, with its power."""
        if self._sizes is None:
            self._sizes = _branch_sizes(self.elements)
        levels, count = self._sizes.get(id(branch), (1, 0))
        state = self.ctx.state(branch)
        p_in, p_out = (state.power_in, state.power_out) if state else (False, False)
        legs = len(branch.legs)
        items = [[(f"{legs} leg{'s' if legs != 1 else ''},", None)],
                 [(f"{levels} level{'s' if levels != 1 else ''},", None)],
                 [(f"{count} instruction{'s' if count != 1 else ''}", None)]]
        return _box("BST", _power_style(p_out), [items], budget, p_in, p_out)

    def _branch(self, branch: Branch, budget: int, level: int) -> _Block:
        """Legs stacked between ``+`` connectors: the left bus joins where
        the legs' wires enter, the right bus where they leave (and, when the
        first leg wraps, the branch's own wire row, where the rung goes on)."""
        state = self.ctx.state(branch)
        p_in, p_out = (state.power_in, state.power_out) if state else (False, False)
        legs = [self._leg(leg, budget - 4, p_in, level + 1) for leg in branch.legs]
        inner = max(leg.width for leg in legs)
        lines: list[Line] = []
        entries, exits = [], []
        for leg in legs:
            entries.append(len(lines) + leg.wire)
            exits.append(len(lines) + leg.exit)
            for r, line in enumerate(leg.lines):
                pad = _wire(inner - leg.width, leg.out) if r == leg.exit else _blank(inner - leg.width)
                lines.append([line, pad])
        entered = set(entries)
        joins = {*exits, entries[0]}
        top, bottom = min(joins), max(joins)
        in_run, out_run = ("-", _power_style(p_in)), ("-", _power_style(p_out))
        joined = []
        for r, line in enumerate(lines):
            left = "+" if r in entered else "|" if entries[0] < r < entries[-1] else " "
            right = "+" if r in joins else "|" if top < r < bottom else " "
            on_wire = r == entries[0]
            joined.append([in_run if on_wire else (" ", None), (left, _power_style(p_in and left != " ")), line,
                           (right, _power_style(p_out and right != " ")), out_run if on_wire else (" ", None)])
        return _Block(joined, entries[0], inner + 4, p_out)

    def _leg(self, leg: list[Element], budget: int, power_in: bool, level: int) -> _Block:
        """One leg of a branch: its series side by side, or, when that is
        wider than ``budget``, wrapped into rows a column clear of the buses."""
        _, budgets, wrapped = self._leg_plan(leg, budget, level)
        if not leg:
            return _wire_block(2, power_in)
        if not wrapped:
            return _side_by_side([self.block(el, budget, level) for el in leg])
        rows = self.rows(leg, budgets.__getitem__, len(leg), budget - 2, power_in, rails=False, level=level)
        return _with_edges(rows, ("-", " ", _power_style(power_in)), ("-", " ", _power_style(rows.out)))

    def rung(self, width: int, max_lines: int | None = None) -> _Block:
        """The rung's elements between the rails, in rows of ``width``; with
        ``max_lines``, only the rows that start within that many lines (a
        long rung is measured and built only as far as it is seen)."""
        elements = self.elements
        full = width - 2
        narrow = width - 2 * len(CONTINUED)
        fits = _fits((self.width(el, full, 0) for el in elements), width - 2)

        def budget(i: int) -> int:
            return full if fits or self.width(elements[i], full, 0) <= narrow else narrow

        return self.rows(elements, budget, _outputs_start(elements, self.ctx), width, True, True, 0, max_lines)

    def rows(self, elements: list[Element], budget: Callable[[int], int], split: int, width: int, power_in: bool,
             rails: bool, level: int, max_lines: int | None = None) -> _Block:
        """A series laid out in rows of ``width`` cells (wider only where one
        element is), wrapped between elements with ``>>`` markers; element
        ``i`` at ``budget(i)``; the wire is filled out before element
        ``split`` (outputs go to the right). With ``rails``, the first row
        starts at the left rail and the last row ends at the right rail.
        With ``max_lines``: the rows up to the one that reaches that many
        lines; the elements after them are not looked at."""
        rail = 1 if rails else 0
        blocks: dict[int, _Block] = {}

        def block(i: int) -> _Block:
            b = blocks.get(i)
            if b is None:
                b = blocks[i] = self.block(elements[i], budget(i), level)
            return b

        out_rows = []
        lines = 0
        for indices, last in _packed(lambda i: self.width(elements[i], budget(i), level), len(elements),
                                     width, rail):
            first = not out_rows
            left_w = rail if first else len(CONTINUED)
            right_w = rail if last else len(CONTINUED)
            parts = [block(i) for i in indices]
            room = width - left_w - right_w - sum(b.width for b in parts)
            if room > 0:
                at = next((n for n, i in enumerate(indices) if i >= split), len(indices)) if last else len(indices)
                before = indices[at] - 1 if at < len(indices) else (indices[-1] if indices else -1)
                on = block(before).out if before >= 0 else power_in
                parts.insert(at, _wire_block(room, on))
            row = _side_by_side(parts) if parts else _wire_block(0, power_in)
            arriving = block(indices[0] - 1).out if indices and indices[0] > 0 else power_in
            left = _RAIL if first and rails else None if first else _continued(arriving)
            right = _RAIL if last and rails else None if last else _continued(row.out)
            out_rows.append(_with_edges(row, left, right))
            lines += len(row.lines)
            if max_lines is not None and lines >= max_lines:
                break
        return _stacked(out_rows)


def _branch_sizes(elements: list[Element]) -> dict[int, tuple[int, int]]:
    """id(branch) -> (levels of branches it holds, itself included;
    instructions in it), for every branch in ``elements``; no recursion,
    whatever the depth."""
    sizes: dict[int, tuple[int, int]] = {}
    stack: list[tuple[Branch, bool]] = [(el, False) for el in elements if isinstance(el, Branch)]
    while stack:
        branch, children_done = stack.pop()
        if id(branch) in sizes:
            continue
        inner = [el for leg in branch.legs for el in leg if isinstance(el, Branch)]
        if not children_done:
            stack.append((branch, True))
            stack.extend((b, False) for b in inner if id(b) not in sizes)
            continue
        levels = 1 + max((sizes[id(b)][0] for b in inner), default=0)
        count = sum(len(leg) for leg in branch.legs) - len(inner) + sum(sizes[id(b)][1] for b in inner)
        sizes[id(branch)] = (levels, count)
    return sizes


def _rows_width(widths: list[int], width: int, rail: int) -> int:
    """The width of :meth:`_Layout.rows` for elements this wide."""
    widest = width
    for k, (indices, last) in enumerate(_packed(widths.__getitem__, len(widths), width, rail)):
        left_w = rail if k == 0 else len(CONTINUED)
        right_w = rail if last else len(CONTINUED)
        widest = max(widest, left_w + right_w + sum(widths[i] for i in indices))
    return widest


def _fits(widths: Iterable[int], limit: int) -> bool:
    """Whether the widths add up to at most ``limit`` (looked at only until
    they do not)."""
    total = 0
    for w in widths:
        total += w
        if total > limit:
            return False
    return True


_RAIL = ("|", "|", None)


def _continued(on: bool) -> tuple[str, str, Style | None]:
    return (CONTINUED, " " * len(CONTINUED), _power_style(on))


def _packed(width_of: Callable[[int], int], n: int, width: int, rail: int) -> Iterable[tuple[list[int], bool]]:
    """The indices of the elements on each row, and whether it is the last
    row: as many as fit, leaving room for the ``>>`` markers; the last row
    ends at the rail instead. Widths are asked for in order, and only one
    row's worth beyond the rows taken."""
    row: list[int] = []
    used = 0
    first = True
    i = 0
    ahead, ahead_sum = 0, 0  # the widths of elements i..ahead-1 add up to ahead_sum
    while i < n:
        left = rail if first else len(CONTINUED)
        limit = width - left - rail - used
        while ahead < n and ahead_sum <= limit:
            ahead_sum += width_of(ahead)
            ahead += 1
        if ahead == n and ahead_sum <= limit:  # the rest fits on this row: the last
            row.extend(range(i, n))
            break
        w = width_of(i)
        if not row or used + w <= width - left - len(CONTINUED):
            row.append(i)
            used += w
            if ahead > i:
                ahead_sum -= w
            else:
                ahead = i + 1
            i += 1
        else:
            yield row, False
            row, used, first = [], 0, False
    yield row, True


def _outputs_start(elements: list[Element], ctx: _Context) -> int:
    split = len(elements)
    while split > 0 and ctx.is_output(elements[split - 1]):
        split -= 1
    return split


# -- renderables ------------------------------------------------------------------------------


def _segments(line: Line) -> Iterable[Segment]:
    for text, style in _runs(line):
        if text:
            yield Segment(text, style)


def _paragraphs(comment: str) -> list[str]:
    """The comment's paragraphs (blank lines separate them), each line
    break inside one a space: the view wraps to its own width."""
    paragraphs, current = [], []
    for line in comment.split("\n"):
        if line.strip():
            current.append(line.strip())
        elif current:
            paragraphs.append(" ".join(current))
            current = []
    if current:
        paragraphs.append(" ".join(current))
    return paragraphs


def _clipped(text: str, limit: int) -> str:
    """The start of ``text`` (about ``limit`` characters, cut between words):
    wrapped, it gives the same first lines as the whole text as long as
    ``limit`` is two lines more than they hold."""
    if len(text) <= limit:
        return text
    cut = text.rfind(" ", 0, limit)
    return text[:cut if cut > 0 else limit]


def _wrapped(console: Console, text: str, width: int, indent: int, style: Style) -> Iterable[list[Segment]]:
    """``text`` wrapped to ``width``, indented: one list of segments a line."""
    for line in Text(text, style=style).wrap(console, max(10, width - indent)):
        line.rstrip()
        yield [Segment(" " * indent), *line.render(console)]


class RungView:
    """One rung, drawn with the data table's current values.

    ``number`` is the rung's number in its file (shown in the header);
    ``power`` a precomputed :func:`power.rung_power` (computed at each
    render when None); ``symbols`` the program's symbols (name ->
    SymbolDecl, Address or address text); ``selected`` marks the rung
    ``>``, ``breakpoint`` ``*``; ``forced`` the forced addresses (canonical
    text, e.g. ``{"I:0/0"}``), marked ``F``; ``tli_status`` shows the
    CONTROL status line of plug-in module instructions (COMSCAN...);
    ``instructions`` the app's instruction set (``app.instructions``), for
    module instructions' operand names; ``max_lines``: draw only the top
    of the rung, that many lines (a long rung is then laid out only as far
    as it is drawn)."""

    def __init__(self, rung: Rung, number: int, table: DataTable, power: Power | None = None,
                 symbols: Mapping[str, object] | None = None, selected: bool = False, breakpoint: bool = False,
                 forced=frozenset(), tli_status: bool = True, instructions: InstructionSet | None = None,
                 max_lines: int | None = None) -> None:
        self.rung = rung
        self.number = number
        self.table = table
        self.power = power
        self.names = symbols if isinstance(symbols, _SymbolNames) else _SymbolNames(symbols)
        self.selected = selected
        self.breakpoint = breakpoint
        self.forced = forced
        self.tli_status = tli_status
        self.instructions = instructions or BUILTIN
        self.max_lines = max_lines

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        lines = self._lines(console, max(options.max_width, 20))
        if self.max_lines is not None:
            lines = itertools.islice(lines, max(self.max_lines, 0))
        for line in lines:
            yield from line
            yield Segment.line()

    def _lines(self, console: Console, width: int) -> Iterable[list[Segment]]:
        power = self.power if self.power is not None else rung_power(self.rung, self.table)
        ctx = _Context(self.table, power, self.names, self.forced, self.instructions, self.tli_status)
        yield [Segment(">" if self.selected else " ", SELECTED if self.selected else None),
               Segment("*" if self.breakpoint else " ", BREAKPOINT),
               Segment(f" Rung {self.number}", SELECTED if self.selected else HEADER)]
        used = 1
        for paragraph in _paragraphs(self.rung.comment or ""):
            if self.max_lines is not None:  # wrap no more of a long comment than is drawn
                if used >= self.max_lines:
                    return
                paragraph = _clipped(paragraph, (self.max_lines - used + 2) * width)
            for line in _wrapped(console, paragraph, width, COMMENT_INDENT, COMMENT):
                yield line
                used += 1
        for fault in dict.fromkeys(power.faults()):
            for line in _wrapped(console, f"! {fault}", width, COMMENT_INDENT, FAULT):
                yield line
                used += 1
        if self.max_lines is not None and used >= self.max_lines:
            return
        rest = None if self.max_lines is None else self.max_lines - used
        for line in _Layout(ctx, self.rung.elements).rung(width, rest).lines:
            yield list(_segments(line))


class ProgramFileView:
    """Consecutive rungs of a program file from rung ``first``, as many as
    fit in ``height`` lines (all of them when None; a first rung taller than
    ``height`` is cut to it; the lines left under the last whole rung show
    the top of the next one). After rendering, ``drawn`` is how many rungs
    were drawn and ``last_drawn`` the number of the last one (None if none).

    ``selected`` is the selected rung's number; ``breakpoints`` holds rung
    numbers or (file, rung) pairs; the rest as for :class:`RungView`."""

    def __init__(self, pfile: ProgramFile, table: DataTable, symbols: Mapping[str, object] | None = None,
                 first: int = 0, selected: int | None = None, breakpoints=frozenset(), forced=frozenset(),
                 height: int | None = None, tli_status: bool = True,
                 instructions: InstructionSet | None = None,
                 power_of: Callable[[Rung, DataTable], Power] = rung_power) -> None:
        self.pfile = pfile
        self.table = table
        self.names = symbols if isinstance(symbols, _SymbolNames) else _SymbolNames(symbols)
        self.first = first
        self.selected = selected
        self.breakpoints = breakpoints
        self.forced = forced
        self.height = height
        self.tli_status = tli_status
        self.instructions = instructions
        self.power_of = power_of
        self.drawn = 0
        self.last_drawn: int | None = None

    def rung_view(self, number: int, max_lines: int | None = None) -> RungView:
        rung = self.pfile.rungs[number]
        marked = number in self.breakpoints or (self.pfile.number, number) in self.breakpoints
        return RungView(rung, number, self.table, power=self.power_of(rung, self.table), symbols=self.names,
                        selected=number == self.selected, breakpoint=marked, forced=self.forced,
                        tli_status=self.tli_status, instructions=self.instructions, max_lines=max_lines)

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        self.drawn, self.last_drawn = 0, None
        height = self.height
        used = 0
        unbounded = options.update(height=None)
        if not self.pfile.rungs:
            yield Segment("   (no rungs)", COMMENT)
            yield Segment.line()
            return
        for number in range(max(0, self.first), len(self.pfile.rungs)):
            # one line more than is left: a rung that gets it does not fit
            room = None if height is None else height - used + 1
            lines = console.render_lines(self.rung_view(number, room), unbounded, pad=False)
            if height is not None and used + len(lines) > height:
                if self.drawn:
                    # fill the rest with the top of the next rung (not counted
                    # as drawn: scrolling brings it fully into view)
                    for line in lines[:height - used]:
                        yield from line
                        yield Segment.line()
                    break
                lines = lines[:height]
            for line in lines:
                yield from line
                yield Segment.line()
            used += len(lines)
            self.drawn += 1
            self.last_drawn = number
            if height is not None and used >= height:
                break

    def rungs_that_fit(self, width: int, height: int | None = None) -> int:
        """How many rungs from ``first`` a render at ``width`` and ``height``
        (default: this view's) would draw; this view is left as it was."""
        probe = copy.copy(self)
        if height is not None:
            probe.height = height
        Console(width=width, color_system=None, file=io.StringIO()).render_lines(probe, pad=False)
        return probe.drawn
