# URL format:    replay://PATH[?port=N|MODULE:N]
# PATH: a trace file (trace.py), absolute or relative to the current
#   directory, taken literally up to the first "?"
# options:
# - "port=N" the port of the trace to play: a COMGENIUS logical port 0-35
#   (default 0), or MODULE:N for another module's port (MODBMAST:1)
"""``replay://``: play back the received side of a port trace.

The port delivers the recorded RX events of one port of a trace file,
with their recorded delays measured from the program's own writes, and
compares what the program writes with the recorded TX events.

Scheduling: each RX event is anchored to the last TX event of its port
before it in the file (or to the start of the trace). Once the program has
written every recorded TX byte up to the end of the anchor (bytes counted
over all TX events in order, whatever the write sizes), the RX event is due
at (clock when that write happened) + (rx.t_ms - anchor.t_ms). RX events
anchored to the start are due at (open time) + (rx.t_ms - time of the
trace's first event); the open time is the clock reading at open, or at the
first ``set_clock()`` after it. RX events are delivered in file order (one
never overtakes the one before), each one whole at its due time.

Checking: written bytes are compared with the recorded TX bytes position by
position; each write that differs within a TX event adds a ``Mismatch``, as
does each write of bytes beyond the recording. Replay goes on after a
mismatch (bytes are counted by position, so later events stay in step).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

from serial.serialutil import SerialException

from ..clocked import Clock, ClockedSerial
from ..trace import MAX_PORT, TraceError, TraceEvent, port_label, read_trace

FORM = "replay://PATH[?port=N|MODULE:N]"
MAX_SHOWN = 5


@dataclass(frozen=True)
class Mismatch:
    """Written bytes that differ from the recording.

    ``tx_index`` is the recorded TX event (0-based, among this port's TX
    events; ``len(tx events)`` for bytes beyond the recording), ``offset``
    the position within it of the first differing byte, ``expected`` and
    ``got`` the differing run, ``t_ns`` the clock at the write, ``line`` the
    TX event's line in the trace (0 beyond the recording)."""

    tx_index: int
    offset: int
    expected: bytes
    got: bytes
    t_ns: int
    line: int


def parse_url(url: str) -> tuple[str, int | str]:
    """``(path, port)``; ValueError when bad."""
    scheme, sep, rest = url.partition("://")
    if not sep or scheme.lower() != "replay":
        raise ValueError(f"not starting with replay:// ({url!r})")
    path, _, query = rest.partition("?")
    if not path:
        raise ValueError("no trace file path")
    port = 0
    if query:
        for option in query.split("&"):
            key, eq, value = option.partition("=")
            if key != "port" or not eq:
                raise ValueError(f"unknown option {option!r}")
            label = port_label(value)
            if label is None:
                raise ValueError(f"port must be 0-{MAX_PORT} or MODULE:N, not {value!r}")
            port = label
    return path, port


def _ns(t_ms: float) -> int:
    return round(t_ms * 1_000_000)


def _hex(data: bytes, limit: int = 16) -> str:
    text = data[:limit].hex(" ").upper()
    return text + (" ..." if len(data) > limit else "") if data else "nothing"


