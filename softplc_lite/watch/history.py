"""Step back: the data table after each of the last scans.

After every scan the History records the whole table as one bytes object
(shared with the previous scan's when nothing changed): memory is DEPTH
times the table's size, and a record costs about a microsecond. ``back()`` and ``forward()``
move through the recorded scans by writing them into the live table (in
place: compiled rungs keep references to the file arrays); running again
starts from the newest scan, which ``latest()`` restores.

The last ``DEPTH`` (1,000) scans are kept, older ones dropped; and at most
``MAX_BYTES`` (256 MiB) of them: a table too big for 1,000 copies in that
(over 256 KiB, say 30 files of 10,000 words changing every scan) keeps
fewer, never less than the last ``MIN_DEPTH`` (10).
"""

from __future__ import annotations

from collections import deque
from typing import NamedTuple

from ..datatable import DataTable

DEPTH = 1000
MAX_BYTES = 256 << 20  # the most memory the kept tables take (when they differ scan to scan)
MIN_DEPTH = 10  # scans kept however big the table


class Frame(NamedTuple):
    """The data table after one scan: the raw bytes of all its files, one
    after the other, in the order and sizes of ``layout`` (one tuple
    shared by the frames of one table layout)."""

    scan: int
    now_ms: int
    layout: tuple[tuple[str, int], ...]  # (file name, bytes)
    raw: bytes

    @property
    def files(self) -> dict[str, bytes]:
        """File name -> raw bytes."""
        out, at = {}, 0
        for name, size in self.layout:
            out[name] = self.raw[at:at + size]
            at += size
        return out


class History:
    def __init__(self, table: DataTable, depth: int = DEPTH, max_bytes: int = MAX_BYTES) -> None:
        self.table = table
        self.depth = max(depth, 1)
        self.max_bytes = max_bytes
        self.frames: deque[Frame] = deque()
        self.kept_bytes = 0  # of the distinct tables the frames hold
        self.position: int | None = None  # index into frames while stepping back; None: live
        self._count = -1  # files in the table when the layout below was taken
        self._layout: tuple[tuple[str, int], ...] = ()
        self._arrays: tuple = ()
        self._bytes = -1

    @property
    def live(self) -> bool:
        return self.position is None

    def record(self, scan: int, now_ms: int) -> None:
        # Recorded after every scan, so kept lean: the whole table as one
        # bytes object (one C-level join of the file arrays, about 1 us for a
        # few KB), shared with the previous frame when nothing changed. The
        # arrays are taken once (they stay in place) and again only when a
        # file is added or grows (forcing N20:0/0 creates N20).
        if len(self.table._files) != self._count:
            self._take_layout()
        raw = b"".join(self._arrays)
        if len(raw) != self._bytes:  # a file grew in place
            self._take_layout()
        frames = self.frames
        if frames and frames[-1].raw == raw and frames[-1].layout is self._layout:
            raw = frames[-1].raw
        else:
            self.kept_bytes += len(raw)
        frames.append(Frame(scan, now_ms, self._layout, raw))
        floor = min(MIN_DEPTH, self.depth)
        while len(frames) > self.depth or (self.kept_bytes > self.max_bytes and len(frames) > floor):
            oldest = frames.popleft()
            if oldest.raw is not frames[0].raw:  # not shared with the next frame
                self.kept_bytes -= len(oldest.raw)

    def amend(self) -> None:
        """Make the newest frame the table as it is now: an edit made
        between two scans (a set value, a toggled bit, a mode change)
        belongs to the scan before it, so stepping back past it and forward
        again shows it rather than undoing it. Nothing to amend before the
        first scan is recorded."""
        frames = self.frames
        if not frames:
            return
        if len(self.table._files) != self._count:
            self._take_layout()
        raw = b"".join(self._arrays)
        if len(raw) != self._bytes:
            self._take_layout()
        old = frames[-1]
        if len(frames) < 2 or frames[-2].raw is not old.raw:  # its bytes were counted for it alone
            self.kept_bytes -= len(old.raw)
        self.kept_bytes += len(raw)
        frames[-1] = old._replace(layout=self._layout, raw=raw)

    def _take_layout(self) -> None:
        files = self.table.files()
        self._count = len(files)
        self._arrays = tuple(f.data for f in files)
        self._layout = tuple((f.name, len(f.data) * f.data.itemsize) for f in files)
        self._bytes = sum(size for _, size in self._layout)

    def _show(self, index: int) -> Frame:
        frame = self.frames[index]
        files = frame.files
        for f in self.table.files():
            raw = files.get(f.name)
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
