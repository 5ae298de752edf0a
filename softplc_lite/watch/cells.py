"""What one rung element looks like in the watch view: a contact or coil
cell, an instruction box with its live operands, wires, and the blocks
(lines of styled runs, all one width) that layout.py composes into rungs.
rungs.py has the picture and the rules; this module draws the pieces.
"""

from __future__ import annotations

import json
from collections.abc import Iterable

from rich.cells import cell_len
from rich.style import Style

from ..datatable import Address, DataTable, ValueKind
from ..datatable.display import format_float, word_shown
from ..ladder.ast import (
    AddressRef,
    Branch,
    Const,
    Element,
    Instruction,
    address_refs,
)
from ..ladder.ast import Text as TextOperand
from ..ladder.instructions import InstructionSet, K
from ..ladder.instr.logix import CD, CU, DN, EN, OV, TT, UN
from ..ladder.instr.logix_string import COMPARISONS
from .naming import SymbolNames
from .power import READ_FAILURES, Power

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
_INFIX = {"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/", "MOD": "MOD", "AND": "AND", "OR": "OR", "XOR": "XOR",
          "LAND": "AND", "LOR": "OR", "LXOR": "XOR"}  # L...: a Logix export's 32-bit forms (ladder/instr/logix_bits.py)
_MOVES = {"MOV", "NEG", "ABS", "SQR", "NOT", "ACI", "AIC", "LNOT"}  # source -> dest
_LIVE_PRESETS = {"TON": (2, 3), "TOF": (2, 3), "RTO": (2, 3), "CTU": (1, 2), "CTD": (1, 2)}  # shown from the table
_STATUS_BITS = {"T": ("EN", "TT", "DN"), "C": ("CU", "CD", "DN", "OV", "UN"), "R": ("EN", "DN", "ER", "EM")}
_STRUCTS = (ValueKind.TIMER, ValueKind.COUNTER, ValueKind.CONTROL)
# A Logix TIMER or COUNTER is three DINTs (CTL, PRE, ACC): its status bits are bits of CTL.
_LOGIX_BITS = {"LTON": ("EN", "TT", "DN"), "LTOF": ("EN", "TT", "DN"), "LRTO": ("EN", "TT", "DN"),
               "LCTU": ("CU", "CD", "DN", "OV", "UN"), "LCTD": ("CU", "CD", "DN", "OV", "UN")}
_LOGIX_MASKS = {"EN": EN, "TT": TT, "DN": DN, "CU": CU, "CD": CD, "OV": OV, "UN": UN}

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


_SymbolNames = SymbolNames  # the names a rung is drawn with: naming.py (a Logix app's are TagPathNames)


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
        return value_run(self.table, address)

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
        return format_float(value)
    if isinstance(value, str):
        text = json.dumps(value)
        return text if len(text) <= STRING_MAX else text[:STRING_MAX - 4] + '..."'
    return str(value)


def value_run(table: DataTable, address: Address) -> Run:
    """An address's value as the watch view shows it, "?" in the fault
    style when it cannot be read."""
    try:
        value = table.read(address)
        # D and A words show as BCD digits / two characters (their radix).
        shown = word_shown(value, address.ftype) if address.kind is ValueKind.WORD else None
        return (shown or _value_text(value), None)
    except READ_FAILURES:
        return ("?", FAULT)


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
        if not (name and ctx.names.replaces_address):
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
    title = ctx.names.mnemonic(ins.mnemonic)
    if ins.mnemonic == "LSCMP":  # a compare of two strings: shown by the compare it is
        title = COMPARISONS[ins.operands[2].value]
    return _box(title, title_style, _box_items(ins, ctx), budget, p_in, p_out)


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
    elif m == "LSCMP" and len(ops) == 3:
        main = [item(0, False), _prefixed(_COMPARE[COMPARISONS[ops[2].value]], item(1, False))]
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
    elif m in _LOGIX_BITS and len(ops) == 3:
        return [[_structure_item(ops[0], ctx)], [_logix_status(m, ops, ctx)]]
    elif m == "LRES" and len(ops) == 1:
        return [[_structure_item(ops[0], ctx)]]
    elif m in ("LCOP", "LFLL") and len(ops) >= 3:  # COP and FLL: their three Logix operands, not the layout's
        main = [item(0, False), _prefixed("->", item(1, False)), _prefixed("length", item(2, False))]
    elif m == "JSR" and ops and isinstance(ops[0], Const) and ctx.names.file_name(ops[0].value):
        main = [[(ctx.names.file_name(ops[0].value), None)], *(item(i) for i in range(1, len(ops)))]
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
    if name_text and ctx.names.replaces_address:
        shown = name_text
    else:
        shown = f"{name_text}({address})" if name_text else str(address)
    if address.kind in _STRUCTS:
        return [(shown, None)]
    line: Line = [(shown + "=", None), ctx.value(address)]
    if str(address) in ctx.forced:
        line.append((" F", FORCED))
    return line


def _expression_items(node, ctx: _Context) -> list[Line]:
    """The expression's text, then each address it reads with its value."""
    names = ctx.names if ctx.names.replaces_address else None
    items: list[Line] = [[(ctx.names.expression(node), None)]]
    seen = set()
    for ref in address_refs(node):
        text = (names and names.name(ref.address)) or str(ref.address)
        if text not in seen:
            seen.add(text)
            items.append([(text + "=", None), ctx.value(ref.address)])
    return items


def _structure_item(op, ctx: _Context) -> Line:
    """A Logix TIMER or COUNTER operand (its CTL DINT) by its tag's name."""
    if not isinstance(op, AddressRef):
        return _operand_item(op, None, None, ctx)
    name = ctx.names.name(op.address)
    if name and name.upper().endswith(".CTL"):
        return [(name[:-4], None)]
    return [(name or str(op.address), None)]


def _logix_status(m: str, ops, ctx: _Context) -> Line:
    """``EN TT . PRE 2000 ACC 170``: a Logix timer's or counter's status
    bits (bits of its CTL) and its PRE and ACC, live from the table."""
    try:
        words = [ctx.table.read(op.address) if isinstance(op, AddressRef) else op.value for op in ops]
    except (*READ_FAILURES, AttributeError):
        return [("?", FAULT)]
    line: Line = []
    for bit in _LOGIX_BITS[m]:
        on = bool(words[0] & _LOGIX_MASKS[bit])
        line += [(bit if on else ".", ENERGIZED if on else None), _blank(1)]
    line.append((f"PRE {words[1]} ACC {words[2]}", None))
    return line


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
