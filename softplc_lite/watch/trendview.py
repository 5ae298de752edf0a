"""The watch view's trend panel (docs/trends.md, "The trend panel"): the
session's trend series over the last scans, drawn from the step-back
history's frames (watch/history.py), never from the live table.

The scan does no work for it: the history records every scan anyway, and
the panel reads the values it draws out of those frames when it is drawn.
A frame's values are read once and kept while the frame is in the window
(a redraw reads only the scans that came since the last one). The window
is as many scans as the chart has dot columns (two a character), at most
the history's depth; while stepping back it keeps the shown scan in view
and marks it.

Commands (the ``T`` prompt): ``ADDR`` adds an address or symbol, or
removes it when it is already trended; ``range LO HI`` sets the y axis,
``range auto`` takes it from the data again. ``W`` writes the history's
trend to a CSV or VCD file (trends/record.py's writers).
"""

from __future__ import annotations

from itertools import islice

from rich.console import Console, ConsoleOptions, RenderResult
from rich.text import Text

from ..datatable import ValueKind
from ..ladder.ast import AddressRef, walk
from ..trends.chart import TrendChart, Trace, XAxis
from ..trends.record import TrendFileError, open_writer
from ..trends.series import FLOAT, FrameReader, TrendError, float32_text, resolve_series

MAX_TRENDS = 6  # series in the panel at once (a choice: more lines would not tell apart on a terminal)
COLOURS = ("cyan", "yellow", "green", "magenta", "blue", "red")
PLOT_ROWS = 8  # rows of the y plot when the panel has room (4 dots each)
MIN_PLOT_ROWS = 2
_TRENDABLE = (ValueKind.BIT, ValueKind.WORD, ValueKind.LONG, ValueKind.FLOAT)


def panel_height(session, width: int, height: int) -> int:
    """Lines the panel takes on a ``width`` x ``height`` screen (0 with no
    trend): its chart's plot rows, a band a bit, the legend and the axis;
    at most a third of the body below 120 columns, two fifths from it."""
    series = session.trend
    if not series:
        return 0
    numeric = any(not s.is_bit for s in series)
    wanted = 2 + (PLOT_ROWS if numeric else 0) + sum(s.is_bit for s in series)
    body = height - 3  # the status bar's two lines and the keys line
    room = body * 2 // 5 if width >= 120 else body // 3
    return max(min(wanted, room), 5 if numeric else 3)


def shown_series(series: list, height: int) -> list:
    """The series that fit ``height`` lines, in order: a numeric one needs
    the plot (MIN_PLOT_ROWS), a bit its band."""
    out, plot, bands = [], 0, 0
    for s in series:
        need_plot = plot or (0 if s.is_bit else MIN_PLOT_ROWS)
        need_bands = bands + (1 if s.is_bit else 0)
        if 2 + need_plot + need_bands > height:
            continue
        plot, bands = need_plot, need_bands
        out.append(s)
    return out


def value_text(series, value) -> str:
    if value is None:
        return "?"
    return float32_text(value) if series.kind == FLOAT else str(value)


class TrendPanel:
    """The chart of ``session.trend`` from its history, ``height`` lines."""

    def __init__(self, session, height: int) -> None:
        self.session = session
        self.height = height

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        s = self.session
        width = options.max_width
        history = s.history
        frames = history.frames
        series = shown_series(s.trend, self.height)
        if not frames or not series:
            why = "no scan recorded yet (n steps, r runs)" if not frames else "no room (a taller terminal shows it)"
            yield Text(f" trend: {why}", style="dim", no_wrap=True, overflow="ellipsis")
            return
        # The window: as many scans as the chart has dot columns, ending at the newest scan, or around the
        # one shown from history. The gutter (the y labels) depends on the values drawn: measured on the
        # widest window first, then the window cut to the columns left.
        count, position = len(frames), history.position
        start, end = _window(count, min(count, max(2, (width - 2) * 2)), position)
        window = list(islice(frames, start, end))
        rows = s.trend_cache.values(series, window, s.engine.table)
        chart = self._chart(series, window, rows, position, start)
        size = min(count, chart.plot_columns(width) * 2)
        if size < len(window):
            cut, _ = _window(count, size, position)
            window, rows = window[cut - start:cut - start + size], rows[cut - start:cut - start + size]
            chart = self._chart(series, window, rows, position, cut)
        yield chart

    def _chart(self, series, window, rows, position, start) -> TrendChart:
        s = self.session
        marker = position - start if position is not None else None
        shown = rows[marker] if marker is not None else rows[-1]
        traces = []
        for k, one in enumerate(series):
            colour = COLOURS[s.trend.index(one) % len(COLOURS)]
            traces.append(Trace(one.label, [row[k] for row in rows], one.is_bit, value_text(one, shown[k]), colour))
        hidden = len(s.trend) - len(series)
        note = f"+{hidden} more" if hidden else ""  # the series a taller terminal shows
        x = XAxis(window[0].scan, window[-1].scan, window[0].now_ms, window[-1].now_ms)
        return TrendChart(traces, x, self.height, s.trend_range, marker, note=note)


