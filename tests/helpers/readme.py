"""The README's "Try it" block as lines, for the tests that run it (in
this checkout, and from a fresh install)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def try_it_lines() -> list[str]:
    """The non-blank lines of the first ```bash block under "## Try it"."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Try it\n", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```bash\n(.*?)```", section, re.DOTALL).group(1)
    return [line for line in block.splitlines() if line.strip()]
