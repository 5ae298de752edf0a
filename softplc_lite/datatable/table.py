"""The emulated data table: files by number, typed and raw access, blocks.

PLC rules, not Python ones:

* file numbers are unique across types (there is no N9 beside ST9);
* N (and O I S B) words are 16-bit signed: a typed write outside
  -32768..32767 is refused, a raw word write takes the bit pattern 0..65535
  and reads back signed;
* F elements are float32 (3.14 reads back as 3.140000104904175);
* L elements are 32-bit signed (-2147483648..2147483647), SI elements 8-bit
  (-128..127), LI elements 64-bit; their bits are addressable, /0../31,
  /0../7 and /0../63;
* D (BCD) and A (ASCII) words are 16-bit words like N; a write also takes
  their text forms: "1234" (four BCD digits, 0x1234) for D, "AB" (two
  characters, high byte first) for A;
* an address past the end of a file is an error, not a silent grow: files
  grow only through :meth:`DataTable.reference` (what a program names or
  declares) and through loading.
"""

from __future__ import annotations

import json
import struct
import sys
from array import array
from typing import Any, Iterator, NamedTuple, Union

from .address import Address, ValueKind, parse_address
from .errors import AddressRangeError, BlockRangeError, DataTableError, ValueRangeError
from .files import DataFile
from .filetypes import (
    DEFAULT_FILES,
    FILE_TYPES,
    INDEX_REGISTER_WORD,
    ITEM_BITS,
    OTHER_INTEGERS,
    MAX_FILE_NUMBER,
    STRING_CHARS,
    WORD_BITS,
    FileType,
    Storage,
    int_range,
    split_file_name,
)

AddressLike = Union[str, Address]

WORD_MIN, WORD_MAX = -32768, 32767
RAW_MAX = 0xFFFF


def bit_mask(bit: int) -> int:
    """Mask of ``bit`` in a *signed* 16-bit word: bit 15 is -32768, so ``w |
    mask`` and ``w & ~mask`` stay inside array('h')'s range."""
    return -32768 if bit == WORD_BITS - 1 else 1 << bit


def item_bit_mask(bit: int, itemsize: int) -> int:
    """Mask of ``bit`` in a signed item of ``itemsize`` bytes: the top bit
    is negative (bit 31 of an L element is -2**31, bit 7 of an SI element
    -128), so ``v | mask`` and ``v & ~mask`` stay inside the array's range."""
    top = 8 * itemsize - 1
    return -(1 << top) if bit == top else 1 << bit


def data_bit_mask(data: array, bit: int) -> int:
    """Mask of ``bit`` in an item of ``data`` (a file's array)."""
    return item_bit_mask(bit, data.itemsize)


_INT_WHAT = {Storage.BYTE: "an 8-bit signed integer", Storage.WORD: "a 16-bit signed integer",
             Storage.LONG: "a 32-bit signed integer", Storage.LONG64: "a 64-bit signed integer"}


def check_item(value: Any, storage: Storage, where: object) -> int:
    """A value for an integer item of ``storage`` (SI, L, LI), range-checked."""
    lo, hi = int_range(ITEM_BITS[storage])
    return _check_int(value, lo, hi, where, _INT_WHAT[storage])


def to_signed(raw: int) -> int:
    """A 16-bit pattern 0..65535 as the signed value a PLC word holds."""
    return raw - 0x10000 if raw & 0x8000 else raw


class Location(NamedTuple):
    """Where an address lands once indirection and indexing are applied."""

    file: DataFile
    index: int  # index into file.data
    bit: int | None


def _as_address(addr: AddressLike) -> Address:
    return parse_address(addr) if isinstance(addr, str) else addr


def shown(value: Any) -> str:
    """A value as a person typed it, for messages: text as it is (quoted
    only when empty or padded), a number as a number, an object or a list
    as JSON; never a Python type name."""
    if isinstance(value, str):
        return value if value and value.strip() == value else json.dumps(value)
    if isinstance(value, (bool, int, float)):
        return str(int(value) if isinstance(value, bool) else value)
    try:
        return json.dumps(value)
    except (TypeError, ValueError):
        return "a value of another kind"


