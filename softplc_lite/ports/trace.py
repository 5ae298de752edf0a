"""Port trace files: what went over the serial ports, one event a line.

A trace is a UTF-8 text file (docs/simulated-wire.md has the full page)::

    # softplc_lite port trace 1
    # port 0: COM1 -> sim://bus?device=echo 38400 8N1 ISO-8859-1
    # time_ms port dir bytes
    0.000 0 TX 02 03 00 00 00 7D 85 D8
    70.312 0 RX 02 03 FA 00 01

- ``#`` starts a comment (to the end of the line); blank lines are ignored.
- An event line has the time in ms (a decimal number, never smaller than the
  time of the line before it), the port, the direction (``TX``: written by
  the program, ``RX``: received by the program) and one or more two-digit hex
  bytes (any case). One event is one line however long it is.
- The port is a COMGENIUS logical port number (0-35), or a port of another
  module written ``MODULE:N`` (``MODBMAST:1``, N 0-35): ``port_label()``.
- The first line is the header ``# softplc_lite port trace 1``. A reader
  tolerates a file without it, but refuses another version number.
- A comment line ``# scans: N`` (anywhere, a remark may follow N; the
  first counts) says how many scans of the program the trace covers:
  ``softplc run --replay TRACE`` without ``--scans`` runs that many
  (``covered_scans()``). Without it the replay stops once every recorded
  byte has been played and written.

Errors name the file, line and column: ``parse_trace`` raises a
``TraceError`` (a ``PortError``), whose ``report()`` reads
``path:line:column: reason``.

>>> events = parse_trace("0.000 0 TX 02 03\\n1.5 0 RX 02 83 # exception\\n")
>>> events[1]
TraceEvent(t_ms=1.5, port=0, direction='RX', data=b'\\x02\\x83')
>>> parse_trace("0.000 0 TX 2\\n", "a.trace")
Traceback (most recent call last):
...
softplc_lite.ports.trace.TraceError: a.trace:1:12: expected a two-digit hex byte, found '2'
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import IO, Sequence

from ..errors import LocatedError, os_error_words
from ..textfile import TRACE, read_text
from .errors import PortError

HEADER = "# softplc_lite port trace 1"
VERSION = 1
MAX_PORT = 35
DIRECTIONS = ("TX", "RX")

_HEADER = re.compile(r"^\s*#\s*softplc_lite port trace\s+(\S+)\s*$")
_TIME = re.compile(r"^[0-9]{1,15}(\.[0-9]{1,9})?$")
_PORT = re.compile(r"^(?:([A-Za-z][A-Za-z0-9_]*):)?([0-9]{1,6})$")
_HEX = re.compile(r"^[0-9A-Fa-f]{2}$")
_FIELD = re.compile(r"\S+")
_SCANS = re.compile(r"^\s*#\s*scans:\s*([0-9]{1,15})(?:\s.*)?$", re.MULTILINE)  # a remark may follow N


class TraceError(PortError):
    """A trace file that cannot be read, with its path, line and column."""


@dataclass(frozen=True)
class TraceEvent:
    """One line of a trace: ``data`` went ``direction`` on ``port`` at ``t_ms``.

    ``line`` is the 1-based line in the file it was read from (0 when not
    read from a file); equality ignores it."""

    t_ms: float
    port: int | str  # a COMGENIUS logical port number, or "MODULE:N"
    direction: str
    data: bytes
    line: int = field(default=0, compare=False, repr=False)


def parse_trace(text: str, path: str = "<trace>") -> list[TraceEvent]:
    """The events of a trace file's text, in file order."""
    events: list[TraceEvent] = []
    previous: TraceEvent | None = None
    for number, raw in enumerate(text.splitlines(), start=1):
        if number == 1:
            header = _HEADER.match(raw)
            if header and header.group(1) != str(VERSION):
                raise TraceError(
                    f"trace format version {header.group(1)} is not supported (this reader knows {VERSION})",
                    path, number, header.start(1) + 1)
        line = raw.split("#", 1)[0]
        fields = list(_FIELD.finditer(line))
        if not fields:
            continue
        event = _parse_event(fields, len(line.rstrip()) + 2, number, path)
        if previous is not None and event.t_ms < previous.t_ms:
            raise TraceError(
                f"time {fields[0].group()} is before the previous event's {previous.t_ms:.3f} "
                f"(line {previous.line}); times must not decrease", path, number, fields[0].start() + 1)
        events.append(event)
        previous = event
    return events


def _parse_event(fields: list[re.Match], end_column: int, number: int, path: str) -> TraceEvent:
    def fail(message: str, column: int) -> TraceError:
        return TraceError(message, path, number, column)

    def need(index: int, what: str) -> re.Match:
        if index >= len(fields):
            raise fail(f"expected {what} after '{fields[index - 1].group()}'", end_column)
        return fields[index]

    time = fields[0]
    if not _TIME.match(time.group()):
        raise fail(f"expected a time in ms such as 12.345, found '{time.group()}'", time.start() + 1)
    port = need(1, "a port (0-35, or MODULE:N)")
    label = port_label(port.group())
    if label is None:
        raise fail(f"expected a port number 0-{MAX_PORT} or MODULE:N, found '{port.group()}'", port.start() + 1)
    direction = need(2, "TX or RX")
    if direction.group() not in DIRECTIONS:
        raise fail(f"expected TX or RX, found '{direction.group()}'", direction.start() + 1)
    need(3, "one or more hex bytes")
    for byte in fields[3:]:
        if not _HEX.match(byte.group()):
            raise fail(f"expected a two-digit hex byte, found '{byte.group()}'", byte.start() + 1)
    data = bytes.fromhex("".join(m.group() for m in fields[3:]))
    return TraceEvent(float(time.group()), label, direction.group(), data, number)


