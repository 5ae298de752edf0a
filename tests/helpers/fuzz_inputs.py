"""Fuzz inputs for softplc: every file and argument a user hands it.

``cases(kinds, profile)`` is a hypothesis strategy of :class:`Case`: a few
files to write into a fresh directory (an app, a config file, a data file, a
trace, a snapshot) and the ``softplc`` commands to run on them. The oracle
(``tests/helpers/fuzz_oracle.py``) runs them; ``tests/test_fuzz.py`` draws a few dozen
of each kind, ``tools/fuzz.py`` draws them for minutes (docs/fuzzing.md).

Each kind starts from valid inputs (programs drawn by ``ladder_strategies``,
the apps in ``programs/``, the documented examples) and breaks them:

* byte level: bit flips, interesting bytes (NUL, 0xFF, a lone UTF-8 lead
  byte), insertions, deletions, duplications, truncation, long lines, CRLF;
* token level: a token replaced by, or spliced with, one of a dictionary
  (huge integers, 1e999, ``0x`` + thousands of digits, branch words,
  brackets, astral characters...);
* encodings: UTF-16 with and without a BOM, a UTF-8 BOM, Latin-1;
* shapes the language allows but nobody types: branches hundreds deep,
  CPT expressions of thousands of terms, DATA/FILE/SYMBOL at the edges.

Four kinds are generated and run by modules of their own, with a driver of
the oracle: ``special_files`` and ``state_damage`` (``fuzz_files``: files that
are not regular files or not of a sane size, damaged real state),
``signals`` (``fuzz_signals``), ``modbus_tcp`` (``fuzz_protocol``).

A :class:`Profile` says which *features* a draw may use. Features are the
input classes known to break the product while it is being fixed
(``KNOWN_OPEN``); the default suite leaves them out, the campaign uses
everything. Large payloads come from a ``random.Random`` seeded by one
hypothesis draw, so a case is reproducible from its files alone (the
campaign saves them) and generation stays cheap.
"""

from __future__ import annotations

import json
import random
import re
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from helpers import fuzz_files
from helpers import fuzz_protocol
from helpers import fuzz_signals
from hypothesis import strategies as st
from helpers.ladder_strategies import programs

from softplc_lite.ladder.fmt import format_program

ROOT = Path(__file__).resolve().parents[2]
PROGRAMS = ROOT / "programs"

# -- profiles ------------------------------------------------------------------------

# Features: input classes a generator uses only when the profile allows them.
FEATURES = {
    "huge_int": "decimal integer literals over 4,300 digits (ladder, addresses, DATA, FILE, JSON, --set, LST, XML, TOML, traces)",
    "huge_hex": "0x literals with thousands of digits (Python's int() has no digit limit for hex)",
    "deep_branch": "branches nested more than 40 levels (mnemonic BST and neutral [ ])",
    "long_expr": "CPT/CMP expressions with hundreds of terms, parentheses or unary operators",
    "inf_float": "float literals that overflow to inf (1e999) in ladder and configs",
    "non_utf8": "config and data files that are not UTF-8 (Latin-1, UTF-16, random bytes)",
    "deep_json": "JSON and TOML nested hundreds of levels",
    "toml_range": "softplc.toml values out of range or of the wrong type",
    "huge_args": "--scan-ms, --width, --height with huge values",
    "empty_program": "programs without a rung (also in watch)",
    "watch_deep": "watch --snapshot of programs with deep branches",
    "jsr_depth": "[scan] jsr_depth at and above the documented limit",
    "format_width": "COMGENIUS formats with huge widths or precisions (%999999999d)",
    "check_run": "programs check accepts and run may refuse: a number beside a file of another type, "
                 "astral characters in DATA strings, [display] addresses past their file",
    "byte_mutation": "random byte and token mutations (may produce any of the above by chance)",
}

# Classes still being fixed: left out of the default suite (the campaign
# draws them all). None is open: a class found open goes here, with a
# FEATURES entry, until it is fixed.
KNOWN_OPEN: frozenset[str] = frozenset()


@dataclass(frozen=True)
class Profile:
    """Which features a draw may use."""

    exclude: frozenset = frozenset()

    def allows(self, feature: str) -> bool:
        assert feature in FEATURES, feature
        return feature not in self.exclude


EVERYTHING = Profile()
MUST_PASS = Profile(KNOWN_OPEN)
# Numbers a JSON list holds as Python ints (the document's huge numbers are drawn as text elsewhere).
SMALL_INTS = Profile(frozenset({"huge_int", "huge_hex", "inf_float"}))

# -- the case --------------------------------------------------------------------------


@dataclass
class Case:
    """Files to write (relative path -> bytes) and commands to run on them.

    In commands, ``{d}`` stands for the directory the files are written to.
    ``app``: the app (directory or .lad) ``check`` is run on; when check
    accepts it, the oracle requires ``run APP --scans 3 --fresh`` to load.
    ``fmt``: .lad files whose ``fmt`` output must parse back and be a fixed
    point, in both styles. ``target``: the fuzzed file; an error about it
    must give ``path:line`` (``located="line"``) or at least its name
    (``"name"``)."""

    kind: str
    files: dict[str, bytes] = field(default_factory=dict)
    commands: list[list[str]] = field(default_factory=list)
    app: str | None = None
    fmt: list[str] = field(default_factory=list)
    target: str | None = None
    located: str = "line"
    note: str = ""
    # A driver of fuzz_oracle.DRIVERS runs the case instead of the commands-only oracle
    # (files that change between commands, signals, a live server); params are its JSON arguments.
    driver: str = ""
    params: dict = field(default_factory=dict)

    def write(self, root: Path) -> None:
        for rel, data in self.files.items():
            p = root / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)

    def to_json(self) -> dict:
        d = dict(self.__dict__)
        d["files"] = {k: v.decode("latin-1") for k, v in self.files.items()}
        return d

    @classmethod
    def from_json(cls, d: dict) -> Case:
        d = dict(d)
        d["files"] = {k: v.encode("latin-1") for k, v in d["files"].items()}
        return cls(**d)


# -- interesting values ------------------------------------------------------------------


def big_decimal(rnd: random.Random, digits: int) -> str:
    return str(rnd.randint(1, 9)) + "".join(rnd.choice("0123456789") for _ in range(digits - 1))


def interesting_int(rnd: random.Random, profile: Profile, signed: bool = True) -> str:
    """An integer literal near an edge: word limits, file limits, huge."""
    choices = [0, 1, 2, 3, 7, 8, 9, 10, 15, 16, 17, 31, 32, 35, 36, 82, 83, 100, 127, 128, 247, 248, 255, 256,
               999, 1000, 9999, 10000, 10001, 32000, 32001, 32767, 32768, 65535, 65536, 2 ** 31 - 1, 2 ** 31,
               2 ** 32, 2 ** 63, 2 ** 64, 10 ** 20, 10 ** 100]
    k = rnd.randrange(10)
    if k == 0:
        text = big_decimal(rnd, rnd.choice([300, 1000, 4000, 4300]))
    elif k == 1 and profile.allows("huge_int"):
        text = big_decimal(rnd, rnd.choice([4301, 5000, 20000, 100000]))
    else:
        text = str(rnd.choice(choices))
    if signed and rnd.randrange(4) == 0:
        text = "-" + text
    return text


def interesting_float(rnd: random.Random, profile: Profile) -> str:
    choices = ["0.0", "-0.0", "0.5", "1.5e3", "3.4028235e38", "3.4028236e38", "3.5e38", "1e38", "-3.5e38",
               "1e-45", "1.4e-45", "1e-46", "1e-400", "1e308", "2.2250738585072014e-308", ".5", "5.", "1e0",
               "0.000000000000000000000000000000000000000001"]
    if profile.allows("inf_float"):
        choices += ["1e999", "-1e999", "1.8e308", "9" * 400 + ".0"]
    return rnd.choice(choices)


def interesting_hex(rnd: random.Random, profile: Profile) -> str:
    choices = ["0x0", "0x7FFF", "0x8000", "0xFFFF", "0x10000", "0xFFFFFFFF", "0x" + "F" * 40]
    if profile.allows("huge_hex"):
        choices += ["0x" + "F" * rnd.choice([5000, 20000]), "0x1" + "0" * 5000]
    return rnd.choice(choices)


def interesting_number(rnd: random.Random, profile: Profile) -> str:
    k = rnd.randrange(5)
    if k <= 2:
        return interesting_int(rnd, profile)
    if k == 3:
        return interesting_float(rnd, profile)
    return interesting_hex(rnd, profile)


ASTRAL = ["\U0001D11E", "\U0001F600", "\U00010000", "\U0010FFFF"]
ODD_CHARS = ["\x00", "\x7f", "\x80", "\xa0", "\u00e9", "\u2028", "\ufeff", "\ufffd", "\uffff", "\u0301"] + ASTRAL


def interesting_text(rnd: random.Random, profile: Profile, max_len: int = 100) -> str:
    k = rnd.randrange(6)
    if k == 0:
        return ""
    if k == 1:
        return "x" * rnd.choice([81, 82, 83, 255, 256, 1000])
    if k == 2 and profile.allows("check_run"):
        return "".join(rnd.choice(ASTRAL + ["a"]) for _ in range(rnd.randint(1, 5)))
    if k == 3:
        return "".join(rnd.choice(ODD_CHARS[:10] + ["a", " ", "%", "\\", '"']) for _ in range(rnd.randint(1, 12)))
    return "".join(rnd.choice("abcXYZ 0123456789%.-_") for _ in range(rnd.randint(1, max_len)))


