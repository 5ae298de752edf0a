"""JSON import and export of a data table (format in docs/datatable.md).

Keys are file names (``"N7"``, ``"ST9"``, ``"R6"``, ``"O0"``; on import
``"O"``, ``"I"``, ``"S"`` are accepted for the fixed files); values are lists
by element:

* O I S B N D A: signed 16-bit integers (D and A words as numbers, what
  they hold; on import a D word may be given as its BCD digits "1234" and
  an A word as its two characters "AB");
* L: signed 32-bit integers;
* F: numbers (float32 values print exactly, e.g. 3.140000104904175);
* ST: strings, or ``{"LEN": n, "CHARS": "..."}`` where the element holds more
  than its string (characters past LEN, or a LEN above 82 from raw writes);
* T C R: objects of members, e.g. ``{"EN":0,"DN":1,"PRE":100,"ACC":5}``, plus
  ``"WORD0"`` (the raw control word) when bits without a name are set.

Loading is partial: a shorter list loads the elements it gives, ``null``
leaves an element as it is, an object may give only some members. Files grow
to what is loaded and missing files are created. A bad document changes
nothing: every value is checked before any is stored.
"""

from __future__ import annotations

import json
import math
import re
from array import array
from typing import Any

from ..errors import LocatedError
from ..textfile import DATA_JSON, read_text
from .errors import DataTableError
from .files import DataFile
from .filetypes import FILE_TYPES, MAX_ELEMENTS, OTHER_INTEGERS, STRING_CHARS, FileType, split_file_name
from .table import (
    RAW_MAX,
    DataTable,
    _check_int,
    bit_mask,
    check_float32,
    check_item,
    member_order,
    read_string,
    to_signed,
    word_from_text,
)


class DataTableJSONError(DataTableError):
    """A JSON document that does not describe a data table; names the
    source, and the line and column (syntax) or the JSON path (content)."""


# -- export -----------------------------------------------------------------


def export_table(table: DataTable) -> dict[str, list[Any]]:
    """The whole table as plain JSON-ready data, files in number order."""
    return {f.name: _export_file(f) for f in table.files()}


def _export_file(f: DataFile) -> list[Any]:
    ftype = f.ftype
    data = f.data
    if not ftype.is_structure or ftype.letter == "F":
        return data.tolist()
    wpe = ftype.words_per_element
    if ftype.is_string:
        return [_export_string(data, e * wpe, ftype.chars) for e in range(f.size)]
    return [_export_struct(data, e * wpe, ftype) for e in range(f.size)]


def _export_string(data: array, start: int, size: int) -> str | dict[str, Any]:
    length = data[start] & RAW_MAX
    units = array("H", data[start + 1:start + 1 + size].tobytes())
    if length <= size and not any(units[length:]):
        return read_string(data, start, size)
    # Raw writes left characters past LEN, or a LEN above 82: keep them all.
    chars = "".join(map(chr, units)).rstrip("\0")
    return {"LEN": length, "CHARS": chars}


def _named_mask(ftype: FileType) -> int:
    mask = 0
    for m in ftype.bit_members:
        mask |= 1 << m.bit
    return mask


def _export_struct(data: array, start: int, ftype: FileType) -> dict[str, int]:
    out: dict[str, int] = {}
    for name in member_order(ftype):
        m = ftype.members_by_name[name]
        out[name] = (data[start] >> m.bit) & 1 if hasattr(m, "bit") else data[start + m.offset]
    word0 = data[start] & RAW_MAX
    if word0 & ~_named_mask(ftype) & RAW_MAX:
        out["WORD0"] = word0
    return out


def dumps(table: DataTable) -> str:
    """JSON text with one line per file (compact, still diff-friendly)."""
    lines = [
        f"  {json.dumps(name)}: {json.dumps(values, ensure_ascii=True, separators=(',', ':'))}"
        for name, values in export_table(table).items()
    ]
    return "{\n" + ",\n".join(lines) + "\n}\n"


# -- import -----------------------------------------------------------------


# JSON numbers with more digits than this hold no data table value; they are
# refused before Python converts them (it converts at most 4,300 digits, in
# quadratic time). Nesting deeper than MAX_JSON_DEPTH is refused as well: no
# data table document nests more than three levels.
MAX_JSON_DIGITS = 40
MAX_JSON_DEPTH = 100
# A string is matched unrolled and possessive: one step a run of plain
# characters ("(a|b)*" keeps a backtracking point a character, about 120
# bytes each: over a GB for a 10 MB string).
_JSON_TOKEN = re.compile(r'"[^"\\]*+(?:\\.[^"\\]*+)*+"|[-0-9][0-9]{%d,}|[\[\]{}]' % MAX_JSON_DIGITS)


