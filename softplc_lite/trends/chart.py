"""A trend chart drawn in braille cells, a rich renderable (docs/trends.md,
"The trend panel").

Each character cell holds 2x4 dots (Unicode braille, U+2800..U+28FF), so a
chart of W columns draws 2W samples across. Words, longs and floats are
lines on one shared y axis (its range from the data, or set); each bit is
a step trace in a one-row band of its own under the plot. Above, a legend
(each label with its current value, in its trace's colour) and whether the
y range is automatic or set; below, the x axis: the first and the last
sample's scan and time. ``marker`` draws a vertical line at one sample
(the watch view's history position while stepping back).

Braille cells rather than plotext (a choice): plotext 6 dropped the 5.x
API (plotsize, build, clear_figure), keeps one global figure (unsafe beside
the scanning thread), and gives ANSI text that rich would have to parse
again; braille cells are plain rich Text, the same on every run, which the
watch view's goldens need.
"""

from __future__ import annotations

from dataclasses import dataclass

from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

BRAILLE = 0x2800
# The dot bit of (column 0..1, row 0..3) in a braille cell (Unicode's dot numbering).
_DOT = ((0x01, 0x02, 0x04, 0x40), (0x08, 0x10, 0x20, 0x80))
LABEL_MAX = 12  # characters of a bit's label in the gutter
MARKER_STYLE = "bold magenta"  # as the status bar's "(history)"


@dataclass(frozen=True)
class Trace:
    label: str
    values: list  # a sample each: a number, or None where the value is unknown (a gap)
    is_bit: bool
    current: str  # the value the legend shows
    style: str = ""


@dataclass(frozen=True)
class XAxis:
    first_scan: int
    last_scan: int
    first_ms: int
    last_ms: int


def number_text(value: float) -> str:
    """A y axis label: an integer as such, else four significant digits."""
    if float(value).is_integer():
        return str(int(value))
    return f"{value:.4g}"


class _Canvas:
    """Dots on ``rows`` x ``cols`` cells, each cell with the style of the
    last trace that drew in it."""

    def __init__(self, rows: int, cols: int) -> None:
        self.rows, self.cols = rows, cols
        self.bits = [[0] * cols for _ in range(rows)]
        self.styles = [[""] * cols for _ in range(rows)]

    def dot(self, x: int, y: int, style: str) -> None:
        if 0 <= x < self.cols * 2 and 0 <= y < self.rows * 4:
            row, col = y // 4, x // 2
            self.bits[row][col] |= _DOT[x % 2][y % 4]
            self.styles[row][col] = style

    def vline(self, x: int, y0: int, y1: int, style: str) -> None:
        if not 0 <= x < self.cols * 2:
            return
        if y0 > y1:
            y0, y1 = y1, y0
        if y0 < 0:
            y0 = 0
        if y1 >= self.rows * 4:
            y1 = self.rows * 4 - 1
        col, dots = x // 2, _DOT[x % 2]
        bits, styles = self.bits, self.styles
        for y in range(y0, y1 + 1):
            row = y >> 2
            bits[row][col] |= dots[y & 3]
            styles[row][col] = style

    def line(self, x0: int, y0: int, x1: int, y1: int, style: str) -> None:
        """From (x0, y0) to (x1, y1), x0 <= x1: each dot column after the
        first gets the dots from just past the column before's height to its
        own, so a line is unbroken however steep, and one dot thick where
        it is flat."""
        if x1 == x0:
            self.vline(x0, y0, y1, style)
            return
        self.dot(x0, y0, style)
        before = y0
        for x in range(x0 + 1, x1 + 1):
            y = int(y0 + (y1 - y0) * (x - x0) / (x1 - x0) + 0.5)
            start = before + (1 if y > before else -1) if y != before else y
            self.vline(x, start, y, style)
            before = y

    def row_text(self, row: int) -> Text:
        text = Text(no_wrap=True)
        cells = [chr(BRAILLE + bits) if bits else " " for bits in self.bits[row]]
        styles = self.styles[row]
        start = 0
        for k in range(1, len(cells) + 1):  # a span a run of one style: far fewer for rich to render
            if k == len(cells) or styles[k] != styles[start]:
                text.append("".join(cells[start:k]), style=styles[start] or None)
                start = k
        return text


