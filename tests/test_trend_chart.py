"""The braille trend chart (softplc_lite/trends/chart.py): exact text for
small cases, the layout rules, and that it renders inside rich at the
console's width."""

from __future__ import annotations

import io

from rich.cells import cell_len
from rich.console import Console

from softplc_lite.trends.chart import BRAILLE, TrendChart, Trace, XAxis, number_text

X8 = XAxis(first_scan=1, last_scan=8, first_ms=10, last_ms=80)


def _plain(chart: TrendChart, width: int) -> list[str]:
    return [line.plain.rstrip() for line in chart.lines(width)]


def test_a_ramp_is_a_diagonal_one_dot_a_sample():
    chart = TrendChart([Trace("N7:0", list(range(8)), False, "7")], X8, height=4)
    assert _plain(chart, 40) == [
        " N7:0 7  y auto 0..7",
        "7┤  ⡠⠊",
        "0┤⡠⠊",
        " └scan 1 0.010 s  scan 8 0.080 s",
    ]


def test_a_step_is_a_vertical_edge_then_flat():
    chart = TrendChart([Trace("N7:0", [0] * 4 + [10] * 4, False, "10")], X8, height=4)
    assert _plain(chart, 40)[1:3] == [
        "10┤  ⡏⠉",
        " 0┤⣀⣀⠇",
    ]


def test_a_bit_is_a_step_trace_in_a_band_of_its_own():
    chart = TrendChart([Trace("B3/0", [0, 0, 1, 1, 1, 0, 0, 1], True, "1")], X8, height=3)
    assert _plain(chart, 40) == [
        " B3/0 1",  # no y range: there is no y axis
        "B3/0│⣀⡏⢹⣸",
        "    └scan 1 0.010 s  scan 8 0.080 s",
    ]


def test_the_marker_is_a_vertical_line_through_plot_and_bands_and_a_caret_on_the_axis():
    chart = TrendChart([Trace("N7:0", list(range(8)), False, "7"), Trace("B3/0", [0, 0, 1, 1, 1, 0, 0, 1], True, "1")],
                       X8, height=5, marker=3)
    assert _plain(chart, 40) == [
        " N7:0 7  B3/0 1  y auto 0..7",
        "   7┤ ⢸⡠⠊",
        "   0┤⡠⢺",
        "B3/0│⣀⣿⢹⣸",
        "    └s▲an 1 0.010 s  scan 8 0.080 s",
    ]


def test_a_set_range_clips_values_to_its_edges_and_a_gap_breaks_the_line():
    chart = TrendChart([Trace("F8:0", [-5.0, None, 2.5, 20.0], False, "20")], XAxis(1, 4, 10, 40), height=4,
                       y_range=(0, 10))
    lines = _plain(chart, 40)
    assert lines[0] == " F8:0 20  y set 0..10"
    # -5 drawn at the bottom edge, nothing for the unknown sample, then 2.5 and 20 (clipped to the top)
    assert lines[1:3] == ["10┤ ⢸", " 0┤⡀⠊"]


def test_more_samples_than_dots_share_columns():
    chart = TrendChart([Trace("N7:0", list(range(100)), False, "99")], XAxis(1, 100, 10, 1000), height=3)
    lines = _plain(chart, 20)
    assert lines[1] == "99┤⣀⣀⣠⠤⠤⠤⠤⠤⠖⠒⠒⠒⠒⠚⠉⠉⠉"
    assert lines[2] == "  └scan 1        100"  # both times do not fit: the scans only


def test_a_flat_line_sits_in_a_range_around_it():
    chart = TrendChart([Trace("N7:0", [5] * 6, False, "5")], XAxis(1, 6, 10, 60), height=4)
    assert chart.y_bounds() == (4, 6)
    assert _plain(chart, 40)[0] == " N7:0 5  y auto 4..6"


def test_height_goes_to_the_plot_first_then_to_the_bands():
    traces = [Trace("N7:0", [1, 2], False, "2")] + [Trace(f"B3/{k}", [0, 1], True, "1") for k in range(4)]
    lines = _plain(TrendChart(traces, XAxis(1, 2, 10, 20), height=5), 40)
    assert len(lines) == 5
    assert [line[:4] for line in lines[2:4]] == ["B3/0", "B3/1"]  # one plot row, two of the four bands
    lines = _plain(TrendChart(traces, XAxis(1, 2, 10, 20), height=9), 40)
    assert len(lines) == 9 and lines[-2].startswith("B3/3")  # three plot rows and every band


def test_every_line_is_the_console_width_and_only_braille_draws():
    traces = [Trace("Level", [k * 7 % 50 for k in range(300)], False, "42", "cyan"),
              Trace("AtSetpoint", [k // 40 % 2 for k in range(300)], True, "1", "green")]
    out = io.StringIO()
    console = Console(width=57, file=out, color_system=None, legacy_windows=False)
    console.print(TrendChart(traces, XAxis(0, 299, 0, 2990), height=7, marker=100))
    lines = out.getvalue().splitlines()
    assert len(lines) == 7 and all(cell_len(line) == 57 for line in lines)
    plot = "".join(line[line.index("┤" if "┤" in line else "│") + 1:] for line in lines[1:-1])
    assert all(ch == " " or BRAILLE <= ord(ch) <= BRAILLE + 0xFF for ch in plot)
    assert lines[-1].count("▲") == 1


def test_number_text():
    assert [number_text(v) for v in (0, 4095, -3.0, 2.5, 1 / 3)] == ["0", "4095", "-3", "2.5", "0.3333"]
