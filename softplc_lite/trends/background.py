"""Recording a trend beside the scan (``softplc run --trend-file``): the
scan only copies the series' raw values into a buffer (well under a
microsecond for 20 addresses); a writer process of its own (trends/writer.py)
turns them into CSV or VCD text, so formatting never slows the scan, and on
a machine with two cores runs beside it.

The rows travel as raw bytes: the scan number and the engine's time in ms
(two 64-bit integers), then runs of each involved file's items as the table
stores them (``RowViews``). A scan's row is one C-level ``join`` of live
views of those runs, written into a fixed buffer (``BUFFER_BYTES``) that
goes on whole when full: no Python work a value, no allocation growing with
the run. On the wall clock the buffer goes to the writer's pipe: the scans
leave the machine idle between them, and the writer keeps up (a 10 ms scan
is 100 rows a second; it formats tens of thousands). On simulated time the
scans run back to back, faster than rows can be formatted, and a writer
beside them would take the shared cores from them: the rows go to a spool
(an unnamed temporary file both processes hold, gone when the recording
closes) that the writer formats once the run ends, while the run waits.
Memory stays constant however long the run.
"""

from __future__ import annotations

import io
import os
import pickle
import signal
import struct
import subprocess
import sys
import tempfile
from array import array
from contextlib import contextmanager
from pathlib import Path

from .record import TrendFileError, format_of
from .series import Series

BUFFER_BYTES = 64 * 1024  # a pipe's capacity: one write the writer reads whole; small enough to stay in cache
SPEC_LENGTH = struct.Struct("<I")
HEAD = "=qq"  # the scan number and the time in ms, ahead of each row's values

GAP = 32  # items between two trended items of a file above which they are copied as two runs
STRUCT_CODE = {1: "b", 2: "h", 4: "i", 8: "q"}  # standard sizes ('=') of the table's integer items, by item size


class RowViews:
    """The series' raw items as live views of the table: each file's
    trended items in runs (items closer than GAP as one run: a view costs
    the scan as much as a few items' bytes), fixed when the recording starts. A row is ``join(parts)``: the
    ``head`` array (scan, time) then each run's current bytes. ``fmt`` is
    the row's struct format (native order: both processes are on this
    machine) and ``place[k]`` says where series ``k``'s value is in an
    unpacked row, and its bit.

    A view holds its array's buffer, and an array with a view cannot grow:
    ``detach`` lets go of the views (an online edit may grow a file) and
    ``attach`` takes them again, of the same runs, so every row keeps the
    width the writer was told."""

    def __init__(self, table, series: list[Series]) -> None:
        by_file: dict[str, set[int]] = {}
        for s in series:
            by_file.setdefault(s.file, set()).add(s.index)
        self._arrays = {name: table.file(name).data for name in by_file}
        runs: list[tuple[str, int, int]] = []  # (file, first item, items)
        for name in sorted(by_file):
            items = sorted(by_file[name])
            start = last = items[0]
            for item in items[1:]:
                if item - last > GAP:
                    runs.append((name, start, last - start + 1))
                    start = item
                last = item
            runs.append((name, start, last - start + 1))
        position: dict[tuple[str, int], int] = {}
        fmt, at = [HEAD], 2
        for name, first, count in runs:
            data = self._arrays[name]
            fmt.append(f"{count}{'f' if data.typecode == 'f' else STRUCT_CODE[data.itemsize]}")
            for k in range(count):
                position[(name, first + k)] = at + k
            at += count
        self.runs = runs
        self.fmt = "".join(fmt)
        self.width = at
        self.place = [(position[(s.file, s.index)], s.bit) for s in series]
        self.head = array("q", [0, 0])
        self.parts: list = []  # the head, then one view a run; changed in place, so a bound hook sees it
        self.attach()

    def attach(self) -> None:
        self.parts[:] = [self.head] + [memoryview(self._arrays[name])[first:first + count]
                                       for name, first, count in self.runs]

    def detach(self) -> None:
        views, self.parts[:] = self.parts[1:], []
        for view in views:
            view.release()