def _columns(count: int, dots: int) -> list[int]:
    """The dot column of each of ``count`` samples spread over ``dots``
    columns: one sample a column when they fit (the first at the left), else
    several a column."""
    if count <= 1:
        return [0] * count
    if count <= dots:
        return list(range(count))
    return [k * (dots - 1) // (count - 1) for k in range(count)]


class TrendChart:
    """``traces`` over the samples the x axis spans, ``height`` lines, the
    console's width. The samples of a trace are spread one a dot column from
    the left (two a character cell); more samples than dot columns share
    them. ``y_range`` (low, high) sets the shared y axis (values beyond it
    are drawn at its edge); None takes it from the data."""

    def __init__(self, traces: list[Trace], x: XAxis, height: int, y_range: tuple[float, float] | None = None,
                 marker: int | None = None, note: str = "") -> None:
        self.traces = traces
        self.x = x
        self.height = height
        self.y_range = y_range
        self.marker = marker
        self.note = note  # said at the end of the legend (the watch view: the series it had no room for)

    def y_bounds(self) -> tuple[float, float]:
        if self.y_range is not None:
            low, high = self.y_range
        else:
            values = [v for t in self.traces if not t.is_bit for v in t.values if v is not None]
            low, high = (min(values), max(values)) if values else (0, 1)
        if high <= low:  # a flat line: in the middle of a range around it
            low, high = low - 1, high + 1
        return low, high

    def legend(self, width: int) -> Text:
        text = Text(no_wrap=True, overflow="ellipsis")
        for k, trace in enumerate(self.traces):
            text.append("  " if k else " ")
            text.append(trace.label, style=trace.style or None)
            text.append(f" {trace.current}")
        if any(not t.is_bit for t in self.traces):
            low, high = self.y_bounds()
            how = "set" if self.y_range is not None else "auto"
            text.append(f"  y {how} {number_text(low)}..{number_text(high)}", style="dim")
        if self.note:
            text.append(f"  {self.note}", style="dim")
        return text

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        yield from self.lines(options.max_width)

    def _layout(self, width: int):
        """(the line traces, the bit traces shown, plot rows, y labels, gutter, plot columns)."""
        numeric = [t for t in self.traces if not t.is_bit]
        bits = [t for t in self.traces if t.is_bit]
        plot_rows = max(1, self.height - 2 - len(bits)) if numeric else 0
        bits = bits[:max(0, self.height - 2 - plot_rows)]
        low, high = self.y_bounds()
        y_labels = [number_text(high), number_text(low)] if numeric else []
        gutter = max([len(s) for s in y_labels] + [min(len(t.label), LABEL_MAX) for t in bits] + [1])
        return numeric, bits, plot_rows, y_labels, gutter, max(1, width - gutter - 1)

    def plot_columns(self, width: int) -> int:
        """The character columns the samples are drawn over at ``width``
        (two samples a column fill it)."""
        return self._layout(width)[-1]

    def lines(self, width: int) -> list[Text]:
        numeric, bits, plot_rows, y_labels, gutter, cols = self._layout(width)
        low, high = self.y_bounds()
        dots = cols * 2
        count = max((len(t.values) for t in self.traces), default=0)
        xs = _columns(count, dots)
        out = [self._fit(self.legend(width), width)]
        if numeric:
            canvas = _Canvas(plot_rows, cols)
            span_y = plot_rows * 4 - 1

            def y_of(v: float) -> int:
                v = min(max(v, low), high)
                return int((high - v) / (high - low) * span_y + 0.5)

            for trace in numeric:
                self._draw(canvas, trace, xs, y_of, step=False)
            self._mark(canvas, xs)
            for row in range(plot_rows):
                if row == 0:
                    label, edge = y_labels[0], "┤"
                elif row == plot_rows - 1:
                    label, edge = y_labels[1], "┤"
                else:
                    label, edge = "", "│"
                if plot_rows == 1:  # the legend says the range
                    label = y_labels[0]
                line = Text(label.rjust(gutter) + edge, style="dim", no_wrap=True)
                line.append_text(canvas.row_text(row))
                out.append(self._fit(line, width))
        for trace in bits:
            band = _Canvas(1, cols)
            self._draw(band, trace, xs, lambda v: 0 if v else 3, step=True)
            self._mark(band, xs)
            line = Text(no_wrap=True)
            line.append(trace.label[:gutter].ljust(gutter), style=trace.style or None)
            line.append("│", style="dim")
            line.append_text(band.row_text(0))
            out.append(self._fit(line, width))
        out.append(self._fit(self._axis(gutter, cols, xs), width))
        return out

    def _draw(self, canvas: _Canvas, trace: Trace, xs: list[int], y_of, step: bool) -> None:
        style = trace.style
        last = None  # (x, y) of the sample before, None after a gap
        for x, value in zip(xs, trace.values):
            if value is None:
                last = None
                continue
            y = y_of(value)
            if last is None:
                canvas.dot(x, y, style)
            elif step:  # held until this sample, then the change
                lx, ly = last
                for hx in range(lx, x):
                    canvas.dot(hx, ly, style)
                canvas.vline(x, ly, y, style)
            elif x == last[0] + 1:  # the next dot column (one sample a column): its dots to this height
                ly = last[1]
                canvas.vline(x, ly + (1 if y > ly else -1) if y != ly else y, y, style)
            else:
                canvas.line(last[0], last[1], x, y, style)
            last = (x, y)

    def _mark(self, canvas: _Canvas, xs: list[int]) -> None:
        if self.marker is None or not 0 <= self.marker < len(xs):
            return
        x = xs[self.marker]
        canvas.vline(x, 0, canvas.rows * 4 - 1, MARKER_STYLE)

    def _axis(self, gutter: int, cols: int, xs: list[int]) -> Text:
        """``scan 120 1.200 s`` under the first sample, the last sample's
        ending under it (just the scans when both do not fit), a ▲ under the
        marker."""
        x = self.x
        data_end = xs[-1] // 2 + 1 if xs else cols
        left = f"scan {x.first_scan} {x.first_ms / 1000:.3f} s"
        right = f"scan {x.last_scan} {x.last_ms / 1000:.3f} s"
        if len(left) + len(right) + 2 > cols:
            left, right = f"scan {x.first_scan}", f"{x.last_scan}"
        end = min(cols, max(data_end, len(left) + len(right) + 2))
        row = [" "] * cols
        at = max(len(left) + 1, end - len(right))
        for k, ch in enumerate(left + " " * (at - len(left)) + right):
            if k < cols:
                row[k] = ch
        if self.marker is not None and 0 <= self.marker < len(xs):
            row[xs[self.marker] // 2] = "▲"
        line = Text(" " * gutter + "└" + "".join(row), style="dim", no_wrap=True)
        if "▲" in row:
            at = gutter + 1 + row.index("▲")
            line.stylize(MARKER_STYLE, at, at + 1)
        return line

    @staticmethod
    def _fit(line: Text, width: int) -> Text:
        line.truncate(width, overflow="ellipsis", pad=True)
        return line
