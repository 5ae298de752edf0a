"""Retentive memory for a running PLC, like battery-backed RAM.

While ``softplc run`` scans, the data table is saved every
``[retentive] save_ms`` of wall-clock time (100 ms by default) at the
latest, so a process killed with SIGKILL loses at most that much (a
snapshot every 0.8 x save_ms less the writes' lag; the rest is margin). The snapshot is encoded by the
scan thread *between two scans* (``Retentive.tick``), so the table on disk
is always the table at the end of one completed scan; a background thread
(:class:`SnapshotWriter`) takes the encoded bytes and does the file work,
so a slow or stuck disk never holds up the scan.

Periodic saves are not fsynced (a killed process does not lose the page
cache); one every ``DURABLE_EVERY_S`` seconds is, and also becomes
``NAME.prev``, the newest snapshot known to be on disk after a power loss.
The final save, when the run stops, is durable too (``Retentive.finish``).

Storage trouble is a minor fault, not a stop (:class:`StorageFaults`): a
failed save or ``--record`` write sets S:17/4 and S:102 (9 save, 10 trace),
is logged once per change of reason, and retried while the PLC keeps
scanning. docs/engine.md has the whole story.
"""

from __future__ import annotations

import collections
import os
import queue
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .datatable import DataTable, DataTableError, snapshot
from .datatable.errors import SnapshotError
from .errors import describe_os_error, shown_path
from .ladder import status as S

DURABLE_EVERY_S = 5.0  # one periodic save in this many seconds is fsynced (and becomes NAME.prev)
# save_ms is the most a killed process may lose. A snapshot is taken every
# PERIOD_SHARE of it, less how long writes have lately taken to land (at
# most LAG_SHARE of it): the rest covers the scan in progress at the kill and
# a write slower than the last ones (measured worst 110 ms with the whole
# period, tests/test_retentive.py).
PERIOD_SHARE = 0.8
LAG_SHARE = 0.2
WRITER_JOIN_S = 30.0  # at stop, how long to wait for a save still being written
HANDOVER_S = 0.0002  # the interpreter's thread switch interval while a save is being written


def restore_snapshot(table: DataTable, path: Path) -> snapshot.Restored:
    """Restore the app's retentive snapshot at ``path`` into ``table`` (the
    program's table), falling back to ``NAME.prev`` as snapshot.restore
    does. A snapshot that does not fit the program (a file number the
    program now uses with another type) raises a SnapshotError that says
    it is the retentive snapshot, where it is, and that ``--fresh`` starts
    without it; the table is not changed then."""
    try:
        restored = snapshot.restore(path)
    except SnapshotError as e:
        raise SnapshotError(f"{e}: the retentive snapshot kept between runs in {path.parent}{os.sep} cannot be "
                            f"read; run with --fresh to start from the program's initial data (the first save "
                            "replaces it)") from None
    if restored.table is not None:
        try:
            table.assign(restored.table)
        except DataTableError as e:
            reason = str(e).replace(" here", " in the program")
            raise SnapshotError(f"{restored.source}: the retentive snapshot kept between runs in {path.parent}"
                                f"{os.sep} does not fit the program ({reason}); run with --fresh to start from "
                                "the program's initial data (the first save replaces it)") from None
    return restored


class StorageFaults:
    """The minor fault for storage trouble, shared by the retentive saves
    and the ``--record`` trace.

    ``failed(source, code, reason)`` on every failed attempt sets S:17/4 and
    S:102 = ``code``, with S:103/S:104 = 0 (no rung caused it); the reason
    is logged only when it differs from the source's last one. ``ok(source,
    message)`` after a failure logs ``message`` and, once no source is
    failing any more, clears S:17/4 (S:102 keeps the last code, as for every
    minor fault). Called from the scan thread only, between scans or in an
    output hook.
    """

    def __init__(self, status_words, log: Callable[[str], None]) -> None:
        self.s = status_words  # the S2 file's words (Engine.s)
        self.log = log
        self.failing: dict[str, str] = {}  # source -> the reason last logged

    def failed(self, source: str, code: int, reason: str, advice: str = "", log: bool = True) -> None:
        s = self.s
        s[S.MINOR_FAULT_BITS] |= 1 << S.MINOR_STORAGE_BIT
        s[S.MINOR_FAULT_CODE] = code
        s[S.MINOR_FAULT_FILE] = 0
        s[S.MINOR_FAULT_RUNG] = 0
        if self.failing.get(source) != reason:
            self.failing[source] = reason
            if log:
                self.log(f"warning: {reason}{advice} (minor fault S:17/{S.MINOR_STORAGE_BIT}, code {code})")

    def ok(self, source: str, message: str) -> None:
        if self.failing.pop(source, None) is None:
            return
        self.log(message)
        if not self.failing:
            self.s[S.MINOR_FAULT_BITS] &= ~(1 << S.MINOR_STORAGE_BIT)


