"""The trend writer process (``python -m softplc_lite.trends.writer FD
SPOOL``): reads the recording's spec from standard input, then the rows of
raw values (trends/background.py) from standard input as they come, or
(SPOOL a file descriptor, not -1) from the spool file once standard input
has closed, and writes them to the file open on FD as CSV or VCD with
record.py's writers, only the changed rows when asked.
A problem (the disk full) is one line on standard error and exit status 1:
the runtime says it."""

from __future__ import annotations

import os
import pickle
import struct
import sys

from ..fdio import read_exactly
from .background import BUFFER_BYTES, SPEC_LENGTH, ignore_interrupts
from .record import CsvWriter, VcdWriter


def _stream(fd_in: int, spool: int, batch: int):
    """The rows' bytes: read from standard input as the runtime sends them
    (``spool`` < 0: a run on the wall clock), or, from a spool file, all at
    once after standard input has closed (simulated time: the scans run back
    to back, and a writer formatting beside them would take the shared
    cores from them)."""
    if spool < 0:
        while chunk := os.read(fd_in, batch):
            yield chunk
        return
    while os.read(fd_in, 4096):  # nothing more comes there: the end of the run closes it
        pass
    at = 0
    while chunk := os.pread(spool, batch, at):
        at += len(chunk)
        yield chunk


def write(fd_out: int, spool: int, fd_in: int = 0) -> None:
    head = read_exactly(fd_in, SPEC_LENGTH.size)
    if len(head) < SPEC_LENGTH.size:
        return
    spec = pickle.loads(read_exactly(fd_in, SPEC_LENGTH.unpack(head)[0]))
    series, place = spec["series"], spec["place"]
    row = struct.Struct(spec["fmt"])
    out = os.fdopen(fd_out, "w", encoding="utf-8", newline="")
    writer = (CsvWriter(out, series, spec["clock"]) if spec["kind"] == "csv"
              else VcdWriter(out, series, spec["app_name"], spec["clock"]))
    words = [at for at, bit in place]
    bits = [(k, bit) for k, (_, bit) in enumerate(place) if bit is not None]
    on_change, last = spec["on_change"], None
    pending = b""
    for chunk in _stream(fd_in, spool, 4 * BUFFER_BYTES):
        pending += chunk
        whole = len(pending) - len(pending) % row.size
        for raw in row.iter_unpack(pending[:whole]):
            values = [raw[at] for at in words]
            for k, bit in bits:
                values[k] = (values[k] >> bit) & 1
            if on_change and values == last:
                continue
            last = values
            writer.row(raw[0], raw[1], values)
        pending = pending[whole:]
    writer.close()
    out.close()


def main() -> int:
    ignore_interrupts()
    try:
        write(int(sys.argv[1]), int(sys.argv[2]))
    except OSError as e:
        print(f"--trend-file: the recording could not be written: {e.strerror or e}", file=sys.stderr)
        return 1
    except Exception as e:  # noqa: BLE001 - a bug: one line, never a traceback
        print(f"--trend-file: the trend writer failed: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