# Addresses a program or a command line may name, valid and not.
ADDRESSES_OK = ["N7:0", "N7:1", "N7:9", "B3/0", "B3:1/1", "B3/17", "O:0/0", "I:012/17", "S:1/15", "S:24", "T4:0",
                "T4:0.ACC", "T4:0/DN", "T4:0.DN", "C5:0", "C5:0.PRE", "C5:0/OV", "R6:0", "R6:0.LEN", "R6:0/ER",
                "F8:0", "F8:2", "ST9:0", "ST9:0.LEN", "#N7:0", "N7:[N7:1]", "N[N7:2]:0", "N7:0/[N7:3]",
                "B3/[N7:3]", "n7:0", "t4:0.dn", "O0:0/0", "T4:0.ACC/3", "N10:0", "F11:0", "ST12:1"]
ADDRESSES_BAD = ["N7:", "N7:-1", "X3:0", "ST9:0/3", "N7:0/16", "F8:0/1", "N7:10000", "I:8", "N2:0", "N7:[N7:[N7:0]]",
                 "N7:[F8:0]", "N7:[N7:0/1]", "#N7:[N7:1]", "N[N7:2]:[N7:1]", "T4:0.FOO", "N7", ":0", "N7:0:0",
                 "N9999:9999", "N10000:0", "B3/160000", "ST9:0.LEN/1", "N7:0/", "N7:[N7:1", "N7:]", "N7:[]",
                 "O:40", "I:77/20", "S:128", "N7:0/-1", "#T4:0.ACC", "N[N7:0]", "N[B3/0]:0", "ST9:9999.LEN",
                 "R6:0.POS/15", "C5:0/13", "N7:00000000000000000000001", "N\u0667:0", "N7:\u0661", "N7:0 ",
                 " N7:0", "N7\x00:0", "N7:0\n", "𝄞7:0", "N7:0/1.5"]


def interesting_address(rnd: random.Random, profile: Profile) -> str:
    k = rnd.randrange(8)
    if k <= 2:
        return rnd.choice(ADDRESSES_OK)
    if k <= 4:
        return rnd.choice(ADDRESSES_BAD)
    if k == 5:  # numbers at the edges in each position
        n = lambda: interesting_int(rnd, profile, signed=rnd.randrange(6) == 0)
        return rnd.choice([f"N{n()}:0", f"N7:{n()}", f"B3/{n()}", f"N7:0/{n()}", f"T4:{n()}.ACC",
                           f"ST{n()}:0", f"I:{n()}/0", f"N7:[N7:{n()}]", f"#N7:{n()}", f"F8:{n()}"])
    if k == 6:  # indirect nesting
        depth = rnd.choice([2, 3, 10, 100])
        return "N7:[" * depth + "N7:0" + "]" * depth
    return mutate_text(rnd, rnd.choice(ADDRESSES_OK), profile, 1)


# -- byte and token mutation ---------------------------------------------------------------

INTERESTING_BYTES = [0x00, 0xFF, 0x80, 0xC0, 0xC3, 0xE2, 0xF0, 0xF4, 0xED, 0xEF, 0xBB, 0xBF, 0x0A, 0x0D, 0x09,
                     0x0C, 0x0B, 0x1A, 0x22, 0x27, 0x5B, 0x5D, 0x28, 0x29, 0x2C, 0x3B, 0x3D, 0x23, 0x25, 0x5C,
                     0x2F, 0x3A, 0x7F, 0x20]

_TOKEN = re.compile(rb"\s+|[()\[\],;\"=<>#:/]|[^\s()\[\],;\"=<>#:/]+")

# Ladder words and punctuation for splicing; numbers and addresses are added per draw.
LADDER_TOKENS = ["BST", "NXB", "BND", "SOR", "EOR", "[", "]", "(", ")", ",", ";", "//", "\"", "=", "FILE", "DATA",
                 "SYMBOL", "LBL", "JMP", "JSR", "SBR", "RET", "TND", "MCR", "AFI", "XIC", "XIO", "OTE", "MOV",
                 "CPT", "CMP", "TON", "CTU", "COP", "FLL", "ONS", "NOT", "MOD", "**", "|", "SQR", "\n", "\r\n",
                 "\t", "#", "ST9", "STRPRINT", "COMPRINT", "MBR_GETSTATUS"]


def _tokens(data: bytes) -> list[bytes]:
    return _TOKEN.findall(data)


MAX_INPUT = 2_000_000


def mutate_bytes(rnd: random.Random, data: bytes, profile: Profile, count: int,
                 dictionary: list[str] | None = None) -> bytes:
    """``count`` random mutations of ``data``: byte level (only when the
    profile allows byte_mutation) and token level (always)."""
    for _ in range(count):
        data = _one_mutation(rnd, data, profile, dictionary or LADDER_TOKENS)
    return data


def _one_mutation(rnd: random.Random, data: bytes, profile: Profile, dictionary: list[str]) -> bytes:
    raw_ops = ["flip", "set", "insert", "delete", "truncate", "nul", "high"]
    token_ops = ["dup_range", "tok_replace", "tok_splice", "tok_dup", "tok_delete", "tok_swap", "line_dup",
                 "line_delete", "line_swap", "long_line", "number", "crlf"]
    # Byte-level damage a quarter of the time: most inputs should still get past the reader.
    op = rnd.choice(raw_ops if profile.allows("byte_mutation") and rnd.randrange(4) == 0 else token_ops)
    n = len(data)
    if n > MAX_INPUT and op in ("dup_range", "line_dup", "long_line", "tok_dup", "insert", "tok_splice"):
        op = "truncate"  # inputs stay under a few MB
    if op == "flip" and n:
        i = rnd.randrange(n)
        return data[:i] + bytes([data[i] ^ (1 << rnd.randrange(8))]) + data[i + 1:]
    if op == "set" and n:
        i = rnd.randrange(n)
        return data[:i] + bytes([rnd.choice(INTERESTING_BYTES)]) + data[i + 1:]
    if op == "insert":
        i = rnd.randrange(n + 1)
        blob = bytes(rnd.choice(INTERESTING_BYTES) if rnd.randrange(2) else rnd.randrange(256)
                     for _ in range(rnd.randint(1, 8)))
        return data[:i] + blob + data[i:]
    if op == "delete" and n:
        i = rnd.randrange(n)
        return data[:i] + data[i + rnd.randint(1, 16):]
    if op == "truncate" and n:
        return data[:rnd.randrange(n)]
    if op == "nul":
        i = rnd.randrange(n + 1)
        return data[:i] + b"\x00" + data[i:]
    if op == "high":
        i = rnd.randrange(n + 1)
        return data[:i] + rnd.choice([b"\xff", b"\xc3", b"\xe2\x82", b"\xed\xa0\x80", b"\xf4\x90\x80\x80",
                                      b"\xc0\xaf", b"\x80"]) + data[i:]
    if op == "dup_range" and n:
        i = rnd.randrange(n)
        j = min(n, i + rnd.randint(1, 200))
        return data[:j] + data[i:j] * rnd.choice([1, 2, 10, 100]) + data[j:]
    if op == "crlf":
        return data.replace(b"\n", rnd.choice([b"\r\n", b"\r", b"\n\n", b"\x0b", b"\x0c"]))
    lines = data.split(b"\n")
    if op == "line_dup":
        i = rnd.randrange(len(lines))
        lines[i:i] = [lines[i]] * rnd.choice([1, 2, 50])
        return b"\n".join(lines)
    if op == "line_delete" and len(lines) > 1:
        del lines[rnd.randrange(len(lines))]
        return b"\n".join(lines)
    if op == "line_swap" and len(lines) > 1:
        i, j = rnd.randrange(len(lines)), rnd.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
        return b"\n".join(lines)
    if op == "long_line":
        i = rnd.randrange(len(lines))
        # The line repeated, up to about 4 MB: mutations applied one after another
        # once multiplied an already long line by 2000 twice (a MemoryError in the harness).
        piece = b" " + ((lines[i].strip() or b"x")[:2000])
        lines[i] = lines[i] + piece * rnd.choice([100, 2000])
        return b"\n".join(lines)
    toks = _tokens(data)
    if not toks:
        return data + rnd.choice(dictionary).encode()
    i = rnd.randrange(len(toks))
    word = _dictionary_word(rnd, profile, dictionary).encode("utf-8", "surrogatepass")
    if op == "number":
        nums = [k for k, t in enumerate(toks) if t[:1].isdigit() or t[:1] == b"-" and t[1:2].isdigit()]
        if nums:
            i = rnd.choice(nums)
        toks[i] = interesting_number(rnd, profile).encode()
    elif op == "tok_replace":
        toks[i] = word
    elif op == "tok_splice":
        toks.insert(i, rnd.choice([word, b" " + word + b" "]))
    elif op == "tok_dup":
        toks[i:i] = [toks[i]] * rnd.choice([1, 2, 30])
    elif op == "tok_delete":
        del toks[i]
    elif op == "tok_swap":
        j = rnd.randrange(len(toks))
        toks[i], toks[j] = toks[j], toks[i]
    return b"".join(toks)


