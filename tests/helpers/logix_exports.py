"""Shared by the Logix export readers' tests: a Project without its
positions (to compare what two formats say), and damaged copies of an
export's text (to check that any input gives a Project or an ExportError)."""

from __future__ import annotations

import dataclasses
import random

from softplc_lite.ladder.ast import NOWHERE


def without_positions(obj):
    """``obj`` (a model dataclass, list or value) with every ``pos`` set
    to NOWHERE, so that equality compares only what the export says."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        changes = {f.name: without_positions(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
        if "pos" in changes:
            changes["pos"] = NOWHERE
        return dataclasses.replace(obj, **changes)
    if isinstance(obj, list):
        return [without_positions(x) for x in obj]
    if isinstance(obj, dict):
        return {k: without_positions(v) for k, v in obj.items()}
    return obj


def damaged_copies(text: str, seed: int, count: int) -> list[str]:
    """Truncations at every tenth of the text, and ``count`` copies with a
    few characters deleted, duplicated or replaced by ones that matter to
    the formats (quotes, brackets, semicolons, angle brackets)."""
    rnd = random.Random(seed)
    out = [text[: len(text) * k // 10] for k in range(10)]
    specials = list("<>/\"'[](),;:=$#&\n") + ["]]>", "<![CDATA[", "END_", "(*", "*)", "16#", "2#zz"]
    for _ in range(count):
        t = text
        for _ in range(rnd.randint(1, 4)):
            i = rnd.randrange(len(t))
            j = min(len(t), i + rnd.randint(1, 12))
            op = rnd.randrange(3)
            if op == 0:
                t = t[:i] + t[j:]
            elif op == 1:
                t = t[:i] + t[i:j] + t[i:j] + t[j:]
            else:
                t = t[:i] + rnd.choice(specials) + t[j:]
        out.append(t)
    return out
