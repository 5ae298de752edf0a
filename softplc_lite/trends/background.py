"""Recording a trend beside the scan (``softplc run --trend-file``): the
scan only copies the series' raw values into a buffer (about a microsecond
for 20 addresses); a writer process of its own (trends/writer.py) turns
them into CSV or VCD text, so formatting never slows the scan, and on a
machine with two cores runs beside it.

The rows travel as raw bytes: the scan number and the engine's time in ms
(two 64-bit integers), then runs of each involved file's items as the table
stores them (``PackedSampler``). The buffer holds
``ROWS_PER_BATCH`` rows and goes on whole. On the wall clock it goes to
the writer's pipe: the scans leave the machine idle between them, and the
writer keeps up (a 10 ms scan is 100 rows a second; it formats tens of
thousands). On simulated time the scans run back to back, faster than rows
can be formatted, and a writer beside them would take the shared cores from
them: the rows go to a spool (an unnamed temporary file both processes
hold, gone when the recording closes) that the writer formats once the run
ends, while the run waits. Memory stays constant however long the run.
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

from .record import TrendFileError, format_of
from .series import Series

ROWS_PER_BATCH = 512
SPEC_LENGTH = struct.Struct("<I")


GAP = 32  # items between two trended items of a file above which they are copied as two runs
WHOLE_FILE = 512  # a file of at most this many items is copied whole each scan


class PackedSampler:
    """The series' raw items as bytes, a few slices a scan: each file's
    trended items in runs (items closer than GAP copied as one run), so a
    scan's row is the scan and time packed, and one ``tobytes`` a run (about
    half a microsecond for 20 addresses in four files). ``row(scan,
    now_ms)`` appends it to the byte buffer; ``fmt`` is the row's struct
    format (native order: both processes are on this machine) and
    ``place[k]`` says where series ``k``'s value is in an unpacked row, and
    its bit."""

    def __init__(self, table, series: list[Series], buf: bytearray) -> None:
        by_file: dict[str, set[int]] = {}
        for s in series:
            by_file.setdefault(s.file, set()).add(s.index)
        arrays = {name: table.file(name).data for name in by_file}
        runs: list[tuple[str, int, int]] = []  # (file, first item, items); items None: the whole file
        for name in sorted(by_file):
            items = sorted(by_file[name])
            if len(arrays[name]) <= WHOLE_FILE:  # copied whole: one memcpy, no slice made
                runs.append((name, 0, None))
                continue
            start = last = items[0]
            for item in items[1:]:
                if item - last > GAP:
                    runs.append((name, start, last - start + 1))
                    start = item
                last = item
            runs.append((name, start, last - start + 1))
        position: dict[tuple[str, int], int] = {}
        fmt, at = ["=qq"], 2
        names = {name: f"d{k}" for k, name in enumerate(sorted(by_file))}
        lines = ["    buf += head(scan, now_ms)"]
        for name, first, count in runs:
            code = arrays[name].typecode
            whole = count is None
            count = len(arrays[name]) if whole else count
            fmt.append(f"{count}{'i' if code == 'l' else code}")
            for k in range(count):
                position[(name, first + k)] = at + k
            at += count
            lines.append(f"    buf += {names[name]}" if whole else
                         f"    buf += {names[name]}[{first}:{first + count}].tobytes()")
        self.fmt = "".join(fmt)
        self.width = at
        self.place = [(position[(s.file, s.index)], s.bit) for s in series]
        self.lines = lines
        self.scope = {"buf": buf, "head": struct.Struct("=qq").pack, **{names[n]: a for n, a in arrays.items()}}
        self.row = self.compiled("row(scan, now_ms)")

    def compiled(self, signature: str, time_of: str = "scan, now_ms", after: str = ""):
        """A function of ``signature`` that appends the row (``time_of``: the
        scan and time expressions), then runs ``after``."""
        head = f"    buf += head({time_of})"
        source = (f"def {signature}:\n    global buf\n" + "\n".join([head] + self.lines[1:])
                  + "\n" + after)
        scope = dict(self.scope)
        exec(compile(source, "<trend row>", "exec"), scope)  # noqa: S102 - our own text, from resolved addresses
        return scope[signature.split("(")[0]]


class BackgroundRecorder:
    """``record`` after each scan; ``close`` at the end waits until the
    writer process has written everything (TrendFileError if it could not)."""

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
        self.buf = bytearray()
        self.sampler = PackedSampler(table, series, self.buf)
        self._row = self.sampler.row
        self.row_bytes = struct.calcsize(self.sampler.fmt)
        self.limit = ROWS_PER_BATCH * self.row_bytes
        self._flushed = 0
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
                             "on_change": on_change, "fmt": self.sampler.fmt, "place": self.sampler.place,
                             "path": str(path), "follow": follow})
        self._send(SPEC_LENGTH.pack(len(spec)) + spec)

    def record(self, scan: int, now_ms: int) -> None:
        self._row(scan, now_ms)
        if len(self.buf) >= self.limit:
            self._flush()

    def hook(self):
        """The Runner's after-scan hook: the row and the flush check in one
        generated function (a call less a scan than ``record``)."""
        self.sampler.scope.update(flush=self._flush, limit=self.limit)
        return self.sampler.compiled("after_scan(engine)", "engine.scans, engine.clock.now_ms",
                                     "    if len(buf) >= limit:\n        flush()\n")

    @property
    def rows(self) -> int:
        """Rows recorded so far (the scans sampled)."""
        return self._flushed + len(self.buf) // self.row_bytes

    def _flush(self) -> None:
        if self.buf:
            self._flushed += len(self.buf) // self.row_bytes
            if self.spool is None:
                self._send(bytes(self.buf))
            else:
                try:
                    os.write(self.spool.fileno(), self.buf)
                except OSError as e:  # the disk full: said at the end, the scan goes on
                    self.spool_error = e.strerror or str(e)
            del self.buf[:]

    spool_error: str | None = None

    def _send(self, data: bytes) -> None:
        if self.proc.poll() is not None:  # the writer ended (close() says why): a write would meet SIGPIPE
            return
        try:
            view = memoryview(data)
            while view:  # unbuffered: nothing is left for a later flush to push into a closed pipe
                view = view[self.proc.stdin.write(view):]
        except (BrokenPipeError, OSError, ValueError):
            pass

    def close(self) -> None:
        """Flush, end the writer's input, and wait for it to finish the file."""
        self._flush()
        try:
            self.proc.stdin.close()
        except (BrokenPipeError, OSError):
            pass
        err = self.proc.stderr.read().decode("utf-8", "replace").strip()
        self.proc.wait()
        self.proc.stderr.close()
        if self.spool is not None:
            self.spool.close()
        if self.spool_error is not None:
            raise TrendFileError(f"--trend-file: the recording's spool could not be written: {self.spool_error}")
        if self.proc.returncode != 0:
            raise TrendFileError(err.splitlines()[-1] if err else f"the trend writer ended with status "
                                                                  f"{self.proc.returncode}")


def ignore_interrupts() -> None:
    """Ctrl-C reaches the whole process group: the runtime ends the writer
    (its input closes) after the last scan, so the file is whole."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
