"""The scan's side of a network server: the module that serves a protocol
holds a ``ServerHandle`` and calls it from its hooks.

The first scan starts the server process (process.py); from then on, at
each scan:

- input point (``on_input``): the writes clients made since the last scan
  are applied, in arrival order, by the protocol's ``apply`` (before the
  forces, so a forced bit stays forced);
- output point (``on_output``): the mapped words are published to the image
  clients read (image.py), so a read is always one whole scan's table; the
  writes applied this scan are acknowledged to the server, which only now
  answers them; the server's counters go to the status words.

The scan never waits for the server: the pipe is read without blocking, and
the image is written without a lock (a seqlock: the server retries a copy
the scan overlapped). The one exception is the first scan of a run in
simulated time, which waits until the server listens (or cannot), so that
every scan of a reproducible run sees it listening; on the wall clock the
server comes up beside the scans.
"""

from __future__ import annotations

import os
import pickle
import select
import subprocess
import sys
import time
from typing import Callable

from . import counters as C
from . import messages as msg
from .image import SharedImage
from .protocol import APPLIED, REFUSED, Protocol, Settings

START_TIMEOUT_S = 20.0  # the server process imports its libraries: about 0.3 s here, far more on a loaded machine
ZERO_COUNTERS = (0,) * C.COUNTERS


