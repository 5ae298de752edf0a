"""A tag's initial value (an export's data, decorated or positional) written
into the data table items its leaves take (tags.py), as a download writes
it. Every value that does not fit its type is a problem at the tag's place.

Positional data (L5K) lists a structure's members in the type's order,
hidden members included and BOOL members left out: their values are the
bits of their host, as Logix stores them (1756-RM084, "Tag data in L5K
format"). An array's elements come in row-major order, flat or nested.
The positional value of a function-block structure (FBD_TIMER ...) is not
read: its layout is not published (types.py).
"""

from __future__ import annotations

import re
from datetime import datetime, timezone

from .model import InitialValue, Problem
from .tags import WORD_BITS, Declared, Leaf
from .types import LogixType, MemberType


class ValueWriter:
    """Collects the items to write, by file: ``items[(letter, file)][item] =
    value``; B files by word."""

    def __init__(self) -> None:
        self.items: dict[tuple[str, int], dict[int, object]] = {}

    def put(self, leaf: Leaf, k: int, value, bit: int | None = None) -> None:
        cells = self.items.setdefault((leaf.letter, leaf.file), {})
        item = leaf.first + k
        if leaf.letter == "B":
            word, b = divmod(item, WORD_BITS)
            mask = 1 << b
            cells[word] = (cells.get(word, 0) & ~mask) | (mask if value else 0)
        elif bit is not None:
            mask = 1 << bit
            cells[item] = (int(cells.get(item, 0)) & ~mask) | (mask if value else 0)
        else:
            cells[item] = value


_DATE_TIME = re.compile(r"(?:L?DT)#(\d{4})-(\d\d)-(\d\d)-(\d\d):(\d\d):(\d\d)(?:\.([\d_]+))?Z$", re.IGNORECASE)


def date_time(text: str) -> int | None:
    """A LINT's date-and-time value (``DT#2022-02-22-06:00:00.000_000Z``, the
    form exports write with the Date/Time radix) as the microseconds since
    1970-01-01 UTC Logix holds (1756-PM020, "LINT ... Date/Time"), or with
    ``LDT#`` (the Date/Time (ns) radix) the nanoseconds; None if the text
    is not one."""
    m = _DATE_TIME.match(text.strip())
    if not m:
        return None
    year, month, day, hour, minute, second, fraction = m.groups()
    try:
        moment = datetime(int(year), int(month), int(day), int(hour), int(minute), int(second), tzinfo=timezone.utc)
    except ValueError:
        return None
    digits = (fraction or "").replace("_", "")
    if text.strip().upper().startswith("LDT#"):  # the nanosecond form (the Date/Time (ns) radix)
        return int(moment.timestamp()) * 1_000_000_000 + (int((digits + "0" * 9)[:9]) if digits else 0)
    micros = int((digits + "000000")[:6]) if digits else 0
    return int(moment.timestamp()) * 1_000_000 + micros


def _flat(value) -> list:
    if isinstance(value, list):
        out = []
        for v in value:
            out += _flat(v) if isinstance(v, list) else [v]
        return out
    return [value]


def _elements(value, t: LogixType, count: int) -> list:
    """An array's ``count`` element values, written flat or nested by
    dimension. An element of a structure is a list (positional) or a dict of
    its own, so only the dimensions' nesting is undone: one level at a time
    while there are fewer values than elements."""
    if t.kind != "struct":
        return _flat(value)
    out = value if isinstance(value, list) else [value]
    while len(out) < count and out and all(isinstance(v, list) for v in out):
        deeper = [e for row in out for e in row]
        if len(deeper) > count:
            break
        out = deeper
    return out