class _QuickHandover:
    """While a save is waiting or being written, the interpreter's thread
    switch interval is ``HANDOVER_S`` instead of its 5 ms default.

    The writer thread gives up the GIL at each system call (open, write,
    rename...) and needs it back for the next line, and first to start at
    all; against a scan thread that never sleeps it would wait a whole
    interval each time, and a save of 0.2 ms of file work would take 10-50
    ms. The scan thread loses the GIL the same number of times either way,
    only sooner. The scan thread lowers the interval when it hands a job
    over (``begin``); the writer puts it back when it has nothing left to
    write and no other writer of the process is busy (``end``). No lock:
    ``set.add``/``discard`` are atomic; two runners saving at once in one
    process can at worst put the interval back while the other one writes,
    which only makes that write slower."""

    def __init__(self) -> None:
        self._busy: set[int] = set()
        self._normal = sys.getswitchinterval()

    def begin(self, writer: object) -> None:
        self._busy.add(id(writer))
        current = sys.getswitchinterval()
        if current > HANDOVER_S:
            self._normal = current
            sys.setswitchinterval(HANDOVER_S)

    def end(self, writer: object) -> None:
        self._busy.discard(id(writer))
        if not self._busy:
            sys.setswitchinterval(self._normal)


_handover = _QuickHandover()


@dataclass(frozen=True)
class _Job:
    seq: int
    data: bytes
    taken_at: float  # time.monotonic() when the scan thread encoded it
    durable: bool


@dataclass(frozen=True)
class WriteResult:
    seq: int
    taken_at: float
    renamed_at: float  # when NAME held it (before the fsync of a durable save)
    durable: bool
    error: str | None  # None: written
    durable_error: str | None = None  # a durable save's fsync or NAME.prev link that failed