def _example_member(ftype) -> str:
    words = ftype.word_members or ftype.bit_members
    return words[0].name if words else "PRE"


def _check_int(value: Any, lo: int, hi: int, where: object, what: str) -> int:
    if isinstance(value, bool):
        value = int(value)
    if not isinstance(value, int):
        span = "0 or 1" if (lo, hi) == (0, 1) else f"{lo}..{hi}"
        raise ValueRangeError(f"{where} holds {what} ({span}), got {shown(value)}")
    if not lo <= value <= hi:
        raise ValueRangeError(f"{value} does not fit {where}, which holds {what} ({lo}..{hi})")
    return value


def check_float32(value: Any, where: object) -> float:
    """A number that fits a float32 element (inf and nan are allowed, as on
    the PLC; a finite value too large for float32 is refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueRangeError(f"{where} holds a float (a number), got {shown(value)}")
    try:
        struct.pack("<f", value)
    except (OverflowError, struct.error):
        raise ValueRangeError(f"{value!r} does not fit {where}, which holds a float32 (about ±3.4e38)")
    return float(value)


_UNIT = {Storage.WORD: "word", Storage.FLOAT: "float", Storage.LONG: "long",
         Storage.BYTE: "short integer", Storage.LONG64: "long long"}


class WordBlock:
    """Consecutive words (or floats, in an F file) starting at an element.

    COMGENIUS packs bytes across words and reads ``%Ld`` from two words, low
    word first; COP and FLL copy blocks. Items read signed; ``__setitem__``
    takes a raw 16-bit pattern 0..65535 and ``set_signed`` a signed value.
    """

    __slots__ = ("file", "start", "count", "origin")

    def __init__(self, file: DataFile, start: int, count: int, origin: Address) -> None:
        self.file = file
        self.start = start
        self.count = count
        self.origin = origin

    def __len__(self) -> int:
        return self.count

    def _index(self, k: int) -> int:
        if not 0 <= k < self.count:
            raise IndexError(f"item {k} outside {self} ({self.count} items)")
        return self.start + k

    def __getitem__(self, k: int) -> int | float:
        return self.file.data[self._index(k)]

    def __setitem__(self, k: int, value: int | float) -> None:
        i = self._index(k)
        storage = self.file.ftype.storage
        if storage in OTHER_INTEGERS:
            self.file.data[i] = check_item(value, storage, f"{_UNIT[storage]} {k} of {self}")
        elif self.file.is_words:
            raw = _check_int(value, 0, RAW_MAX, f"word {k} of {self}", "a raw word")
            self.file.data[i] = to_signed(raw)
        else:
            self.file.data[i] = check_float32(value, f"item {k} of {self}")

    def set_signed(self, k: int, value: int) -> None:
        i = self._index(k)
        self.file.data[i] = _check_int(value, WORD_MIN, WORD_MAX, f"word {k} of {self}", "a signed word")

    def unsigned(self, k: int) -> int:
        return self.file.data[self._index(k)] & RAW_MAX

    def values(self) -> list[int | float]:
        return self.file.data[self.start:self.start + self.count].tolist()

    def __iter__(self) -> Iterator[int | float]:
        return iter(self.values())

    def __str__(self) -> str:
        unit = _UNIT[self.file.ftype.storage]
        return f"{self.count} {unit}{'s' if self.count != 1 else ''} from {self.origin}"


class DataTable:
    """All data files of one PLC, keyed by file number."""

    def __init__(self, *, defaults: bool = True) -> None:
        self._files: dict[int, DataFile] = {}
        if defaults:
            for ftype, number in DEFAULT_FILES:
                self.create_file(ftype.letter, number, ftype.default_size)

    # -- files --------------------------------------------------------------
    def create_file(self, type_letter: str, number: int, elements: int | None = None) -> DataFile:
        """Create file ``type_letter``+``number`` (or grow it if it exists)."""
        ftype = FILE_TYPES.get(type_letter.upper())
        if ftype is None:
            raise DataTableError(
                f"unknown file type '{type_letter}' (expected one of {' '.join(FILE_TYPES)})"
            )
        self._check_number(ftype, number)
        existing = self._files.get(number)
        if existing is not None:
            if existing.ftype is not ftype:
                raise DataTableError(
                    f"file number {number} is already {existing.name}; "
                    f"{ftype.letter}{number} cannot also exist (file numbers are unique)"
                )
            existing.grow(elements or 0)
            return existing
        size = ftype.default_size if elements is None else elements
        f = self._files[number] = DataFile(ftype, number, size)
        return f

    @staticmethod
    def _check_number(ftype: FileType, number: int) -> None:
        if ftype.fixed_number is not None:
            if number != ftype.fixed_number:
                raise DataTableError(
                    f"the {ftype.title} file is {ftype.letter}{ftype.fixed_number}, not "
                    f"{ftype.letter}{number}"
                )
        elif not 3 <= number <= MAX_FILE_NUMBER:
            raise DataTableError(
                f"{ftype.letter}{number}: {ftype.letter} files are numbered 3..{MAX_FILE_NUMBER}"
            )

    def file(self, ref: str | int) -> DataFile:
        """A file by number (7) or name ("N7", "O0", "O", "ST9")."""
        if isinstance(ref, int):
            number = ref
            f = self._files.get(number)
            if f is None:
                raise AddressRangeError(f"there is no data file number {number}")
            return f
        text = ref.strip().upper()
        ftype, digits = split_file_name(text)
        if ftype is None or not (digits.isdigit() or (not digits and ftype.fixed_number is not None)):
            raise DataTableError(f"bad file name '{ref}': expected a type and number such as N7 or ST9")
        number = int(digits) if digits else ftype.fixed_number
        f = self._files.get(number)
        if f is None or f.ftype is not ftype:
            raise AddressRangeError(f"there is no data file {ftype.letter}{number}")
        return f

    def files(self) -> list[DataFile]:
        """Every file, in file-number order."""
        return [self._files[n] for n in sorted(self._files)]

    def __contains__(self, name: str) -> bool:
        try:
            self.file(name)
        except DataTableError:
            return False
        return True

    def reference(self, addr: AddressLike) -> None:
        """Make the table hold everything ``addr`` can name directly: create
        its file and grow it to the element (what a program referencing the
        address needs). Indirect parts are referenced in turn; an element
        chosen at run time is checked at run time."""
        a = _as_address(addr)
        for part in (a.file, a.element, a.bit):
            if isinstance(part, Address):
                self.reference(part)
        if isinstance(a.file, Address):
            return
        f = self.create_file(a.type_letter, a.file, 0)
        if isinstance(a.element, int):
            f.grow(a.element + 1)

    # -- resolving ------------------------------------------------------------
    def _word_value(self, addr: Address) -> int:
        loc = self.resolve(addr)
        return loc.file.data[loc.index]

    def index_register(self) -> int:
        """S:24, the offset added to ``#`` (indexed) addresses."""
        status = self._files.get(2)
        if status is None or len(status.data) <= INDEX_REGISTER_WORD:
            return 0
        return status.data[INDEX_REGISTER_WORD]

    def resolve(self, addr: AddressLike) -> Location:
        """Apply indirection and indexing and bounds-check the result."""
        a = _as_address(addr)
        ftype = a.ftype
        number = a.file if isinstance(a.file, int) else self._word_value(a.file)
        f = self._files.get(number)
        if f is None or f.ftype is not ftype:
            via = f" (from {a.file} = {number})" if isinstance(a.file, Address) else ""
            raise AddressRangeError(f"{a}: there is no data file {ftype.letter}{number}{via}")
        bit = a.bit if not isinstance(a.bit, Address) else self._word_value(a.bit)
        if a.element is None:  # B3/[N7:0]: bit number across the file
            if not 0 <= bit < f.size * WORD_BITS:
                raise AddressRangeError(
                    f"{a}: bit {bit} (from {a.bit}) is outside {f.name} "
                    f"({f.size} words, bits 0..{f.size * WORD_BITS - 1})"
                )
            element, bit = divmod(bit, WORD_BITS)
        else:
            element = a.element if isinstance(a.element, int) else self._word_value(a.element)
            top = WORD_BITS if a.member is not None else ftype.element_bits
            if bit is not None and not 0 <= bit < top:
                raise AddressRangeError(f"{a}: bit {bit} (from {a.bit}) is outside 0..{top - 1}")
        if a.indexed:
            offset = self.index_register()
            element += offset
            if not 0 <= element < f.size:
                raise AddressRangeError(
                    f"{a}: index register S:24 = {offset} puts it at element {element}, "
                    f"outside {f.name} (elements 0..{f.size - 1})"
                )
        if not 0 <= element < f.size:
            via = f" (from {a.element})" if isinstance(a.element, Address) else ""
            raise AddressRangeError(
                f"{a}: element {element}{via} is past the end of {f.name} "
                f"({f.size} element{'s' if f.size != 1 else ''})"
            )
        index = element * ftype.words_per_element
        if a.member is not None:
            index += ftype.members_by_name[a.member].offset
        return Location(f, index, bit)

    # -- typed values -----------------------------------------------------------
    def read(self, addr: AddressLike) -> Any:
        """The value at ``addr``, typed as the PLC sees it: a bit (0/1), a
        signed word, a float, a string, or a dict of members for T/C/R."""
        a = _as_address(addr)
        f, i, bit = self.resolve(a)
        kind = a.kind
        data = f.data
        if kind is ValueKind.BIT:
            return (data[i] >> bit) & 1
        if kind is ValueKind.WORD or kind is ValueKind.FLOAT or kind is ValueKind.LONG:
            return data[i]
        if kind is ValueKind.STRING:
            return read_string(data, i, f.ftype.chars)
        return {m: self._member(data, i, f.ftype, m) for m in member_order(f.ftype)}

    @staticmethod
    def _member(data: array, start: int, ftype: FileType, name: str) -> int:
        m = ftype.members_by_name[name]
        if hasattr(m, "bit"):
            return (data[start + m.word] >> m.bit) & 1
        return data[start + m.offset]

    def write(self, addr: AddressLike, value: Any) -> None:
        """Write a typed value; refuses values the element cannot hold (the
        address is turned into text only for that message)."""
        a = _as_address(addr)
        f, i, bit = self.resolve(a)
        kind = a.kind
        data = f.data
        if kind is ValueKind.BIT:
            on = _check_int(value, 0, 1, a, "a bit")
            mask = data_bit_mask(data, bit)
            data[i] = (data[i] | mask) if on else (data[i] & ~mask)
        elif kind is ValueKind.WORD:
            if f.ftype.is_string and a.member == "LEN":
                data[i] = _check_int(value, 0, f.ftype.chars, str(a), "a string length")
            elif isinstance(value, str) and f.ftype.radix != "decimal" and a.member is None:
                data[i] = word_from_text(value, f.ftype, str(a))
            else:
                data[i] = _check_int(value, WORD_MIN, WORD_MAX, a, "a 16-bit signed integer")
        elif kind is ValueKind.FLOAT:
            data[i] = check_float32(value, a)
        elif kind is ValueKind.LONG:
            data[i] = check_item(value, f.ftype.storage, a)
        elif kind is ValueKind.STRING:
            write_string(data, i, value, str(a), f.ftype.chars)
        else:
            self._write_members(f, i, value, a)

    def _write_members(self, f: DataFile, start: int, value: Any, a: Address) -> None:
        ftype = f.ftype
        if not isinstance(value, dict):
            raise ValueRangeError(
                f"{a} is a {ftype.title} element: give its members as an object, e.g. "
                f"{{\"{_example_member(ftype)}\": 10}} (members {ftype.member_names()}), or one member "
                f"({a}.{_example_member(ftype)})"
            )
        checked: list[tuple[Any, int]] = []
        for name, v in value.items():
            m = ftype.members_by_name.get(str(name).upper())
            if m is None:
                raise ValueRangeError(
                    f"'{name}' is not a member of {a}; members are {ftype.member_names()}"
                )
            where = f"{a}.{m.name}"
            if hasattr(m, "bit"):
                checked.append((m, _check_int(v, 0, 1, where, "a bit")))
            else:
                checked.append((m, _check_int(v, WORD_MIN, WORD_MAX, where, "a 16-bit signed integer")))
        # Validate everything first so a bad member leaves the element untouched.
        data = f.data
        for m, v in checked:
            if hasattr(m, "bit"):
                mask = bit_mask(m.bit)
                w = data[start + m.word]
                data[start + m.word] = (w | mask) if v else (w & ~mask)
            else:
                data[start + m.offset] = v

    # -- raw words ----------------------------------------------------------------
    def _word_location(self, a: Address) -> Location:
        loc = self.resolve(a)
        if loc.file.ftype.storage in OTHER_INTEGERS:
            ftype = loc.file.ftype
            raise DataTableError(f"{a} is a {ftype.item_bits}-bit {ftype.title}; {ftype.letter} files have no raw 16-bit words")
        if not loc.file.is_words:
            raise DataTableError(f"{a} is a float; F files have no raw 16-bit words")
        if loc.bit is not None:
            raise DataTableError(f"{a} is a bit; raw access takes a word address")
        return loc

    def read_word(self, addr: AddressLike) -> int:
        """The raw 16-bit word at ``addr`` (word 0 for a T/C/R/ST element), signed."""
        f, i, _ = self._word_location(_as_address(addr))
        return f.data[i]

    def write_word(self, addr: AddressLike, raw: int) -> None:
        """Write a raw 16-bit pattern 0..65535 (it reads back signed)."""
        a = _as_address(addr)
        f, i, _ = self._word_location(a)
        f.data[i] = to_signed(_check_int(raw, 0, RAW_MAX, str(a), "a raw word"))

    def block(self, addr: AddressLike, count: int) -> WordBlock:
        """``count`` consecutive words (floats in an F file) from ``addr``."""
        a = _as_address(addr)
        f, i, bit = self.resolve(a)
        if bit is not None:
            raise DataTableError(f"{a} is a bit; a block starts at a word or an element")
        if count < 1:
            raise DataTableError(f"a block from {a} needs at least one word, not {count}")
        total = len(f.data)
        if i + count > total:
            unit = _UNIT[f.ftype.storage] + "s"
            raise BlockRangeError(
                f"a block of {count} {unit} from {a} runs past the end of {f.name}: "
                f"{f.name} has {f.size} element{'s' if f.size != 1 else ''} ({total} {unit}), "
                f"the block needs {unit} {i}..{i + count - 1}"
            )
        return WordBlock(f, i, count, a)

    def word_ref(self, addr: AddressLike) -> tuple[array, int]:
        """The array and index of a direct word or float address: the access
        path compiled rungs bind once and then index directly."""
        a = _as_address(addr)
        if not a.is_direct:
            raise DataTableError(f"{a} is indirect or indexed; resolve it each scan")
        if a.kind is ValueKind.BIT:
            raise DataTableError(f"{a} is a bit; use bit_ref")
        if a.kind not in (ValueKind.WORD, ValueKind.FLOAT, ValueKind.LONG):
            raise DataTableError(f"{a} is a whole {a.kind.value} element, not a word or float")
        f, i, _ = self.resolve(a)
        return f.data, i

    def bit_ref(self, addr: AddressLike) -> tuple[array, int, int]:
        """Array, index and signed mask of a direct bit address."""
        a = _as_address(addr)
        if not a.is_direct:
            raise DataTableError(f"{a} is indirect or indexed; resolve it each scan")
        f, i, bit = self.resolve(a)
        if bit is None:
            raise DataTableError(f"{a} is not a bit address")
        return f.data, i, data_bit_mask(f.data, bit)

    def assign(self, other: "DataTable") -> None:
        """Take ``other``'s values, keeping this table's arrays.

        Restoring a snapshot into a running table must not break the
        references compiled rungs hold, nor shrink files the program
        references: every file is overwritten in place, grown if ``other``'s
        is larger, and zero past the end of ``other``'s; files ``other`` lacks
        are zeroed. A file number used with another type is refused before
        anything changes."""
        for number, theirs in other._files.items():
            mine = self._files.get(number)
            if mine is not None and mine.ftype is not theirs.ftype:
                raise DataTableError(
                    f"cannot load {theirs.name}: file number {number} is {mine.name} here"
                )
        for number, mine in self._files.items():
            if number not in other._files:
                mine.data[:] = array(mine.data.typecode, bytes(len(mine.data) * mine.data.itemsize))
        for number, theirs in other._files.items():
            mine = self.create_file(theirs.ftype.letter, number, 0)
            extra = len(mine.data) - len(theirs.data)
            mine.data[:] = theirs.data
            if extra > 0:
                mine.data.frombytes(bytes(extra * mine.data.itemsize))

    # -- comparison -------------------------------------------------------------
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, DataTable):
            return NotImplemented
        if self._files.keys() != other._files.keys():
            return False
        for n, f in self._files.items():
            g = other._files[n]
            if f.ftype is not g.ftype or f.data.tobytes() != g.data.tobytes():
                return False
        return True

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"<DataTable {' '.join(f'{f.name}[{f.size}]' for f in self.files())}>"


