"""Step back: the data table after each of the last scans.

After every scan the History records each data file's contents, sharing
the previous scan's bytes for a file that did not change, so memory grows
with what changes, not with the table's size. ``back()`` and ``forward()``
move through the recorded scans by writing them into the live table (in
place: compiled rungs keep references to the file arrays); running again
starts from the newest scan, which ``latest()`` restores.

At least ``DEPTH`` (1,000) scans are kept; older ones are dropped.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from ..datatable import DataTable

DEPTH = 1000


@dataclass(frozen=True)
class Frame:
    """The data table after one scan: file name -> raw bytes."""

    scan: int
    now_ms: int
    files: dict[str, bytes]


class History:
    def __init__(self, table: DataTable, depth: int = DEPTH) -> None:
        self.table = table
        self.frames: deque[Frame] = deque(maxlen=max(depth, 1))
        self.position: int | None = None  # index into frames while stepping back; None: live

    @property
    def live(self) -> bool:
        return self.position is None

    def record(self, scan: int, now_ms: int) -> None:
        previous = self.frames[-1].files if self.frames else {}
        files = {}
        for f in self.table.files():
            raw = f.data.tobytes()
            old = previous.get(f.name)
            files[f.name] = old if old == raw else raw  # share unchanged bytes
        self.frames.append(Frame(scan, now_ms, files))

    def _show(self, index: int) -> Frame:
        frame = self.frames[index]
        for f in self.table.files():
            raw = frame.files.get(f.name)
            if raw is not None and raw != f.data.tobytes():
                f.data[:] = type(f.data)(f.data.typecode, raw)
        return frame

    def back(self) -> Frame | None:
        """Show the scan before the one shown; None at the oldest kept."""
        if not self.frames:
            return None
        index = (len(self.frames) - 1 if self.position is None else self.position) - 1
        if index < 0:
            return None
        self.position = index
        return self._show(index)

    def forward(self) -> Frame | None:
        """Show the next recorded scan; None when already live (run a scan then)."""
        if self.position is None:
            return None
        index = self.position + 1
        if index >= len(self.frames) - 1:
            return self.latest()
        self.position = index
        return self._show(index)

    def latest(self) -> Frame | None:
        """Back to the newest scan (live), e.g. before running again."""
        self.position = None
        return self._show(-1) if self.frames else None

    @property
    def shown(self) -> Frame | None:
        if not self.frames:
            return None
        return self.frames[-1 if self.position is None else self.position]