class Serial(ClockedSerial):
    """A port playing back one port of a trace (see the module docstring)."""

    def __init__(self, *args, **kwargs) -> None:
        self.path = ""
        self.trace_port = 0
        self.mismatches: list[Mismatch] = []
        self._rebased = False
        super().__init__(*args, **kwargs)

    # - - - opening: the plan - - -

    def _open_port(self) -> None:
        try:
            path, port = parse_url(self._port)
        except ValueError as e:
            raise SerialException(f'expected a string in the form "{FORM}": {e}') from None
        try:
            events = read_trace(path)
        except TraceError as e:
            raise SerialException(f"replay: {e.report()}") from None
        mine = [e for e in events if e.port == port]
        if not mine:
            ports = sorted({e.port for e in events})
            raise SerialException(f"replay: {path}: no events for port {port} "
                                  f"(ports in the trace: {', '.join(map(str, ports)) or 'none'})")
        self.path, self.trace_port = path, port
        self._t0 = _ns(events[0].t_ms)
        self._tx: list[TraceEvent] = [e for e in mine if e.direction == "TX"]
        self._tx_end: list[int] = []
        total = 0
        for e in self._tx:
            total += len(e.data)
            self._tx_end.append(total)
        self._rx: list[tuple[TraceEvent, int]] = []
        anchor = -1
        for e in mine:
            if e.direction == "TX":
                anchor += 1
            else:
                self._rx.append((e, anchor))
        self._anchor_ns: list[int | None] = [None] * len(self._tx)
        self._written = 0
        self._next_rx = 0
        self._last_rx_ns: int | None = None
        self._buffer = bytearray()
        self._times: list[int] = []  # arrival (due) time of each byte in the buffer
        self.mismatches = []
        self._open_ns = self._clock()
        self._rebased = self._clock_set

    def _close_port(self) -> None:
        pass

    def _configure(self) -> None:
        pass

    def set_clock(self, fn: Clock) -> None:
        super().set_clock(fn)
        if self.is_open and not self._rebased:
            self._open_ns = fn()
            self._rebased = True

    # - - - delivery - - -

    def _due(self, i: int) -> int | None:
        event, anchor = self._rx[i]
        if anchor < 0:
            due = self._open_ns + _ns(event.t_ms) - self._t0
        else:
            written_at = self._anchor_ns[anchor]
            if written_at is None:
                return None
            due = written_at + _ns(event.t_ms) - _ns(self._tx[anchor].t_ms)
        last = self._last_rx_ns
        return due if last is None or due > last else last

    def _pump(self, now: int) -> None:
        while self._next_rx < len(self._rx):
            due = self._due(self._next_rx)
            if due is None or due > now:
                return
            data = self._rx[self._next_rx][0].data
            self._buffer += data
            self._times += [due] * len(data)
            self._last_rx_ns = due
            self._next_rx += 1

    def _take(self, size: int, now: int) -> bytes:
        if not self.is_open:
            return b""
        self._pump(now)
        data = bytes(self._buffer[:size])
        del self._buffer[:size]
        del self._times[:size]
        return data

    def _take_timed(self, now: int) -> tuple[bytes, list[int]]:
        """Each recorded RX event's bytes arrive together, at its due time."""
        if not self.is_open:
            return b"", []
        self._pump(now)
        data, times = bytes(self._buffer), self._times
        self._buffer.clear()
        self._times = []
        return data, times

    def _available(self, now: int) -> int:
        self._pump(now)
        return len(self._buffer)

    def _pending(self, now: int) -> int:
        return 0

    def _reset_input(self, now: int) -> None:
        self._pump(now)
        self._buffer.clear()
        self._times.clear()

    def _reset_output(self, now: int) -> None:
        pass

    # - - - checking - - -

    def _write(self, data: bytes, now: int) -> None:
        self._pump(now)
        pos, end = self._written, self._written + len(data)
        total = self._tx_end[-1] if self._tx_end else 0
        j = bisect.bisect_right(self._tx_end, pos)
        while j < len(self._tx) and self._tx_end[j] - len(self._tx[j].data) < end:
            event = self._tx[j]
            ev_start = self._tx_end[j] - len(event.data)
            lo, hi = max(pos, ev_start), min(end, self._tx_end[j])
            expected = event.data[lo - ev_start:hi - ev_start]
            got = data[lo - pos:hi - pos]
            if expected != got:
                diff = [k for k in range(len(got)) if got[k] != expected[k]]
                first, last = diff[0], diff[-1] + 1
                self.mismatches.append(Mismatch(j, lo - ev_start + first, expected[first:last],
                                                got[first:last], now, event.line))
            if hi == self._tx_end[j]:
                self._anchor_ns[j] = now
            j += 1
        if end > total:
            start = max(pos, total)
            self.mismatches.append(Mismatch(len(self._tx), start - total, b"", data[start - pos:], now, 0))
        self._written = end

    # - - - results - - -

    @property
    def finished(self) -> bool:
        """All RX events delivered and all recorded TX bytes written."""
        self._check_open()
        self._pump(self._clock())
        return self._next_rx == len(self._rx) and self._written >= (self._tx_end[-1] if self._tx_end else 0)

    def _exchanges(self) -> tuple[int, int]:
        """(complete, total): an exchange is a TX event with the RX events
        after it, plus a leading group of RX events before any TX."""
        groups: dict[int, int] = {}  # anchor -> RX events not yet delivered
        for i, (_, anchor) in enumerate(self._rx):
            groups[anchor] = groups.get(anchor, 0) + (i >= self._next_rx)
        for j in range(len(self._tx)):
            groups.setdefault(j, 0)
        done = sum(1 for anchor, waiting in groups.items()
                   if not waiting and (anchor < 0 or self._written >= self._tx_end[anchor]))
        return done, len(groups)

    def report(self) -> str:
        """A short summary: exchanges done, and the first output differences."""
        self._check_open()
        self._pump(self._clock())
        done, total = self._exchanges()
        head = f"replay port {self.trace_port} of {self.path}: {done} of {total} exchanges"
        if not self.mismatches:
            tx_total = self._tx_end[-1] if self._tx_end else 0
            if self._written < tx_total:
                j = bisect.bisect_right(self._tx_end, self._written)
                return f"{head}, output matched so far (next: TX {j}, line {self._tx[j].line})"
            return f"{head}, output matched"
        lines = [f"{head}, {len(self.mismatches)} output difference(s):"]
        for m in self.mismatches[:MAX_SHOWN]:
            if m.line:
                lines.append(f"  line {m.line}: TX {m.tx_index} byte {m.offset}: "
                             f"expected {_hex(m.expected)}, got {_hex(m.got)}")
            else:
                lines.append(f"  after the recording: {len(m.got)} extra byte(s) {_hex(m.got)}")
        if len(self.mismatches) > MAX_SHOWN:
            lines.append(f"  ... and {len(self.mismatches) - MAX_SHOWN} more")
        return "\n".join(lines)

    def __repr__(self) -> str:
        if not self.is_open:
            return f"<replay port {self._port!r} closed>"
        return (f"<replay port {self._port!r} {self._settings()}: port {self.trace_port}, "
                f"{self._next_rx} of {len(self._rx)} RX events delivered, "
                f"{self._written} bytes written, {len(self.mismatches)} mismatch(es)>")
