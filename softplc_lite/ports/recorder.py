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
"""

from __future__ import annotations

from typing import Callable

from .errors import PortError
from .trace import TraceWriter


class Recorder:
    """Buffers port traffic and writes it as a trace, in time order."""

    def __init__(self, path: str) -> None:
        self.path = path
        self._writer: TraceWriter | None = None
        self._comments: list[str] = []
        self._events: list[tuple[int, int, str, str, bytes]] = []  # (t_ns, seq, label, direction, data)
        self._seq = 0
        self._start_ns: int | None = None  # the trace's time 0: when the first port was added
        self._last_ns = 0

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
        when it cannot be written."""
        try:
            self._writer = TraceWriter(self.path, self._comments)
        except OSError as e:
            raise PortError(f"--record: cannot write {self.path}: {e.strerror}") from None

    def flush(self) -> None:
        """Write what was recorded, in time order (a frame never goes before
        one already written: their times are equal then)."""
        if not self._events or self._writer is None:
            return
        events = sorted(self._events)
        self._events.clear()
        start = self._start_ns or 0
        for t_ns, _, label, direction, data in events:
            t_ns = max(t_ns, self._last_ns)
            self._last_ns = t_ns
            self._writer.event((t_ns - start) / 1e6, label, direction, data)

    def close(self) -> None:
        if self._writer is None:  # never opened: the run did not start
            return
        self.flush()
        self._writer.close()
