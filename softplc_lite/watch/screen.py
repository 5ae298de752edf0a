"""The watch view's screen: the status bar over the rungs, the watch list,
forces, ports and network servers beside them (or below, on a narrow
terminal), and the keys at the bottom. Each part is a renderable of its
own; this module only composes them for the space there is (80x24 and
up)."""

from __future__ import annotations

import textwrap

from rich.cells import cell_len
from rich.console import Console, ConsoleOptions, Group, RenderResult
from rich.layout import Layout
from rich.padding import Padding
from rich.text import Text

from ..ladder import status as S
from ..ladder.host import Mode
from .portsview import PortsView
from .serversview import ServersView
from .session import WatchSession
from .trendview import TrendPanel, panel_height
from .xref import XrefPanel

WIDE = 120  # from this width the side panels go beside the rungs
FORCES_SHOWN = 64  # forces listed by name; the rest are counted
SIDE_WIDTH = 46
FIND_LINES = 8  # the find list's lines at most (its title and seven uses around the current one)
# The keys line at the foot, the longest that fits (from 80 columns "? help" and "q quit" always show);
# "?" lists every key (terminal.py's table).
KEY_LINES = ("n step  r run  p pause  +/- speed  ↑↓ rung  g go to  f file  b break  ⌫ back  F/U force  = set  "
             "t toggle  M mode  C clear fault  T trend  W write trend  ? help  q quit",
             "n step  r run  p pause  ↑↓ rung  b break  ⌫ back  F/U force  = set  t toggle  M mode  C clear fault  "
             "? help  q quit",
             "n step  r run  p pause  ↑↓ rung  b break  ⌫ back  F/U force  = set  t toggle  M mode  ? help  q quit",
             "n step  r run  p pause  ⌫ back  = set  t toggle  ? help  q quit",
             "n step  r run  p pause  ? help  q quit")


class HelpOverlay:
    """Every key and what it does (the ``?`` key): ``keys`` is terminal.py's
    table of (key label, help text), one key a line in one column, a text
    too long for the width wrapped under itself (never cut). When the keys
    need more lines than the height, they are shown in pages (``page``,
    from 0): ``pages`` says how many after a render. Space or PgDn shows the
    next page, PgUp the one before; any other key closes the list."""

    def __init__(self, keys, page: int = 0) -> None:
        self.keys = keys
        self.page = page
        self.pages = 1

    def entries(self, width: int) -> list[list[Text]]:
        """Each key's lines at ``width``."""
        label_w = max(cell_len(label) for label, _ in self.keys)
        indent = 2 + label_w + 2
        room = max(10, width - indent)
        out = []
        for label, text in self.keys:
            wrapped = textwrap.wrap(text, room) or [""]
            first = Text(no_wrap=True)
            first.append(f"  {label.ljust(label_w)}  ", style="bold")
            first.append(wrapped[0])
            out.append([first] + [Text(" " * indent + more, no_wrap=True) for more in wrapped[1:]])
        return out

    def paged(self, width: int, height: int) -> list[list[Text]]:
        """The entries in pages of at most ``height`` lines (a key's lines never split)."""
        pages: list[list[Text]] = [[]]
        for lines in self.entries(width):
            if pages[-1] and len(pages[-1]) + len(lines) > height:
                pages.append([])
            pages[-1].extend(lines)
        return pages

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        height = max(1, (options.height or console.height) - 1)
        pages = self.paged(options.max_width, height)
        self.pages = len(pages)
        page = min(max(0, self.page), len(pages) - 1)
        if len(pages) == 1:
            yield Text(" keys (any key closes this)", style="bold underline")
        else:
            yield Text(f" keys, page {page + 1} of {len(pages)} (space: more, PgUp: back; other keys close this)",
                       style="bold underline", no_wrap=True, overflow="ellipsis")
        yield from pages[page]


class EditErrors:
    """Every error of a rejected online program edit (the ``E`` key; any
    key closes it): ``report`` is OnlineEdit.report(), a header line, then
    one ``file:line:col: message`` an error."""

    def __init__(self, report: str) -> None:
        self.report = report

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        yield Text(" online edit errors (any key closes this)", style="bold underline")
        lines = self.report.splitlines()
        room = max(1, (options.height or console.height) - 1)
        if len(lines) > room:  # the rest is in the editor's file anyway: say how much is left out
            lines = lines[:room - 1] + [f"... and {len(lines) - room + 1} more lines"]
        for line in lines:
            yield Text(f" {line}", overflow="fold")  # wrapped, not cut: a long path must not hide the message


