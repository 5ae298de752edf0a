"""Online program edit: watching an app's program files while it runs.

``ProgramWatcher(app)`` notices when a ``.lad`` file of the app changes on
disk (or one is added or removed in an app directory): ``check()`` stats
each file, at most once per ``interval_s`` of wall time. A change is taken
once the files have stayed the same for one more check (an editor still
saving is not read half-written); then the app is loaded again the way
``softplc run`` loads it (app.load_app, without the code cache: parse,
validate, the table check, the modules' instruction set) and compiled
(ladder/online.precompile) in a background thread while the old program
keeps running. If the files changed while they
were read, the result is dropped and they are read again.

``poll()`` returns None, or an ``OnlineEdit``: ``accepted`` with the new
program and its ProgramChanges, or not, with the errors (each
``file:line:col: message``). A rejected version is not read again until a
file changes again. ``apply(engine)`` (from the scan thread, between
scans) polls and, for an accepted edit, replaces the engine's program
(Engine.replace_program): the only place the engine is touched.
docs/engine.md, "Online program edit".
"""

from __future__ import annotations

import hashlib
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from .app import App, AppError, lad_files, load_app
from .ladder.ast import Program
from .ladder.online import EditRefused, ProgramChanges, precompile, program_changes
from .textfile import PROGRAM, read_bytes

CHECK_INTERVAL_S = 0.2  # the least wall time between two looks at the files


@dataclass
class OnlineEdit:
    """One new version of the program files: valid (``program``,
    ``changes``) or not (``errors``, one ``file:line:col: message`` each)."""

    program: Program | None = None
    source_program: Program | None = None
    changes: ProgramChanges | None = None
    errors: list[str] = field(default_factory=list)
    applied: bool = False  # replace_program took it
    code: dict | None = field(default=None, repr=False)  # precompiled in the worker (ladder/online.precompile)

    @property
    def accepted(self) -> bool:
        return not self.errors

    def summary(self) -> str:
        """One line: what changed, or why nothing did."""
        if self.accepted:
            return f"online edit accepted: {self.changes.summary() if self.changes is not None else 'no rung changed'}"
        first = self.errors[0].splitlines()[0] if self.errors else ""
        more = f" (and {len(self.errors) - 1} more)" if len(self.errors) > 1 else ""
        return f"online edit rejected, the program is unchanged: {first}{more}"

    def report(self) -> str:
        """The summary, then every error in full (with its source line)."""
        if self.accepted:
            return self.summary()
        return "\n".join(["online edit rejected, the program is unchanged:", *self.errors])


Signature = tuple  # ((path, mtime_ns, size), ...) of the files in name order


class ProgramWatcher:
    def __init__(self, app: App, interval_s: float = CHECK_INTERVAL_S) -> None:
        self.app = app
        self.interval_s = interval_s
        self._next_check = 0.0
        self._base = self._signature()  # the version running (or last rejected): not read again
        self._base_hashes = self._hashes()
        self._seen: Signature | None = None  # a new signature seen at the previous check
        self._lock = threading.Lock()
        self._worker: threading.Thread | None = None
        self._ready: OnlineEdit | None = None  # from the worker, for poll
        self.last: OnlineEdit | None = None  # the last edit poll returned (the view shows its errors)

    # -- the files ---------------------------------------------------------------------
    def _files(self) -> list[Path]:
        return lad_files(self.app.path) if self.app.is_dir else list(self.app.lad_files)

    def _signature(self) -> Signature:
        out = []
        for f in self._files():
            try:
                st = f.stat()
            except OSError:
                out.append((str(f), None, None))
            else:
                out.append((str(f), st.st_mtime_ns, st.st_size))
        return tuple(out)

    def _hashes(self) -> tuple:
        out = []
        for f in self._files():
            try:
                out.append((str(f), hashlib.sha256(read_bytes(f, PROGRAM)).hexdigest()))
            except OSError:
                out.append((str(f), None))
        return tuple(out)

    # -- between scans -----------------------------------------------------------------
    def check(self, now: float | None = None) -> bool:
        """Look at the files (at most once per interval): start reading a
        changed version once it has stayed the same for one check. True when
        a new version is being read."""
        now = time.monotonic() if now is None else now
        if now < self._next_check or self._worker is not None:
            return self._worker is not None
        self._next_check = now + self.interval_s
        signature = self._signature()
        if signature == self._base:
            self._seen = None
            return False
        if signature != self._seen:  # still changing, or just changed: look again next time
            self._seen = signature
            return False
        hashes = self._hashes()
        if hashes == self._base_hashes:  # touched, same text
            self._base, self._seen = signature, None
            return False
        self._worker = threading.Thread(target=self._read, args=(signature, hashes), name="softplc online edit",
                                        daemon=True)
        self._worker.start()
        return True

    def _read(self, signature: Signature, hashes: tuple) -> None:
        """The worker: load the app again and compare; never raises."""
        try:
            edit = self._load()
        except Exception as exc:  # a bug here must not end the run: the edit is refused, in words
            edit = OnlineEdit(errors=[f"internal error reading the program: {type(exc).__name__}: {exc}"])
        if self._hashes() != hashes:  # written again while being read: read the newer version
            edit = None
        with self._lock:
            self._ready = edit
            if edit is not None:
                self._base, self._base_hashes = signature, hashes
            self._seen = None
            self._worker = None

    def _load(self) -> OnlineEdit:
        try:
            new = load_app(self.app.path, use_cache=False)
        except AppError as e:
            errors = [x.report() for x in e.errors] if e.errors else [str(e)]
            return OnlineEdit(errors=errors)
        try:  # compiled here, in the background: the scan boundary only binds it
            code = precompile(new.program, self.app.settings)
        except Exception:  # the scan thread compiles it then, and reports what goes wrong
            code = None
        return OnlineEdit(program=new.program, source_program=new.source_program,
                          changes=program_changes(self.app.program, new.program), code=code)

    def poll(self) -> OnlineEdit | None:
        """A new version read since the last poll, accepted or not; else None."""
        self.check()
        if self._ready is None:  # the common case, every scan: no lock
            return None
        with self._lock:
            edit, self._ready = self._ready, None
        if edit is not None:
            self.last = edit
        return edit

    def apply(self, engine) -> OnlineEdit | None:
        """From the scan thread, between scans: poll, and put an accepted
        edit in the engine. Returns the edit (its summary says what
        changed), or None when there is nothing new."""
        edit = self.poll()
        return self.install(engine, edit) if edit is not None else None

    def install(self, engine, edit: OnlineEdit) -> OnlineEdit:
        """Put an accepted edit from ``poll`` in the engine (from the scan
        thread, between scans; later than the poll if the caller waits, e.g.
        a watch view stepping back in its history): the engine's program is
        replaced and the app's with it. A rejected edit is returned as is;
        one the table cannot take becomes rejected (EditRefused's errors)."""
        if not edit.accepted or edit.applied:
            return edit
        try:
            edit.changes = engine.replace_program(edit.program, edit.code)
        except EditRefused as e:
            edit.errors = [x.report() for x in e.errors]
            return edit
        edit.applied = True
        app = self.app
        app.program = edit.program
        app.source_program = edit.source_program
        # The code cache holds the old text's code under the old text's key:
        # nothing of this run may be saved there any more.
        app.code, app.code_cache = None, None
        return edit

    def wait(self, timeout_s: float) -> OnlineEdit | None:
        """For tests and scripts: poll until an edit arrives or ``timeout_s`` passes."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            edit = self.poll()
            if edit is not None:
                return edit
            time.sleep(self.interval_s / 4)
        return None
