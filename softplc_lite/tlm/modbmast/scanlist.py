"""A port's scan list (manual 3.3): which request goes next, and when.

The list holds the port's ``run`` requests in configuration order (ports,
slaves and requests as the file lists them). The request at the front is
the one being processed; when it completes or fails it moves to the rear
("a failed request goes to the end of the list"). A request whose
``minPeriod`` has not passed since it was last sent is passed over, keeping
its place, so the others go round as fast as the wire allows and the
periodic one goes as soon as its period is up.

One-shots go before the list: on each entry to RUN the ``start`` requests
are queued (from PROGRAM, TEST or FAULTED-then-PROGRAM, Table 6), on leaving
RUN for PROGRAM or FAULTED the ``stop`` requests; a change of mode drops the
one-shots of the other kind that have not gone yet. A one-shot is sent once
(with its retries: ``attempts``); it is not repeated when it fails.

Demotion (a softplc_lite extension, off unless ``demoteAfter`` > 0): a slave
whose last ``demoteAfter`` x (its run requests) requests in a row got no
reply at all (it stayed Not Present through that many passes of its
requests) is demoted: its run requests are passed over, except that one of
them is sent every ``demotePeriod`` ms as a probe. Any reply promotes it
again. So a dead slave costs one timeout per demotePeriod, not one per
request per pass.
"""

from __future__ import annotations

from collections import deque

from .config import Request, Slave
from .status import SlaveStatus

NEVER = 1 << 62


class ScanList:
    def __init__(self, requests: list[Request], slaves: dict[int, Slave], status: dict[int, SlaveStatus]) -> None:
        self.run = [r for r in requests if r.when == "run"]
        self.start_requests = [r for r in requests if r.when == "start"]
        self.stop_requests = [r for r in requests if r.when == "stop"]
        self.next_allowed = [0] * len(self.run)  # ns: last send + minPeriod
        self.cursor = 0  # index of the front of the list
        self.oneshots: deque[Request] = deque()
        self.oneshot_kind = ""
        self.status = status
        self.slaves = slaves
        self._runs_of = {sid: sum(1 for r in self.run if r.slave == sid) for sid in slaves}

    def __len__(self) -> int:
        return len(self.run) + len(self.start_requests) + len(self.stop_requests)

    # -- modes ------------------------------------------------------------------------------
    def entered_run(self) -> None:
        self._queue("start", self.start_requests)

    def left_run(self) -> None:
        self._queue("stop", self.stop_requests)

    def _queue(self, kind: str, requests: list[Request]) -> None:
        if self.oneshot_kind != kind:
            self.oneshots.clear()
        self.oneshot_kind = kind
        self.oneshots.extend(requests)

    # -- choosing -----------------------------------------------------------------------------
    def next(self, now: int) -> tuple[Request | None, int]:
        """The request to send at ``now`` and its run-list index (-1 for a
        one-shot), or (None, the earliest time one may go)."""
        if self.oneshots:
            return self.oneshots.popleft(), -1
        run = self.run
        n = len(run)
        if not n:
            return None, NEVER
        allowed = self.next_allowed
        status = self.status
        earliest = NEVER
        for step in range(n):
            k = (self.cursor + step) % n
            t = allowed[k]
            request = run[k]
            s = status[request.slave]
            if s.demoted:
                t = max(t, s.probe_at)
            if t <= now:
                self.cursor = (k + 1) % n
                if s.demoted:
                    s.probe_at = now + self.slaves[request.slave].demote_period_ms * 1_000_000
                return request, k
            if t < earliest:
                earliest = t
        return None, earliest

    def sent(self, index: int, at: int, request: Request) -> None:
        """A run request went on the wire at ``at`` (its minPeriod starts)."""
        if index >= 0:
            self.next_allowed[index] = at + request.min_period_ms * 1_000_000

    def unanswered(self, request: Request, now: int) -> None:
        """A request failed without any reply: demote its slave after
        ``demoteAfter`` passes of its requests."""
        slave = self.slaves[request.slave]
        s = self.status[request.slave]
        runs = self._runs_of.get(request.slave, 0)
        if slave.demote_after and runs and not s.demoted and s.silent_requests >= slave.demote_after * runs:
            s.demoted = True
            s.probe_at = now + slave.demote_period_ms * 1_000_000