def _dictionary_word(rnd: random.Random, profile: Profile, dictionary: list[str]) -> str:
    k = rnd.randrange(6)
    if k == 0:
        return interesting_number(rnd, profile)
    if k == 1:
        return interesting_address(rnd, profile)
    if k == 2:
        return rnd.choice(ODD_CHARS[:10]) if not profile.allows("check_run") else rnd.choice(ODD_CHARS)
    return rnd.choice(dictionary)


def mutate_text(rnd: random.Random, text: str, profile: Profile, count: int) -> str:
    """Token mutations of a short text (an address, an argument)."""
    out = mutate_bytes(rnd, text.encode("utf-8"), profile, count)
    return out.decode("utf-8", "replace") if not profile.allows("byte_mutation") else out.decode("utf-8", "surrogateescape")


def encode_variant(rnd: random.Random, text: str, profile: Profile) -> bytes:
    """``text`` as UTF-8, or (when the profile allows non_utf8) in another
    encoding, with or without a BOM."""
    k = rnd.randrange(1, 7) if profile.allows("non_utf8") and rnd.randrange(4) == 0 else 0
    if k == 1:
        return b"\xef\xbb\xbf" + text.encode("utf-8", "surrogatepass")
    if k == 2:
        return text.encode("utf-16", "surrogatepass")  # with a BOM
    if k == 3:
        return text.encode(rnd.choice(["utf-16-le", "utf-16-be"]), "surrogatepass")
    if k == 4:
        return text.encode("latin-1", "replace") + b"\xe9\xff"
    if k == 5:
        raw = bytearray(text.encode("utf-8", "surrogatepass"))
        if raw:
            raw[rnd.randrange(len(raw))] = rnd.choice([0xFF, 0x80, 0xC3, 0xFE])
        return bytes(raw)
    return text.encode("utf-8", "surrogatepass") if k != 6 else b"\xef\xbb\xbf" + text.encode("utf-8", "surrogatepass")


# -- ladder ------------------------------------------------------------------------------------

def deep_branch(rnd: random.Random, depth: int, neutral: bool) -> str:
    if neutral:
        shape = rnd.randrange(3)
        if shape == 0:
            return "[" * depth + "XIC(B3/0)" + ",XIO(B3/1)]" * depth + "OTE(O:0/0);\n"
        if shape == 1:  # outputs at the bottom of every leg
            return "XIC(B3/0)" + "[XIC(B3/1)," * depth + "OTE(O:0/0)" + "]" * depth + ";\n"
        return "[" * depth + "XIC(B3/0)" + "]" * depth + "OTE(O:0/0);\n"
    shape = rnd.randrange(3)
    if shape == 0:
        return "BST " * depth + "XIC B3/0 " + "NXB XIO B3/1 BND " * depth + "OTE O:0/0\n"
    if shape == 1:
        return "XIC B3/0 " + "BST XIC B3/1 NXB " * depth + "OTE O:0/0 " + "BND " * depth + "\n"
    return "SOR " + "BST XIC B3/0 NXB\n" * depth + "XIO B3/2 " + "BND\n" * depth + "OTE O:0/1 EOR\n"


def long_expression(rnd: random.Random, size: int, profile: Profile) -> str:
    k = rnd.randrange(6)
    if k == 0:
        return " + ".join(rnd.choice(["N7:1", "1", "2.5", "F8:0", "N7:[N7:1]"]) for _ in range(size))
    if k == 1:
        return "(" * size + "N7:1" + ")" * size
    if k == 2:
        return "NOT " * size + "N7:1"
    if k == 3:
        return "-" * size + "N7:1" if rnd.randrange(2) else "- " * size + "N7:1"
    if k == 4:
        return "ABS(" * size + "N7:1" + ")" * size
    ops = ["+", "-", "*", "|", "MOD", "**", "AND", "OR", "XOR"]
    out = "N7:1"
    for _ in range(size):
        out = f"({out} {rnd.choice(ops)} {rnd.choice(['N7:2', '3', 'F8:1', '0'])})"
    return out


def ladder_shape(rnd: random.Random, profile: Profile) -> tuple[str, str]:
    """A hand-made program at an edge of the language: (text, note)."""
    k = rnd.randrange(14)
    neutral = rnd.randrange(2) == 1
    if k == 0:
        depth = rnd.choice([2, 10, 40] + ([100, 300, 1000, 3000] if profile.allows("deep_branch") else []))
        return deep_branch(rnd, depth, neutral), f"branches {depth} deep ({'neutral' if neutral else 'mnemonic'})"
    if k == 1:
        size = rnd.choice([3, 20, 50] + ([200, 1000, 5000] if profile.allows("long_expr") else []))
        expr = long_expression(rnd, size, profile)
        ins = rnd.choice(["CPT", "CMP"])
        if ins == "CMP":
            expr = f"{expr} > 0"
        text = f"CPT(N7:0,{expr});\n" if neutral and ins == "CPT" else (
            f"CMP({expr})OTE(O:0/0);\n" if neutral else
            (f'CPT N7:0 "{expr}"\n' if ins == "CPT" else f'CMP "{expr}" OTE O:0/0\n'))
        return "MOV 3 N7:1\n" + text, f"{ins} of {size} ({'neutral' if neutral else 'mnemonic'})"
    if k == 2:  # numbers at the edges as operands
        num = interesting_number(rnd, profile)
        tmpl = rnd.choice(["MOV {n} N7:0", "MOV {n} F8:0", "ADD {n} {n} N7:0", "TON T4:0 1.0 {n} 0",
                           "CTU C5:0 {n} 0", "MOV(N7:1,N7:0)ADD({n},1,F8:0);", "CPT N7:0 \"{n} * 2\"",
                           "EQU N7:0 {n} OTE O:0/0", "JMP {n}\nLBL {n} OTE O:0/1", "MOV -{n} N7:0",
                           "FLL {n} #N7:0 3", "COP #N7:0 #N7:3 {n}", "BTD {n} 0 N7:0 0 16", "JSR {n}"])
        if "F8" in tmpl and not profile.allows("inf_float"):
            num = num if "e" not in num or "999" not in num else "1.5"
        return tmpl.replace("{n}", num) + "\n", f"number {num[:30]}"
    if k == 3:  # DATA declarations
        lines = []
        for _ in range(rnd.randint(1, 4)):
            ftype = rnd.choice(["N", "B", "F", "ST", "T", "C", "R", "I", "O", "S", "X", "n", "st"])
            number = rnd.choice(["3", "9", "10", "12", "999", "9999", "10000", "0", "1", "2", "-1"] +
                                [interesting_int(rnd, profile, signed=False)])
            size = rnd.choice(["0", "1", "3", "82", "10000", "10001"] + [interesting_int(rnd, profile, signed=False)])
            values = []
            for _ in range(rnd.randint(0, 5)):
                if ftype.upper() == "ST" or rnd.randrange(5) == 0:
                    s = interesting_text(rnd, profile, 30).replace('"', '\\"').replace("\n", " ").replace("\r", " ")
                    values.append('"' + s + '"')
                else:
                    values.append(rnd.choice([interesting_number(rnd, profile), "-5", "1", "0"]))
            lines.append(f"DATA {ftype}{number} {size}" + (" = " + " ".join(values) if values else ""))
        if profile.allows("check_run") and rnd.randrange(3) == 0:
            lines.append("DATA ST9 1 = \"a\"\nDATA N9 2")
        return "\n".join(lines) + "\nXIC B3/0 OTE O:0/0\n", "DATA declarations"
    if k == 4:  # FILE headers
        n = rnd.choice(["0", "1", "2", "3", "999", "1000", "-1", "3 Name", "3 Name // c", "3 3"] +
                       [interesting_int(rnd, profile, signed=False)])
        return (f"JSR 3\nFILE {n}\nSBR\nMOV 1 N7:0\nRET\n" + rnd.choice(["", "FILE 3\nXIC B3/0 OTE O:0/0\n", "FILE 2\n"]),
                f"FILE {n[:30]}")
    if k == 5:  # SYMBOL declarations
        name = rnd.choice(["Start", "XIC", "BST", "N7", "A" * 1000, "_", "a1", "\u00e9t\u00e9", "Start Start"])
        target = interesting_address(rnd, profile)
        return f"SYMBOL {name} {target}\nXIC B3/0 OTE O:0/0\n" + rnd.choice(["", f"MOV 1 {name.split()[0]}\n"]), "SYMBOL"
    if k == 6 and profile.allows("empty_program"):
        return rnd.choice(["", "\n", "// only a comment\n", "SYMBOL A N7:0\n", "DATA N10 3\n", "FILE 3\nSBR\n",
                           "\ufeff", "FILE 2\n"]), "no rungs"
    if k == 7:  # strings in DATA
        s = interesting_text(rnd, profile, 90).replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        return f'DATA ST9 2 = "{s}" "\\x41\\u00e9"\nXIC B3/0 OTE O:0/0\n', "DATA string"
    if k == 8:  # a self-recursive subroutine
        return "JSR 3\nFILE 3\nSBR\nADD N7:0 1 N7:0\nJSR 3\nRET\n", "JSR recursion"
    if k == 9:  # a backward jump: a watchdog fault after S:28 ms
        return "LBL 1\nADD N7:0 1 N7:0\nJMP 1\n", "backward JMP loop"
    if k == 10:  # many rungs
        n = rnd.choice([100, 2000, 20000])
        return "XIC B3/0 OTE O:0/0\n" * n, f"{n} rungs"
    if k == 11:  # many operands / instructions on one rung
        n = rnd.choice([50, 1000, 10000])
        return "XIC B3/0 " * n + "OTE O:0/0\n", f"{n} instructions in series"
    if k == 12:  # strings and escapes as operands
        return rnd.choice(['MOV "abc" N7:0\n', 'CPT N7:0 "\\"1\\""\n', 'CPT N7:0 ""\n', 'CMP "" OTE O:0/0\n',
                           'XIC "B3/0" OTE O:0/0\n', 'CPT N7:0 "N7:0 = 1"\n', 'CMP "1 = 1 = 1" OTE O:0/0\n',
                           'CPT N7:0 "1 / 2"\n', 'CPT N7:0 "SQR(-1)"\n', 'CPT F8:0 "LN(0)"\n',
                           'CPT F8:0 "10 ** 40"\n', 'CPT N7:0 "2 ** 2 ** 2"\n', 'CPT F8:0 "ASN(2)"\n',
                           'CPT N7:0 "FOO(1)"\n', 'CPT N7:0 "N7:0 N7:1"\n']), "expression text"
    if k == 13 and rnd.randrange(2):  # comments and strings where they may confuse fmt
        return rnd.choice([
            "// c ; d\nXIC(B3/0)OTE(O:0/0); // e ; f\n", "XIC B3/0 OTE O:0/0 //\n", "//\n//\nXIC B3/0 OTE O:0/0\n",
            "SOR XIC B3/0 // inside\n OTE O:0/0 EOR // after\n", "XIC(B3/0) // inside\nOTE(O:0/0);\n",
            "// EOR\nXIC B3/0 OTE O:0/0\n", 'DATA ST9 1 = "// not a comment"\nXIC B3/0 OTE O:0/0\n',
            'DATA ST9 1 = "a;b" // c\nXIC B3/0 OTE O:0/0\n', 'CPT N7:0 "1 // 2"\n', "XIC B3/0\tOTE O:0/0\f\n",
            "SYMBOL A N7:0 // c\nDATA N10 2 // d\nFILE 3 Sub // e\nSBR\n", "FILE 2 // c\nXIC B3/0 OTE O:0/0\n",
            'DATA ST9 2 = "\\" "\\\\" "\\n"\nXIC B3/0 OTE O:0/0\n', 'DATA ST9 1 = "a\\"b"\nXIC B3/0 OTE O:0/0\n',
            "XIC B3/0 OTE O:0/0 // \u00e9 \U0001F600\n", "XIC B3/0 OTE O:0/0\r\nXIO B3/1 OTE O:0/1\r\n",
            "SOR\nXIC B3/0\n\nOTE O:0/0\nEOR\n", "XIC(B3/0)\n\n\nOTE(O:0/0);\n", "XIC(B3/0)OTE(O:0/0)\n;\n",
            "// a\n\n// b\nXIC B3/0 OTE O:0/0\n", "XIC b3/0 ote o:0/0\n", "xic(b3/0)ote(o:0/0);\n",
            "sor xic b3/0 ote o:0/0 eor\n", "XIC B3/0 bst OTE O:0/0 nxb OTE O:0/1 bnd\n",
            "file 3\nsbr\nret\ndata n10 2 = 1 2\nsymbol a n7:0\n", "LBL 0 XIC B3/0 OTE O:0/0\nJMP 0\n",
        ]), "comments and strings"
    # MCR/AFI/TND/ONS corner shapes
    return rnd.choice(["MCR\nMCR\n", "MCR\n", "AFI\n", "TND\n", "ONS B3/0\n", "OTE O:0/0 XIC B3/0\n", "SOR EOR\n",
                       "SOR\nEOR\n", ";\n", "[];\n", "[,];\n", "XIC(B3/0)[,OTE(O:0/0)];\n", "RET\n", "SBR\n",
                       "BST BND OTE O:0/0\n", "BST NXB BND OTE O:0/0\n", "XIC B3/0 BST OTE O:0/0 NXB BND\n",
                       "LBL 1\nLBL 1\n", "XIC B3/0 // c\n", "XIC(B3/0)OTE(O:0/0); XIC(B3/1)OTE(O:0/1);\n",
                       "XIC B3/0 OTE O:0/0 XIC(B3/1)OTE(O:0/1);\n"]), "corner rung"


