"""Run-time address resolution for indirect and indexed addresses: the
general resolver (any shape, through ``DataTable.resolve``) and the fast
paths the compiler binds for the common shapes. A resolver returns
``(array, index, mask)``; an address outside its file is a major fault
(``address_fault``: 20, or 24 for a file number naming no file).
"""

from __future__ import annotations

from ..datatable import Address, DataTable, data_bit_mask, item_bit_mask
from ..datatable.errors import AddressRangeError, DataTableError
from . import status as S
from .semantics import MajorFault


def address_fault(addr: Address, error: AddressRangeError) -> MajorFault:
    code = S.FAULT_INDIRECT_FILE if "no data file" in str(error) else S.FAULT_INDIRECT_RANGE
    return MajorFault(code, str(error))


def resolver(table: DataTable, addr: Address):
    resolve = table.resolve

    def locate():
        try:
            f, index, bit = resolve(addr)
        except AddressRangeError as e:
            raise address_fault(addr, e) from None
        return f.data, index, (data_bit_mask(f.data, bit) if bit is not None else None)

    return _fast_resolver(table, addr, locate) or locate


def _fast_resolver(table: DataTable, addr: Address, slow):
    """The common indirect shapes, ``N12:[N13:3]`` and ``O:[N13:13]/[N13:14]``
    (a fixed file, element and bit numbers from direct words), without the
    general resolver: the pointer words' arrays are bound once (arrays grow
    in place), and only an out-of-range number takes ``slow``, which faults
    with the full message. None when ``addr`` has another shape."""
    if addr.indexed or not isinstance(addr.element, Address):
        return None
    try:
        ed, ei = table.word_ref(addr.element)
        bd, bi = table.word_ref(addr.bit) if isinstance(addr.bit, Address) else (None, 0)
        if isinstance(addr.file, Address):
            fd, fi = table.word_ref(addr.file)
            return _file_indirect(table, addr, slow, fd, fi, ed, ei) if bd is None else None
        f = table.file(addr.file)
    except (DataTableError, AddressRangeError):
        return None
    if f.ftype is not addr.ftype:
        return None
    data = f.data
    wpe = f.ftype.words_per_element
    offset = f.ftype.members_by_name[addr.member].offset if addr.member is not None else 0
    # The masks of the element's bits, by the item's width (16 for a
    # word or a member, 32 for an L element, 8 and 64 for SI and LI).
    masks = tuple(data_bit_mask(data, b) for b in range(16 if addr.member else f.ftype.element_bits))
    top = len(masks)
    if bd is None:
        mask = data_bit_mask(data, addr.bit) if addr.bit is not None else None

        def locate():
            e = ed[ei]
            if e < 0 or (e + 1) * wpe > len(data):
                return slow()
            return data, e * wpe + offset, mask
    else:
        def locate():
            e = ed[ei]
            b = bd[bi]
            if e < 0 or (e + 1) * wpe > len(data) or not 0 <= b < top:
                return slow()
            return data, e * wpe + offset, masks[b]
    return locate


def _file_indirect(table: DataTable, addr: Address, slow, fd, fi, ed, ei):
    """``N[N13:15]:[N13:11]``: the file number from a word too; the file is
    looked up each time (files are created, never replaced), the rest as
    the fast path above; a bit number from a word takes the general path."""
    files = table._files
    ftype = addr.ftype
    wpe = ftype.words_per_element
    offset = ftype.members_by_name[addr.member].offset if addr.member is not None else 0
    mask = item_bit_mask(addr.bit, ftype.item_bits // 8) if addr.bit is not None else None

    def locate():
        f = files.get(fd[fi])
        e = ed[ei]
        if f is None or f.ftype is not ftype or e < 0 or (e + 1) * wpe > len(f.data):
            return slow()
        return f.data, e * wpe + offset, mask
    return locate