class _HugeNumber(ValueError):
    pass


def _json_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_JSON_DIGITS:
        raise _HugeNumber(text)
    return int(text)


def parse_json(text: str, source: str = "<json>") -> Any:
    """Any JSON value, with the errors a user can act on: a syntax error at
    its line and column, a number too long or nesting too deep located too;
    never a RecursionError or Python's int-conversion ValueError."""
    problem = json_limit_problem(text)
    if problem is not None:
        raise DataTableJSONError(f"{source}:{problem}")
    try:
        return json.loads(text, parse_int=_json_int)
    except json.JSONDecodeError as e:
        raise DataTableJSONError(f"{source}:{e.lineno}:{e.colno}: {e.msg}") from None
    except (_HugeNumber, RecursionError):  # a case json_limit_problem missed: still a clear error
        raise DataTableJSONError(f"{source}: a number longer than {MAX_JSON_DIGITS} digits or nesting "
                                 f"deeper than {MAX_JSON_DEPTH} levels") from None


def json_limit_problem(text: str) -> str | None:
    """``line:column: message`` for the first number too long or bracket too
    deep (outside strings), else None."""
    depth = 0
    for m in _JSON_TOKEN.finditer(text):
        token = m.group()
        if token[0] == '"':
            continue
        if token in "[{":
            depth += 1
            if depth <= MAX_JSON_DEPTH:
                continue
            message = f"nested more than {MAX_JSON_DEPTH} levels deep"
        elif token in "]}":
            depth -= 1
            continue
        else:
            message = (f"number {token[:12]}... has {len(token.lstrip('-'))} digits; no data table element holds "
                       f"a number of more than {MAX_JSON_DIGITS} digits")
        line = text.count("\n", 0, m.start()) + 1
        column = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
        return f"{line}:{column}: {message}"
    return None


def json_kind(value: Any) -> str:
    """What a JSON value is, in JSON's words: "a number", "text", "an
    object"; never a Python type name."""
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, (int, float)):
        return f"a number ({value})"
    if isinstance(value, str):
        return "text"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    return "null" if value is None else "a value of another kind"


def loads(text: str, source: str = "<json>") -> dict[str, Any]:
    """Parse JSON text, reporting a syntax error with source, line and column."""
    doc = parse_json(text, source)
    if not isinstance(doc, dict):
        raise DataTableJSONError(
            f"{source}: expected an object of files such as {{\"N7\": [1, 2]}}, "
            f"got {json_kind(doc)}"
        )
    return doc


def load_into(table: DataTable, doc: dict[str, Any], source: str = "<json>") -> None:
    """Load a parsed document into ``table``; all or nothing."""
    # Dry run on a copy first: a bad value deep in the document must not leave
    # the live table half-loaded.
    _apply(_copy(table), doc, source)
    _apply(table, doc, source)


def load_text(table: DataTable, text: str, source: str = "<json>") -> None:
    load_into(table, loads(text, source), source)


def load_file(table: DataTable, path: str) -> None:
    try:
        text = read_text(path, limit=DATA_JSON)
    except LocatedError as e:  # bad encoding
        raise DataTableJSONError(e.report()) from None
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: permission denied"
        raise DataTableJSONError(str(e)) from None
    load_text(table, text, path)


def table_from_json(text: str, source: str = "<json>") -> DataTable:
    table = DataTable()
    load_text(table, text, source)
    return table


def _copy(table: DataTable) -> DataTable:
    twin = DataTable(defaults=False)
    for f in table.files():
        g = twin.create_file(f.ftype.letter, f.number, 0)
        g.data.extend(f.data)
    return twin


def _file_key(key: str, source: str) -> tuple[FileType, int]:
    ftype, digits = split_file_name(key.strip())
    if ftype is None:
        raise DataTableJSONError(
            f"{source}: key {key!r}: unknown file type (expected a file name such as N7, ST9, "
            f"O0; types are {' '.join(FILE_TYPES)})"
        )
    if not digits and ftype.fixed_number is not None:
        return ftype, ftype.fixed_number
    if not digits.isdigit() or not digits.isascii() or len(digits) > 5:
        shown = key if len(key) <= 30 else key[:20] + "..."
        raise DataTableJSONError(f"{source}: key {shown!r}: expected a file name such as N7 or ST9")
    return ftype, int(digits)