def port_label(text: str | int) -> int | str | None:
    """A trace's port field: the number for "0".."35", "MODULE:N" (module
    name upper-cased) for a module's port, None when it is neither.

    >>> port_label("3"), port_label("modbmast:1"), port_label("36"), port_label("x")
    (3, 'MODBMAST:1', None, None)
    """
    m = _PORT.match(str(text).strip())
    if m is None or int(m.group(2)) > MAX_PORT:
        return None
    return f"{m.group(1).upper()}:{int(m.group(2))}" if m.group(1) else int(m.group(2))


def read_trace(path: str | os.PathLike) -> list[TraceEvent]:
    """The events of the trace file at ``path``; a file that cannot be read
    or parsed raises ``TraceError`` naming it."""
    name = os.fspath(path)
    try:
        text = read_text(name, limit=TRACE)
    except LocatedError as e:
        raise TraceError(e.message, name, e.line, e.column) from None
    except OSError as e:  # errors.FileAccessError: "cannot read PATH: not a regular file (a FIFO)"
        raise TraceError(f"cannot read trace file: {os_error_words(e)}", name) from None
    return parse_trace(text, name)


def scans_in(text: str) -> int | None:
    """The N of a trace text's first ``# scans: N`` comment, None without one.

    >>> scans_in("# softplc_lite port trace 1\\n# scans: 1195\\n0.000 0 TX 01\\n")
    1195
    >>> scans_in("# scans: 40 (at 10 ms a scan)\\n")
    40
    >>> scans_in("0.000 0 TX 01  # scans: 5\\n") is None
    True
    """
    m = _SCANS.search(text)
    return int(m.group(1)) if m else None


def covered_scans(path: str | os.PathLike) -> int | None:
    """The scans the trace file at ``path`` says it covers (``# scans: N``),
    None without that comment or when the file cannot be read (opening the
    replay port then says why)."""
    try:
        return scans_in(read_text(os.fspath(path), limit=TRACE))
    except (OSError, LocatedError):
        return None


def format_event(t_ms: float, port: int | str, direction: str, data: bytes) -> str:
    """One event line (no newline): time with 3 decimals, hex in upper case."""
    return f"{t_ms:.3f} {port} {direction} {data.hex(' ').upper()}"


class TraceWriter:
    """Writes a trace: the header, the ``comments`` (each line prefixed by
    ``# ``), then one line per ``event()``.

    ``path_or_file`` is a path (the file is created, and closed by
    ``close()``) or an open text file (left open: ``close()`` only flushes
    it). Also a context manager.

    >>> import io
    >>> out = io.StringIO()
    >>> with TraceWriter(out, ["port 0: loop://"]) as w:
    ...     w.event(0, 0, "TX", b"\\x02\\x03")
    ...     w.event(70.3125, 0, "RX", b"\\x02\\xfa")
    >>> print(out.getvalue(), end="")
    # softplc_lite port trace 1
    # port 0: loop://
    0.000 0 TX 02 03
    70.312 0 RX 02 FA
    """

    def __init__(self, path_or_file: str | os.PathLike | IO[str], comments: Sequence[str] = ()) -> None:
        if isinstance(path_or_file, (str, os.PathLike)):
            self.path = os.fspath(path_or_file)
            self._file: IO[str] = open(self.path, "w", encoding="utf-8", newline="\n")
            self._owned = True
        else:
            self.path = getattr(path_or_file, "name", "<trace>")
            self._file = path_or_file
            self._owned = False
        self._last_t = 0.0
        self._file.write(HEADER + "\n")
        for comment in comments:
            for line in str(comment).splitlines() or [""]:
                self._file.write(f"# {line}".rstrip() + "\n")

    def event(self, t_ms: float, port: int | str, direction: str, data: bytes) -> None:
        """Write one event. Nothing is written for empty ``data``. Raises
        ValueError for a bad port or direction, or a time that is negative,
        not finite, or before the previous event's."""
        label = port_label(port)
        if label is None:
            raise ValueError(f"port {port!r} is not 0-{MAX_PORT} or MODULE:N")
        if direction not in DIRECTIONS:
            raise ValueError(f"direction must be TX or RX, not {direction!r}")
        if not math.isfinite(t_ms) or t_ms < 0:
            raise ValueError(f"time {t_ms!r} ms is not a time")
        if t_ms < self._last_t:
            raise ValueError(f"time {t_ms} ms is before the previous event's {self._last_t} ms")
        if not data:
            return
        self._last_t = t_ms
        self._file.write(format_event(t_ms, label, direction, bytes(data)) + "\n")

    def flush(self) -> None:
        self._file.flush()

    def close(self) -> None:
        if self._file.closed:
            return
        if self._owned:
            self._file.close()
        else:
            self._file.flush()

    def __enter__(self) -> "TraceWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
