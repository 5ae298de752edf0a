"""``softplc run --record TRACE``: one trace file for the ports of every module.

Each module hands its ports to the run's ``Recorder`` (``add_port``): their
traffic is buffered and written to the trace (trace.py), which the engine
opens once every module has attached (``open()``), in time order when a
module calls ``flush()`` at its output point, so that a driver which catches
up on simulated time within a scan (MODBMAST), and modules whose hooks run in
either order, still give a file whose times never go back. Every port's
frames carry its ``label``: COMGENIUS's logical numbers ("0"), MODBMAST's
"MODBMAST:1"; ``softplc run --replay TRACE`` plays each port back by that
label.

A trace that cannot be written (a full disk) does not stop the run: the
lines wait in memory (up to ``MAX_PENDING`` bytes; events beyond that are
counted, not kept, and a comment in the trace says how many when writing
works again), the write is tried again every ``RETRY_S`` seconds, and each
failure and the recovery are told to ``on_problem`` (the runner makes them a
minor fault, S:17/4 code 10, and logs them once per change).
"""

from __future__ import annotations

import io
import os
import time
from typing import Callable

from ..errors import os_error_words, shown_path
from .errors import PortError
from .trace import TraceWriter

WRITE_AT = 8192  # bytes of trace text gathered before a write (as a buffered file would)
MAX_PENDING = 4 * 1024 * 1024  # bytes kept while the trace cannot be written
RETRY_S = 0.1  # while writes fail, the next attempt at most this often


class Recorder:
    """Buffers port traffic and writes it as a trace, in time order."""

    def __init__(self, path: str) -> None:
        self.path = path
        self._writer: TraceWriter | None = None
        self._text: io.StringIO | None = None  # what the TraceWriter formats, not yet in _pending
        self._fd: int | None = None
        self._pending = bytearray()  # formatted, not yet written
        self._comments: list[str] = []
        self._events: list[tuple[int, int, str, str, bytes]] = []  # (t_ns, seq, label, direction, data)
        self._seq = 0
        self._start_ns: int | None = None  # the trace's time 0: when the first port was added
        self._last_ns = 0
        self.problem: str | None = None  # why the last write failed; None when writing works
        self.dropped = 0  # events not recorded (the memory limit was reached while writes failed)
        self._dropped_now = 0  # of those, the ones the trace has no comment about yet
        self._retry_at = 0.0
        # on_problem(reason or None): every failed write, and the first good one after
        self.on_problem: Callable[[str | None], None] | None = None

    def add_port(self, port, description: str, now_ns: Callable[[], int]) -> None:
        """Record ``port``'s traffic from now on, timed by ``now_ns``; the
        description goes into the trace's header comments."""
        self._comments.append(f"port {port.label}: {description}")
        if self._start_ns is None:
            self._start_ns = now_ns()

        def record(label: str, direction: str, data: bytes, at_ns: int | None = None) -> None:
            self._seq += 1
            self._events.append((now_ns() if at_ns is None else at_ns, self._seq, label, direction, bytes(data)))

        port.record = record

    def open(self) -> None:
        """Create the file (the header and the port comments). PortError
        when it cannot be created."""
        try:
            self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as e:
            raise PortError(f"--record: cannot write {shown_path(self.path)}: {os_error_words(e)}") from None
        self._text = io.StringIO()
        self._writer = TraceWriter(self._text, self._comments)
        self._take_text()  # written with the first events

    def flush(self) -> None:
        """Write what was recorded, in time order (a frame never goes before
        one already written: their times are equal then)."""
        if self._writer is None:
            return
        if self._events:
            events = sorted(self._events)
            self._events.clear()
            start = self._start_ns or 0
            for t_ns, _, label, direction, data in events:
                t_ns = max(t_ns, self._last_ns)
                self._last_ns = t_ns
                self._writer.event((t_ns - start) / 1e6, label, direction, data)
            if self._no_room():
                self._write()  # the file may take the waiting bytes now
            if self._no_room():
                self._dropped_now += len(events)
                self.dropped += len(events)
                self._text.seek(0)
                self._text.truncate()
            else:
                self._take_text()
        if len(self._pending) >= WRITE_AT or self._dropped_now:
            self._write()

    def _no_room(self) -> bool:
        """Events are dropped from when the waiting bytes reach MAX_PENDING
        until they are all written."""
        return bool(self._dropped_now) or len(self._pending) + self._text.tell() > MAX_PENDING

    def _take_text(self) -> None:
        self._pending += self._text.getvalue().encode("utf-8")
        self._text.seek(0)
        self._text.truncate()

    def _write(self, force: bool = False) -> None:
        """Write the pending bytes; keep what the file did not take."""
        if self.problem is not None and not force and time.monotonic() < self._retry_at:
            return
        try:
            while self._pending:
                del self._pending[:os.write(self._fd, self._pending)]
        except OSError as e:
            self.problem = f"cannot write {shown_path(self.path)}: {os_error_words(e)}"
            self._retry_at = time.monotonic() + RETRY_S
            if self.on_problem is not None:
                self.on_problem(self.problem)
            return
        if self._dropped_now:
            self._pending += (f"# softplc: {self._dropped_now} events not recorded here: "
                              f"the trace could not be written ({self.problem})\n").encode("utf-8")
            self._dropped_now = 0
            self._write(force=True)
            return
        if self.problem is not None:
            self.problem = None
            if self.on_problem is not None:
                self.on_problem(None)

    @property
    def complete(self) -> bool:
        """Every event recorded is in the file (after ``close``)."""
        return not self._pending and not self.dropped and self.problem is None

    def close(self) -> None:
        """Write the rest and close the file. Never raises: a trace that
        could not be completed shows in ``problem``/``dropped``/``complete``."""
        if self._writer is None:  # never opened: the run did not start
            return
        self.flush()
        self._take_text()
        self._write(force=True)
        self._writer = None
        try:
            os.close(self._fd)
        except OSError as e:  # e.g. a network file system reporting a late write error
            self.problem = self.problem or f"cannot write {shown_path(self.path)}: {os_error_words(e)}"
        self._fd = None