COMGENIUS_RUNGS = ["XIC B3/0 STRPRINT ST12:1 2 N7:0 F8:0", "STRSCAN R6:0 ST12:0 1 F8:0 N7:0",
                   "STRPRINT(ST12:1,2,N7:0,F8:0);", "XIC S:1/15 COMPRINT R6:1 0 1 N7:0 N7:1",
                   "COMSCAN R6:2 0 2 N7:2 N7:3", "COMRCVSTS 0 C5:0", "COMRCVCLEAR 0", "COMXMITCLEAR 0"]


def ladder_text(draw, rnd: random.Random, profile: Profile) -> tuple[str, str]:
    """A program: drawn by ladder_strategies (and printed in either style),
    or a hand-made shape; then 0..4 token mutations."""
    if rnd.randrange(3):
        prog = draw(programs(max_rungs=5))
        style = rnd.choice(["mnemonic", "neutral"])
        text = format_program(prog, style)
        note = f"generated ({style})"
        if rnd.randrange(4) == 0:  # mix the styles rung by rung
            other = format_program(prog, "neutral" if style == "mnemonic" else "mnemonic").splitlines()
            lines = text.splitlines()
            if len(other) == len(lines):
                text = "\n".join(a if rnd.randrange(2) else b for a, b in zip(lines, other)) + "\n"
                note += " mixed styles"
    else:
        text, note = ladder_shape(rnd, profile)
    return text, note


def ladder_bytes(rnd: random.Random, text: str, profile: Profile) -> tuple[bytes, str]:
    n = rnd.choice([0, 0, 0, 1, 1, 2, 3])
    data = mutate_bytes(rnd, text.encode("utf-8", "surrogatepass"), profile, n)
    note = f" +{n} mutations" if n else ""
    if profile.allows("non_utf8") and rnd.randrange(10) == 0:
        data = encode_variant(rnd, data.decode("utf-8", "replace"), profile)
        note += " re-encoded"
    return data, note


# -- base apps -------------------------------------------------------------------------------


def program_files(name: str) -> dict[str, bytes]:
    """The files of programs/NAME (no .softplc state)."""
    base = PROGRAMS / name
    return {f"app/{p.name}": p.read_bytes() for p in sorted(base.iterdir()) if p.is_file()}


RUN = ["run", "{d}/app", "--scans", "3", "--fresh", "--state", "{d}/state"]
CHECK = ["check", "{d}/app"]


# -- per-kind case generators -----------------------------------------------------------


def case_ladder(draw, rnd, profile) -> Case:
    text, note = ladder_text(draw, rnd, profile)
    data, more = ladder_bytes(rnd, text, profile)
    files = {"app/main.lad": data}
    if rnd.randrange(4) == 0:  # an app with COMGENIUS, and some of its instructions
        files.update({"app/MODULES.LST": b"COMGENIUS\n",
                      "app/COMGENIUS.LST": (PROGRAMS / "loopback" / "COMGENIUS.LST").read_bytes()})
        extra = "\n".join(rnd.sample(COMGENIUS_RUNGS, rnd.randint(1, 3))) + "\n"
        files["app/main.lad"] = data + b"\n" + extra.encode()
    commands = [RUN + ["--executor", "reference"]] if rnd.randrange(4) == 0 else []
    if rnd.randrange(6) == 0 and (profile.allows("watch_deep") or "branches" not in note) and (
            profile.allows("empty_program") or "no rungs" not in note):
        commands.append(["watch", "{d}/app", "--snapshot", "{d}/view.txt", "--scans", "2", "--fresh",
                         "--state", "{d}/state"])
    return Case("ladder", files, commands, app="app", fmt=["app/main.lad"], target="app/main.lad",
                note=note + more)


def _toml_value(rnd, profile) -> str:
    k = rnd.randrange(40)
    good = rnd.choice(["10", "1", "0", "500", "32", '"clamp"', '"wrap"', '"overflow"', '"fault"', "100"])
    if k < 6 or k > 12 or not profile.allows("toml_range"):
        return good
    if k == 6:
        return interesting_int(rnd, profile)
    if k == 7:
        return rnd.choice(["-1", "32768", "2147483648", "9223372036854775807", "-9223372036854775808",
                           "0x7FFF", "0o777", "0b1", "1_000", "+5", "99999999999999999999999"])
    if k == 8:
        return rnd.choice(["1.5", "1e3", "inf", "-inf", "nan", "1e999" if profile.allows("inf_float") else "1e300"])
    if k == 9:
        return rnd.choice(["true", "false", '""', '"10"', "'clamp'", '"CLAMP"', '"""clamp"""'])
    if k == 10:
        return rnd.choice(["[]", "[1, 2]", "{}", "{ a = 1 }", "1979-05-27", "07:32:00", "1979-05-27T07:32:00Z"])
    if k == 11 and profile.allows("deep_json"):
        depth = rnd.choice([50, 500, 5000])
        return rnd.choice(["[" * depth + "]" * depth, "{ a = " * depth + "1" + " }" * depth])
    return good