class SnapshotWriter:
    """A thread that writes encoded snapshots handed to it with
    :meth:`submit`, newest first: a snapshot submitted while another is
    being written replaces any that is still waiting (no queue builds up
    behind a slow disk). The scan thread never waits for it and never takes
    a lock it holds: ``submit`` stores the job in an attribute and, when the
    thread is not already woken, puts a token in a ``queue.SimpleQueue``
    (which never blocks). The outcome of each write is in :attr:`result`.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self._latest: _Job | None = None
        self._wake: queue.SimpleQueue = queue.SimpleQueue()
        self._woken = False
        self._stopping = False
        self.result: WriteResult | None = None  # the last write's outcome (replaced whole: atomic)
        self.taken = 0  # the seq of the last job the thread took
        self._thread = threading.Thread(target=self._loop, name="softplc-retentive", daemon=True)
        self._thread.start()

    def submit(self, job: _Job) -> None:
        self._latest = job
        if not self._woken:
            self._woken = True
            _handover.begin(self)
            self._wake.put(None)

    def stop(self, timeout: float = WRITER_JOIN_S) -> bool:
        """Drop what is waiting, let the write in progress finish, end the
        thread. False when it is still writing after ``timeout`` seconds."""
        self._stopping = True
        self._wake.put(None)
        self._thread.join(timeout)
        _handover.end(self)  # also after a submit cut short (Ctrl-C) that the thread never saw
        return not self._thread.is_alive()

    def _loop(self) -> None:
        written = 0
        while True:
            self._wake.get()
            self._woken = False
            job = self._latest
            if self._stopping or job is None or job.seq <= written:
                if not self._woken:
                    _handover.end(self)
                if self._stopping:
                    return
                continue
            written = self.taken = job.seq
            error = durable_error = None
            try:
                snapshot.write(job.data, self.path, False)
            except Exception as e:  # noqa: BLE001 - reported as a minor fault; the thread must live on
                error = describe_os_error(e, self.path)
            renamed_at = time.monotonic()
            if job.durable and error is None:
                try:
                    snapshot.make_durable(self.path)
                except Exception as e:  # noqa: BLE001
                    durable_error = describe_os_error(e, self.path)
            self.result = WriteResult(job.seq, job.taken_at, renamed_at, job.durable, error, durable_error)
            if not self._woken and self._latest is job:  # nothing new: the interval goes back
                _handover.end(self)


class Retentive:
    """Saves of a running app's data table (``path``: APP/.softplc/datatable.snap).

    The runner calls :meth:`tick` between two scans whenever
    ``time.monotonic() >= self.due``, and :meth:`finish` once the run has
    stopped. ``save_ms`` 0: no periodic saves (``due`` is infinite), only
    the final one.
    """

    def __init__(self, path: Path, save_ms: int, faults: StorageFaults,
                 durable_every_s: float = DURABLE_EVERY_S) -> None:
        self.path = Path(path)
        self.shown = shown_path(self.path)  # as messages name it
        self.save_s = save_ms / 1000
        self.durable_every_s = durable_every_s
        self.faults = faults
        self.removed_stale = snapshot.remove_stale(self.path)
        self._writer: SnapshotWriter | None = None
        self._seq = 0
        self._seen = 0  # the last result handled
        self._durable_seq = 0  # the last job asked to be durable
        self._latencies: collections.deque[float] = collections.deque(maxlen=16)
        self.saves = 0  # periodic snapshots written
        now = time.monotonic()
        self._last_durable = now
        self.due = now + self.save_s * PERIOD_SHARE if save_ms > 0 else float("inf")

    @property
    def lag_s(self) -> float:
        """How long a write took recently (from encoding to the rename), at
        most, but no more than LAG_SHARE of save_ms: the next snapshot is
        taken that much before save_ms is up, so that it is on disk by then.
        (Capped so that on a machine too busy to write in time, saving more
        often, which would make it busier, never goes past a third more.)"""
        return min(max(self._latencies, default=0.0), self.save_s * LAG_SHARE)

    def tick(self, table: DataTable, now: float) -> None:
        """Between scans, when due: take the outcome of the last write (the
        minor fault, the log), encode the table and hand it to the writer."""
        self._collect()
        data = snapshot.encode(table)
        self._seq += 1
        if self._writer is None:
            self._writer = SnapshotWriter(self.path)
        writer = self._writer
        # A durable job replaced before the writer took it hands its durability on.
        durable = now - self._last_durable >= self.durable_every_s or writer.taken < self._durable_seq
        if durable:
            self._last_durable = now
            self._durable_seq = self._seq
        writer.submit(_Job(self._seq, data, now, durable))
        # Early enough that this write's bytes are on disk within save_s of the last one's.
        self.due = now + self.save_s * PERIOD_SHARE - self.lag_s

    def _collect(self) -> None:
        writer = self._writer
        result = writer.result if writer is not None else None
        if result is None or result.seq == self._seen:
            return
        self._seen = result.seq
        self._latencies.append(result.renamed_at - result.taken_at)
        if result.error is None:
            self.saves += 1
            self.faults.ok("save", f"the retentive snapshot {self.shown} is saved again")
        else:
            self._failed(result.error, f"; the PLC keeps running and tries again every "
                                       f"{round(self.save_s * 1000)} ms")
        if result.durable_error is not None:
            # Its own source: the saves themselves work, so this is told once, not every 5 s.
            self.faults.failed("durable", S.MINOR_CODE_SAVE, f"cannot put the retentive snapshot {self.shown} on "
                               f"disk (fsync, {shown_path(self.path.name)}.prev): {result.durable_error}",
                               f"; it is saved, but may not survive a power loss; tried again every "
                               f"{self.durable_every_s:.0f} s")
        elif result.durable and result.error is None:
            self.faults.ok("durable", f"the retentive snapshot {self.shown} is put on disk again")

    def _failed(self, reason: str, advice: str = "", log: bool = True) -> None:
        self.faults.failed("save", S.MINOR_CODE_SAVE, f"cannot save the retentive snapshot {self.shown}: {reason}",
                           advice, log)

    def finish(self, table: DataTable) -> str | None:
        """The final save, durable (fsync), once the run has stopped: stop
        the writer (its write in progress completes), then write the table
        as it is now. None when saved, else the error message (not logged
        here: the caller reports it), with the minor fault set in the table."""
        self.due = float("inf")
        writer = self._writer
        if writer is not None:
            finished = writer.stop()
            self._collect()
            self._writer = None
            if not finished:
                reason = f"a save is still being written after {WRITER_JOIN_S:.0f} s; the final save is not made"
                self._failed(reason, log=False)
                return f"cannot save the retentive snapshot {self.shown}: {reason}"
        try:
            snapshot.write(snapshot.encode(table), self.path, True)
        except Exception as e:  # noqa: BLE001 - reported, the run's output still printed
            reason = describe_os_error(e, self.path)
            self._failed(reason, log=False)
            return f"cannot save the retentive snapshot {self.shown} at the end of the run: {reason}"
        self.faults.ok("save", f"the retentive snapshot {self.shown} is saved again")
        self.faults.ok("durable", f"the retentive snapshot {self.shown} is put on disk again")
        return None
