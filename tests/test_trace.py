"""Port trace files: parsing with positions, writing, round trips."""

from __future__ import annotations

import doctest
import io
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from softplc_lite.ports import trace
from softplc_lite.ports.trace import TraceError, TraceEvent, TraceWriter, parse_trace, read_trace

EXAMPLE = """\
# softplc_lite port trace 1
# port 0: COM1 -> sim://bus?device=echo 38400 8N1 ISO-8859-1
# time_ms port dir bytes
0.000 0 TX 02 03 00 00 00 7D 85 D8
70.312 0 RX 02 03 FA 00 01
"""


def test_parse_the_documented_example():
    events = parse_trace(EXAMPLE)
    assert events == [
        TraceEvent(0.0, 0, "TX", bytes.fromhex("020300 00007D85D8")),
        TraceEvent(70.312, 0, "RX", b"\x02\x03\xfa\x00\x01"),
    ]
    assert [e.line for e in events] == [4, 5]


def test_comments_blank_lines_case_and_no_header():
    text = "\n   \n1 35 RX 0a Ff # trailing comment 12 34\n\t2.5\t3\tTX\t00   \n# 3 0 TX 01\n"
    assert parse_trace(text) == [TraceEvent(1.0, 35, "RX", b"\x0a\xff"), TraceEvent(2.5, 3, "TX", b"\x00")]


def test_equal_times_are_allowed():
    assert len(parse_trace("1.000 0 TX 01\n1.000 1 RX 02\n1.000 0 TX 03\n")) == 3


@pytest.mark.parametrize("text,line,column,message", [
    ("x 0 TX 01\n", 1, 1, "expected a time in ms such as 12.345, found 'x'"),
    ("-1.0 0 TX 01\n", 1, 1, "expected a time in ms"),
    ("1. 0 TX 01\n", 1, 1, "expected a time in ms"),
    ("0 36 TX 01\n", 1, 3, "expected a port number 0-35 or MODULE:N, found '36'"),
    ("0 p1 TX 01\n", 1, 3, "expected a port number 0-35 or MODULE:N, found 'p1'"),
    ("0 MODBMAST:36 TX 01\n", 1, 3, "expected a port number 0-35 or MODULE:N, found 'MODBMAST:36'"),
    ("0 :1 TX 01\n", 1, 3, "expected a port number 0-35 or MODULE:N, found ':1'"),
    ("0 0 tx 01\n", 1, 5, "expected TX or RX, found 'tx'"),
    ("0 0 TX 01\n  0 0 TX 0G\n", 2, 10, "expected a two-digit hex byte, found '0G'"),
    ("0 0 TX 0102\n", 1, 8, "expected a two-digit hex byte, found '0102'"),
    ("0 0 TX\n", 1, 8, "expected one or more hex bytes after 'TX'"),
    ("0 0 TX # 01\n", 1, 8, "expected one or more hex bytes after 'TX'"),
    ("0\n", 1, 3, "expected a port (0-35, or MODULE:N) after '0'"),
    ("0 0\n", 1, 5, "expected TX or RX after '0'"),
    ("1.5 0 TX 01\n\n1.25 0 RX 02\n", 3, 1, "time 1.25 is before the previous event's 1.500 (line 1)"),
    ("# softplc_lite port trace 2\n0 0 TX 01\n", 1, 27, "trace format version 2 is not supported"),
])
def test_errors_name_line_and_column(text, line, column, message):
    with pytest.raises(TraceError) as info:
        parse_trace(text, "t.trace")
    error = info.value
    assert (error.path, error.line, error.column) == ("t.trace", line, column)
    assert message in error.message
    assert str(error).startswith(f"t.trace:{line}:{column}: ")


def test_read_trace(tmp_path: Path):
    path = tmp_path / "a.trace"
    path.write_text(EXAMPLE)
    assert read_trace(path) == parse_trace(EXAMPLE)
    bad = tmp_path / "bad.trace"
    bad.write_text("0 0 RX zz\n")
    with pytest.raises(TraceError, match=r"bad.trace:1:8: expected a two-digit hex byte"):
        read_trace(str(bad))