class ServerHandle:
    """One server process, from the runtime. ``log`` says a line as the
    module's; ``where`` names what to check when the server cannot listen
    (the configuration's address and port, and its documentation)."""

    def __init__(self, protocol: Protocol, settings: Settings, log: Callable[[str], None], where: str,
                 status_words: C.StatusWords | None = None) -> None:
        self.protocol = protocol
        self.settings = settings
        self.log = log
        self.where = where
        self.words = status_words
        self._refusal_counters = status_words.refusal_counters if status_words is not None else ()
        self.image: SharedImage | None = None
        self.process: subprocess.Popen | None = None
        self.port: int | None = None
        self.failed: str | None = None
        self.started = False  # the first scan starts the server
        self._ready_by: float | None = None  # starting: the time it should listen by
        self._from_server = -1
        self._reader = msg.Reader()
        self._files: list = []
        self._applied = 0  # the sequence number of the last write applied (or refused)
        self._acked = 0
        self._refused: list[int] = []  # writes the scan refused since the last acknowledgement
        self.writes_applied = 0
        self._status = None
        self._rate_mark = (time.monotonic(), 0)
        self.rate = 0

    def attach(self, table, status=None) -> None:
        """Take the engine's data table, which holds the protocol's regions;
        ``status``: the address of the status block, or None."""
        self._files = [(table.file(name).data, index, n, offset)
                       for name, index, n, offset in self.protocol.regions()]
        if status is not None:
            loc = table.resolve(status)
            self._status = (loc.file.data, loc.index)

    # -- the server process -----------------------------------------------------------------
    def _start(self, engine) -> None:
        """Start the server process (the first scan's input point); what
        goes wrong is said once and leaves the server failed, the scan going on."""
        self.started = True
        try:
            self.image = self.protocol.segments.create_image(self.protocol.image_bytes)
            self._publish()
            self._spawn()
        except OSError as e:
            self._discard_image()
            self._lost(f"cannot start the server process: {e.strerror or 'the system refused'}")
            return
        self._ready_by = time.monotonic() + START_TIMEOUT_S
        if not engine.clock.realtime:  # simulated time: every scan of the run sees it listening
            self._wait_ready(engine.table)

    def _spawn(self) -> None:
        read_fd, write_fd = os.pipe()
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", self.protocol.process_module, str(write_fd), str(self.image.fd)],
                stdin=subprocess.PIPE, pass_fds=(write_fd, self.image.fd), close_fds=True)
        except OSError:
            os.close(read_fd)
            raise
        finally:
            os.close(write_fd)
        self._from_server = read_fd
        os.set_blocking(read_fd, False)
        init = pickle.dumps({"protocol": self.protocol, "settings": self.settings, "size": self.image.size})
        try:
            self.process.stdin.write(msg.LENGTH.pack(len(init)) + init)  # a few KiB: the pipe takes them
            self.process.stdin.flush()
        except OSError:
            pass  # the process died at once: the end of its pipe says so

    def _wait_ready(self, table) -> None:
        """Block until the server listens or cannot (simulated time only);
        a write that comes with its READY is applied to ``table``."""
        while self._ready_by is not None and self._from_server >= 0:
            select.select([self._from_server], [], [], 0.05)
            self._read_server(table)

    def wait_until_listening(self, timeout: float = START_TIMEOUT_S) -> int | None:
        """For a caller beside the scan (a test, an example, a benchmark),
        scanning or not: the port, once the server listens; None if it
        failed, ended, or did not listen in time. Reads only the shared
        image and the process's state, never the scan's pipe."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.failed is None:
            image, process = self.image, self.process
            if image is not None:
                try:
                    counters = image.counters()
                except ValueError:  # closed meanwhile: the run ended
                    return None
                if counters[C.LISTENING]:
                    return counters[C.PORT]
            if process is not None and process.poll() is not None:
                return None
            time.sleep(0.01)
        return None

    def _bound_port(self) -> int | None:
        """The port listened on: from READY, or from the image when the
        server listens and the scan has not read READY yet."""
        if self.port is None and self.image is not None and self.failed is None:
            counters = self.image.counters()
            if counters[C.LISTENING]:
                return counters[C.PORT]
        return self.port

    @property
    def listening(self) -> str:
        port = self._bound_port()
        where = f"{self.settings.host}:{port if port is not None else self.settings.port}"
        if not self.started:
            return f"{where}, not started (the first scan starts it)"
        return where if port is not None else f"{where}, starting"

    # -- each scan ---------------------------------------------------------------------------
    def on_input(self, engine) -> None:
        if not self.started:
            self._start(engine)
        if self._from_server >= 0:
            self._read_server(engine.table)

    def _read_server(self, table) -> None:
        """What the server sent: READY, FAILED, and the clients' writes,
        applied to ``table``."""
        try:
            data = os.read(self._from_server, 1 << 20)
        except BlockingIOError:
            if self._ready_by is not None and time.monotonic() > self._ready_by:
                self._lost(f"the server process did not start in {START_TIMEOUT_S:.0f} s")
            return
        except OSError:
            data = b""
        if not data:
            self._lost("the server process ended" if self._ready_by is None
                       else "the server process ended as it started")
            return
        for m in self._reader.feed(data):
            if m[0] == msg.WRITE:
                self._apply(m[1], m[2], table)
            elif m[0] == msg.READY:
                self.port, self._ready_by = m[1], None
            elif m[0] == msg.FAILED:  # the end of the pipe follows
                self._lost(m[1])
                return

    def _apply(self, seq: int, payload: bytes, table) -> None:
        outcome = self.protocol.apply(payload, table)
        self._applied = seq
        if outcome == APPLIED:
            self.writes_applied += 1
        elif outcome == REFUSED:
            self._refused.append(seq)

    def on_output(self, engine, outputs_enabled: bool) -> None:
        if self.image is None:  # not started, or could not start
            if self._status is not None:
                self._status_words(ZERO_COUNTERS)
            return
        self._publish()
        self._update_status()  # before the answers: a client that has its answer has its write counted
        if self._applied != self._acked and self.process is not None:
            self._acked = self._applied
            refused, self._refused = self._refused, []
            try:
                self.process.stdin.write(b"".join(msg.refused(seq) for seq in refused) + msg.ack(self._acked))
                self.process.stdin.flush()
            except (OSError, ValueError):
                self._lost("the server process ended")
                self._update_status()  # its failed bit in this scan's words

    def _update_status(self) -> None:
        if self._status is not None:
            counters = self.image.counters()
            self._measure_rate(counters[C.REQUESTS])
            self._status_words(counters)
        else:
            self._measure_rate(None)

    def _publish(self) -> None:
        image = self.image
        image.begin()
        for data, index, n, offset in self._files:
            image.put(offset, data[index:index + n])
        image.end()

    def _measure_rate(self, requests: int | None) -> None:
        """Requests answered normally a second, over each whole second (the
        watch view and the status words); ``requests`` None: read from the
        image only when a second has passed (no status words want the
        counters each scan)."""
        now = time.monotonic()
        mark_t, mark_n = self._rate_mark
        if now - mark_t >= 1.0:
            if requests is None:
                requests = self.image.counters()[C.REQUESTS]
            self.rate = int(round((requests - mark_n) / (now - mark_t)))
            self._rate_mark = (now, requests)

    def _status_words(self, counters) -> None:
        data, i = self._status
        w = self.words
        bits = 0
        if counters[C.LISTENING] and self.failed is None:
            bits |= C.BIT_LISTENING
        if self.failed is not None:
            bits |= C.BIT_FAILED
        if counters[C.CONNECTED]:
            bits |= C.BIT_CLIENT
        data[i + w.bits] = bits
        for word, counter in w.copied:
            data[i + word] = C.word(counters[counter])
        data[i + w.rate] = C.word(min(self.rate, 32767))
        data[i + w.writes_applied] = C.word(self.writes_applied)
        data[i + w.refusals] = C.word(sum(counters[c] for c in self._refusal_counters))

    def _lost(self, why: str) -> None:
        self._ready_by = None
        if self.failed is None:
            self.failed = why
            if self.port is None:
                where = f" ({self.where})" if why.startswith("cannot listen") else ""
                self.log(f"{why}{where}; clients are not served (the scan goes on)")
            else:
                self.log(f"{why}; clients are no longer served (the scan goes on)")
        if self._from_server >= 0:
            os.close(self._from_server)
            self._from_server = -1

    def server_status(self) -> C.ServerStatus:
        """The server as the watch view shows it."""
        counters = self.image.counters() if self.image is not None else ZERO_COUNTERS
        names = self.words.refusal_names if self.words is not None else ()
        refused = {name: counters[c] for name, c in names if counters[c]}
        noted = {name: counters[c] for name, c in (self.words.noted_names if self.words is not None else ())
                 if counters[c]}
        bound = self.failed is None and self._bound_port() is not None
        return C.ServerStatus(self.failed or self.listening, bound, counters[C.CONNECTED],
                              self.rate, counters[C.REQUESTS], self.writes_applied, sum(refused.values()),
                              refused, noted or None, pending=self.failed is None and not bound)

    # -- the end -----------------------------------------------------------------------------
    def close(self) -> None:
        process, self.process = self.process, None
        if process is not None:
            try:
                process.stdin.close()  # the server's signal to stop
            except OSError:
                pass
            try:
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        if self._from_server >= 0:
            os.close(self._from_server)
            self._from_server = -1
        self._discard_image()

    def _discard_image(self) -> None:
        if self.image is not None:
            self.image.close()
            self.image = None
