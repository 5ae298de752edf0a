"""A watch session: one app's engine with history, forces, breakpoints and
a watch list, driven by commands (keys, or calls from tests); no terminal
here (terminal.py reads keys, screen.py draws).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field

from ..errors import shown_path
from ..app import App
from ..datatable import DataTableError, ValueKind
from ..datatable.display import format_read
from ..ladder.ast import AddressRef, walk
from ..ladder.host import Mode, ModeError
from ..ladder.symbols import SymbolError, resolve_name
from ..program_watcher import ProgramWatcher
from ..runner import Runner, RunOptions
from .breakpoints import Breakpoints, Hit
from .datagrid import DataGrid, grid_for, next_radix
from .forces import Forces, parse_force
from . import trendview
from .history import History
from .naming import Naming
from .st_ran import RanRungs
from .st_view import goto_line, hit_said, st_lines
from .watchlist import WatchList
from .xref import Finding, XrefIndex

# Run speeds ("+" and "-"): scans per second of wall time; 0 = as fast as it goes.
SPEEDS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 0)
# How rung comments are drawn ("c" cycles): all of it, its first line, none.
COMMENTS = ("full", "first line", "hidden")


@dataclass
class WatchOptions:
    run: RunOptions = field(default_factory=RunOptions)
    watch: tuple[str, ...] = ()
    forces: tuple[str, ...] = ()
    break_when: tuple[str, ...] = ()
    trend: tuple[str, ...] = ()  # the trend panel's series (watch/trendview.py)
    speed: int = 6  # index into SPEEDS: 100 scans/s
    # online program edit: watch the app's .lad files and put a saved valid version in place
    # (off for a snapshot, which must not depend on a file saved meanwhile)
    online: bool = True


class WatchSession:
    def __init__(self, app: App, options: WatchOptions | None = None, rung_power=None) -> None:
        self.app = app
        self.options = options = options or WatchOptions()
        self.runner = Runner(app, options.run)
        self.engine = engine = self.runner.engine
        symbols = app.program.symbols
        self.history = History(engine.table)
        try:
            self.forces = Forces(engine)
            for text in options.forces:
                self.forces.set(parse_force(text, symbols))
            if rung_power is None:
                from .power import rung_power
            self.breaks = Breakpoints(engine, rung_power)
            for text in options.break_when:
                self.breaks.add_condition(text, symbols)
            self.watch = WatchList(list(options.watch), symbols)
            self.trend: list = []  # the trend panel's Series, drawn from the history (trendview.py)
            self.trend_range: tuple[float, float] | None = None  # its y axis; None: from the data
            self.trend_cache = trendview.FrameValues()
            if options.trend:
                trendview.add(self, list(options.trend), what="--trend")
        except BaseException:
            engine.close()  # a bad --force/--break-when/--watch: release the ports opened
            raise
        self.ran = RanRungs(engine)  # which rungs of the ST routines ran (st_ran.py); before any breakpoint
        self._st = None  # the shown ST file's lines (listing)
        if engine.mode is not Mode.RUN:
            engine.set_mode(Mode.RUN)
        self.running = False
        self.speed = min(max(options.speed, 0), len(SPEEDS) - 1)
        self.files = sorted(app.program.files)
        self.naming = Naming(app)  # how operands, instructions and files are named (naming.py)
        # the shown program file: 2 (the main one), else the first; None when there is none
        self.file: int | None = self.naming.first_file(self.files)
        self.selected = 0  # selected rung of the shown file
        if self.listing is not None:  # an ST routine's: its first line with a statement
            self.selected = self.listing.normal(0)
        self.top = 0  # first rung shown
        self.message = ""
        self.comments = COMMENTS[0]
        self.last_hit: Hit | None = None
        self.xref: XrefIndex | None = None  # built at the first find, again when the program is replaced
        self.finding: Finding | None = None  # the last find: its uses, the current one
        self.grid: DataGrid | None = None  # the data-file monitor, while it is shown
        self.watch.sample(engine.table)
        self.online = ProgramWatcher(app) if options.online else None
        self.pending_edit = None  # an accepted edit polled while stepping back: put in when live
        self.last_edit = None  # the last online edit (the E key shows its errors)
        self.edit_report: str | None = None  # the E overlay's text while it is shown

    # -- scanning ---------------------------------------------------------------------------
    def scan(self) -> Hit | None:
        """One scan forward: from history when stepping back, else a new one."""
        if self.history.position is not None:  # not live
            frame = self.history.forward()
            self.message = f"history: scan {frame.scan}" if not self.history.live else "live"
            self.watch.sample(self.engine.table, trend=False)
            return None
        engine = self.engine
        before = engine.scans
        engine.scan()
        if engine.scans != before:
            self.history.record(engine.scans, engine.clock.now_ms)
        else:
            # PROGRAM mode: the I/O update ran, the ladder did not, so no scan is counted and none
            # recorded (a frame of its own would be "scan N of N" in the history, not a scan); what
            # the update changed belongs to the newest scan's frame, as an edit does.
            self.history.amend()
            self.message = "PROGRAM mode: the ladder does not run (inputs and outputs updated; M run to run it)"
        if self.watch.items:
            self.watch.sample(engine.table)
        hit = self.breaks.after_scan()
        if engine.mode is Mode.FAULTED:
            self.running = False
            self._show_fault()
        if hit is not None:
            self.running = False
            self.last_hit = hit
            self.message = hit_said(hit, self.app.program, self.naming)
            if hit.file is not None:
                self.file, self.selected = hit.file, hit.rung
                self.top = min(self.top, hit.rung)
        return hit

    def run_for(self, seconds: float) -> int:
        """Scan for up to ``seconds`` of wall time at the run speed (or until
        a breakpoint or fault stops the run); returns the scans done."""
        if self.engine.mode is Mode.FAULTED:
            self.running = False
            return 0
        if not self.history.live:
            self.history.latest()
        rate = SPEEDS[self.speed]
        clock = time.monotonic
        end = clock() + seconds
        done = 0
        if not rate:  # full speed: look at the clock every 8 scans, not every scan
            scan = self.scan
            while self.running and clock() < end:
                for _ in range(8):
                    if scan() is not None or not self.running:
                        break
                    done += 1
            self._run_scans += done
            return done
        while self.running and clock() < end:
            due = int((clock() - self._run_started) * rate) - self._run_scans
            if due <= 0:
                time.sleep(min(0.005, seconds))
                continue
            self.scan()
            done += 1
            self._run_scans += 1
        return done

    def start(self) -> None:
        if self.engine.mode is Mode.FAULTED:
            self.message = "FAULTED: C clears the fault (to PROGRAM), then M run"
            return
        if not self.history.live:
            self.history.latest()
        self.running = True
        self.message = "running"
        self._run_started = time.monotonic()
        self._run_scans = 0

    def pause(self) -> None:
        self.running = False
        self.message = f"paused at scan {self.engine.scans}"

    def faster(self) -> None:
        self.speed = min(self.speed + 1, len(SPEEDS) - 1)
        self._reset_rate()

    def slower(self) -> None:
        self.speed = max(self.speed - 1, 0)
        self._reset_rate()

    def _reset_rate(self) -> None:
        self._run_started = time.monotonic()
        self._run_scans = 0

    @property
    def speed_text(self) -> str:
        rate = SPEEDS[self.speed]
        return f"{rate} scans/s" if rate else "full speed"

    def back(self) -> None:
        frame = self.history.back()
        self.running = False
        if frame is None:
            self.message = "history: no earlier scan kept"
        else:
            self.message = f"history: scan {frame.scan} (n forward, r runs live)"
        self.watch.sample(self.engine.table, trend=False)

    @property
    def shown_scan(self) -> int:
        frame = self.history.shown
        return frame.scan if frame is not None else self.engine.scans

    # -- navigation ---------------------------------------------------------------------------
    @property
    def rungs(self) -> list:
        """The shown file's rungs (none when the program has no file)."""
        return self.app.program.files[self.file].rungs if self.file is not None else []

    @property
    def listing(self):
        """The shown file's lines when it is a Structured Text routine
        (st_view.StLines; the selection is then a line's first rung), else None."""
        self._st = st_lines(self.app.program.files[self.file] if self.file is not None else None, self._st)
        return self._st

    def move(self, delta: int) -> None:
        st = self.listing
        if st is not None:  # by lines holding statements; the view scrolls the line into sight (st_view.py)
            self.selected = st.step(self.selected, delta)
            self.top = min(self.top, st.line_of(self.selected))
            return
        self.selected = max(0, min(len(self.rungs) - 1, self.selected + delta))
        if self.selected < self.top:
            self.top = self.selected

    def goto(self, rung: int) -> None:
        self.selected = max(0, min(len(self.rungs) - 1, rung))
        self.top = self.selected
        if self.listing is not None:  # the top is a line of the text, the comment above the selected one first
            self.selected = self.listing.normal(self.selected)
            self.top = self.listing.top_for(self.selected)

    def goto_text(self, text: str) -> None:
        """The ``g`` prompt: a rung number of the shown file."""
        count = len(self.rungs)
        if not count:
            self.message = "no rung to go to"
            return
        if self.listing is not None:
            goto_line(self, self.listing, text)
            return
        try:
            rung = int(text.strip())
        except ValueError:
            self.message = f"go to rung {text.strip()!r}: expected a rung number, 0 to {count - 1}"
            return
        self.goto(rung)
        self.message = "" if rung == self.selected else \
            f"go to rung: file {self.file} has rungs 0 to {count - 1}; at rung {self.selected}"

    def first_rung(self) -> None:
        self.goto(0)

    def last_rung(self) -> None:
        self.goto(len(self.rungs) - 1)

    def cycle_comments(self) -> None:
        self.comments = COMMENTS[(COMMENTS.index(self.comments) + 1) % len(COMMENTS)]
        self.message = f"rung comments: {self.comments}"

    def next_file(self) -> None:
        if not self.files:
            self.message = "no program file"
            return
        k = self.files.index(self.file)
        self.file = self.files[(k + 1) % len(self.files)]
        self.selected = self.top = 0
        if self.listing is not None:
            self.selected = self.listing.normal(0)

    # -- find and cross-reference, the data-file monitor (docs/watch.md) ---------------------
    def find(self, text: str) -> None:
        """Every rung that reads or writes what ``text`` names (an address,
        a word, a file, a symbol); selects the first use at or after the
        selected rung."""
        program = self.app.program
        if self.xref is None or self.xref.program is not program:
            self.xref = XrefIndex(program, self.app.instructions)
        try:
            finding = self.xref.find(text)
        except DataTableError as e:  # an AddressError's reason, without the text quoted again
            self.message = f"find {text.strip()}: {getattr(e, 'reason', e)}"
            return
        self.finding = finding
        finding.start_at(self.file, self.selected)
        self.next_use()

    def next_use(self) -> None:
        self._to_use(self.finding.next() if self.finding is not None else None)

    def prev_use(self) -> None:
        self._to_use(self.finding.previous() if self.finding is not None else None)

    def _to_use(self, where) -> None:
        f = self.finding
        if f is None:
            self.message = "nothing found yet: / finds an address or symbol"
            return
        if where is None:
            self.message = f"find {f.title}: not used in any rung"
            return
        self.file = where[0]
        self.goto(where[1])
        self.message = f"{f.title} {f.current + 1} of {len(f.uses)}: {f.uses[f.current].describe(self.naming)}"

    def show_file(self, text: str) -> None:
        """Show a data file as a grid (``N7``, or ``N7:20`` from element 20);
        a Logix app's tags by name (tagbrowser.py) when ``text`` is empty, ``tags``
        or a tag path."""
        try:
            tags = self.naming.tag_grid(self.engine.table, text)
            self.grid = tags or grid_for(self.engine.table, text)
        except DataTableError as e:
            self.message = str(e)
            return
        self.message = tags.opened() if tags else f"data file {self.grid.file.name}: R radix, PgUp/PgDn page, Esc closes"

    def cycle_radix(self) -> None:
        if self.grid is None:
            self.message = "R is the data-file grid's radix: d shows a data file"
            return
        self.grid.radix = next_radix(self.grid.radix)
        if hasattr(self.grid, "radix_said"):  # the tag monitor
            self.message = self.grid.radix_said()
            return
        floats = " (an F file shows floats in any radix)" if self.grid.file.ftype.letter == "F" else ""
        self.message = f"data file {self.grid.file.name}: radix {self.grid.radix}{floats}"

    def close_panels(self) -> None:
        """Esc: the grid first, then the find list."""
        if self.grid is not None:
            self.grid = None
        else:
            self.finding = None
        self.message = ""

    # -- the trend panel (docs/trends.md, "The trend panel") ----------------------------------
    def trend_command(self, text: str) -> None:
        """``ADDR`` adds or removes a series, ``range LO HI`` or ``range auto`` sets the y axis."""
        trendview.command(self, text)

    def add_trend(self, *texts: str) -> None:
        """Add series to the panel (what it did, or why not, on the message line)."""
        trendview.add(self, list(texts))

    def remove_trend(self, text: str) -> None:
        if not trendview.remove(self, text):
            self.message = f"trend: {text.strip()} is not trended"

    def write_trend(self, path: str) -> None:
        """The history's trend to a .csv or .vcd file."""
        trendview.write(self, path)

    # -- online program edit (docs/engine.md, "Online program edit") ---------------------------
    def poll_online(self) -> None:
        """Between scans (the terminal loop calls it every turn, running or
        paused): a saved version of the program files is put in place when
        valid, its errors kept when not."""
        if self.online is None:
            return
        edit = self.online.poll()
        if edit is not None:
            self.pending_edit = edit
        edit = self.pending_edit
        if edit is None or (edit.accepted and not self.history.live):
            return  # stepping back in history: the new program goes in once live again
        self.pending_edit = None
        edit = self.online.install(self.engine, edit)
        self.last_edit = edit
        extra = self._program_replaced(edit.changes) if edit.applied else ""
        if edit.accepted:
            self.message = f"{edit.summary()} (at scan {self.engine.scans}){extra}"
        else:
            # the key first and the app's own path off the file names: a status line
            # cut at the terminal's width must still say how to see the rest
            where = shown_path(self.app.path) + "/"
            self.message = f"(E: every error) {edit.summary().replace(where, '')}"

    def _program_replaced(self, changes) -> str:
        """The view follows the new program: files, the selected rung (where
        it went), breakpoints, the last find. Returns what the message adds."""
        self.ran.install()  # the new program's blocks, before the breakpoints wrap them
        dropped = self.breaks.program_replaced(changes)
        self.files = sorted(self.app.program.files)
        if self.file not in self.files:
            self.file = 2 if 2 in self.files else self.files[0] if self.files else None
            self.selected = self.top = 0
        else:
            new = changes.new_rung(self.file, self.selected)
            self.selected = new if new is not None else min(self.selected, max(len(self.rungs) - 1, 0))
            self.top = min(self.top, self.selected)
        self.xref = None  # indexed again from the new program
        if self.finding is not None:  # the list shows the new rung numbers; the selection stays
            file, selected, top = self.file, self.selected, self.top
            query, said = self.finding.query, self.message
            self.find(query)
            self.file, self.selected, self.top, self.message = file, selected, top, said
        return f"; {len(dropped)} breakpoint(s) on edited rungs cleared" if dropped else ""

    def show_edit_errors(self) -> None:
        """The E key: every error of the last rejected online edit (an overlay;
        any key closes it)."""
        edit = self.last_edit
        if edit is None or edit.accepted:
            self.message = "no rejected online edit" if edit is None else \
                f"the last online edit was accepted: {edit.summary()}"
            return
        self.edit_report = edit.report()

    def toggle_breakpoint(self) -> None:
        if not self.rungs:
            self.message = "no rung to set a breakpoint on"
            return
        on = self.breaks.toggle(self.file, self.selected)
        self.message = f"breakpoint {'set' if on else 'cleared'}: file {self.file} rung {self.selected}"

    def force(self, text: str) -> None:
        """``ADDR=1`` or ``ADDR=0`` typed at the prompt; a bad entry changes
        nothing and the message names what was typed."""
        try:
            force = parse_force(text, self.app.program.symbols, prompt=True)
        except DataTableError as e:
            self.message = str(e)
            return
        self._go_live()
        self.forces.set(force)
        self._edited()
        self.message = f"forced {text}"

    # -- online data edits ---------------------------------------------------------------------
    # The view only changes the table between two scans (the session scans
    # in whole scans), so an edit is at a scan boundary when it is made: it
    # shows at once, the next scan reads it, and the newest history frame
    # takes it in (History.amend) so stepping back and forward keeps it.
    def set_value(self, text: str) -> None:
        """``ADDR = VALUE`` (ADDR an address or symbol, members too:
        ``T4:0.PRE = 50``): VALUE is a number, a quoted string, ``{"PRE": 10}``
        for a whole element, or plain text for an ST element. A bad entry
        changes nothing and says why on the message line."""
        name, eq, raw = text.partition("=")
        name, raw = name.strip(), raw.strip()
        if not eq or not name or not raw:
            self.message = f"set {text.strip()!r}: expected ADDR = VALUE, e.g. N7:0 = 150 or ST9:0 = \"text\""
            return
        try:
            address = resolve_name(name, self.app.program.symbols)
            try:
                value = json.loads(raw)
            except ValueError:
                value = raw  # plain text: only an ST element takes it (write() says so otherwise)
            self._go_live()
            self.engine.table.write(address, value)
        except (DataTableError, ValueError, TypeError, OverflowError) as e:
            self.message = f"set {name}: {_reason(e)}"
            return
        self._edited()
        self.message = f"set {name} = {format_read(self.engine.table, address)}{self._forced_note(address)}"

    def toggle(self, text: str) -> None:
        """Invert a bit (RSLogix's Ctrl-T): ``B3/5``, ``O:0/0``, a symbol."""
        name = text.strip()
        try:
            address = resolve_name(name, self.app.program.symbols)
            if address.kind is not ValueKind.BIT:
                self.message = f"toggle {name}: expected a bit address (B3/5, O:0/0, N7:0/3, T4:0.EN)"
                return
            self._go_live()
            table = self.engine.table
            table.write(address, 1 - table.read(address))
        except (DataTableError, ValueError) as e:
            self.message = f"toggle {name}: {_reason(e)}"
            return
        self._edited()
        self.message = f"toggled {name}: now {self.engine.table.read(address)}{self._forced_note(address)}"

    def selected_bit(self) -> str:
        """The first bit operand of the selected rung (what ``t`` offers to
        toggle), or "" when it has none."""
        rungs = self.rungs
        if not rungs:
            return ""
        for ins in walk(rungs[self.selected].elements):
            for operand in getattr(ins, "operands", ()):
                if isinstance(operand, AddressRef) and operand.address.kind is ValueKind.BIT:
                    return str(operand.address)
        return ""

    def _forced_note(self, address) -> str:
        forced = str(address) in self.forces.forces
        return " (forced: the force holds it at the next scan)" if forced else ""

    def _go_live(self) -> None:
        """Edits apply to the newest scan's table, not to one shown from history."""
        if not self.history.live:
            self.history.latest()
            self.watch.sample(self.engine.table, trend=False)

    def _edited(self) -> None:
        self.history.amend()
        self.watch.sample(self.engine.table, trend=False)  # shown at once, not after the next scan

    def set_mode(self, text: str) -> None:
        """PROGRAM, RUN or TEST (any case, or P/R/T). PROGRAM while in
        PROGRAM asks the modules to reload their configuration (SoftPLC's
        PROGRAM -> PROGRAM, MODBMAST manual 5.2)."""
        modes = {"P": Mode.PROGRAM, "PROGRAM": Mode.PROGRAM, "R": Mode.RUN, "RUN": Mode.RUN, "T": Mode.TEST,
                 "TEST": Mode.TEST}
        mode = modes.get(text.strip().upper())
        if mode is None:
            self.message = f"mode {text!r}: expected program, run or test"
            return
        engine = self.engine
        again = engine.mode is mode
        try:
            self._go_live()
            engine.set_mode(mode)
        except ModeError as e:
            self.message = str(e)
            return
        self._edited()  # the mode word S:1 is in the table
        if engine.mode is Mode.FAULTED:
            self.running = False
            self._show_fault()
        elif again and mode is Mode.PROGRAM:
            self.message = "PROGRAM again: the modules reloaded their configuration"
        else:
            self.message = f"mode {mode.name}"

    def clear_fault(self) -> None:
        """Clear a major fault: to PROGRAM (RSLogix's "clear faults"); RUN
        again with ``M run`` or ``r`` after it."""
        engine = self.engine
        if engine.mode is not Mode.FAULTED:
            self.message = "no major fault to clear"
            return
        fault = engine.fault
        self.running = False
        self._go_live()
        engine.set_mode(Mode.PROGRAM)
        self._edited()
        self.message = f"fault cleared ({fault.code if fault else '?'}): PROGRAM mode; M run to run again"

    def _show_fault(self) -> None:
        """The fault on the message line, its rung selected (and its file shown)."""
        fault = self.engine.fault
        self.message = str(fault)
        if fault is not None and fault.file in self.files and fault.rung is not None:
            self.file = fault.file
            self.goto(fault.rung)

    def unforce(self, text: str) -> None:
        text = text.strip()
        try:
            address = resolve_name(text, self.app.program.symbols)
        except DataTableError as e:
            self.message = f"unforce {text}: {_reason(e)}"
            return
        if address.bit is None or not address.is_direct:
            self.message = f"unforce {text}: only a direct bit address is forced (e.g. O:0/0, B3/5, N7:0/3)"
            return
        found = self.forces.remove(address)
        self.watch.sample(self.engine.table, trend=False)
        self.message = f"force removed: {text}" if found else f"{text} is not forced"

    # -- the end ---------------------------------------------------------------------------------
    def quit(self) -> None:
        """Save the retentive data table (the newest scan) and close the ports."""
        self.running = False
        if not self.history.live:
            self.history.latest()
        try:
            self.runner.save()
        finally:
            self.engine.close()


def _reason(e: Exception) -> str:
    """An error's text after the name the message already shows (a
    symbol's error repeats the name it was given)."""
    return e.reason if isinstance(e, SymbolError) else str(e)
