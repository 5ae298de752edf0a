"""Values as an engineer reads them on a terminal (CLI --print, watch view)."""

from __future__ import annotations

import json
from typing import Any


def format_value(value: Any) -> str:
    """``42``, ``3.140000104904175``, ``"HELLO"`` (JSON-quoted, so control
    characters and lone surrogates show as escapes), or ``EN=1 DN=0 PRE=5``
    for a timer, counter or control element."""
    if isinstance(value, dict):
        return " ".join(f"{k}={v}" for k, v in value.items())
    if isinstance(value, str):
        return json.dumps(value)
    return repr(value)