def word_from_text(text: str, ftype: FileType, where: str) -> int:
    """A D word from its four BCD digits ("1234" -> 0x1234), an A word from
    its two characters ("AB" -> 0x4142, high byte first); signed, as stored."""
    if ftype.radix == "bcd":
        if not (1 <= len(text) <= 4 and text.isascii() and text.isdigit()):
            raise ValueRangeError(f"{text!r} does not fit {where}, which holds four BCD digits (\"0\"..\"9999\")")
        return to_signed(int(text, 16))
    codes = [ord(c) for c in text]
    if len(codes) > 2 or any(c > 0xFF for c in codes):
        raise ValueRangeError(f"{text!r} does not fit {where}, which holds two 8-bit characters (high byte first)")
    codes = (codes + [0, 0])[:2]
    return to_signed(codes[0] << 8 | codes[1])


def word_text(word: int, ftype: FileType) -> str | None:
    """The text form of a D or A word ("1234", "AB"), or None when the word
    has none (a D word that is not BCD) or the file shows decimals."""
    raw = word & RAW_MAX
    if ftype.radix == "bcd":
        digits = format(raw, "04X")
        return digits if digits.isdigit() else None
    if ftype.radix == "ascii":
        text = chr(raw >> 8) + chr(raw & 0xFF)
        return text[:1] if text[1] == "\0" else text  # "A" for 0x4100; 0x0041 stays "\0A"
    return None