def _apply(table: DataTable, doc: dict[str, Any], source: str) -> None:
    for key, values in doc.items():
        ftype, number = _file_key(key, source)
        where = f"{source}: {key}"
        if not isinstance(values, list):
            raise DataTableJSONError(f"{where}: expected a list of elements, got {json_kind(values)}")
        if len(values) > MAX_ELEMENTS:
            raise DataTableJSONError(f"{where}: {len(values)} elements; a file holds at most {MAX_ELEMENTS}")
        try:
            f = table.create_file(ftype.letter, number, 0)
            f.grow(len(values))
        except DataTableError as e:
            raise DataTableJSONError(f"{where}: {e}") from None
        for element, value in enumerate(values):
            if value is None:
                continue
            try:
                _load_element(f, element, value)
            except DataTableError as e:
                raise DataTableJSONError(f"{source}: {key}[{element}]: {e}") from None


def _load_element(f: DataFile, element: int, value: Any) -> None:
    ftype = f.ftype
    name = f"{f.name}:{element}"
    start = element * ftype.words_per_element
    data = f.data
    if ftype.letter == "F":
        if isinstance(value, float) and math.isnan(value):
            data[start] = value
        else:
            data[start] = check_float32(value, name)
    elif ftype.is_string:
        _load_string(data, start, value, name, ftype.chars)
    elif ftype.is_structure:
        _load_struct(data, start, ftype, value, name)
    elif ftype.storage in OTHER_INTEGERS:
        data[start] = check_item(value, ftype.storage, name)
    elif isinstance(value, str) and ftype.radix != "decimal":
        data[start] = word_from_text(value, ftype, name)
    else:
        data[start] = _check_int(value, -32768, 32767, name, "a 16-bit signed integer")


def _load_string(data: array, start: int, value: Any, name: str, size: int) -> None:
    from .table import write_string

    if isinstance(value, str):
        write_string(data, start, _utf16_units(value), name, size)
        return
    if not isinstance(value, dict):
        raise DataTableError(f"{name} is a string element; give a string or {{\"LEN\":..,\"CHARS\":..}}")
    unknown = set(value) - {"LEN", "CHARS"}
    if unknown:
        raise DataTableError(f"{name}: unknown member {sorted(unknown)[0]!r}; members are LEN CHARS")
    length = value.get("LEN")
    if "CHARS" in value:
        chars = value["CHARS"]
        keep = data[start]
        if isinstance(chars, str):
            chars = _utf16_units(chars)
        write_string(data, start, chars, name, size)  # checks width and 16-bit range
        data[start] = keep
    if length is not None:
        data[start] = to_signed(_check_int(length, 0, RAW_MAX, f"{name}.LEN", "a raw word"))


def _utf16_units(text: str) -> str:
    """JSON strings are UTF-16: ``"\\ud83d\\ude00"`` (or a literal emoji) is two
    code units, and json.loads joins such a pair into one character. Split it
    back so every code unit is one ST character, as it was exported."""
    if all(ord(c) <= 0xFFFF for c in text):
        return text
    out = []
    for c in text:
        code = ord(c)
        if code > 0xFFFF:
            code -= 0x10000
            out.append(chr(0xD800 + (code >> 10)) + chr(0xDC00 + (code & 0x3FF)))
        else:
            out.append(c)
    return "".join(out)


def _load_struct(data: array, start: int, ftype: FileType, value: Any, name: str) -> None:
    if not isinstance(value, dict):
        raise DataTableError(
            f"{name} is a {ftype.title} element; give an object of members ({ftype.member_names()})"
        )
    if "WORD0" in value:
        data[start] = to_signed(_check_int(value["WORD0"], 0, RAW_MAX, f"{name}.WORD0", "a raw word"))
    for key, v in value.items():
        if key == "WORD0":
            continue
        m = ftype.members_by_name.get(key.upper())
        if m is None:
            raise DataTableError(
                f"'{key}' is not a member of {name}; members are {ftype.member_names()} (and WORD0)"
            )
        if hasattr(m, "bit"):
            on = _check_int(v, 0, 1, f"{name}/{m.name}", "a bit")
            mask = bit_mask(m.bit)
            data[start] = (data[start] | mask) if on else (data[start] & ~mask)
        else:
            data[start + m.offset] = _check_int(v, -32768, 32767, f"{name}.{m.name}", "a 16-bit signed integer")
