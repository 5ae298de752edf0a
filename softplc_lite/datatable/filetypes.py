"""The PLC-5/SoftPLC data file types and the layout of their elements.

Every file type is described once here; the address parser, the storage
classes, JSON import/export and the snapshot format all read these specs, so a
member name or a bit position is written down in exactly one place.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

#: Most elements one file may hold (PLC-5 and SoftPLC: 0..9999).
MAX_ELEMENTS = 10_000
#: Highest file number.
MAX_FILE_NUMBER = 9999
#: Characters in one ST element (SoftPLC: UCS-2, any 16-bit code unit).
STRING_CHARS = 82
#: Characters in one SL element: a softplc choice, the longest string type
#: real Logix exports declare (STRING_100 .. a DATA of 4,950 SINTs), rounded up.
LONG_STRING_CHARS = 5000
#: Bits in a data table word.
WORD_BITS = 16
#: An L element's range (1747-RM001 / 1763-RM001: -2,147,483,648..2,147,483,647).
LONG_MIN, LONG_MAX = -(2 ** 31), 2 ** 31 - 1


class Storage(Enum):
    """How a file's elements are stored."""

    WORD = "word"  # 16-bit words in array('h')
    FLOAT = "float"  # IEEE float32 in array('f')
    LONG = "long"  # 32-bit signed integers in a 4-byte array (SLC/MicroLogix L files)
    BYTE = "byte"  # 8-bit signed integers in array('b') (SI files: Logix SINT)
    LONG64 = "long64"  # 64-bit signed integers in array('q') (LI files: Logix LINT)


#: Bits in one item of each storage: the bit numbers /0../n-1 an element of
#: an integer file takes, and the range of a signed integer item.
ITEM_BITS = {Storage.BYTE: 8, Storage.WORD: 16, Storage.LONG: 32, Storage.LONG64: 64, Storage.FLOAT: 32}
#: Storages whose items are signed integers wider or narrower than a word.
OTHER_INTEGERS = (Storage.LONG, Storage.BYTE, Storage.LONG64)


def int_range(bits: int) -> tuple[int, int]:
    """The range of a signed integer of ``bits`` bits."""
    return -(1 << (bits - 1)), (1 << (bits - 1)) - 1


@dataclass(frozen=True)
class WordMember:
    """A named 16-bit word inside a structured element (``T4:0.ACC``)."""

    name: str
    offset: int  # word offset inside the element


@dataclass(frozen=True)
class BitMember:
    """A named status bit of a structured element (``T4:0/DN``), in word 0."""

    name: str
    bit: int
    word: int = 0


