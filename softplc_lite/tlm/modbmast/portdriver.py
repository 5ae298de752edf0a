"""One MODBMAST port: its transactions, timed as the manual and the Modbus
serial-line specification say (manual 3.3-3.4; docs/modbmast.md).

A transaction: pick the next request from the scan list; with ModemControl,
raise RTS and wait for CTS (``waitDelayCTS``, else -4 NO CTS); send the
request; time ``requestTimeout`` from the end of its transmission to the
first reply byte (else -3 NO REPLY, and again at once while ``attempts``
remain); after the first byte, the specification's inter-character timeout
(RTU: 1.5 character times, 750 us above 19200 baud; ASCII: 1 s) ends an
unfinished reply (-2 INCOMPLETE REPLY). A reply is complete at the length
its function and byte count give (RTU) or at CR LF (ASCII); then its CRC or
LRC (-1 BAD CRC) and its match with the request (-7 BAD REPLY) are checked.
The next request waits ``requestGap`` after the reply, and never less than
the RTU frame gap of 3.5 character times (1.75 ms above 19200 baud).

Time: a simulated port (``sim://``, ``replay://``) runs on the engine's
clock. At each call the driver catches up to the engine's time, processing
every event at its exact time (the wire gives each byte's arrival time), so
a port's throughput does not depend on the scan time. A real port runs on
the wall clock and is looked at each time the driver is called (the engine's
input and output points): its timing is as fine as the scan, and its
inter-character timeout is at least ``REAL_INTER_CHAR_NS`` (an OS and a USB
adapter deliver bytes in bursts; the specification's 1.5 characters cannot be
measured between scans).
"""

from __future__ import annotations

from typing import Callable

from ...ladder.host import Mode
from ...modbus.framing import FRAMERS, FrameError, rtu_intervals_ns
from ...ports import SerialPort, hexdump
from .config import PortConfig
from .prepared import Prepared
from .scanlist import ScanList
from .status import (BAD_CRC, BAD_REPLY, INCOMPLETE_REPLY, NO_CTS, NO_REPLY, NO_XMIT_ROOM, WAIT_XMITTED,
                     SlaveStatus, code_name)

IDLE, CTS_WAIT, SENDING, WAITING, RECEIVING = "idle", "cts", "sending", "waiting", "receiving"
ASCII_INTER_CHAR_NS = 1_000_000_000  # serial-line spec 2.5.2.1: up to 1 s between characters
REAL_INTER_CHAR_NS = 20_000_000  # on a real port, see the module docstring
MAX_STEPS = 10_000  # events handled in one call at most (a wire at "rate=unlimited" takes no time)
MS = 1_000_000


class Transaction:
    __slots__ = ("prepared", "index", "attempt", "frame", "sent_at", "tx_end", "deadline", "buffer", "last_at",
                 "written", "rts_at", "expected")

    def __init__(self, prepared: Prepared, index: int, attempt: int) -> None:
        self.prepared = prepared
        self.index = index
        self.attempt = attempt
        self.frame = b""
        self.sent_at = self.tx_end = self.deadline = self.last_at = self.rts_at = 0
        self.buffer = bytearray()
        self.written = 0
        self.expected: int | None = None  # an RTU reply's length, once its first bytes tell