def test_read_trace_missing_or_binary_file(tmp_path: Path):
    with pytest.raises(TraceError) as info:
        read_trace(tmp_path / "missing.trace")
    assert info.value.path == str(tmp_path / "missing.trace")
    assert "cannot read trace file: no such file or directory" in str(info.value)
    binary = tmp_path / "bin.trace"
    binary.write_bytes(b"# softplc_lite port trace 1\n\xff\xfe\x00")
    with pytest.raises(TraceError, match=r"bin.trace:2:1: byte 0xff is not UTF-8 text"):
        read_trace(binary)


def test_writer_output_is_exact():
    out = io.StringIO()
    with TraceWriter(out, ["port 0: COM1 -> sim://bus?device=echo 38400 8N1 ISO-8859-1", "time_ms port dir bytes"]) as w:
        w.event(0, 0, "TX", bytes.fromhex("02030000007D85D8"))
        w.event(70.3124, 0, "RX", bytearray(b"\x02\x03\xfa\x00\x01"))
        w.event(80, 0, "RX", b"")  # nothing to write
    assert out.getvalue() == EXAMPLE
    assert not out.closed  # a file given to the writer stays open


def test_writer_to_a_path(tmp_path: Path):
    path = tmp_path / "w.trace"
    writer = TraceWriter(path, ["two\nlines"])
    writer.event(1.5, 2, "TX", b"\xab" * 40)
    writer.flush()
    assert path.read_text().splitlines()[-1] == "1.500 2 TX " + " ".join(["AB"] * 40)
    writer.close()
    writer.close()  # harmless
    lines = path.read_text().splitlines()
    assert lines[:3] == [trace.HEADER, "# two", "# lines"]
    assert read_trace(path) == [TraceEvent(1.5, 2, "TX", b"\xab" * 40)]


@pytest.mark.parametrize("args,message", [
    ((1.0, 36, "TX", b"\x01"), "port 36 is not 0-35 or MODULE:N"),
    ((1.0, "MODBMAST", "TX", b"\x01"), "port 'MODBMAST' is not 0-35 or MODULE:N"),
    ((1.0, 0, "tx", b"\x01"), "direction must be TX or RX"),
    ((-0.5, 0, "TX", b"\x01"), "is not a time"),
    ((float("nan"), 0, "TX", b"\x01"), "is not a time"),
    ((0.5, 0, "TX", b"\x01"), "before the previous event's 1.0 ms"),
])
def test_writer_rejects_bad_events(args, message):
    w = TraceWriter(io.StringIO())
    w.event(1.0, 0, "TX", b"\x00")
    with pytest.raises(ValueError, match=message):
        w.event(*args)


events_strategy = st.lists(
    st.tuples(
        st.integers(0, 5_000),  # time step in us
        st.integers(0, 35),
        st.sampled_from(["TX", "RX"]),
        st.binary(min_size=1, max_size=300),
    ),
    max_size=20,
)


@settings(max_examples=60, deadline=None)
@given(events_strategy, st.lists(st.text(alphabet=st.characters(blacklist_categories=["Cs"]), max_size=20), max_size=3))
def test_round_trip(steps, comments):
    out = io.StringIO()
    writer = TraceWriter(out, comments)
    expected = []
    t_us = 0
    for step, port, direction, data in steps:
        t_us += step
        t_ms = t_us / 1000
        writer.event(t_ms, port, direction, data)
        expected.append(TraceEvent(t_ms, port, direction, data))
    text = out.getvalue()
    assert text.startswith(trace.HEADER + "\n")
    parsed = parse_trace(text)
    assert parsed == expected
    event_lines = [n for n, line in enumerate(text.splitlines(), 1) if not line.startswith("#")]
    assert [e.line for e in parsed] == event_lines


def test_module_doctests():
    result = doctest.testmod(trace, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_module_ports_are_labelled_module_colon_number():
    """A port of a module other than COMGENIUS is written MODULE:N (upper
    case) and read back as that label; plain numbers stay numbers."""
    out = io.StringIO()
    with TraceWriter(out) as w:
        w.event(0.0, 0, "TX", b"\x01")
        w.event(1.5, "modbmast:3", "RX", b"\x02\x03")
    text = out.getvalue()
    assert "1.500 MODBMAST:3 RX 02 03" in text
    events = parse_trace(text)
    assert [e.port for e in events] == [0, "MODBMAST:3"]
    assert events[1] == TraceEvent(1.5, "MODBMAST:3", "RX", b"\x02\x03")
