"""The MODBTCPS module (TLM): a Modbus TCP server over the data table, for
HMIs and SCADA (docs/modbtcps.md).

Registered like any third-party module, in pyproject.toml::

    [project.entry-points."softplc_lite.tlms"]
    MODBTCPS = "softplc_lite.tlm.modbtcps:ModbTcpServer"

It reads MODBTCPS.XML (config.py). An engine that takes it (``attach``)
only places the map in its data table: a program that is compiled, checked
or rendered starts no server. The first scan starts the server process
(serverproc.py: pymodbus's server); from then on, at each scan:

- input point: the writes clients made since the last scan are applied, in
  arrival order (before the forces, so a forced bit stays forced);
- output point: the mapped words are published to the image clients read
  (image.py), so a read is always one whole scan's table; the writes applied
  this scan are acknowledged to the server, which only now answers them; the
  server's counters go to the status words (status.py).

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
from pathlib import Path
from typing import Mapping

from ..api import TLM
from . import messages as msg
from . import status as C
from .config import CONFIG_FILE, ServerConfig, config_references, load_config
from .image import SharedImage
from .layout import Layout, string_lengths_fit

START_TIMEOUT_S = 20.0  # the server process imports pymodbus: about 0.3 s here, far more on a loaded machine
WHERE = "MODBTCPS.XML address and port; docs/modbtcps.md"
ZERO_COUNTERS = (0,) * C.COUNTERS


class ModbTcpServer(TLM):
    name = "MODBTCPS"
    title = "Modbus TCP server over the data table (for HMIs and SCADA)"
    config_file = CONFIG_FILE
    libraries = ("pymodbus",)  # imported by the server process only: the load checks it is installed (registry)

    def __init__(self, config: ServerConfig | None = None) -> None:
        self.config = config or ServerConfig()
        self.engine = None
        self.layout: Layout | None = None
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
        self._writes_applied = 0
        self._status = None
        self._rate_mark = (time.monotonic(), 0)
        self.rate = 0

    # -- configuration ----------------------------------------------------------------------
    def configure(self, app_dir: Path | None) -> list[str]:
        if app_dir is not None:
            self.config = load_config(app_dir)
        return list(self.config.warnings)

    def config_references(self) -> list:
        return config_references(self.config)

    # -- the server process -----------------------------------------------------------------
    def attach(self, engine, options: Mapping[str, object]) -> list[str]:
        self.engine = engine
        table = engine.table
        for address in self.config_references():
            table.reference(address)
        self.layout = Layout.build(self.config, table)
        self._files = [(table.file(s.file).data, s.index, s.words, s.offset)
                       for s in self.layout.slots]
        if self.config.status is not None:
            loc = table.resolve(self.config.status)
            self._status = (loc.file.data, loc.index)
        return []

    def _start(self, engine) -> None:
        """Start the server process (the first scan's input point); what
        goes wrong is said once and leaves the server failed, the scan going on."""
        self.started = True
        try:
            self.image = SharedImage.create(self.layout.size)
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
                [sys.executable, "-m", "softplc_lite.tlm.modbtcps.serverproc", str(write_fd), str(self.image.fd)],
                stdin=subprocess.PIPE, pass_fds=(write_fd, self.image.fd), close_fds=True)
        except OSError:
            os.close(read_fd)
            raise
        finally:
            os.close(write_fd)
        self._from_server = read_fd
        os.set_blocking(read_fd, False)
        init = pickle.dumps({"config": self.config, "layout": self.layout, "size": self.image.size})
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
        where = f"{self.config.host}:{port if port is not None else self.config.port}"
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
            if m[0] == msg.READY:
                self.port, self._ready_by = m[1], None
            elif m[0] == msg.FAILED:  # the end of the pipe follows
                self._lost(m[1])
                return
            else:
                self._apply(m, table)

    def _apply(self, m: tuple, table) -> None:
        if m[0] == msg.WRITE:
            _, seq, unit, kind, address, values = m
        else:  # MASK: applied to the register as the table holds it now (Modbus spec 6.16)
            _, seq, unit, address, and_mask, or_mask = m
            kind, values = "holding_registers", None
        pieces = self.layout.find(unit, kind, address, 1 if values is None else len(values))
        self._applied = seq
        if pieces is None:  # the server checked it against the same layout
            return
        if values is None:
            current = Layout.load(pieces, table)[0]
            values = [(current & and_mask) | (or_mask & ~and_mask & 0xFFFF)]
            if not string_lengths_fit(pieces, values):  # the LEN check of 6, 16 and 23, on the result
                self._refused.append(seq)
                return
        Layout.store(pieces, values, table)
        self._writes_applied += 1

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
        watch view and word 2); ``requests`` None: read from the image only
        when a second has passed (no status words want the counters each scan)."""
        now = time.monotonic()
        mark_t, mark_n = self._rate_mark
        if now - mark_t >= 1.0:
            if requests is None:
                requests = self.image.counters()[C.REQUESTS]
            self.rate = int(round((requests - mark_n) / (now - mark_t)))
            self._rate_mark = (now, requests)

    def _status_words(self, counters) -> None:
        data, i = self._status
        bits = 0
        if counters[C.LISTENING] and self.failed is None:
            bits |= C.BIT_LISTENING
        if self.failed is not None:
            bits |= C.BIT_FAILED
        if counters[C.CONNECTED]:
            bits |= C.BIT_CLIENT
        data[i + C.W_BITS] = bits
        for w, c in C.COPIED:
            data[i + w] = C.word(counters[c])
        data[i + C.W_RATE] = C.word(min(self.rate, 32767))
        data[i + C.W_WRITES_APPLIED] = C.word(self._writes_applied)
        data[i + C.W_REFUSALS] = C.word(sum(counters[c] for c in C.REFUSAL_COUNTERS))

    def _lost(self, why: str) -> None:
        self._ready_by = None
        if self.failed is None:
            self.failed = why
            if self.port is None:
                where = f" ({WHERE})" if why.startswith("cannot listen") else ""
                self.log(f"{why}{where}; clients are not served (the scan goes on)")
            else:
                self.log(f"{why}; clients are no longer served (the scan goes on)")
        if self._from_server >= 0:
            os.close(self._from_server)
            self._from_server = -1

    def server_status(self) -> C.ServerStatus | None:
        """The server as the watch view shows it."""
        if self.layout is None:  # not attached to an engine
            return None
        counters = self.image.counters() if self.image is not None else ZERO_COUNTERS
        refused = {name: counters[c] for name, c in C.REFUSAL_NAMES if counters[c]}
        bound = self.failed is None and self._bound_port() is not None
        return C.ServerStatus(self.failed or self.listening, bound, counters[C.CONNECTED],
                              self.rate, counters[C.REQUESTS], self._writes_applied, sum(refused.values()),
                              refused, pending=self.failed is None and not bound)

    def network_servers(self) -> list:
        status = self.server_status()
        return [status] if status is not None else []

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