class PortDriver:
    def __init__(self, config: PortConfig, port: SerialPort, prepared: dict[int, Prepared],
                 status: dict[int, SlaveStatus], mode: Callable[[], Mode], log: Callable[[int, str], None]) -> None:
        self.config = config
        self.port = port
        self.mode = mode
        self.log = log
        self.status = status
        self.prepared = prepared  # by id() of each configured request
        self.scan = ScanList([r for s in config.slaves.values() for r in s.requests], config.slaves, status)
        self.framer = FRAMERS[config.framing]
        self.ascii = config.framing == "ASCII"
        self.char_ns = port.settings.char_ns
        if self.ascii:
            self.inter_ns, silent = ASCII_INTER_CHAR_NS, 0
        else:
            self.inter_ns, silent = rtu_intervals_ns(config.baud, self.char_ns)
        self.t35_ns = silent
        self.gap_ns = max(config.request_gap_ms * MS, silent)
        self.state = IDLE
        self.free_at = 0  # the line is free for the next request (after the gap)
        self.ready_at = 0  # when the next request may go: free_at, or later when none is due yet
        self.vt = 0  # the port's clock (ns): the time of the event being handled
        # A simulated port has been read up to this time since the last
        # write: reading it again up to then cannot find anything new.
        self.read_to = 0
        self.tx: Transaction | None = None
        self.retry: Transaction | None = None
        self.transactions = self.good = 0  # counts, for diagnostics and benchmarks
        # Replies completed at the output point wait for the next input point,
        # so the data table changes only there (and input forces hold).
        self.pending: list[tuple[Prepared, bytes]] = []
        self.at_input = True
        self.input_target = -1  # the time the last input point caught up to
        self.was_up = False

    def clock(self) -> int:
        return self.vt

    def _say(self, level: int, message: str) -> None:
        """A debug line stamped with the port and its own clock (the exact
        wire time of the event, which can lie between two scans)."""
        self.log(level, f"port {self.config.num} @{self.vt / MS:.3f}ms {message}")

    def __repr__(self) -> str:
        return f"<PortDriver {self.config.num} {self.port.url} {self.state}>"

    # -- the driver's calls ----------------------------------------------------------------
    def started(self, now: int) -> None:
        """The port opened (or came back) at ``now``."""
        self.vt = self.ready_at = self.free_at = now
        if not self.port.clocked:
            self.inter_ns = max(self.inter_ns, REAL_INTER_CHAR_NS)
        if self.config.wait_cts_ms is not None:
            self.port.set_rts(False)  # raised only to send (manual 1.4.2)
        self.was_up = True

    def advance(self, target: int, input_point: bool) -> None:
        """Handle everything due by ``target`` (ns on the port's clock).
        At the input point a send due exactly at ``target`` waits for the
        output point, so it carries this scan's outputs."""
        port = self.port
        self.at_input = input_point
        if input_point and self.pending:
            for prepared, data in self.pending:
                prepared.store(data)
            self.pending.clear()
        if not port.up:
            self._down(target)
            return
        clocked = port.clocked
        if input_point:
            self.input_target = target
        elif clocked and target == self.input_target and self.state is not IDLE:
            return  # the same instant as the input point, which handled all but a send due right now
        for _ in range(MAX_STEPS):
            state = self.state
            if state is IDLE:
                t = self.ready_at
                if t > target or (t == target and input_point and clocked):
                    return
                self.vt = t if clocked else target
                self._begin()
            elif state is WAITING or state is RECEIVING:
                due = self._due()
                if not clocked:
                    step = target
                elif state is RECEIVING and self.tx.expected is not None and target < due:
                    return  # an RTU reply of known length cannot be complete yet; its byte times tell the rest
                else:
                    step = min(due, target)
                if not clocked or step > self.read_to:
                    self.vt = step
                    data, times = port.read_timed()
                    self.read_to = step
                    if data:
                        self._received(data, times or [step] * len(data))
                        continue  # the reply may be complete, or has moved on: look again
                    if not port.up:
                        return
                if step >= due:
                    self.vt = step
                    self._expired()
                elif step >= target:
                    return
            elif state is CTS_WAIT:
                tx = self.tx
                deadline = tx.rts_at + self.config.wait_cts_ms * MS
                self.vt = min(deadline, target) if clocked else target
                on, since = port.cts()
                if on:
                    if clocked and since is not None:
                        self.vt = max(since, tx.rts_at)
                    self._send()
                elif self.vt >= deadline:
                    self.vt = deadline if clocked else self.vt
                    port.set_rts(False)
                    self._fail(NO_CTS, self.vt)
                else:
                    return
            else:  # SENDING: the port took part of the request; the rest when it has room
                self.vt = target
                self._send_more()
                if self.state is SENDING:
                    return
        self._say(1, f"more than {MAX_STEPS} events in one scan; the rest waits")

    # -- sending ------------------------------------------------------------------------------
    def _begin(self) -> None:
        """Start the next transaction at ``vt``, or note when one may go."""
        if self.retry is not None:
            tx, self.retry = self.retry, None
        else:
            request, index = self.scan.next(self.vt)
            if request is None:
                self.ready_at = index  # the earliest time one is due (NEVER: none in this mode)
                return
            tx = Transaction(self.prepared[id(request)], index, 1)
        self.tx = tx
        idle = tx.prepared.request.when == "run" and self.mode() is not Mode.RUN
        tx.frame = tx.prepared.frame(idle)
        self.scan.sent(tx.index, self.vt, tx.prepared.request)
        stale, _ = self.port.read_timed()  # what came in since the last reply is no one's reply
        if stale:
            self._say(2, f"{len(stale)} stray byte(s) dropped before a request: "
                        f"{hexdump(stale, 16)}")
        if self.config.wait_cts_ms is not None:
            tx.rts_at = self.vt
            self.port.set_rts(True)
            self.state = CTS_WAIT
            return
        self._send()

    def _send(self) -> None:
        tx = self.tx
        tx.sent_at = self.read_to = self.vt  # a reply to this can come before times read already
        tx.written = 0
        self.state = SENDING
        self._send_more()

    def _send_more(self) -> None:
        tx = self.tx
        n = self.port.write(tx.frame[tx.written:])
        tx.written += n
        if tx.written < len(tx.frame):
            if not self.port.up:
                self._fail(NO_XMIT_ROOM, self.vt)
            elif self.vt - tx.sent_at >= tx.prepared.request.timeout_ms * MS:
                self.port.reset_output()
                self._fail(NO_XMIT_ROOM, self.vt)
            return
        # The timeout runs from the end of the transmission (manual 3.4): the
        # last bytes handed over leave the port one character time each.
        tx.tx_end = self.vt + n * self.char_ns
        tx.deadline = tx.tx_end + tx.prepared.request.timeout_ms * MS
        tx.buffer.clear()
        self.transactions += 1
        self.state = WAITING
        self._say(2, f"slave {tx.prepared.slave}: {tx.prepared.request.name} sent "
                    f"{hexdump(tx.frame, 24)}")

    # -- receiving ------------------------------------------------------------------------------
    def _due(self) -> int:
        """When the transaction must be looked at next: its deadline while
        waiting for the first byte; while receiving, when the reply should be
        complete or the inter-character timeout would end it."""
        tx = self.tx
        if self.state is WAITING:
            return tx.deadline
        limit = tx.last_at + self.char_ns + self.inter_ns
        expected = tx.expected
        if expected is not None and expected > len(tx.buffer):
            return max(limit, tx.last_at + (expected - len(tx.buffer)) * self.char_ns)
        return limit

    def _received(self, data: bytes, times: list[int]) -> None:
        tx = self.tx
        char, inter = self.char_ns, self.inter_ns
        if self.state is WAITING:
            if self.port.clocked and times[0] > tx.deadline:
                return  # too late: the timeout comes first
            self.state = RECEIVING
            previous = times[0] - char  # as if a character had just ended: no silence before the first
        else:
            previous = tx.last_at
        # Bytes after a silence longer than the inter-character timeout are
        # not part of the reply. One subtraction tells when there is none.
        cut = len(data)
        if times[-1] - previous > cut * char + inter:
            last = previous
            for k, t in enumerate(times):
                if t - last - char > inter:
                    cut = k
                    break
                last = t
        if cut:
            tx.buffer += data[:cut]
            tx.last_at = times[cut - 1]
        buffer = tx.buffer
        if self.ascii:
            end = self.framer.frame_end(bytes(buffer))
            complete = end is not None
        else:
            if tx.expected is None:
                tx.expected = self.framer.response_length(bytes(buffer[:3]))
            end = tx.expected
            complete = end is not None and len(buffer) >= end
        if complete:
            self._ended(times[end - (len(buffer) - cut) - 1], complete=True, length=end)
        elif cut < len(data):
            self._ended(tx.last_at + char + inter, complete=False)
        elif len(buffer) > (self.framer.MAX_FRAME_LENGTH if self.ascii else self.framer.MAX_ADU_LENGTH):
            self._ended(tx.last_at, complete=False)

    def _expired(self) -> None:
        tx = self.tx
        if self.state is WAITING:
            if self.port.out_waiting() > 0:
                self._fail(WAIT_XMITTED, tx.deadline if self.port.clocked else self.vt)
                return
            self._timeout()
        else:  # nothing came after the last byte for longer than the inter-character limit
            self._ended(tx.last_at + self.char_ns + self.inter_ns if self.port.clocked else self.vt, complete=False)

    def _timeout(self) -> None:
        tx = self.tx
        at = tx.deadline if self.port.clocked else self.vt
        status = self.status[tx.prepared.slave]
        status.timed_out()
        request = tx.prepared.request
        if tx.attempt < request.attempts:  # manual 3.3: tried again at once, at that point in the scan list
            self._say(1, f"slave {tx.prepared.slave}: {request.name}: no reply in "
                        f"{request.timeout_ms} ms, attempt {tx.attempt + 1} of {request.attempts}")
            self.retry = Transaction(tx.prepared, tx.index, tx.attempt + 1)
            self._next(max(at, tx.tx_end + self.t35_ns))
            return
        self._fail(NO_REPLY, at)

    def _ended(self, at: int, complete: bool, length: int = 0) -> None:
        """The reply ended at ``at``: whole (``length`` bytes) or cut short."""
        if self.port.clocked:
            self.vt = at
        tx = self.tx
        p = tx.prepared
        status = self.status[p.slave]
        frame = bytes(tx.buffer[:length]) if complete else bytes(tx.buffer)
        if self.ascii and complete:
            frame = frame[self.framer.frame_start(frame):]
        try:
            unit, pdu = self.framer.decode(frame)
        except FrameError as e:
            code = BAD_CRC if e.kind in ("crc", "lrc") else (INCOMPLETE_REPLY if not complete else BAD_REPLY)
            if e.kind in ("crc", "lrc") and not complete:
                code = INCOMPLETE_REPLY
            status.present, status.silent_requests, status.demoted = True, 0, False
            self._fail(code, at, frame)
            return
        if not complete:  # a whole frame, but not of the length the request's reply has
            status.present, status.silent_requests, status.demoted = True, 0, False
            self._fail(BAD_REPLY, at, frame)
            return
        code, data = p.check_reply(pdu) if unit == p.slave and pdu else (BAD_REPLY, b"")
        if code == BAD_REPLY:
            status.present, status.silent_requests, status.demoted = True, 0, False
            self._fail(BAD_REPLY, at, frame)
            return
        # A pty ignores the baud rate: a reply can come before the request's
        # computed end of transmission. A response time is never negative.
        response_ms = max(at - tx.tx_end, 0) / MS
        status.replied(response_ms)
        if code:
            self._fail(code, at, frame)
            return
        if self.at_input:
            p.store(data)
        else:
            self.pending.append((p, data))
        status.succeeded()
        self.good += 1
        self._say(2, f"slave {p.slave}: {p.request.name} ok in {response_ms:.2f} ms: {hexdump(frame, 24)}")
        self.tx = None
        self._next(at + self.gap_ns)

    def _fail(self, code: int, at: int, frame: bytes = b"") -> None:
        if self.port.clocked:
            self.vt = at
        tx = self.tx
        p = tx.prepared
        status = self.status[p.slave]
        was_present = status.present
        status.failed(p.function, code)
        if code in (NO_REPLY, NO_CTS, NO_XMIT_ROOM, WAIT_XMITTED):
            self.scan.unanswered(p.request, at)
        shown = f": {hexdump(frame, 24)}" if frame else ""
        self._say(1, f"slave {p.slave}: {p.request.name} failed: {code} "
                    f"{code_name(code)}{shown}")
        if was_present and not status.present:
            self._say(1, f"slave {p.slave}: Not Present")
        self.tx = None
        replied = code not in (NO_REPLY, NO_CTS, NO_XMIT_ROOM, WAIT_XMITTED)
        self._next(at + self.gap_ns if replied else max(at, (tx.tx_end or at) + self.t35_ns))

    def _next(self, at: int) -> None:
        self.state = IDLE
        self.ready_at = self.free_at = at
        if self.config.wait_cts_ms is not None:
            self.port.set_rts(False)

    # -- the port going down and coming back -----------------------------------------------------
    def _down(self, now: int) -> None:
        if self.was_up:
            self.was_up = False
            for slave in self.config.slaves:
                s = self.status[slave]
                s.present = False
                s.last_code = NO_XMIT_ROOM
            self.tx = self.retry = None
            self.state = IDLE
            self._say(1, f"down ({self.port.error}): its slaves are Not Present")
        if self.port.retry():
            self.started(now)

    def mode_changed(self, old: Mode, new: Mode, now: int) -> None:
        """Table 6: start requests on entering RUN, stop requests on leaving
        it for PROGRAM or FAULTED; they go as soon as the line is free after
        ``now``, the time of the change."""
        if new is Mode.RUN and old is not Mode.RUN:
            self.scan.entered_run()
        elif old is Mode.RUN and new in (Mode.PROGRAM, Mode.FAULTED):
            self.scan.left_run()
        if self.state is IDLE and self.scan.oneshots:
            self.ready_at = max(self.free_at, min(self.ready_at, now))
