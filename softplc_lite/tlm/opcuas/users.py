"""The OPC UA server's user file, ``OPCUAS.USERS`` beside ``OPCUAS.XML``:
who may open a session with a user name and password, and whether that
user may write (docs/opcuas.md, "Security").

One user a line, three fields separated by blanks; ``#`` starts a comment::

    # name     rights  password hash
    operator   write   scrypt$16384$8$1$<salt>$<key>
    viewer     read    scrypt$16384$8$1$<salt>$<key>

* a name is 1 to 64 of ``A-Z a-z 0-9 _ . @ -``, each name once;
* rights are ``read`` or ``write`` (write includes read);
* the hash is scrypt (RFC 7914) with its cost (N, r, p), a salt of its own
  per user and the derived key, salt and key in base64. scrypt, from
  Python's hashlib, is a choice: memory-hard, so a stolen file costs an
  attacker far more per guess than a fast hash; the cost is stored with
  each line so a later, dearer cost leaves old lines valid.

``softplc opcua-user`` writes the lines (commands/opcua_user.py); a person
never types a hash. Checking a password compares keys in constant time
(hmac.compare_digest), and a name not in the file costs one derivation
too, so a client cannot tell an unknown name from a wrong password by the
time the answer takes."""

from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import os
import re
import secrets
from dataclasses import dataclass
from pathlib import Path

from ...errors import file_error
from ...textfile import read_text
from ..errors import ModuleError, ModuleErrors

FILE_NAME = "OPCUAS.USERS"
RIGHTS = ("read", "write")
NAME = re.compile(r"[A-Za-z0-9_.@-]{1,64}")
# scrypt's cost, a choice: 16 MiB and about 50 ms a derivation. OWASP's
# Password Storage Cheat Sheet asks N=2^17 for a web login; a PLC's server,
# whose sessions must not starve the machine it shares with the scan, takes less.
COST = (2 ** 14, 8, 1)
SALT_BYTES = 16
KEY_BYTES = 32
_MAX_N = 2 ** 20  # a line asking more would cost a server 1 GiB a session


@dataclass(frozen=True)
class UserEntry:
    """One line of the file: the user, ``write`` or not, and the hash text."""

    name: str
    can_write: bool
    hash: str


def hash_password(password: str, cost: tuple[int, int, int] = COST) -> str:
    """The hash field for ``password``, with a fresh salt."""
    n, r, p = cost
    salt = secrets.token_bytes(SALT_BYTES)
    key = _derive(password, salt, n, r, p)
    return f"scrypt${n}${r}${p}${_b64(salt)}${_b64(key)}"


def _derive(password: str, salt: bytes, n: int, r: int, p: int) -> bytes:
    return hashlib.scrypt(password.encode("utf-8"), salt=salt, n=n, r=r, p=p,
                          maxmem=128 * r * (n + p + 2) + (1 << 20), dklen=KEY_BYTES)


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def _hash_problem(text: str) -> str | None:
    """What is wrong with a hash field, or None."""
    parts = text.split("$")
    if len(parts) != 6 or parts[0] != "scrypt":
        return "expected a password hash scrypt$N$r$p$SALT$KEY (softplc opcua-user writes it)"
    n, r, p = parts[1:4]
    if not all(x.isdigit() for x in (n, r, p)):
        return "expected the scrypt cost N$r$p as three whole numbers"
    n, r, p = int(n), int(r), int(p)
    if n < 2 or n > _MAX_N or n & (n - 1) or not 1 <= r <= 32 or not 1 <= p <= 16:
        return f"expected N a power of 2 from 2 to {_MAX_N}, r from 1 to 32 and p from 1 to 16"
    try:
        salt = base64.b64decode(parts[4], validate=True)
        key = base64.b64decode(parts[5], validate=True)
    except binascii.Error:
        return "expected the salt and the key in base64"
    if len(salt) < 8 or len(key) != KEY_BYTES:
        return f"expected a salt of 8 bytes or more and a key of {KEY_BYTES} bytes"
    return None


class Users:
    """The users of one server, read from the file (an empty set when there
    is no file: then only anonymous and certificate sessions exist)."""

    def __init__(self, entries: list[UserEntry] | None = None, path: str | None = None) -> None:
        self.entries = {e.name: e for e in entries or []}
        self.path = path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "Users":
        """The file's users; no file is no users. Raises ModuleErrors naming
        every bad line (file:line:col), FileAccessError when unreadable."""
        path = os.fspath(path)
        if not os.path.exists(path):
            return cls([], path)
        return cls(parse(read_text(path), path), path)

    def check(self, name: str | None, password: str | None) -> UserEntry | None:
        """The user when ``password`` is theirs, else None."""
        entry = self.entries.get(name or "")
        stored = entry.hash if entry else _DUMMY
        n, r, p, salt, key = stored.split("$")[1:]
        derived = _derive(password or "", base64.b64decode(salt), int(n), int(r), int(p))
        ok = hmac.compare_digest(derived, base64.b64decode(key))
        return entry if ok and entry is not None else None

    def set(self, name: str, password: str, can_write: bool) -> UserEntry:
        entry = UserEntry(name, can_write, hash_password(password))
        self.entries[name] = entry
        return entry

    def remove(self, name: str) -> bool:
        return self.entries.pop(name, None) is not None

    def save(self, path: str | os.PathLike[str] | None = None) -> None:
        """Write the file (mode 0600: the hashes are secrets) through a
        temporary file renamed over it, so a reader never sees half."""
        target = Path(os.fspath(path if path is not None else self.path))
        lines = ["# OPC UA users: name, rights (read or write), password hash (docs/opcuas.md)"]
        lines += [f"{e.name}\t{'write' if e.can_write else 'read'}\t{e.hash}" for e in self.entries.values()]
        temp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        try:
            fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write("\n".join(lines) + "\n")
            os.replace(temp, target)
        except OSError as e:
            temp.unlink(missing_ok=True)
            raise file_error(e, target, "write") from None


_DUMMY = hash_password(secrets.token_hex(16))


def parse(text: str, path: str) -> list[UserEntry]:
    """The entries of a user file's text; ModuleErrors with every problem."""
    problems: list[ModuleError] = []
    entries: list[UserEntry] = []
    seen: dict[str, int] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        body = line.split("#", 1)[0]
        fields = [(m.group(), m.start() + 1) for m in re.finditer(r"\S+", body)]
        if not fields:
            continue

        def problem(message: str, column: int) -> None:
            problems.append(ModuleError(message, path, number, column))

        if len(fields) != 3:
            column = fields[3][1] if len(fields) > 3 else len(body.rstrip()) + 1
            what = "nothing more" if len(fields) > 3 else "three fields: name, rights (read or write), password hash"
            problem(f"expected {what}", column)
            continue
        (name, name_col), (rights, rights_col), (hashed, hash_col) = fields
        bad = False
        if not NAME.fullmatch(name):
            problem(f"expected a user name of 1 to 64 letters, digits, _ . @ or -, not {name[:70]!r}", name_col)
            bad = True
        elif name in seen:
            problem(f"user {name!r} is named twice (first on line {seen[name]})", name_col)
            bad = True
        else:
            seen[name] = number
        if rights not in RIGHTS:
            problem(f"expected rights read or write, not {rights[:40]!r}", rights_col)
            bad = True
        why = _hash_problem(hashed)
        if why:
            problem(why, hash_col)
            bad = True
        if not bad:
            entries.append(UserEntry(name, rights == "write", hashed))
    if problems:
        raise ModuleErrors(problems)
    return entries