class _Sink(io.RawIOBase):
    """Where the full buffer goes (the writer's pipe or the spool), counting
    the bytes. A failed write is kept, not raised: it would reach the scan.
    A dead writer is said by close() from its exit status; a full disk from
    ``error``."""

    def __init__(self, fd: int) -> None:
        super().__init__()
        self.fd = fd
        self.written = 0
        self.error: str | None = None

    def writable(self) -> bool:
        return True

    def tell(self) -> int:
        return self.written

    def write(self, data) -> int:
        size = len(data)
        if self.error is None:
            try:
                view = memoryview(data)
                while view:  # a pipe may take part of it
                    view = view[os.write(self.fd, view):]
            except OSError as e:
                self.error = e.strerror or str(e)
        self.written += size
        return size


class BackgroundRecorder:
    """``hook()`` (or ``record``) after each scan; ``close`` at the end
    waits until the writer process has written everything (TrendFileError
    if it could not)."""

    def __init__(self, table, series: list[Series], path: str | Path, app_name: str, clock: str,
                 on_change: bool = False, follow: bool = True) -> None:
        """``follow``: the writer formats the rows as they come (a run on
        the wall clock, whose scans leave the machine idle between them);
        False: only once the recording closes (simulated time: the scans
        run back to back, and a writer beside them would take the shared
        cores from them)."""
        kind = format_of(path)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as e:
            raise TrendFileError(f"--trend-file {str(path)!r}: cannot write it: {e.strerror or e}") from None
        self.views = RowViews(table, series)
        self.row_bytes = struct.calcsize(self.views.fmt)
        self.spool = None
        if not follow:
            try:
                self.spool = tempfile.TemporaryFile()  # unnamed: gone with the last process that holds it
            except OSError as e:
                os.close(fd)
                raise TrendFileError(f"--trend-file: no temporary file for the recording: {e.strerror or e}") \
                    from None
        spool_fd = self.spool.fileno() if self.spool is not None else -1
        try:
            self.proc = subprocess.Popen([sys.executable, "-m", "softplc_lite.trends.writer", str(fd), str(spool_fd)],
                                         stdin=subprocess.PIPE, stderr=subprocess.PIPE,
                                         pass_fds=(fd,) + ((spool_fd,) if spool_fd >= 0 else ()), bufsize=0)
        finally:
            os.close(fd)
        spec = pickle.dumps({"kind": kind, "series": series, "app_name": app_name, "clock": clock,
                             "on_change": on_change, "fmt": self.views.fmt, "place": self.views.place,
                             "path": str(path), "follow": follow})
        pipe = _Sink(self.proc.stdin.fileno())
        pipe.write(SPEC_LENGTH.pack(len(spec)) + spec)
        self.sink = pipe if self.spool is None else _Sink(spool_fd)
        self.sink.written = 0  # rows only: the spec is not one
        self.out = io.BufferedWriter(self.sink, BUFFER_BYTES)

    def record(self, scan: int, now_ms: int) -> None:
        head = self.views.head
        head[0], head[1] = scan, now_ms
        self.out.write(b"".join(self.views.parts))

    def hook(self):
        """The Runner's after-scan hook: two stores and one C-level copy
        into the buffer a scan."""
        head, parts, join, write = self.views.head, self.views.parts, b"".join, self.out.write

        def after_scan(engine) -> None:
            head[0] = engine.scans
            head[1] = engine.clock.now_ms
            write(join(parts))
        return after_scan

    @contextmanager
    def detached(self):
        """No views of the table held inside: for an online edit between
        scans, which may grow a file (an array with a view cannot)."""
        self.views.detach()
        try:
            yield
        finally:
            self.views.attach()

    @property
    def rows(self) -> int:
        """Rows recorded so far (the scans sampled)."""
        return self.out.tell() // self.row_bytes

    def close(self) -> None:
        """Flush, end the writer's input, and wait for it to finish the file."""
        self.out.flush()
        self.views.detach()
        try:
            self.proc.stdin.close()
        except (BrokenPipeError, OSError):
            pass
        err = self.proc.stderr.read().decode("utf-8", "replace").strip()
        self.proc.wait()
        self.proc.stderr.close()
        if self.spool is not None:
            self.spool.close()
        if self.proc.returncode != 0:
            raise TrendFileError(err.splitlines()[-1] if err else f"the trend writer ended with status "
                                                                  f"{self.proc.returncode}")
        if self.spool is not None and self.sink.error is not None:
            raise TrendFileError(f"--trend-file: the recording's spool could not be written: {self.sink.error}")


def ignore_interrupts() -> None:
    """Ctrl-C reaches the whole process group: the runtime ends the writer
    (its input closes) after the last scan, so the file is whole."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