def apply_initial(d: Declared, writer: ValueWriter, problems: list[Problem]) -> None:
    """Write tag ``d``'s initial value, if it has one."""
    iv: InitialValue | None = d.tag.value
    if iv is None or d.type is None:
        return
    positional = iv.form == "positional"

    def bad(message: str) -> None:
        problems.append(Problem(iv.pos if iv.pos.line else d.tag.pos, f"tag {d.tag.name}: initial value: {message}"))

    def atomic(t: LogixType, path, k, value, bit=None):
        leaf = d.leaves.get(path)
        if leaf is None:
            return
        if isinstance(value, str) and value.upper().startswith(("DT#", "LDT#")) and t.name == "LINT":
            stamp = date_time(value)
            if stamp is None:
                bad(f"{value!r}: expected DT#YYYY-MM-DD-hh:mm:ss.ffffffZ")
                return
            value = stamp
        if isinstance(value, str) and t.name != "BOOL":
            bad(f"{value!r} is not a number for a {t.name}")
            return
        if t.name == "REAL":
            writer.put(leaf, k, float(value))
            return
        if not isinstance(value, (int, float, bool)):
            bad(f"expected a number for a {t.name}, found {value!r}")
            return
        v = int(value)
        if t.name == "BOOL" or bit is not None:
            writer.put(leaf, k, v & 1, bit)
            return
        lo, hi = -(1 << (t.bits - 1)), (1 << (t.bits - 1)) - 1
        if not lo <= v <= hi:
            v &= (1 << t.bits) - 1  # a pattern written unsigned (16#FFFF for an INT): its bits
            v = v - (1 << t.bits) if v > hi else v
        writer.put(leaf, k, v)

    def string(t: LogixType, path, k, value):
        leaf = d.leaves.get(path)
        if isinstance(value, dict):
            text = value.get("DATA", value.get("Data", ""))
            length = value.get("LEN", value.get("Len"))
            value = text[: int(length)] if isinstance(text, str) and isinstance(length, int) else text
        elif isinstance(value, list) and value and isinstance(value[0], int):
            length = value[0]
            text = value[1] if len(value) > 1 and isinstance(value[1], str) else ""
            value = text[:length]
        if not isinstance(value, str):
            bad(f"expected the text of a {t.name}, found {value!r}")
            return
        value = value.rstrip("\x00")
        if len(value) > t.chars:
            bad(f"{len(value)} characters for a {t.name} of {t.chars}")
            return
        writer.put(leaf, k, value)

    def member_value(value, m: MemberType, index: int):
        if isinstance(value, dict):
            for key, v in value.items():
                if key.upper() == m.name.upper():
                    return v, True
            return None, False
        if isinstance(value, list):
            return (value[index], True) if index < len(value) else (None, False)
        return None, False

    def one(t: LogixType, path, k, value):
        if t.kind == "atomic":
            atomic(t, path, k, value)
        elif t.kind == "string":
            string(t, path, k, value)
        else:
            struct(t, path, k, value)

    def struct(t: LogixType, path, k, value):
        if not isinstance(value, (dict, list)):
            bad(f"expected the members of a {t.name}, found {value!r}")
            return
        if positional and not t.positional:  # a layout of Logix's own (types.py): the value is not read
            return
        stored = [m for m in t.members if m.host is None]
        for index, m in enumerate(stored):
            v, found = member_value(value, m, index)
            if not found:
                continue
            sub = path + (m.name.upper(),)
            if m.dim:
                elems = _elements(v, m.type, m.dim)
                for j, e in enumerate(elems[:m.dim]):
                    one(m.type, sub, k * m.dim + j, e)
            else:
                one(m.type, sub, k, v)
        if not positional and isinstance(value, dict):
            for m in t.members:
                if m.host is None:
                    continue
                v, found = member_value(value, m, 0)
                if found and v is not None:
                    atomic(t, path + (m.host.upper(),), k, v, bit=m.bit)

    if d.dims:
        count = 1
        for n in d.dims:
            count *= n
        elems = _elements(iv.data, d.type, count)
        if len(elems) > count:
            bad(f"{len(elems)} values for {count} elements")
        for k, e in enumerate(elems[:count]):
            one(d.type, (), k, e)
    else:
        one(d.type, (), 0, iv.data)


_BITS = {"SI": 8, "N": 16, "B": 16, "L": 32, "LI": 64}


def data_files(writer: ValueWriter, table) -> list[tuple[str, int, list]]:
    """(letter, file, values) for each file written: the values of items 0
    to the file's last, the items not written as the table holds them."""
    out = []
    for (letter, file), cells in sorted(writer.items.items(), key=lambda x: x[0][1]):
        f = table.file(f"{letter}{file}")
        size = len(f.data) // f.ftype.words_per_element
        values = []
        bits = _BITS.get(letter)
        for item in range(size):
            if item in cells:
                v = cells[item]
                if bits and isinstance(v, int):  # a pattern (a CTL with bit 31 set) as the signed item it is
                    v &= (1 << bits) - 1
                    v = v - (1 << bits) if v >> (bits - 1) else v
                values.append(v)
            else:
                values.append("" if letter in ("ST", "SL") else (0.0 if letter == "F" else 0))
        out.append((letter, file, values))
    return out