def _window(count: int, size: int, position: int | None) -> tuple[int, int]:
    """(start, end) of ``size`` frames of ``count``: the newest, or while
    stepping back the ones around ``position`` (it in the right half)."""
    end = count
    if position is not None and position < count - size:
        end = min(count, position + 1 + size // 2)
    return end - size, end


class FrameValues:
    """The series' values of each frame, read once while the frame stays in
    the window: ``reads`` counts the frames read (what a redraw costs)."""

    def __init__(self) -> None:
        self.reader: FrameReader | None = None
        self.series: tuple = ()
        self.kept: dict[int, tuple[object, list]] = {}  # id(frame) -> (the frame, its values)
        self.reads = 0

    def values(self, series: list, window: list, table) -> list[list]:
        if tuple(series) != self.series:
            self.series, self.kept = tuple(series), {}
            self.reader = FrameReader(series, table)
        kept, fresh = self.kept, {}
        out = []
        for frame in window:
            hit = kept.get(id(frame))
            if hit is None or hit[0] is not frame:
                hit = (frame, self.reader.values(frame))
                self.reads += 1
            fresh[id(frame)] = hit
            out.append(hit[1])
        self.kept = fresh  # frames gone from the window are let go
        return out


# -- commands -------------------------------------------------------------------------------
def command(session, text: str) -> None:
    """The ``T`` prompt: ``ADDR`` (add, or remove when trended), ``range LO
    HI``, ``range auto``; what it did, or why not, on the message line."""
    words = text.split()
    if words and words[0].lower() == "range":
        set_range(session, words[1:])
        return
    name = text.strip()
    if not remove(session, name):
        add(session, [name])


def remove(session, name: str) -> bool:
    """Remove the series ``name`` names (as typed, its label or its
    address); False when none is trended."""
    for one in session.trend:
        if name.strip() in (one.text, one.label, str(one.address)):
            session.trend.remove(one)
            session.message = f"trend: {one.label} removed" + ("" if session.trend else " (the panel closes)")
            return True
    return False


def add(session, texts: list[str], what: str = "trend") -> None:
    """Add the series ``texts`` name; TrendError for the command line (what
    says where they came from), the message line for the prompt."""
    try:
        found = resolve_series(texts, session.engine.table, session.app.program.symbols, what=what,
                               limit=MAX_TRENDS)
    except TrendError as e:
        if what != "trend":
            raise
        session.message = "; ".join(e.problems)
        return
    have = {(s.file, s.index, s.bit) for s in session.trend}
    new = [s for s in found if (s.file, s.index, s.bit) not in have]
    if len(session.trend) + len(new) > MAX_TRENDS:
        problem = f"{what}: at most {MAX_TRENDS} series in the panel (T NAME removes one)"
        if what != "trend":
            raise TrendError([problem])
        session.message = problem
        return
    session.trend.extend(new)
    session.message = f"trend: {', '.join(s.label for s in new)} added" if new else \
        f"trend: {', '.join(s.label for s in found)} already shown (T {found[0].label} again removes it)"


def set_range(session, words: list[str]) -> None:
    if len(words) == 1 and words[0].lower() == "auto":
        session.trend_range = None
        session.message = "trend: y range from the data"
        return
    try:
        low, high = (float(w) for w in words)
    except ValueError:
        session.message = f"trend range {' '.join(words)}: expected two numbers LO HI (range 0 4095) or range auto"
        return
    if not low < high:
        session.message = f"trend range {' '.join(words)}: LO must be below HI"
        return
    session.trend_range = (int(low) if low.is_integer() else low, int(high) if high.is_integer() else high)
    session.message = f"trend: y range {words[0]} to {words[1]}"


def offered(session) -> str:
    """What ``T`` offers: the selected rung's first operand a trend can
    follow (a direct bit, word, long or float), by its symbol when one
    names it; "" when there is none."""
    rungs = session.rungs
    if not rungs:
        return ""
    names = {decl.address: name for name, decl in session.app.program.symbols.items()}
    for ins in walk(rungs[session.selected].elements):
        for operand in getattr(ins, "operands", ()):
            if isinstance(operand, AddressRef):
                address = operand.address
                if address.is_direct and address.kind in _TRENDABLE:
                    return names.get(address, str(address))
    return ""


def write(session, path: str) -> None:
    """Write the history's trend (every kept scan) to ``path`` (.csv or
    .vcd); where, and how many scans, on the message line."""
    path = path.strip()
    series, frames = list(session.trend), list(session.history.frames)
    if not series:
        session.message = "write trend: no trend (T adds an address)"
        return
    if not frames:
        session.message = "write trend: no scan recorded yet"
        return
    clock = "wall clock" if session.engine.clock.realtime else "simulated"
    try:
        writer = open_writer(path, series, session.app.name, clock)
    except TrendFileError as e:
        session.message = str(e).replace("--trend-file", "write trend", 1)
        return
    reader = FrameReader(series, session.engine.table)
    try:
        for frame in frames:
            writer.row(frame.scan, frame.now_ms, reader.values(frame))
    finally:
        writer.close()
        if not writer.out.closed:
            writer.out.close()
    session.message = f"trend of {len(frames)} scans ({frames[0].scan} to {frames[-1].scan}) written to {path}"
