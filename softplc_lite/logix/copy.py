"""COP, CPS and FLL on tags: the Logix rules (ladder/instr/logix_data.py)
applied to the tag layout (tags.py).

What is copied is a run of Logix elements (the destination's: RM003 counts
the length in destination elements). Each atomic leaf of the element type
is a file (an array leaf) or an item of a shared file (a scalar), so a copy
of one array of an atomic type is one LCOP on its file, and a copy of an
array of a user-defined type (or a TIMER, COUNTER, CONTROL) is one LCOP per
member leaf, each covering the same elements: that is Logix's byte copy
between two tags of the same type, member for member. What Logix copies
byte-wise between different structures (or a string and a SINT array) has
no counterpart in this layout: such a rung is not run, with a warning that
says why (a softplc choice).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..datatable import Address
from ..ladder.ast import AddressRef, Const, Instruction
from . import operands
from .expr import number
from .operands import Operands, Skip
from .tags import PathError, Resolved


@dataclass
class Run:
    """A run of Logix elements of one tag from a resolved path: its type and
    each atomic leaf (by member path below the element) as (first item
    Address, items per element, end item of the leaf)."""

    type: object
    leaves: dict[tuple[str, ...], tuple[Address, int, int]]


def element_run(r: Resolved, pos, ctx) -> Run:
    """The elements starting at ``r`` (an element, or a whole array from
    its first element)."""
    from . import rungs

    d = r.declared
    if d is None:
        raise PathError(f"{r.text}: expected a tag")
    if r.address is not None and r.address.bit is not None or r.type.name == "BOOL":
        raise Skip(f"{r.text.strip()} is a BOOL: COP, CPS and FLL take SINT, INT, DINT, LINT, REAL, strings "
                   f"and structures (1756-RM003)")
    count = 1
    for n in d.dims:
        count *= n
    t = d.type
    for key in r.path:
        m = t.member(key)
        count *= max(m.dim, 1)
        t = m.type
    if r.address is not None and is_characters(r.address):  # Str.DATA[k]: the characters k.. of its type
        return Run(r.type, {(): (r.address, 1, t.chars - int(r.address.member[4:]))})
    if r.address is not None:  # one atomic value or string: its address has its index (tags.py)
        leaf = d.leaves[r.path]
        return Run(r.type, {(): (r.address, 1, leaf.first + leaf.count)})
    whole = 1
    for n in r.dims:
        whole *= n
    base = r.flat * whole
    terms = [(text, size, stride * whole) for text, size, stride in r.terms]
    leaves = {}
    for path, leaf in d.leaves.items():
        if path[:len(r.path)] != r.path:
            continue
        if leaf.letter == "B":
            raise Skip(f"{r.text.strip()} holds a BOOL array; its bits are not copied by softplc_lite")
        per = leaf.count // count
        first = leaf.first + base * per
        if terms:
            scaled = [(text, size, stride * per) for text, size, stride in terms]
            element = rungs._indexer(pos, ctx)(scaled, first, leaf.count)
        else:
            element = first
        leaves[path[len(r.path):]] = (Address(leaf.letter, leaf.file, element), per, leaf.first + leaf.count)
    return Run(r.type, leaves)


def translate(el, pos, rung, ctx) -> Instruction | None:
    """COP/CPS(source, dest, length) and FLL(source, dest, length)."""
    return operands.translate(el, pos, rung, ctx, _build)


def _build(ops: Operands) -> list[Instruction]:
    ops.count(3)
    dest = element_run(ops.resolve(1), ops.where(1), ops.ctx)
    length = ops.value(2)
    if ops.el.mnemonic == "FLL":
        return _fill(ops, dest, length)
    return copy_run(element_run(ops.resolve(0), ops.where(0), ops.ctx), ops.where(0), dest, length, ops.pos)


def is_characters(address: Address) -> bool:
    """``Str.DATA[k]`` (the word member DATAk of a string element)."""
    return address.member is not None and address.member.startswith("DATA")


def _characters(source: Run, dest: Run) -> None:
    """A copy or fill with a string's DATA: its characters as Logix's SINTs,
    with a SINT array or another string's DATA; anything else is a byte copy
    this layout does not keep (a softplc choice)."""
    for run, other in ((source, dest), (dest, source)):
        address = next(iter(run.leaves.values()))[0] if run.leaves else None
        if address is not None and is_characters(address) and other.type.name != "SINT":
            raise Skip(f"a copy between a string's DATA and {other.type.name} copies Logix's bytes, which "
                       f"softplc_lite's tag layout does not keep (a SINT array's are)")


def _kind(t) -> str:
    return "string" if t.kind == "string" else ("atomic" if t.kind == "atomic" else t.name)


def copy_run(source: Run, where, dest: Run, length, pos) -> list[Instruction]:
    """An LCOP per leaf of ``dest`` from the same leaf of ``source``."""
    _characters(source, dest)
    sk, dk = _kind(source.type), _kind(dest.type)
    if sk != dk:
        raise Skip(f"a copy from a {source.type.name} into a {dest.type.name} copies Logix's byte layout, which "
                   f"softplc_lite's tag layout does not keep")
    out = []
    for path, (d_address, per, d_end) in dest.leaves.items():
        s_address, s_per, s_end = source.leaves[path]
        operands = [AddressRef(s_address, where), AddressRef(d_address, pos), length, Const(per, pos),
                    Const(d_end, pos), Const(s_end, pos)]
        chars = _chars(dest.type, path), _chars(source.type, path)
        if chars[0] is not None and chars[1] is not None and (
                chars[0] < chars[1] or s_address.type_letter != d_address.type_letter):
            # a string into a smaller string type, or between ST and SL elements: one by one, cut to fit
            operands.append(Const(chars[0], pos))
        out.append(Instruction("LCOP", operands, pos))
    return out


def _chars(t, path: tuple[str, ...]) -> int | None:
    """The characters of the string type at ``path`` below type ``t``, or
    None (not a string)."""
    for key in path:
        m = t.member(key)
        if m is None:
            return None
        t = m.type
    return t.chars if t.kind == "string" else None


def _fill(ops: Operands, dest: Run, length) -> list[Instruction]:
    pos = ops.pos
    string_source = False
    if number(ops.text(0)) is None:
        r = ops.resolve(0)
        string_source = r.type.kind == "string" and not r.dims
        if r.address is None or r.type.kind not in ("atomic", "string") or r.address.bit is not None:
            raise Skip(f"a FLL source of type {r.type.name}{' array' if r.dims else ''} is not filled by "
                       f"softplc_lite (an atomic value or a string is)")
        source = AddressRef(r.address, ops.where(0))
    else:
        source = ops.value(0)
    zero = isinstance(source, Const) and source.value == 0
    if string_source != (dest.type.kind == "string") and not zero:
        raise Skip(f"a FLL of a {'string' if string_source else 'number'} into {dest.type.name} fills Logix's "
                   f"bytes, which softplc_lite's tag layout does not keep")
    if dest.type.kind not in ("atomic", "string") and not zero:
        raise Skip(f"a FLL of a number into {dest.type.name} structures fills Logix's bytes, which softplc_lite's "
                   f"tag layout does not keep (a FLL of 0 clears them)")
    return [Instruction("LFLL", [source, AddressRef(d_address, pos), length, Const(per, pos), Const(d_end, pos)], pos)
            for d_address, per, d_end in dest.leaves.values()]
