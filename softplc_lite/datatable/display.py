"""Values as an engineer reads them on a terminal (CLI --print, watch view)."""

from __future__ import annotations

import json
from typing import Any

from .address import Address, ValueKind
from .filetypes import FileType
from .table import word_text


def format_value(value: Any) -> str:
    """``42``, ``3.140000104904175``, ``"HELLO"`` (JSON-quoted, so control
    characters and lone surrogates show as escapes), or ``EN=1 DN=0 PRE=5``
    for a timer, counter or control element."""
    if isinstance(value, dict):
        return " ".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, str):
        return json.dumps(value)
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
