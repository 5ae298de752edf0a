"""A serial line with scripted replies: the device behind
``sim://NAME?device=scripted``.

A rule is (match, reply): when the bytes the port has sent since the last
match end with ``match``, the device sends ``reply``, ``delay_ms`` after the
arrival of the match's last byte (a device's turnaround, exact as every
device's is: see simdevices.py). Rules are tried in order at each byte; the
bytes up to a match are forgotten once it matched, so a request is answered
once. Bytes no rule matches wait for more (only the last bytes a rule could
still match are kept). This is enough to stand in for an instrument that
answers a fixed command ("?" -> "OK\\r\\n"), a scale, a barcode reader polled
by a string, or a device that answers garbage.

Options (``sim://NAME?device=scripted&match=%3F&reply=OK%0D%0A&delay_ms=5``;
any other option is a ValueError):

- ``match``, ``reply``: the first rule, text whose characters are bytes
  0-255 (ISO-8859-1), percent-encoded in a URL; ``match2``/``reply2`` ..
  ``match9``/``reply9`` more rules. A reply may be empty (the device takes
  the request and answers nothing); a match may not.
- ``delay_ms``: the time from a match's last byte to its reply (default 0;
  a number >= 0).

From Python: ``ScriptedLine([(b"?", b"OK\\r\\n")], delay_ms=5)``. Its score:
``received`` (bytes), ``replies`` (replies sent), ``hits`` (replies a rule,
by rule index), ``unmatched`` (bytes no rule has matched yet), and ``log``,
the last 50 (request, reply) pairs.
"""

from __future__ import annotations

from collections import deque

from . import simdevices
from .simdevices import SimDevice, check_options, float_option

KIND = "scripted"
RULES = 9
OPTIONS = ("delay_ms", *(f"{key}{n if n > 1 else ''}" for n in range(1, RULES + 1) for key in ("match", "reply")))


class ScriptedLine(SimDevice):
    """Answers each request that ends with a rule's match with its reply."""

    name = KIND

    def __init__(self, rules, delay_ms: float = 0.0) -> None:
        self.rules: list[tuple[bytes, bytes]] = []
        for i, rule in enumerate(rules):
            try:
                match, reply = rule
            except (TypeError, ValueError):
                raise ValueError(f"{KIND} device: rule {i + 1} must be a (match, reply) pair, not {rule!r}") from None
            match, reply = _bytes(match, f"rule {i + 1}'s match"), _bytes(reply, f"rule {i + 1}'s reply")
            if not match:
                raise ValueError(f"{KIND} device: rule {i + 1}'s match is empty (it would match before any byte)")
            self.rules.append((match, reply))
        if not self.rules:
            raise ValueError(f"{KIND} device: expected at least one (match, reply) rule")
        if not (isinstance(delay_ms, (int, float)) and delay_ms >= 0):
            raise ValueError(f"{KIND} device: delay_ms must be a number >= 0, not {delay_ms!r}")
        self.delay_ns = round(delay_ms * 1_000_000)
        self._keep = max(len(m) for m, _ in self.rules)
        self._buffer = bytearray()
        self.received = self.replies = 0
        self.hits = [0] * len(self.rules)
        self.log: deque[tuple[bytes, bytes]] = deque(maxlen=50)
        self._request = bytearray()  # the bytes since the last match, for the log

    def receive(self, data: bytes, times_ns: list[int]) -> None:
        for byte, t in zip(data, times_ns):
            self.received += 1
            self._buffer.append(byte)
            self._request.append(byte)
            for i, (match, reply) in enumerate(self.rules):
                if self._buffer.endswith(match):
                    if reply:
                        self.end.send(reply, t + self.delay_ns)
                    self.replies += 1
                    self.hits[i] += 1
                    self.log.append((bytes(self._request), reply))
                    self._buffer.clear()
                    self._request.clear()
                    break
            else:
                if len(self._buffer) > self._keep:
                    del self._buffer[:-self._keep]
                if len(self._request) > 4096:
                    del self._request[:-4096]

    def next_due(self, now_ns: int) -> int | None:
        return None  # it acts only on what it receives

    @property
    def unmatched(self) -> int:
        return len(self._request)

    def __repr__(self) -> str:
        return (f"<ScriptedLine {len(self.rules)} rule(s): {self.received} bytes received, "
                f"{self.replies} replies>")


def _bytes(value, what: str) -> bytes:
    if isinstance(value, str):
        try:
            return value.encode("latin-1")
        except UnicodeEncodeError:
            raise ValueError(f"{KIND} device: {what} must be bytes 0-255 (ISO-8859-1 text), not {value!r}") from None
    if isinstance(value, (bytes, bytearray)):
        return bytes(value)
    raise ValueError(f"{KIND} device: {what} must be bytes or text, not {value!r}")


def create(options: dict[str, str]) -> ScriptedLine:
    """The ``scripted`` device factory: ``options`` as given in the URL."""
    check_options(KIND, options, OPTIONS)
    rules = []
    for n in range(1, RULES + 1):
        suffix = str(n) if n > 1 else ""
        match, reply = options.get("match" + suffix), options.get("reply" + suffix)
        if (match is None) != (reply is None):
            given, missing = ("match", "reply") if reply is None else ("reply", "match")
            raise ValueError(f"{KIND} device: {given}{suffix} needs {missing}{suffix}")
        if match is not None:
            rules.append((match, reply))
    return ScriptedLine(rules, float_option(KIND, options, "delay_ms", 0.0))


simdevices.register_device(KIND, create)
