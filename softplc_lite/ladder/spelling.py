"""How close a misspelt name is to a known one, for "did you mean".

Closeness is the optimal string alignment distance (Damerau-Levenshtein
without repeated edits of one substring): an insertion, a deletion, a
substitution or a swap of two neighbouring letters is one edit, so ``XCI``
is one edit from ``XIC``. A name is suggested only within a distance that
grows with its length (one edit for a name of up to five letters). Among
names equally close: a name of the typed letters in another order first
(``XCI``: XIC rather than ACI, one wrong letter away too), then the
caller's preference (an output instruction where an output stands), then a
name of the typed length (a wrong letter is likelier than a missing one),
then letters typed on a neighbouring key (``OTR``: R is beside E, so OTE
rather than OTL or OTU), then the order the caller lists its names in (the
most common first). Case is ignored. These are softplc_lite choices.
"""

from __future__ import annotations

from typing import Callable, Iterable

# Neighbouring keys on a QWERTY keyboard (letters and digits, same row and the rows above and below).
_ROWS = ("1234567890", "QWERTYUIOP", "ASDFGHJKL", "ZXCVBNM")


def _neighbours() -> dict[str, frozenset[str]]:
    near: dict[str, set[str]] = {}
    for r, row in enumerate(_ROWS):
        for c, key in enumerate(row):
            keys = near.setdefault(key, set())
            for rr in (r - 1, r, r + 1):
                if 0 <= rr < len(_ROWS):
                    other = _ROWS[rr]
                    # rows are staggered about half a key: the keys at c-1..c+1 of the rows above and below
                    keys.update(other[k] for k in (c - 1, c, c + 1) if 0 <= k < len(other) and other[k] != key)
    return {k: frozenset(v) for k, v in near.items()}


NEIGHBOURS = _neighbours()


def distance(a: str, b: str) -> int:
    """The optimal string alignment distance between ``a`` and ``b``."""
    a, b = a.upper(), b.upper()
    previous2: list[int] = []
    previous = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        row = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = 0 if a[i - 1] == b[j - 1] else 1
            row[j] = min(previous[j] + 1, row[j - 1] + 1, previous[j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                row[j] = min(row[j], previous2[j - 2] + 1)
        previous2, previous = previous, row
    return previous[len(b)]


def allowed(name: str) -> int:
    """The most edits a suggestion for ``name`` may be away: one for up to
    five letters, then one more for every three."""
    return 1 + max(0, len(name) - 3) // 3


def _near_keys(typed: str, known: str) -> int:
    """How many of ``typed``'s letters that differ from ``known`` at the same
    place are a neighbouring key of its letter (same length only)."""
    if len(typed) != len(known):
        return 0
    return sum(1 for t, k in zip(typed.upper(), known.upper()) if t != k and t in NEIGHBOURS.get(k, ()))


def closest(name: str, known: Iterable[str], prefer: Callable[[str], bool] | None = None) -> str | None:
    """The name of ``known`` closest to ``name`` (see the module's rules),
    or None when none is within ``allowed(name)`` edits. ``prefer``: names
    the caller would rather suggest among equally close ones."""
    limit = allowed(name)
    letters = sorted(name.upper())
    best, best_key = None, None
    for order, candidate in enumerate(known):
        d = distance(name, candidate)
        if d > limit:
            continue
        key = (d, sorted(candidate.upper()) != letters, 0 if prefer is None or prefer(candidate) else 1,
               abs(len(candidate) - len(name)), -_near_keys(name, candidate), order)
        if best_key is None or key < best_key:
            best, best_key = candidate, key
    return best