class StatusBar:
    """Mode, scan, time, scan times, faults, and what the session is doing.

    ``measured``: the scan times measured on the wall clock (the live
    view); otherwise the status file's S:8 and S:9 (whole ms: the simulated
    ``scan_ms`` on simulated time), so a snapshot of a simulated run is the
    same every time."""

    def __init__(self, session: WatchSession, measured: bool = True) -> None:
        self.session = session
        self.measured = measured

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        s = self.session
        e = s.engine
        line = Text(no_wrap=True, overflow="ellipsis")
        line.append(f" {s.app.name} ", style="bold reverse")
        mode_style = {"RUN": "green", "FAULTED": "bold red"}.get(e.mode.name, "yellow")
        line.append(f" {e.mode.name} ", style=mode_style)
        fault = e.fault if e.mode is Mode.FAULTED else None
        if fault is not None:  # where, first: the rest of the line may be cut
            line.append(f" {_fault_place(fault, s)} ", style="bold red")
        if s.history.live:
            line.append(f" scan {e.scans}")
        else:
            line.append(f" scan {s.shown_scan} of {e.scans} (history)", style="bold magenta")
        frame = s.history.shown
        now_ms = frame.now_ms if frame is not None and not s.history.live else e.clock.now_ms
        line.append(f"  {now_ms / 1000:.3f} s {'real' if e.clock.realtime else 'sim'}")
        line.append("  RUNNING " if s.running else "  PAUSED ", style="bold green" if s.running else "bold")
        line.append(s.speed_text, style="dim")
        if self.measured:
            line.append(f"  scan time {e.last_scan_ms:.2f} ms, max {e.max_scan_ms:.2f}", style="dim")
        else:
            line.append(f"  scan time {e.s[S.LAST_SCAN_MS]} ms, max {e.s[S.MAX_SCAN_MS]}", style="dim")
        second = Text(no_wrap=True, overflow="ellipsis")
        if fault is not None:  # the whole fault, or what the last command said (the first line says where)
            said = s.message and s.message != str(fault)
            second.append(f" {s.message if said else fault}", style="cyan" if said else "bold red")
        else:
            minor = e.s[S.MINOR_FAULT_BITS]
            overflow = e.s[S.PLC5_MINOR_FAULT_BITS] >> S.MINOR_OVERFLOW_BIT & 1  # PLC-5's overflow bit S:10/14
            if minor or overflow:
                shown = ["S:10/14 overflow"] if overflow else []
                shown += [f"S:17={minor & 0xFFFF:#06x}"] if minor else []
                second.append(f" minor faults {' '.join(shown)} code {e.s[S.MINOR_FAULT_CODE]}", style="yellow")
            if s.message:
                second.append(f" {s.message}", style="cyan")
        yield line
        yield second


def _fault_place(fault, session) -> str:
    """``fault 20: file 2 rung 2 MOV``: which fault, and where; in a
    Structured Text routine the line (``fault 20: MainProgram.Fill line
    3``): its rungs and their instructions are the translation's."""
    where = f"fault {fault.code}"
    pfile = session.app.program.files.get(fault.file) if fault.file is not None else None
    listing = pfile.listing if pfile is not None else None
    if listing is not None and fault.rung is not None and 0 <= fault.rung < len(listing.rung_lines):
        return f"{where}: {session.naming.where(fault.file)} line {listing.rung_lines[fault.rung] + 1}"
    if fault.file is not None:
        where += f": file {fault.file} rung {fault.rung}"
        if fault.instruction:
            where += f" {fault.instruction.split()[0]}"
    return where


class ForcesView:
    def __init__(self, session: WatchSession) -> None:
        self.session = session

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        forced = self.session.forces.listed()
        text = Text("forces: ", style="bold")
        if not forced:
            text.append("none", style="dim")
        for k, f in enumerate(forced[:FORCES_SHOWN]):
            text.append(("  " if k else "") + f"{f.address}={'ON' if f.on else 'OFF'}", style="bold red")
        if len(forced) > FORCES_SHOWN:
            text.append(f"  and {len(forced) - FORCES_SHOWN} more", style="bold")
        yield text


class RungsPanel:
    """The shown program file's rungs from the session's first rung, as many
    as fit; scrolls the session so the selected rung stays in view."""

    def __init__(self, session: WatchSession, view_factory) -> None:
        self.session = session
        self.view_factory = view_factory

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        s = self.session
        height = options.height or console.height
        yield self.header()
        view = self.view_factory(s, height - 1)
        yield view
        last = getattr(view, "last_drawn", None)
        if last is not None and s.selected > last and s.top < s.selected:
            s.top += max(1, s.selected - last)  # keep the selection in view next time


    def header(self) -> Text:
        """``program file 2 MAIN  rung 3 of 12  files: 2 MAIN  3 FILL``: the
        shown file (number and name), the selected rung, every file."""
        s = self.session
        line = Text(no_wrap=True, overflow="ellipsis")
        if s.file is None:
            line.append(" no program file", style="bold underline")
            return line
        files = s.app.program.files
        label, labels = s.naming.what_files
        line.append(f" {label} {s.naming.file_label(files[s.file])}", style="bold underline")
        st = s.listing
        if st is None:
            line.append(f"  rung {s.selected} of {len(s.rungs)}", style="bold")
        else:  # a Structured Text routine is shown as its text (st_view.py)
            line.append(f"  line {st.line_of(s.selected) + 1} of {st.count}", style="bold")
            ran = f"  ● ran in scan {s.engine.scans}" if s.history.live else "  ● marks: live only"
            line.append(ran, style="dim")
        line.append(f"  comments {s.comments}" if s.comments != "full" else "", style="dim")
        if len(files) > 1:
            line.append(f"  {labels}: " + "  ".join(s.naming.file_label(files[n]) for n in s.files), style="dim")
        return line