@dataclass(frozen=True)
class FileType:
    """One data file type: its letter, its element layout and its rules."""

    letter: str
    title: str
    storage: Storage
    words_per_element: int  # items per element: 1 for F, L, SI, LI
    word_members: tuple[WordMember, ...] = ()
    bit_members: tuple[BitMember, ...] = ()
    has_bits: bool = True  # /n bit addressing on the element word
    fixed_number: int | None = None  # O is always 0, I 1, S 2
    octal: bool = False  # I/O word and bit numbers are octal on PLC-5
    default_number: int | None = None
    default_size: int = 1
    bits_across_file: bool = False  # B3/17 form
    # How text forms (DATA values, --print, the watch view) show a word:
    # "decimal", "bcd" (D: four BCD digits) or "ascii" (A: two characters).
    radix: str = "decimal"
    chars: int = 0  # a string file: the code units an element holds after its LEN word
    members_by_name: dict[str, WordMember | BitMember] = field(
        init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        table: dict[str, WordMember | BitMember] = {}
        for m in self.word_members + self.bit_members:
            table[m.name] = m
        for k in range(self.chars):  # ST9:0.DATA3: one code unit as a word
            table[f"DATA{k}"] = WordMember(f"DATA{k}", 1 + k)
        object.__setattr__(self, "members_by_name", table)

    @property
    def is_structure(self) -> bool:
        return bool(self.word_members or self.bit_members)

    @property
    def item_bits(self) -> int:
        """Bits in one item of the file's array (16 for a word)."""
        return ITEM_BITS[self.storage]

    @property
    def element_bits(self) -> int:
        """The bit numbers /0../n-1 an element (not a member) takes."""
        return self.item_bits if self.has_bits else 0

    @property
    def is_string(self) -> bool:
        return self.chars > 0

    def bit_name(self, bit: int) -> str | None:
        """The mnemonic of a status bit in word 0, if it has one."""
        for m in self.bit_members:
            if m.bit == bit:
                return m.name
        return None

    def member_names(self) -> str:
        return " ".join(m.name for m in self.bit_members + self.word_members)


def _bits(*pairs: tuple[str, int]) -> tuple[BitMember, ...]:
    return tuple(BitMember(name, bit) for name, bit in pairs)


OUTPUT = FileType("O", "output image", Storage.WORD, 1, fixed_number=0, octal=True,
                  default_number=0, default_size=32)
INPUT = FileType("I", "input image", Storage.WORD, 1, fixed_number=1, octal=True,
                 default_number=1, default_size=32)
STATUS = FileType("S", "status", Storage.WORD, 1, fixed_number=2, default_number=2,
                  default_size=128)
BINARY = FileType("B", "binary", Storage.WORD, 1, default_number=3, bits_across_file=True)
TIMER = FileType(
    "T", "timer", Storage.WORD, 3,
    word_members=(WordMember("PRE", 1), WordMember("ACC", 2)),
    bit_members=_bits(("EN", 15), ("TT", 14), ("DN", 13)),
    default_number=4,
)
COUNTER = FileType(
    "C", "counter", Storage.WORD, 3,
    word_members=(WordMember("PRE", 1), WordMember("ACC", 2)),
    bit_members=_bits(("CU", 15), ("CD", 14), ("DN", 13), ("OV", 12), ("UN", 11)),
    default_number=5,
)
CONTROL = FileType(
    "R", "control", Storage.WORD, 3,
    word_members=(WordMember("LEN", 1), WordMember("POS", 2)),
    bit_members=_bits(("EN", 15), ("EU", 14), ("DN", 13), ("EM", 12), ("ER", 11),
                      ("UL", 10), ("IN", 9), ("FD", 8)),
    default_number=6,
)
INTEGER = FileType("N", "integer", Storage.WORD, 1, default_number=7)
FLOAT = FileType("F", "float", Storage.FLOAT, 1, has_bits=False, default_number=8)
# An ST element is its LEN word followed by 82 UCS-2 code units, one word each.
STRING = FileType(
    "ST", "string", Storage.WORD, 1 + STRING_CHARS,
    word_members=(WordMember("LEN", 0),),
    has_bits=False, chars=STRING_CHARS,
)
# A long string element (softplc choice: no PLC-5 file type holds one): LEN,
# then LONG_STRING_CHARS code units. SL clashes with no PLC-5/SLC letter.
LONG_STRING = FileType(
    "SL", "long string", Storage.WORD, 1 + LONG_STRING_CHARS,
    word_members=(WordMember("LEN", 0),),
    has_bits=False, chars=LONG_STRING_CHARS,
)

# PLC-5 BCD and ASCII files (1785-6.1 data table: D and A file types): 16-bit
# words like N; what they hold only changes how text shows them (docs/datatable.md).
BCD = FileType("D", "BCD", Storage.WORD, 1, radix="bcd")
ASCII = FileType("A", "ASCII", Storage.WORD, 1, radix="ascii")
# SLC 5/03+ and MicroLogix long integer file (1747-RM001, 1763-RM001): one
# 32-bit signed integer an element. Its bits /0../31 are addressable, as a
# Logix DINT's are (1756-RM003, bit addressing): L9:0/31 is the sign bit.
LONG = FileType("L", "long integer", Storage.LONG, 1)
# Logix SINT and LINT (1756-RM003, data types) as files of their own: no
# PLC-5 or SLC file type holds them. The two-letter types SI and LI clash
# with no PLC-5/SLC letter (softplc choice); bits /0../7 and /0../63.
SINT = FileType("SI", "short integer", Storage.BYTE, 1)
LINT = FileType("LI", "long long integer", Storage.LONG64, 1)

FILE_TYPES: dict[str, FileType] = {
    t.letter: t
    for t in (OUTPUT, INPUT, STATUS, BINARY, TIMER, COUNTER, CONTROL, INTEGER, FLOAT, STRING,
              BCD, ASCII, LONG, SINT, LINT, LONG_STRING)
}


def split_file_name(text: str) -> tuple[FileType | None, str]:
    """``("N7")`` -> (N, "7"), ``"ST9"`` -> (ST, "9"), ``"SI12"`` -> (SI,
    "12"): the file type its leading letters name (upper case) and the rest;
    None when the letters name no type."""
    n = 0
    while n < len(text) and text[n].isascii() and text[n].isalpha():
        n += 1
    return FILE_TYPES.get(text[:n].upper()), text[n:]

#: The files every data table starts with, in PLC-5 order.
DEFAULT_FILES: tuple[tuple[FileType, int], ...] = tuple(
    (t, t.default_number) for t in FILE_TYPES.values() if t.default_number is not None
)


def file_name(ftype: FileType, number: int) -> str:
    """Canonical file name: ``N7``, ``ST9``, ``O0``."""
    return f"{ftype.letter}{number}"

#: Word of the status file holding the index register used by ``#`` addresses.
INDEX_REGISTER_WORD = 24
