"""Logix's file instructions on tags (COP, CPS, FLL), bound objects run by
both executors. The Logix translator (logix/copy.py) writes one per atomic
leaf of what is copied: an array of one atomic type is one leaf, an array of
a user-defined type one leaf per member (tags.py lays each member of an
array of structures out as a file of its own).

Rules (1756-RM003, Logix 5000 Controllers General Instructions, "Copy File
(COP), Synchronous Copy File (CPS)" and "File Fill (FLL)"):

- The length counts elements of the destination; the bytes copied are the
  length times the destination element's size ("Byte Count = Length *
  number of bytes in the Destination data type").
- A length past the end of the destination array stops at the array's end;
  no fault ("If the Length is too big, the instruction stops at the end of
  the array. No major fault is generated").
- COP and CPS copy bytes: between two atomic types the destination gets the
  source's bytes, not converted values (Logix's byte layout: little-endian
  SINT, INT, DINT, LINT, IEEE REAL).
- FLL converts the source into the destination's type (RM003, "Data
  conversions": a REAL into an integer rounds, half to even); a string
  source fills strings with itself, 0 clears them (and structures).
- A source that ends before the length does: Logix copies "unpredictable
  data" for the rest; softplc_lite copies what the source holds and leaves
  the rest of the destination as it is (a softplc choice).
- A length of zero or less copies nothing (a softplc choice).
- A string copied into a string type of fewer characters is cut to fit,
  LEN with it (a softplc choice: Logix copies the destination's bytes and
  leaves the source's LEN, larger than the destination's DATA).
- CPS differs from COP in that nothing may change the data while it copies;
  nothing does during a softplc_lite scan, so CPS is COP.
"""

from __future__ import annotations

from array import array

from ...datatable.table import read_string, store_text
from ..ast import AddressRef
from ..bound import BoundInstruction
from ..specs import InstructionSpec, K, OperandSpec


def _spec(mnemonic: str, title: str, *names: str) -> InstructionSpec:
    return InstructionSpec(mnemonic, title, tuple(OperandSpec(n, K.ANY) for n in names), True)


SPECS = [
    InstructionSpec("LCOP", "Logix copy file", tuple(OperandSpec(n, K.ANY) for n in (
        "source", "dest", "length", "items per element", "dest end", "source end", "capacity")), True, optional=1),
    _spec("LFLL", "Logix file fill", "source", "dest", "length", "items per element", "dest end"),
]
LOGIX_NAMES = {"LCOP": "COP", "LFLL": "FLL"}


def _is_characters(operand) -> bool:
    """A string's DATA[k] (the member DATAk): its end operand counts the
    characters left from k, not an item (logix/copy.py)."""
    member = operand.address.member
    return member is not None and member.startswith("DATA")


def _byte_unit(value: int) -> int:
    """A SINT stored as a string's character: its byte as the code unit
    (0..255), as Logix's DATA holds bytes."""
    return value & 0xFF


def _signed_byte(unit: int) -> int:
    """A string's character read as a SINT: the low byte, signed."""
    unit &= 0xFF
    return unit - 256 if unit > 127 else unit


def _copy_characters(instr, access):
    """COP/CPS with a string's DATA and a SINT array (or another DATA): one
    byte each, a character's low byte (signed) into a SINT, a SINT's byte
    into a character (a softplc choice: an ST element holds 16-bit units)."""
    src, dest, length, per, dest_end, src_end = instr.operands[:6]
    get_src, get_dest, get_length = access.location(src), access.location(dest), access.value(length)
    src_chars, dest_chars = _is_characters(src), _is_characters(dest)
    dest_end, src_end = dest_end.value, src_end.value

    def run(c: bool) -> bool:
        if c:
            dd, di, _ = get_dest()
            sd, si, _ = get_src()
            n = min(int(get_length()), dest_end if dest_chars else dest_end - di,
                    src_end if src_chars else src_end - si)
            if n <= 0:
                return c
            values = sd[si:si + n].tolist()
            if src_chars and not dest_chars:
                values = [_signed_byte(u) for u in values]
            elif dest_chars:
                values = [_byte_unit(v) for v in values]
            dd[di:di + n] = array(dd.typecode, values)
        return c
    return run