def _display_value(rnd, profile) -> str:
    k = rnd.randrange(12)
    if k == 0:
        return json.dumps(interesting_address(rnd, profile), ensure_ascii=False)
    if k == 1:
        addr = rnd.choice(["N7:0", "N11:0", "C5:0.ACC", "T4:0", "F8:0", "ST9:0", "B3/0", "O:0", "N7:[N7:1]",
                           "Lamp", "N7:9999"])
        return f'"#{addr} {rnd.choice(["1", "8", "1000", "1", "0", "1001", interesting_int(rnd, profile, False)])}"'
    if k == 2:
        return rnd.choice(["1", "[]", "{}", "true", '"#N7:0"', '"# N7:0 5"', '"#N7:0 -1"', '"Lamp"', '""'])
    return json.dumps(rnd.choice(["C5:0.ACC", "Lamp", "N7:0", "O:0/0", "T4:1.ACC", "S:8"]))


def toml_text(rnd, profile) -> str:
    sections = {"math": ["overflow", "divide_by_zero"], "scan": ["scan_ms", "watchdog_ms", "jsr_depth"],
                "retentive": ["save_ms"]}
    lines = []
    names = sorted(sections) + ["display"] + (["other"] if rnd.randrange(8) == 0 else [])
    for name in rnd.sample(names, rnd.randint(1, len(names))):
        lines.append(f"[{name}]")
        if name == "display":
            for part in rnd.sample(["status", "summary"] + (["other"] if rnd.randrange(8) == 0 else []), rnd.randint(1, 2)):
                items = ", ".join(f'{json.dumps(interesting_text(rnd, profile, 10) if rnd.randrange(4) == 0 else f"v{i}", ensure_ascii=False)} = {_display_value(rnd, profile)}'
                                  for i in range(rnd.randint(0, 4)))
                lines.append(f"{part} = {{ {items} }}")
            continue
        keys = sections.get(name, ["x"])
        for key in rnd.sample(keys + (["unknown"] if rnd.randrange(8) == 0 else []), rnd.randint(1, len(keys))):
            value = _toml_value(rnd, profile)
            if key == "jsr_depth" and not profile.allows("jsr_depth"):
                value = rnd.choice(["1", "8", "32"])
            lines.append(f"{key} = {value}")
    return "\n".join(lines) + "\n"


def case_toml(draw, rnd, profile) -> Case:
    base = rnd.choice(["blinker", "modbus_master", "modbus_scada", "motor"])
    files = program_files(base)
    original = files.get("app/softplc.toml", b"").decode()
    text = toml_text(rnd, profile) if rnd.randrange(3) or not original else original
    data = encode_variant(rnd, text, profile)
    n = rnd.choice([0, 0, 0, 0, 1, 2])
    data = mutate_bytes(rnd, data, profile, n, ["[", "]", "=", '"', "{", "}", ",", "[scan]", "[display]", "\n",
                                                "scan_ms", "#", "'''", '"""'])
    files["app/softplc.toml"] = data
    return Case("toml", files, [RUN, ["run", "{d}/app", "--scans", "3", "--state", "{d}/state"]], app="app",
                target="app/softplc.toml", note=f"{base} +{n} mutations")


def json_doc(rnd, profile) -> str:
    doc: dict = {}
    for _ in range(rnd.randint(0, 5)):
        key = rnd.choice(["N7", "F8", "ST9", "T4", "C5", "R6", "B3", "O", "I", "S", "O0", "S2", "N10", "n7", "X3",
                          "N2", "N9999", "N10000", "ST9:0", "", "N07", "F8 ", "T4", "F7", "N9", "ST7", "T3", "B9", "N" + interesting_int(rnd, profile, False)])
        values = []
        for _ in range(rnd.randint(0, 5)):
            k = rnd.randrange(10)
            if k <= 2:
                values.append(int(interesting_int(rnd, SMALL_INTS)))
            elif k == 3:
                values.append(rnd.choice([0.5, -0.0, 3.4e38, 1e39, 1e-45, float("inf"), float("nan"), 1e308]))
            elif k == 4:
                values.append(interesting_text(rnd, profile, 90))
            elif k == 5:
                values.append(None)
            elif k == 6:
                values.append({m: int(interesting_int(rnd, SMALL_INTS)) for m in
                               rnd.sample(["PRE", "ACC", "EN", "TT", "DN", "CU", "OV", "LEN", "POS", "WORD0", "FOO"],
                                          rnd.randint(0, 3))})
            elif k == 7:
                values.append({"LEN": int(interesting_int(rnd, SMALL_INTS)), "CHARS": interesting_text(rnd, profile, 90)})
            elif k == 8:
                values.append(rnd.choice([[], [1], {}, True, "5"]))
            else:
                values.append(rnd.randint(-3, 3))
        doc[key] = values if rnd.randrange(8) else rnd.choice([5, "x", {}, None, [[1]]])
    text = json.dumps(doc, ensure_ascii=rnd.randrange(2) == 0)
    k = rnd.randrange(8)
    if k == 0 and profile.allows("huge_int"):
        text = text.replace("1", big_decimal(rnd, 5000), 1) if "1" in text else '{"N7": [' + big_decimal(rnd, 5000) + "]}"
    elif k == 1 and profile.allows("deep_json"):
        depth = rnd.choice([200, 1000, 100000])
        text = rnd.choice(['{"N7": ' + "[" * depth + "]" * depth + "}", "[" * depth + "]" * depth,
                           '{"T4": [' + '{"PRE": ' * depth + "1" + "}" * depth + "]}"])
    elif k == 2:
        text = rnd.choice(["[]", "5", '"x"', "null", "", "{", '{"N7": [1,]}', '{"N7": [1] "F8": []}', "{}",
                           '{"N7": [1], "N7": [2]}', '{"ST9": ["\\ud800"]}', '{"ST9": ["\\udc00\\ud800"]}',
                           '{"F8": [NaN, Infinity, -Infinity]}', '{"N7": [1e400]}', '{"N7": [-0]}',
                           '{"N7": [1.0]}', '{"N7": [1.5]}', '{"N7": [true]}', "\ufeff{}", '{"N7": [00]}'])
    return text


def case_datatable_json(draw, rnd, profile) -> Case:
    text = json_doc(rnd, profile) if rnd.randrange(4) else (ROOT / "docs/examples/datatable.json").read_text()
    data = encode_variant(rnd, text, profile)
    n = rnd.choice([0, 0, 1, 2])
    data = mutate_bytes(rnd, data, profile, n, ["[", "]", "{", "}", ",", ":", '"', "null", "NaN", "-", "1e999",
                                                '"N7"', '"PRE"'])
    files = program_files(rnd.choice(["blinker", "motor", "strings"]))
    files["app/datatable.json"] = data
    printed = ["--print", rnd.choice(["N7:0", "ST9:0", "T4:0", "F8:0", "N10:0", "B3/2"])]
    return Case("datatable_json", files,
                [["run", "{d}/app", "--scans", "3", "--state", "{d}/state"] + printed,
                 ["datatable", "{d}/app/datatable.json", "--dump"], ["datatable", "{d}/app/datatable.json"] + printed],
                app="app", target="app/datatable.json", located="name", note=f"+{n} mutations")


def case_load_json(draw, rnd, profile) -> Case:
    text = json_doc(rnd, profile)
    data = mutate_bytes(rnd, encode_variant(rnd, text, profile), profile, rnd.choice([0, 1]),
                        ["[", "]", "{", "}", ",", ":", '"'])
    files = program_files(rnd.choice(["blinker", "strings"]))
    files["load.json"] = data
    return Case("load_json", files,
                [RUN + ["--load", "{d}/load.json", "--dump", "{d}/out.json"],
                 ["datatable", "{d}/load.json", "--save", "{d}/out.snap", "--print", "N7:0"]],
                target="load.json", located="name")


def case_modules_lst(draw, rnd, profile) -> Case:
    base = rnd.choice(["strings", "loopback", "modbus_scada", "blinker"])
    files = program_files(base)
    names = ["COMGENIUS", "MODBMAST", "comgenius", "ModbMast", "MODBSLAV", "", "; comment", "COMGENIUS ; c",
             " COMGENIUS ", "COMGENIUS COMGENIUS", "COM GENIUS", "\tMODBMAST", "x" * 5000, "\u00c9", "1"]
    lines = [rnd.choice(names) for _ in range(rnd.randint(0, 4))]
    text = "\n".join(lines) + rnd.choice(["\n", "", "\r\n"])
    data = mutate_bytes(rnd, encode_variant(rnd, text, profile), profile, rnd.choice([0, 1]), names + [";"])
    files["app/MODULES.LST"] = data
    return Case("modules_lst", files, [RUN], app="app", target="app/MODULES.LST", note=base)


def format_string(rnd, profile) -> str:
    """A COMGENIUS format: conversions with flags, widths, precisions, modifiers."""
    out = []
    for _ in range(rnd.randint(0, 6)):
        if rnd.randrange(3) == 0:
            out.append(rnd.choice(["abc", " ", "\\r\\n", "\\x02", "\\u20ac", "\\0", "\\377", "%%", "% ", "\\\\", "\\\""]))
            continue
        flags = "".join(rnd.sample("-+ 0#*", rnd.randint(0, 2)))
        width = rnd.choice(["", "", "3", "12", "*", "0", "82", "255", "1000"] +
                           (["999999999", "99999999999999999999"] if profile.allows("format_width") else []))
        prec = rnd.choice(["", "", ".2", ".0", ".*", ".250", ".1000", "."] +
                          ([".999999999"] if profile.allows("format_width") else []))
        mod = rnd.choice(["", "", "l", "L", "h", "H", "ll"])
        conv = rnd.choice("diuoxXbfeEgGscCSRn%kq")
        out.append(f"%{flags}{width}{prec}{mod}{conv}")
    return "".join(out)


