"""Values as an engineer reads them on a terminal (CLI --print, the watch
view's rungs and watch list, status lines). JSON output (``--dump``,
datatable.json) does not come through here and keeps floats exact.

Floats show 7 significant digits (``FLOAT_DIGITS``): an F element is an
IEEE single, good to about 7 digits, so ``3.14`` and not the double it
widens to, ``3.140000104904175`` (softplc choice, docs/watch.md)."""

from __future__ import annotations

import json
from typing import Any

from .address import Address, ValueKind
from .filetypes import FileType
from .table import word_text


FLOAT_DIGITS = 7


def format_float(value: float) -> str:
    """``3.14``, ``150.0``, ``1.5e+07``, ``inf``: ``FLOAT_DIGITS`` significant
    digits; a whole number keeps its ``.0`` so a float never reads as a word."""
    text = f"{value:.{FLOAT_DIGITS}g}"
    return text + ".0" if text.lstrip("-").isdigit() else text


def format_value(value: Any) -> str:
    """``42``, ``3.14``, ``"HELLO"`` (JSON-quoted, so control
    characters and lone surrogates show as escapes), or ``EN=1 DN=0 PRE=5``
    for a timer, counter or control element."""
    if isinstance(value, dict):
        return " ".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, float):
        return format_float(value)
    return repr(value)


def word_shown(word: int, ftype: FileType) -> str | None:
    """A D word as its four BCD digits (``0012``), an A word as its two
    characters, quoted (``"AB"``): the watch view's cells. None for other
    files and for a D word that is not BCD (the plain number shows then)."""
    text = word_text(word, ftype)
    if text is None:
        return None
    return text if ftype.radix == "bcd" else json.dumps(text)


def format_read(table, address: Address) -> str:
    """``format_value(table.read(address))``, with D and A words in their
    text forms beside the number: ``4660 (BCD 1234)``, ``16706 (ASCII "AB")``
    (``--set D10:0='"1234"'`` writes that text form; a number is the word)."""
    value = table.read(address)
    shown = format_value(value)
    if address.kind is ValueKind.WORD and address.member is None and address.ftype.radix != "decimal":
        text = word_shown(value, address.ftype)
        if text is not None:
            shown += f" ({'BCD' if address.ftype.radix == 'bcd' else 'ASCII'} {text})"
    return shown