def _copy(instr, access):
    if _is_characters(instr.operands[0]) or _is_characters(instr.operands[1]):
        return _copy_characters(instr, access)
    if len(instr.operands) == 7:
        return _copy_strings(instr, access)
    src, dest, length, per, dest_end, src_end = instr.operands
    get_src, get_dest, get_length = access.location(src), access.location(dest), access.value(length)
    per, dest_end, src_end = per.value, dest_end.value, src_end.value
    wpe_d = dest.address.ftype.words_per_element
    wpe_s = src.address.ftype.words_per_element

    def run(c: bool) -> bool:
        if c:
            n = int(get_length()) * per
            if n <= 0:
                return c
            dd, di, _ = get_dest()
            sd, si, _ = get_src()
            n = min(n, dest_end - di // wpe_d)
            have = src_end - si // wpe_s
            if n <= 0 or have <= 0:
                return c
            if sd.typecode == dd.typecode:
                n = min(n, have) * wpe_d
                dd[di:di + n] = sd[si:si + n]
                return c
            raw = sd[si:si + have * wpe_s].tobytes()[:n * wpe_d * dd.itemsize]
            n = len(raw) // dd.itemsize
            dd[di:di + n] = array(dd.typecode, raw[:n * dd.itemsize])
        return c
    return run


def _copy_strings(instr, access):
    """Strings into strings of a smaller type (the 7th operand, its
    characters): each cut to fit, LEN with it (a softplc choice: Logix
    copies the destination's bytes, leaving a LEN larger than its DATA)."""
    src, dest, length, per, dest_end, src_end, capacity = instr.operands
    get_src, get_dest, get_length = access.location(src), access.location(dest), access.value(length)
    per, dest_end, src_end, cap = per.value, dest_end.value, src_end.value, capacity.value
    wpe = dest.address.ftype.words_per_element
    src_size, dest_size = src.address.ftype.chars, dest.address.ftype.chars

    def run(c: bool) -> bool:
        if c:
            dd, di, _ = get_dest()
            sd, si, _ = get_src()
            swpe = src_size + 1
            n = min(int(get_length()) * per, dest_end - di // wpe, src_end - si // swpe)
            texts = [read_string(sd, si + k * swpe, src_size) for k in range(max(n, 0))]
            for k, text in enumerate(texts):
                store_text(dd, di + k * wpe, text[:cap], dest_size)
                dd[di + k * wpe] = min(len(text), cap)
        return c
    return run


def _fill(instr, access):
    source, dest, length, per, dest_end = instr.operands
    if _is_characters(dest):
        return _fill_characters(instr, access)
    if isinstance(source, AddressRef) and source.address.ftype.is_string:
        return _fill_strings(instr, access)
    value, get_dest, get_length = access.value(source), access.location(dest), access.value(length)
    per, dest_end = per.value, dest_end.value
    machine = access.machine
    wpe = dest.address.ftype.words_per_element  # an ST element's words, cleared by a FLL of 0

    def run(c: bool) -> bool:
        if c:
            dd, di, _ = get_dest()
            n = min(int(get_length()) * per, dest_end - di // wpe)
            if n > 0:
                machine.fll(value(), dd, di, n * wpe)
        return c
    return run


def _fill_characters(instr, access):
    """FLL into a string's DATA: the value as a SINT's byte into each character."""
    source, dest, length, _, dest_end = instr.operands
    value, get_dest, get_length = access.value(source), access.location(dest), access.value(length)
    left = dest_end.value

    def run(c: bool) -> bool:
        if c:
            dd, di, _ = get_dest()
            n = min(int(get_length()), left)
            if n > 0:
                dd[di:di + n] = array("h", [_byte_unit(int(value()))]) * n
        return c
    return run


def _fill_strings(instr, access):
    """A string source: each destination string gets it whole."""
    source, dest, length, per, dest_end = instr.operands
    get_src, get_dest, get_length = access.location(source), access.location(dest), access.value(length)
    wpe, per, dest_end = dest.address.ftype.words_per_element, per.value, dest_end.value
    src_size, dest_size = source.address.ftype.chars, dest.address.ftype.chars
    same, cap = src_size == dest_size, dest_size

    def run(c: bool) -> bool:
        if c:
            dd, di, _ = get_dest()
            n = min(int(get_length()) * per, dest_end - di // wpe)
            if n > 0:
                sd, si, _ = get_src()
                if same:
                    dd[di:di + n * wpe] = sd[si:si + wpe] * n
                else:  # between ST and SL: the text, cut to the destination's type
                    text = read_string(sd, si, src_size)[:cap]
                    for k in range(n):
                        store_text(dd, di + k * wpe, text, dest_size)
        return c
    return run


INSTRUCTIONS = [BoundInstruction(SPECS[0], _copy), BoundInstruction(SPECS[1], _fill)]