def pick(rnd: random.Random, good: list, bad: list, one_in: int = 10):
    """Mostly a good value, now and then a bad one: a case should break one
    thing, so that the rest of it gets through to what lies behind."""
    return rnd.choice(bad) if bad and rnd.randrange(one_in) == 0 else rnd.choice(good)


def comgenius_text(rnd, profile, base: str) -> str:
    if rnd.randrange(3) == 0:
        return base
    n = lambda: interesting_int(rnd, profile)
    lines = ["[DRIVER]"]
    for key in rnd.sample(["DEBUG", "PORT_ERRORS", "RETRY_MS", "COM1"] + (["VERBOSE"] if rnd.randrange(10) == 0 else []),
                          rnd.randint(0, 3)):
        val = {"DEBUG": pick(rnd, ["0", "1", "2"], ["3", "-1", ""]),
               "PORT_ERRORS": pick(rnd, ["STOP", "RETRY", "retry"], ["x"]),
               "RETRY_MS": pick(rnd, ["10", "1000", "50"], [n(), "5", "x"]),
               "COM1": pick(rnd, ["loop://", "sim://c?device=echo"], ["", "/nonexistent"]), "VERBOSE": "1"}[key]
        lines.append(f"{key}={val}")
    lines.append("[PORTS]")
    for port in range(rnd.randint(0, 2)):
        fields = [pick(rnd, [str(port), str(port + 34)], ["36", "-1", "A", n()]),
                  pick(rnd, ["loop://", "loop://", "sim://x?device=echo", "COM1"], ["", "COM99", "/nonexistent/tty"]),
                  pick(rnd, ["ISO-8859-1", "UTF-8", "UTF-16BE", "UTF-16LE", "US-ASCII", "utf-8"], ["EBCDIC"]),
                  pick(rnd, ["38400", "9600", "1"], ["0", "-5", n()]), pick(rnd, ["8", "7", "5"], ["9", n()]),
                  pick(rnd, ["N", "E", "O", "n"], ["M"]), pick(rnd, ["1", "2"], ["3"]),
                  pick(rnd, ["0", "100", "5"], ["-5", n()])]
        if rnd.randrange(12) == 0:
            fields = fields[:rnd.randrange(8)] + fields[:rnd.randrange(3)]
        lines.append(", ".join(fields))
    lines.append("[STRINGS]")
    for k in range(rnd.randint(1, 6)):
        fmt_text = format_string(rnd, profile)
        lines.append(pick(rnd, [f'{k + 1} "{fmt_text}"', f'"{fmt_text}" c', f'"{fmt_text}"'],
                          ["", "; x", f'"{fmt_text}', f'{k + 1} "{fmt_text}" "x"']))
    return "\n".join(lines) + "\n"


FORMAT_PARAMS = ["N10:0", "N10:1", "N10:11", "N10:12", "N10:19", "F8:0", "F8:1", "ST9:0", "ST9:2", "T4:0.ACC", "S:24",
                 "B3:0", "C5:0.PRE", "N7:[N7:1]", "#N10:0", "0", "-1", "3", "250", "32767", "1.5", "-2.5e3"]


def format_app(rnd: random.Random, formats: int) -> str:
    """A COMGENIUS app that prints and scans with every format 0..formats on
    every scan (STRPRINT, STRSCAN) and sends and matches them on a loop://
    port (COMPRINT, COMSCAN), each with random Params."""
    def params(scan: bool) -> str:
        pool = [p for p in FORMAT_PARAMS if not (scan and p[0] in "-0123456789")]
        return " ".join(rnd.choice(pool) for _ in range(rnd.randint(0, 6)))

    lines = ["// Every format of COMGENIUS.LST, printed, scanned, sent and matched on each scan.",
             'DATA ST9 3 = "WT: 1234.5 kg #42" "A_STRing -3.14 -4555" "\\x01\\x02"',
             "DATA N10 20 = 1 2 3 4 5 6 7 8 9 10 -1 -32768 32767 0 4 250 65 66 67 68",
             "MOV 5 N7:1"]
    for k in range(formats + 1):
        lines.append(f"STRPRINT ST9:1 {k} {params(False)}")
        lines.append(f"STRSCAN R6:{k} ST9:{rnd.randrange(3)} {k} {params(True)}")
        lines.append(f"XIO B3/1 COMPRINT R6:{20 + k} 0 {k} {params(False)}")
        lines.append(f"COMSCAN R6:{40 + k} 0 {k} {params(True)}")
    lines.append("XIC S:1/15 OTL B3/1")
    return "\n".join(lines) + "\n"


def case_comgenius_lst(draw, rnd, profile) -> Case:
    base = rnd.choice(["strings", "loopback", "modbus_master", "format"])
    if base == "format":
        files = {"app/MODULES.LST": b"COMGENIUS\n", "app/main.lad": format_app(rnd, 6).encode()}
        original = ("[DRIVER]\nDEBUG=" + rnd.choice("0012") + "\n[PORTS]\n0, loop://, " +
                    rnd.choice(["ISO-8859-1", "UTF-8", "UTF-16BE", "US-ASCII"]) + ", 38400, 8, N, 1, 20\n[STRINGS]\n" +
                    "".join(f'"{format_string(rnd, profile)}"\n' for _ in range(6)))
    else:
        files = program_files(base)
        original = files["app/COMGENIUS.LST"].decode("latin-1")
    text = comgenius_text(rnd, profile, original)
    data = text.encode("latin-1", "replace")
    n = rnd.choice([0, 0, 0, 1, 2])
    data = mutate_bytes(rnd, data, profile, n, ["[DRIVER]", "[PORTS]", "[STRINGS]", ",", '"', "%", "\\", ";", "=",
                                                "%d", "%.*hc", "%#R", "%s", "\\u", "\\x", "\\400"])
    files["app/COMGENIUS.LST"] = data
    run = ["run", "{d}/app", "--scans", "5", "--fresh", "--state", "{d}/state", "--set", "B3/0=1"]
    if base == "strings":
        run += ["--set", "NewReading=1", "--print", "Ticket"]
    return Case("comgenius_lst", files, [run], app="app", target="app/COMGENIUS.LST", note=f"{base} +{n} mutations")


MODBMAST_REQUESTS = [
    '<ReadCoils><refNum>{r0}</refNum><toBlock dest="{bdest}" count="{c}" fmt="bit"/></ReadCoils>',
    '<ReadInputDiscretes><refNum>{r1}</refNum><toBlock dest="I:0" count="{c}" fmt="{fmt}"/></ReadInputDiscretes>',
    '<ReadMultipleRegisters><refNum>{r4}</refNum><toBlock dest="{dest}" count="{c}" fmt="i2"/></ReadMultipleRegisters>',
    '<ReadInputRegisters when="{when}"><refNum>{r3}</refNum><toBlock dest="{dest}" count="{c}" fmt="i2"/>'
    '<toBlock dest="N12:0" count="1" fmt="i2"/></ReadInputRegisters>',
    '<WriteCoil><refNum>{r0}</refNum><fromBlock source="B3:1/3" count="1" fmt="bit"/></WriteCoil>',
    '<WriteSingleRegister><refNum>{r4}</refNum><fromBlock source="{dest}" count="1" fmt="i2"/></WriteSingleRegister>',
    '<ForceMultipleCoils><refNum>{r0}</refNum><fromBlock source="O:0/14" count="{c}" fmt="bit"/></ForceMultipleCoils>',
    '<WriteMultipleRegisters><refNum>{r4}</refNum><fromBlock count="{c}" fmt="i2"><const>{const}</const></fromBlock>'
    '</WriteMultipleRegisters>',
    '<MaskWriteRegister><refNum>{r4}</refNum><andMask>{n}</andMask><fromBlock source="N7:45" count="1" fmt="i2"/>'
    '</MaskWriteRegister>',
    '<ReadWriteRegisters><refNum>{r4}</refNum><toBlock dest="{dest}" count="{c}" fmt="i2"/><refNum>{r4}</refNum>'
    '<fromBlock source="N7:55" count="{c}" fmt="i2"/></ReadWriteRegisters>',
]