def member_order(ftype: FileType) -> list[str]:
    """Member names in display/export order: status bits, then words."""
    return [m.name for m in ftype.bit_members] + [m.name for m in ftype.word_members]


def read_string(data: array, start: int, chars: int = STRING_CHARS) -> str:
    """The characters of the string element (``chars`` code units: ST 82,
    SL more) whose LEN word is ``data[start]``. Each 16-bit code unit is one
    character (UCS-2), surrogates included."""
    length = min(data[start] & RAW_MAX, chars)
    units = array("H", data[start + 1:start + 1 + length].tobytes())
    return "".join(map(chr, units))


def write_string(data: array, start: int, text: Any, where: str, chars: int = STRING_CHARS) -> None:
    if not isinstance(text, str):
        raise ValueRangeError(f"{where} holds a string (text), got {shown(text)}")
    if len(text) > chars:
        raise ValueRangeError(
            f"a {len(text)}-character string does not fit {where}: at most {chars} characters"
        )
    units = [ord(c) for c in text]
    wide = next((c for c in units if c > RAW_MAX), None)
    if wide is not None:
        raise ValueRangeError(
            f"U+{wide:X} does not fit {where}: ST characters are UCS-2 (16-bit code units)"
        )
    store_text(data, start, text, chars)


_NATIVE_UTF16 = "utf-16-le" if sys.byteorder == "little" else "utf-16-be"


def store_text(data: array, start: int, text: str, chars: int = STRING_CHARS) -> None:
    """Store the first ``chars`` characters of ``text`` into the string
    element whose LEN word is ``data[start]`` and zero the rest, in one slice
    write. A character above U+FFFF keeps its low 16 bits (UCS-2)."""
    text = text[:chars]
    raw = text.encode(_NATIVE_UTF16, "surrogatepass")
    if len(raw) != 2 * len(text):  # a character above U+FFFF took two units
        raw = array("H", [ord(c) & RAW_MAX for c in text]).tobytes()
    data[start] = len(text)
    data[start + 1:start + 1 + chars] = array("h", raw + bytes(2 * chars - len(raw)))
