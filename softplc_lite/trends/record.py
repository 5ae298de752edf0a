"""Trends written to files (docs/trends.md, "Recording"): every scan's (or,
on change, only the changed scans') values of the series, with the scan
number and the time, as CSV or as a VCD (value change dump) that waveform
viewers (GTKWave, Surfer) open.

One ``Recorder`` samples the table after a scan and hands the row to a
writer; writers stream to their file as rows come, so a recording of any
length takes constant memory. The VCD is written by pyvcd (the maintained
VCD library: its header, identifiers and value encodings), never by hand.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import IO

from .series import BIT, FLOAT, LONG, Sampler, Series, float32_text

FORMATS = {".csv": "csv", ".vcd": "vcd"}
VCD_SCOPE = "plc"
_VCD_NAME = re.compile(r"[^A-Za-z0-9_]")


class TrendFileError(ValueError):
    pass


def format_of(path: str | Path) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise TrendFileError(f"--trend-file {str(path)!r}: expected a .csv or .vcd file name (the suffix picks "
                             "the format)")
    return FORMATS[suffix]


def value_text(series: Series, value) -> str:
    return float32_text(value) if series.kind == FLOAT else str(value)


class CsvWriter:
    """A header (scan, time_s, one column a series by its label), then a row
    a recorded scan. Time in seconds with millisecond digits."""

    def __init__(self, out: IO[str], series: list[Series], clock: str) -> None:
        self.out = out
        self.series = series
        self.writer = csv.writer(out, lineterminator="\n")
        self.writer.writerow(["scan", f"time_s ({clock})", *[s.label for s in series]])

    def row(self, scan: int, now_ms: int, values: list) -> None:
        self.writer.writerow([scan, f"{now_ms / 1000:.3f}",
                              *[value_text(s, v) for s, v in zip(self.series, values)]])

    def close(self) -> None:
        self.out.flush()


def vcd_name(label: str) -> str:
    """A label as a VCD reference: letters, digits and '_' (``N7:0`` is
    ``N7_0``, ``B3/4`` ``B3_4``, ``Loop[2]`` ``Loop_2_``), which every viewer
    reads as one name; a symbol's name stays as it is."""
    return _VCD_NAME.sub("_", label) or "_"


class VcdWriter:
    """Bits as 1-bit wires, words as 16-bit and longs as 32-bit integer
    vectors, floats as reals, under one scope named after the app; the
    timescale 1 ms, time the engine's (simulated or wall clock). pyvcd
    writes only what changed."""

    def __init__(self, out: IO[str], series: list[Series], app_name: str, clock: str) -> None:
        from vcd import VCDWriter  # the optional dependency is imported only when a VCD is asked for

        self.out = out
        self.series = series
        self.writer = VCDWriter(out, timescale="1 ms", date=None, comment=f"softplc_lite {app_name}, {clock} time",
                                version="softplc_lite")
        self.vars = []
        names: set[str] = set()
        for s in series:
            name = vcd_name(s.label)
            while name in names:  # two labels that read the same once cleaned
                name += "_"
            names.add(name)
            if s.kind == BIT:
                var = self.writer.register_var(vcd_name(app_name), name, "wire", size=1)
            elif s.kind == FLOAT:
                var = self.writer.register_var(vcd_name(app_name), name, "real")
            else:
                var = self.writer.register_var(vcd_name(app_name), name, "integer", size=s.address.ftype.item_bits if s.kind == LONG else 16)
            self.vars.append(var)

    def row(self, scan: int, now_ms: int, values: list) -> None:
        change = self.writer.change
        for var, value in zip(self.vars, values):
            change(var, now_ms, value)

    def close(self) -> None:
        self.writer.close()


def open_writer(path: str | Path, series: list[Series], app_name: str, clock: str):
    """The writer for ``path``'s format, its file open; TrendFileError for a
    name or place that cannot be written, said in one line."""
    kind = format_of(path)
    try:
        out = open(path, "w", encoding="utf-8", newline="")
    except OSError as e:
        raise TrendFileError(f"--trend-file {str(path)!r}: cannot write it: {e.strerror or e}") from None
    if kind == "csv":
        return CsvWriter(out, series, clock)
    try:
        return VcdWriter(out, series, app_name, clock)
    except ImportError:
        out.close()
        raise TrendFileError("--trend-file: a .vcd needs the Python package 'pyvcd' (pip install 'pyvcd>=0.5,<0.6')") \
            from None


class Recorder:
    """Samples the series after each scan and writes a row: every scan, or
    (``on_change``) only a scan whose values differ from the last row's
    (the first scan always)."""

    def __init__(self, table, series: list[Series], writer, on_change: bool = False) -> None:
        self.sampler = Sampler(table, series)
        self.writer = writer
        self.on_change = on_change
        self.last: list | None = None
        self.rows = 0

    def record(self, scan: int, now_ms: int) -> None:
        values = self.sampler.values()
        if self.on_change and values == self.last:
            return
        self.last = values
        self.writer.row(scan, now_ms, values)
        self.rows += 1

    def close(self) -> None:
        self.writer.close()
        out = getattr(self.writer, "out", None)
        if out is not None and not out.closed:
            out.close()