def modbmast_xml(rnd, profile) -> str:
    def num() -> str:
        return rnd.choice(["1", "2", "0", "10", "0x10", "0x0010", "-1", "", " 5 ", "1.5", "0x", "abc",
                           interesting_int(rnd, profile), interesting_hex(rnd, profile)])

    def attr(value_ok: str) -> str:
        return value_ok if rnd.randrange(12) else num()

    ports = []
    for p in range(rnd.randint(0, 2)):
        slaves = []
        for s in range(rnd.randint(0, 3)):
            reqs = []
            for _ in range(rnd.randint(0, 3)):
                c = attr(rnd.choice(["1", "2", "16", "125"]))
                reqs.append(rnd.choice(MODBMAST_REQUESTS).format(
                    r0=attr("00001"), r1=attr("10001"), r3=attr("30001"), r4=attr("40001"), c=c,
                    fmt=rnd.choice(["bit", "i2", "i2", "i2", "x"]),
                    dest=rnd.choice(["N10:0", "N7:0", "N10:5", "N11:0", "B3:0", "O:0", "T4:0.ACC", "N11:9999"] +
                                    (["S:0", "F8:0", "ST9:0", "N7:[N7:1]"] if rnd.randrange(6) == 0 else [])),
                    bdest=rnd.choice(["B3:0", "B3/0", "B3/3", "O:0/0"]), when=rnd.choice(["run", "run", "start", "stop", "x"]),
                    n=num(), const=", ".join(num() for _ in range(rnd.randint(0, 4)))))
            slaves.append(f'<Slave id="{attr(str(s + 1))}" attempts="{attr("1")}">' + "".join(reqs) + "</Slave>")
        device = rnd.choice(["sim://scada?device=modbus&amp;id=1,2&amp;values=index", "loop://",
                             "sim://l?device=echo", "sim://scada?device=modbus&amp;id=1&amp;turnaround_ms=" + num()])
        ports.append(f'<Port num="{attr(str(p + 1))}" baudrate="{attr("19200")}" requestTimeout="{attr("30")}" '
                     f'device="{device}" framing="{rnd.choice(["RTU", "RTU", "ascii", "x"])}">' + "".join(slaves) + "</Port>")
    head = rnd.choice(['<?xml version="1.0" encoding="UTF-8"?>\n', "", '<?xml version="1.0"?>',
                       '<?xml version="1.0" encoding="ISO-8859-1"?>\n'])
    return head + f'<ModbusSerial debug="{attr("0")}">' + "".join(ports) + "</ModbusSerial>\n"


XML_SPECIALS = ['<!DOCTYPE x [<!ENTITY a "aaaa">]>', "&a;", "&amp;", "&#0;", "&#x110000;", "<![CDATA[x]]>",
                "<!-- c -->", "<?pi x?>", "<x:Port/>", 'xmlns="urn:x"', "<Port/>", "<Slave/>", "</Port>", "<", ">",
                "'", '"', "=", "<ModbusSerial>", "\x00"]


def case_modbmast_xml(draw, rnd, profile) -> Case:
    files = program_files("modbus_scada")
    text = files["app/MODBMAST.XML"].decode() if rnd.randrange(3) == 0 else modbmast_xml(rnd, profile)
    k = rnd.randrange(8)
    if k == 0 and profile.allows("deep_json"):
        depth = rnd.choice([100, 1000, 50000])
        text = "<ModbusSerial>" + "<Port>" * depth + "</Port>" * depth + "</ModbusSerial>"
    elif k == 1:
        text = '<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;">]><ModbusSerial debug="&lol2;"/>'
    data = encode_variant(rnd, text, profile)
    n = rnd.choice([0, 0, 0, 1, 2])
    data = mutate_bytes(rnd, data, profile, n, XML_SPECIALS)
    name = rnd.choice(["MODBMAST.XML", "MODBMAST.XML", "modbus.xml"])
    del files["app/MODBMAST.XML"]
    if "<Slave id=\"3\" requestTimeout=\"30\">" not in text:  # its [display] names files the original fills
        del files["app/softplc.toml"]
    files[f"app/{name}"] = data
    return Case("modbmast_xml", files, [["run", "{d}/app", "--scans", "20", "--fresh", "--state", "{d}/state"]],
                app="app", target=f"app/{name}", note=f"+{n} mutations")


def _set_value(rnd, profile) -> str:
    k = rnd.randrange(8)
    if k == 0:
        return interesting_number(rnd, profile)
    if k == 1:
        return json.dumps(interesting_text(rnd, profile, 100), ensure_ascii=rnd.randrange(2) == 0)
    if k == 2:
        return rnd.choice(['{"PRE": 10}', '{"PRE": -1}', '{"FOO": 1}', '{"LEN": 90, "CHARS": "x"}', "[1, 2]", "null",
                           '{"PRE": "x"}', '{"PRE": 1.5}', '{"DN": 2}', '{"LEN": -1}', '{"WORD0": 65535}', '{"ACC": null}',
                           '{"CHARS": 5}', '{"LEN": 83}', '{"PRE": true}', '{"EN": 1, "TT": 1, "DN": 1, "PRE": 1, "ACC": 9}',
                           "true", "NaN", "Infinity", "-Infinity", '{"PRE": 1e999}', '""', "1.0", "-0", "=", "==1"])
    if k == 3 and profile.allows("deep_json"):
        depth = rnd.choice([100, 5000])
        return "[" * depth + "]" * depth
    if k == 4:
        return interesting_text(rnd, profile, 20)
    return str(rnd.randint(-40000, 40000))


def case_cli_args(draw, rnd, profile) -> Case:
    base = rnd.choice(["strings", "blinker", "loopback", "motor"])
    files = program_files(base)
    argv = ["run", "{d}/app", "--fresh", "--state", "{d}/state", "--scans",
            rnd.choice(["0", "1", "3", "3", "20"]) if rnd.randrange(6) else
            rnd.choice(["-1", "x", "", "1e3", "3.0", "0x10", " 3", "٣"] + ([big_decimal(rnd, 5000)] if profile.allows("huge_int") else []))]
    symbols = {"strings": ["NewReading", "Ticket", "Weight", "TicketNo", "Reading"], "blinker": ["Lamp"],
               "loopback": ["GotRack", "Rack"], "motor": ["Start", "StopOk", "Motor"]}[base]
    for _ in range(rnd.randint(0, 4)):
        opt = rnd.choice(["--set", "--set", "--print", "--print", "--scan-ms", "--port", "--executor", "--load",
                          "--dump", "--record", "--realtime"])
        if opt == "--set":
            addr = rnd.choice(symbols) if rnd.randrange(3) == 0 else interesting_address(rnd, profile)
            argv += ["--set", rnd.choice([f"{addr}={_set_value(rnd, profile)}", addr, f"={_set_value(rnd, profile)}",
                                          f" {addr} = 5"])]
        elif opt == "--print":
            argv += ["--print", rnd.choice(symbols) if rnd.randrange(3) == 0 else interesting_address(rnd, profile)]
        elif opt == "--scan-ms":
            values = ["0", "1", "10", "1", "10", "100", "-1", "32767", "32768", "x", "1.5"]
            if profile.allows("huge_args"):
                values += ["1000000", "2147483648", "99999999999999999999", str(10 ** 30)]
            argv += ["--scan-ms", rnd.choice(values)]
        elif opt == "--port":
            argv += ["--port", rnd.choice(["0=loop://", "1=loop://", "36=loop://", "0=", "=loop://", "0", "x=loop://",
                                           "COMGENIUS:0=loop://", "MODBMAST:0=loop://", "0=sim://a?device=echo",
                                           "0=/nonexistent/tty", "-1=loop://", "0=loop://", "0=sim://",
                                           "0=replay:///nonexistent?port=0", "0=sim://x?device=nosuch",
                                           f"{interesting_int(rnd, profile)}=loop://"])]
        elif opt == "--executor":
            argv += ["--executor", rnd.choice(["compiled", "reference", "reference", "x"])]
        elif opt == "--load":
            argv += ["--load", rnd.choice(["{d}/nonexistent.json", "{d}/app", "{d}/app/main.lad"])]
        elif opt == "--dump":
            argv += ["--dump", rnd.choice(["{d}/out.json", "{d}/nonexistent/out.json", "{d}/app"])]
        elif opt == "--record":
            argv += ["--record", rnd.choice(["{d}/rec.trace", "{d}/nonexistent/rec.trace", "{d}/app"])]
        else:
            argv += ["--realtime", "--scan-ms", rnd.choice(["0", "1", "2"])]
    return Case("cli_args", files, [argv], note=base)


def trace_text(rnd, profile, base: str) -> str:
    lines = base.splitlines()
    events = [k for k, line in enumerate(lines) if line.strip() and not line.startswith("#")]
    changed = set(rnd.sample(events, min(len(events), rnd.choice([0, 0, 1, 1, 2]))))
    out = []
    for number, line in enumerate(lines):
        if number not in changed:
            out.append(line)
            continue
        parts = line.split()
        k = rnd.randrange(6)
        if k == 0:
            parts[0] = rnd.choice(["0", "1e3", "-1", "99999999999999999999.5", "1.", ".5", "nan", "inf",
                                   big_decimal(rnd, rnd.choice([400, 5000])) if profile.allows("huge_int") else "9" * 300])
        elif k == 1:
            parts[1] = rnd.choice(["0", "35", "36", "MODBMAST:1", "COMGENIUS:0", "X:0", interesting_int(rnd, profile)])
        elif k == 2:
            parts[2] = rnd.choice(["TX", "RX", "tx", "XX"])
        elif k == 3:
            parts = parts[:3] + [rnd.choice(["00", "FF", "0G", "1", "123"]) for _ in range(rnd.choice([0, 1, 300, 5000]))]
        elif k == 4:
            parts = parts[:rnd.randrange(len(parts))]
        else:
            out.append(line)
        out.append(" ".join(parts))
    if rnd.randrange(5) == 0:
        out.insert(0, rnd.choice(["# softplc_lite port trace 2", "# softplc_lite port trace x",
                                  "# softplc_lite port trace " + interesting_int(rnd, profile)]))
    return "\n".join(out) + "\n"