class WatchScreen:
    def __init__(self, session: WatchSession, view_factory, prompt: str | None = None,
                 measured: bool = True) -> None:
        self.session = session
        self.status = StatusBar(session, measured)
        self.rungs = RungsPanel(session, view_factory)
        self.ports = PortsView(session.engine)
        self.servers = ServersView(session.engine)
        self.forces = ForcesView(session)
        self.prompt = prompt
        self.help = None  # the key table while the help overlay is shown
        self.help_page = 0  # the help overlay's page shown
        self.help_pages = 1  # its pages at the size it was last drawn (the Controller pages through them)

    def side(self) -> Group:
        parts = [self.session.watch, self.forces]
        if self.session.finding is not None:  # the find list first, above the watch list
            parts.insert(0, XrefPanel(self.session.finding, height=FIND_LINES, naming=self.session.naming))
        if self.ports:
            parts.append(self.ports)
        if self.servers:
            parts.append(self.servers)
        return Group(*parts)

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = options.max_width
        height = options.height or console.height
        root = Layout()
        if self.prompt:
            bottom = Text(f" {self.prompt}", style="bold reverse")
        else:
            keys = next((k for k in KEY_LINES if cell_len(k) < width), KEY_LINES[-1])
            if self.session.listing is not None:  # a Structured Text file: the arrows move by line
                keys = keys.replace("↑↓ rung", "↑↓ line")
            bottom = Text(f" {keys}", style="dim", no_wrap=True, overflow="ellipsis")
        root.split_column(Layout(self.status, size=2), Layout(name="body"), Layout(bottom, size=1))
        body = root["body"]
        overlay = HelpOverlay(self.help, self.help_page) if self.help else None  # the help wins over the rest
        if overlay is None and self.session.edit_report is not None:
            overlay = EditErrors(self.session.edit_report)
        if overlay is None and self.session.grid is not None:  # the data-file monitor: the body until Esc
            overlay = self.session.grid
        if overlay is not None:
            body.update(overlay)
            yield from root.__rich_console__(console, options.update(height=height))
            if isinstance(overlay, HelpOverlay):
                self.help_pages = overlay.pages
            return
        side = self.side()
        trend_lines = panel_height(self.session, width, height)
        if width < WIDE and trend_lines:  # never below the rungs' 8 lines (a line saying so at the least)
            trend_lines = max(1, min(trend_lines, height - 3 - 8))
        trend = TrendPanel(self.session, trend_lines) if trend_lines else None
        if width >= WIDE:  # the trend across the whole width under the rungs and the side panels
            top = body
            if trend is not None:
                body.split_column(Layout(name="top"), Layout(trend, size=trend_lines))
                top = body["top"]
            top.split_row(Layout(self.rungs), Layout(Padding(side, (0, 0, 0, 1)), size=SIDE_WIDTH))
        else:  # the trend, then the side panels below the rungs, all of their lines if the rungs keep 8
            side_lines = len(console.render_lines(side, options.update(width=width, height=None), pad=False))
            rung_lines = max(8, height - 3 - side_lines - trend_lines)
            parts = [Layout(self.rungs, size=rung_lines)]
            if trend is not None:
                parts.append(Layout(trend, size=trend_lines))
            body.split_column(*parts, Layout(side))
        yield from root.__rich_console__(console, options.update(height=height))


def rung_view(session: WatchSession, height: int):
    """The rungs of the session's shown file that fit ``height`` lines."""
    from ..ladder.ast import ProgramFile
    from .rungs import ProgramFileView

    s = session
    pfile = s.app.program.files[s.file] if s.file is not None else ProgramFile(2, None, [])  # none: "(no rungs)"
    st = s.listing
    if st is not None:  # a Structured Text routine: its text, values and the lines that ran (st_view.py)
        from .st_view import StView

        def scrolled(top: int) -> None:
            s.top = top

        ran = s.ran.last_scan(s.file) if s.history.live else None
        return StView(pfile, st, s.engine.table, s.naming.for_file(s.file), ran, s.selected, top=s.top,
                      height=height, breakpoints=frozenset(s.breaks.rungs), forced=frozenset(s.forces.forces),
                      scrolled=scrolled)
    return ProgramFileView(pfile, s.engine.table, symbols=s.naming.for_file(s.file),
                           first=s.top, selected=s.selected, breakpoints=frozenset(s.breaks.rungs),
                           forced=frozenset(s.forces.forces), height=height, instructions=s.app.instructions,
                           comments=s.comments)
