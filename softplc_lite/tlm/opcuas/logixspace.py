"""A Studio 5000 export's tags in the OPC UA address space (docs/opcuas.md,
"Logix tags"): each tag by its path, as Logix names it, built in the
runtime from the export's tag directory (logix/tags.py) into space.py's
Space. A structure (a user-defined type, TIMER, COUNTER, CONTROL ...) is an
object with its members, an array an object with its elements, an atomic
value a variable of its OPC UA type: BOOL Boolean, SINT SByte, INT Int16,
DINT Int32, LINT Int64, REAL Float, a string String. A BOOL member kept in a
bit of a hidden host is a variable over that bit; hidden members are not
shown. A tag's External Access None keeps it out; program tags are under an
object ``Program:NAME``. A variable is writable where a ``<Writable tag>``
names it (``Space.names_opened``) and the export's External Access leaves
its storage Read/Write (``Space.may_write``, the ranges ENIPS's checks
give: enips/logixconfig.py); every other is read-only.
"""

from __future__ import annotations

from itertools import product

from .space import APP, Obj, Space, Var

KIND_OF_LETTER = {"N": "Int16", "L": "Int32", "F": "Float", "SI": "SByte", "LI": "Int64"}


def add_tags(space: Space, by_name: dict, directory) -> None:
    """Every tag of ``directory`` under the app's object (a program's under
    its own); ``by_name``: the image's slots by file name."""
    for scope, tags in directory.scopes.items():
        parent = APP
        if scope is not None:
            parent = f"Program:{scope}"
            space.objects.append(Obj(parent, parent, APP, f"The program {scope}'s tags"))
        for d in sorted(tags.values(), key=lambda d: d.tag.name.upper()):
            access = (d.tag.external_access or "Read/Write").strip().upper()
            if d.type is None or d.opaque or d.tag.alias_for or access == "NONE":
                if d.opaque:
                    space.skipped.append(f"tag {d.tag.name}: {d.opaque}")
                continue
            name = d.tag.name if scope is None else f"{parent}.{d.tag.name}"
            _value(space, by_name, d, d.type, (), list(d.dims), 0, name, d.tag.name, parent,
                   d.tag.description or "")


def _value(space, by_name, d, t, path, dims, flat, node, shown, parent, description) -> None:
    """``t`` at ``path`` of tag ``d``, ``dims`` the array dimensions still to
    open, ``flat`` the index reached so far (row-major over every dimension
    on the way, as the directory lays the leaves out)."""
    if dims:
        space.objects.append(Obj(node, shown, parent, description))
        for index in product(*(range(n) for n in dims)):
            k = 0
            for i, n in zip(index, dims):
                k = k * n + i
            text = f"{node}[{','.join(map(str, index))}]"
            _value(space, by_name, d, t, path, [], flat * _count(dims) + k, text,
                   f"{shown}[{','.join(map(str, index))}]", node, "")
        return
    if t.kind == "struct":
        space.objects.append(Obj(node, shown, parent, description))
        for m in t.members:
            if m.hidden:
                continue
            if m.host is not None:  # a BOOL in a bit of its host member
                leaf = d.leaves.get(path + (m.host.upper(),))
                if leaf is not None:
                    _atomic(space, by_name, leaf, flat, f"{node}.{m.name}", m.name, node, m.description or "",
                            bit=m.bit)
                continue
            _value(space, by_name, d, m.type, path + (m.name.upper(),), [m.dim] if m.dim else [], flat,
                   f"{node}.{m.name}", m.name, node, m.description or "")
        return
    leaf = d.leaves.get(path)
    if leaf is not None:
        _atomic(space, by_name, leaf, flat, node, shown, parent, description, string=t.kind == "string")


def _atomic(space, by_name, leaf, flat, node, shown, parent, description, bit=None, string=False) -> None:
    found = by_name.get(f"{leaf.letter}{leaf.file}")
    if found is None:
        return
    k, slot, _ = found
    if string:
        item = (leaf.first + flat) * slot.per
        space.variables.append(Var(node, shown, parent, "String", slot.offset + item * slot.itemsize, k,
                                   size=slot.per * 2, description=description, writable=space.may_write(slot, item) and space.names_opened(node)))
        return
    if leaf.letter == "B":  # a BOOL tag: a bit of a B file, whose leaves count bits
        word, b = divmod(leaf.first + flat, 16)
        space.variables.append(Var(node, shown, parent, "Boolean", slot.offset + word * 2, k, bit=b,
                                   description=description, writable=space.may_write(slot, word, b) and space.names_opened(node)))
        return
    item = leaf.first + flat
    offset = slot.offset + item * slot.itemsize
    w = space.may_write(slot, item) and space.names_opened(node)
    if bit is not None:
        space.variables.append(Var(node, shown, parent, "Boolean", offset, k, bit=bit, size=slot.itemsize,
                                   description=description, writable=w))
        return
    kind = KIND_OF_LETTER.get(leaf.letter)
    if kind is not None:
        space.variables.append(Var(node, shown, parent, kind, offset, k, size=slot.itemsize, description=description,
                                   writable=w))


def _count(dims) -> int:
    n = 1
    for x in dims:
        n *= x
    return n