def case_trace(draw, rnd, profile) -> Case:
    files = program_files("modbus_master")
    base = files.pop("app/pymodbus-session.trace").decode()
    text = trace_text(rnd, profile, base)
    data = mutate_bytes(rnd, encode_variant(rnd, text, profile), profile, rnd.choice([0, 0, 0, 1, 2]),
                        ["TX", "RX", "#", "00", "FF", "0", "MODBMAST:1", "\n"])
    files["replay.trace"] = data
    scans = rnd.choice(["100", "400", "1200"])
    return Case("trace", files, [["run", "{d}/app", "--fresh", "--state", "{d}/state", "--replay", "{d}/replay.trace",
                                  "--scans", scans]], target="replay.trace")


def snapshot_bytes(rnd, profile) -> bytes:
    """A snapshot: valid, or corrupted, with the CRC recomputed half of the
    time so the structure checks (not just the CRC) are what refuse it."""
    from softplc_lite.datatable import DataTable, snapshot

    t = DataTable()
    for addr, value in [("N7:5", 12), ("ST9:1", "HELLO"), ("F8:2", 1.5), ("T4:1.PRE", 10), ("N10:0", -1)]:
        if rnd.randrange(2):
            t.reference(addr)
            t.write(addr, value)
    if rnd.randrange(3) == 0:  # a file the program declares with another type (the program changed since)
        for addr in rnd.sample(["N9:3", "F7:0", "ST7:0", "T3:1", "B9:0", "N6:0", "C8:2", "R7:0", "F10:9999"], 2):
            try:
                t.reference(addr)
            except Exception:  # noqa: BLE001 - a number already taken by another type
                pass
    raw = bytearray(snapshot.encode(t))
    head, trailer = 24, 12
    k = rnd.randrange(9)
    if k == 0:
        return bytes(raw)
    if k == 1:  # header fields
        field_at = rnd.choice([(8, "<H"), (10, "<H"), (12, "<I"), (16, "<Q")])
        value = rnd.choice([0, 1, 2, 0xFFFF, 0xFFFFFFFF, 2 ** 63, len(raw)]) % (256 ** struct.calcsize(field_at[1]))
        struct.pack_into(field_at[1], raw, field_at[0], value)
    elif k == 2:  # a file record's fields
        struct.pack_into("<2sHI", raw, head, rnd.choice([b"N ", b"ST", b"X ", b"\xff\xff", b"  ", b"n ", b"S ", b"O "]),
                         rnd.choice([0, 1, 2, 3, 7, 9999, 10000, 65535]), rnd.choice([0, 1, 5, 9999, 10000, 10001, 2 ** 32 - 1]))
    elif k == 3:
        del raw[rnd.randrange(len(raw)):]
    elif k == 4:
        raw += bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 20)))
    elif k == 5:
        return bytes(rnd.randrange(256) for _ in range(rnd.choice([0, 1, 43, 44, 100])))
    else:
        for _ in range(rnd.randint(1, 4)):
            i = rnd.randrange(len(raw))
            raw[i] = rnd.randrange(256)
    if rnd.randrange(2) and len(raw) >= head + trailer:
        body_len = len(raw) - head - trailer
        struct.pack_into("<Q", raw, 16, body_len) if rnd.randrange(2) else None
        crc = zlib.crc32(bytes(raw[head:head + body_len]), zlib.crc32(bytes(raw[:head])))
        struct.pack_into("<I8s", raw, head + body_len, crc, b"SPLCEND!")
    return bytes(raw)


def case_snapshot_file(draw, rnd, profile) -> Case:
    files = {"t.snap": snapshot_bytes(rnd, profile)}
    printed = ["--print", rnd.choice(["N7:5", "ST9:1", "F8:2", "T4:1", "N10:0", "S:0"])]
    return Case("snapshot_file", files, [["datatable", "{d}/t.snap", "--dump"], ["datatable", "{d}/t.snap"] + printed,
                                         ["datatable", "{d}/t.snap", "--save", "{d}/out.snap"]],
                target="t.snap", located="name")


def case_snapshot_app(draw, rnd, profile) -> Case:
    files = program_files(rnd.choice(["blinker", "strings"]))
    files["app/.softplc/datatable.snap"] = snapshot_bytes(rnd, profile)
    if rnd.randrange(2):
        files["app/.softplc/datatable.snap.prev"] = snapshot_bytes(rnd, profile)
    return Case("snapshot_app", files, [["run", "{d}/app", "--scans", "3", "--print", "N7:5"]],
                target="app/.softplc/datatable.snap", located="name")


def case_address(draw, rnd, profile) -> Case:
    args = [interesting_address(rnd, profile) for _ in range(rnd.randint(1, 4))]
    return Case("address", {}, [["address", *args]])


def case_watch(draw, rnd, profile) -> Case:
    base = rnd.choice(["blinker", "motor", "strings", "generated"])
    if base == "generated":
        prog = draw(programs(max_rungs=4))
        files = {"app/main.lad": format_program(prog, "mnemonic").encode()}
    else:
        files = program_files(base)
    argv = ["watch", "{d}/app", "--snapshot", rnd.choice(["{d}/view.txt", "{d}/view.svg"]), "--scans",
            rnd.choice(["0", "1", "5", "5", "20"] + (["-1"] if rnd.randrange(8) == 0 else [])), "--fresh", "--state", "{d}/state"]
    sizes = ["40", "100", "60", "12", "200", "120"] + (["39", "11", "x"] if rnd.randrange(8) == 0 else []) + (
        ["100000", "2147483648"] if profile.allows("huge_args") and rnd.randrange(4) == 0 else [])
    if rnd.randrange(2):
        argv += ["--width", rnd.choice(sizes), "--height", rnd.choice(sizes)]
    for _ in range(rnd.randint(0, 3)):
        opt = rnd.choice(["--watch", "--force", "--break-when", "--set", "--watch-file"])
        if opt == "--watch":
            argv += ["--watch", interesting_address(rnd, profile)]
        elif opt == "--force":
            argv += ["--force", rnd.choice([f"{interesting_address(rnd, profile)}={rnd.choice(['0', '1', '2', 'x', ''])}",
                                            "B3/0=1", "O:0/0=0", "N7:0=1", "B3/0", "I:0/0=1", "Lamp=1", "Start=1",
                                            "ST9:0=1", "T4:0/DN=1", "T4:0=1", "N7:0/3=1", "B3/[N7:1]=1", "S:1/15=1"])]
        elif opt == "--break-when":
            size = rnd.choice([1, 3] + ([300, 3000] if profile.allows("long_expr") else []))
            argv += ["--break-when", rnd.choice([
                "N7:0 > 100", "R6:0/ER", "B3/0", "N7:0 = " + interesting_number(rnd, profile), "N7:0 >", "> 1",
                "", "N7:0 > 1 > 2", "(N7:0 > 1)", "NOT B3/0", "N7:0 + 1 > 2", long_expression(rnd, size, profile) + " > 0",
                "S:1/15", "T4:0/DN", "F8:0 > 1e999", "ST9:0 = 1", interesting_address(rnd, profile),
                'ST9:0 = "x"', "ST9:0 > ST9:1", "F8:0 > N7:0", "T4:0 > 1", "R6:0 = 1", "#N7:0 > 1", "N7:[N7:1] > 0",
                "T4:0.ACC >= T4:0.PRE", "N7:0 <> 0", "B3/0 = 1", "N7:0/3", "Lamp", "Start = 1", "N7:0 > 1.5",
                "NOT", "N7:0 = = 1", "1 > 0", "N7:0 AND 3"])]
        elif opt == "--set":
            argv += ["--set", f"{interesting_address(rnd, profile)}={_set_value(rnd, profile)}"]
        else:
            lines = [interesting_address(rnd, profile) for _ in range(rnd.randint(0, 5))] + ["# c", "", "  N7:0  "]
            files["watch.txt"] = encode_variant(rnd, "\n".join(rnd.sample(lines, len(lines))), profile)
            argv += ["--watch-file", "{d}/watch.txt"]
    return Case("watch", files, [argv], note=base)


GENERATORS = {
    "ladder": case_ladder,
    "toml": case_toml,
    "datatable_json": case_datatable_json,
    "load_json": case_load_json,
    "modules_lst": case_modules_lst,
    "comgenius_lst": case_comgenius_lst,
    "modbmast_xml": case_modbmast_xml,
    "cli_args": case_cli_args,
    "trace": case_trace,
    "snapshot_file": case_snapshot_file,
    "snapshot_app": case_snapshot_app,
    "address": case_address,
    "watch": case_watch,
    # Kinds of other modules: files that are not what their name promises, damaged state,
    # signals at random moments, hostile Modbus TCP requests.
    "special_files": fuzz_files.case_special_files,
    "state_damage": fuzz_files.case_state_damage,
    "signals": fuzz_signals.case_signals,
    "modbus_tcp": fuzz_protocol.case_modbus_tcp,
}
KINDS = list(GENERATORS)


@st.composite
def cases(draw, kinds: list[str] | None = None, profile: Profile = EVERYTHING) -> Case:
    """A case of one of ``kinds`` (default: every kind)."""
    number = draw(st.integers(0, 2 ** 32 - 1))
    rnd = random.Random(number)
    kind = rnd.choice(kinds or KINDS)  # uniform (hypothesis would favour the first)
    case = GENERATORS[kind](draw, rnd, profile)
    # A command line cannot hold NUL; everything else goes.
    case.commands = [[a.replace("\x00", "") for a in argv] for argv in case.commands]
    return case
