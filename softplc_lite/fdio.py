"""Reading a file descriptor whole, for the processes the runtime starts
and talks to over pipes (the network servers, the trend writer)."""

from __future__ import annotations

import os


def read_exactly(fd: int, n: int) -> bytes:
    """``n`` bytes from ``fd``, or fewer when it ends first."""
    out = bytearray()
    while len(out) < n:
        chunk = os.read(fd, n - len(out))
        if not chunk:
            break
        out += chunk
    return bytes(out)
