"""ENIPS.XML and OPCUAS.XML for a Logix app (docs/enips.md, "Logix tags";
docs/opcuas.md, "Logix tags"): the export's
tags made writable by ``<Writable tag="..."/>``, and the storage of every
tag or member the export makes Read Only or None kept closed to clients
whatever ``<Writable>`` opens (1756-PM004, "Data access control": external
applications cannot change such a value).

The result is item ranges per data table file, which ENIPS's image slots
(protocol.build_slots) and OPCUAS's address space (opcuas/space.py) take: a
client's write is checked against them in the server process and again by
the scan.
"""

from __future__ import annotations

from ..errors import ModuleError, ModuleErrors
from ...cip.status import PRIVILEGE_VIOLATION
from .config import ServerConfig
from .logixtags import LogixCatalogue, StructTarget, _segments
from .logixview import LogixTag, LogixView
from .tagnames import ST_ITEMS, PathError

Ranges = dict[str, list[tuple[int, int]]]  # file name -> [first item, end)


def tag_ranges(view: LogixView, config: ServerConfig) -> tuple[Ranges, list[ModuleError]]:
    """The items each ``<Writable tag>`` opens, and a problem for each that
    names no tag, or a tag or member the export makes Read Only or None."""
    cat = LogixCatalogue(None, view)
    ranges: Ranges = {}
    problems: list[ModuleError] = []
    for w in config.writable:
        if w.tag is None:
            continue
        text = w.tag
        where = (config.path, w.line, w.column)
        segments = _segments(text)
        try:
            if not segments:
                raise PathError(0, "expected a tag path")
            target = cat.target(segments)
        except PathError as e:
            why = ("its External Access is None in the export" if e.status == PRIVILEGE_VIOLATION else e.reason)
            problems.append(ModuleError(f"<Writable tag={text!r}>: {why}", *where))
            continue
        access = target.access
        if access != "rw":
            problems.append(ModuleError(f"<Writable tag={text!r}>: the export makes it Read Only (External Access): "
                                        "clients may read it, not write it", *where))
            continue
        one = text.rstrip().endswith("]")  # an element named: that element only
        for file, lo, hi in _spans(cat, target, one):
            ranges.setdefault(file, []).append((lo, hi))
    return ranges, problems


def export_ranges(view: LogixView, config: ServerConfig) -> tuple[Ranges, Ranges]:
    """(what the config's <Writable tag>s open, what the export keeps
    closed), as ENIPS and OPCUAS both hold an export's tags to them;
    ModuleErrors listing every path the export does not open."""
    opened, problems = tag_ranges(view, config)
    if problems:
        raise ModuleErrors(problems)
    return opened, closed_ranges(view)


def _spans(cat: LogixCatalogue, target, one: bool):
    if isinstance(target, StructTarget):
        count = 1 if one else target.units
        for f in cat.fields_of(target.template):
            if f.access != "rw":
                continue
            leaf = target.tag.leaves[target.path + f.path]
            first = leaf.first + target.flat * f.per
            n = count * f.per
            if f.kind == "string":
                yield leaf.file, first * ST_ITEMS, (first + n) * ST_ITEMS
            elif f.kind == "bool":  # a B file's ranges count bits
                yield leaf.file, first, first + n
            else:
                yield leaf.file, first, first + n
        return
    t = target.target
    if t.kind == "B":  # a BOOL tag, or an element of a BOOL array: its bit alone (a B file's ranges count bits)
        yield t.file, t.item * 16 + t.bit, t.item * 16 + t.bit + 1
        return
    units = 1 if one or t.bit is not None else t.units
    yield t.file, t.item, t.item + units * t.items_per_unit


def closed_ranges(view: LogixView) -> Ranges:
    """The storage of every tag and member the export makes Read Only or
    None: no ``<Writable>`` opens it."""
    cat = LogixCatalogue(None, view)
    closed: Ranges = {}
    for tags in view.tags.values():
        for tag in tags:
            for file, lo, hi in _closed_of(cat, tag):
                closed.setdefault(file, []).append((lo, hi))
    return closed


def _closed_of(cat: LogixCatalogue, tag: LogixTag):
    if tag.kind == "alias":
        return
    whole = tag.access != "rw"
    count = 1
    for d in tag.dims:
        count *= d
    if tag.kind == "struct":
        for f in cat.fields_of(cat.view.templates[tag.template]):
            if whole or f.access != "rw":
                leaf = tag.leaves[f.path]
                yield from _leaf_items(leaf, f.kind)
        return
    if whole:
        for leaf in tag.leaves.values():
            yield from _leaf_items(leaf, tag.kind)


def _leaf_items(leaf, kind: str):
    if kind == "string":
        yield leaf.file, leaf.first * ST_ITEMS, (leaf.first + leaf.count) * ST_ITEMS
    else:  # items; bits in a B file, whose ranges count bits as the leaf's first and count do
        yield leaf.file, leaf.first, leaf.first + leaf.count
