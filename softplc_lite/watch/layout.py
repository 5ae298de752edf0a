"""Laying a rung out: series side by side or wrapped into rows, branches
stacked between connectors, outputs against the right rail, each element
measured before it is built so that layout takes time linear in the rung's
size (rungs.py shows the result; cells.py draws the pieces).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from rich.style import Style

from ..ladder.ast import (
    Branch,
    Element,
    Instruction,
)
from .cells import (
    CONTINUED, _GLYPHS, Line, _Block, _Context, _bit_cell, _blank, _box, _box_cell, _power_style,
    _side_by_side, _stacked, _wire, _wire_block, _with_edges,
)



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
