"""The interactive watch view: keys in, screen out.

Keys are read unbuffered from the terminal (cbreak mode, restored on
exit). While running, scanning happens in short slices between key checks,
and the screen is redrawn at most REDRAW_HZ times a second whatever the
scan rate, so a fast run never waits on drawing.
"""

from __future__ import annotations

import os
import select
import sys
import termios
import time
import tty
from typing import NamedTuple

from rich.console import Console
from rich.live import Live

from ..datatable import DataTableError
from .screen import WatchScreen
from . import trendview
from .session import WatchSession

REDRAW_HZ = 10  # at most
DRAW_SHARE = 0.04  # of the wall time spent drawing while running, at most
SLICE_S = 0.02  # scanning time between two looks at the keyboard
PAUSED_SERVERS_S = 1.0  # while paused, the servers panel is redrawn this often (its counts are live)
PROMPT_MAX = 200  # characters a prompt (g, F, U, M, =, t, /, d, T, W) takes

_ESCAPES = {"\x1b[A": "up", "\x1b[B": "down", "\x1bOA": "up", "\x1bOB": "down",
            "\x1b[5~": "pgup", "\x1b[6~": "pgdown",
            # Home and End as xterm, tmux and the Linux console send them
            "\x1b[H": "home", "\x1b[F": "end", "\x1bOH": "home", "\x1bOF": "end",
            "\x1b[1~": "home", "\x1b[4~": "end", "\x1b[7~": "home", "\x1b[8~": "end"}
CTRL_T = "\x14"


class Binding(NamedTuple):
    """A key: its label (as the help shows it), the key values RawKeys
    gives for it, the Controller's action, and what it does."""

    label: str
    keys: tuple[str, ...]
    action: str
    help: str


# Every key of the view, the one list: the Controller dispatches from it,
# the help overlay ("?") and ``softplc watch --help`` (KEYS) show it.
BINDINGS: tuple[Binding, ...] = (
    Binding("n, space", ("n", " "), "step", "one scan forward (from history when stepped back)"),
    Binding("r", ("r",), "run", "run: scan continuously"),
    Binding("p", ("p",), "pause", "pause"),
    Binding("+ / -", ("+", "-"), "speed", "run faster / slower"),
    Binding("up/down, k/j", ("up", "k", "down", "j"), "move", "select the rung above / below"),
    Binding("PgUp/PgDn", ("pgup", "pgdown"), "move", "ten rungs up / down"),
    Binding("Home/End", ("home", "end"), "ends", "first / last rung of the file"),
    Binding("g", ("g",), "goto", "go to a rung (asks for its number; a line in a Structured Text routine)"),
    Binding("f", ("f",), "next_file", "show the next program file"),
    Binding("c", ("c",), "comments", "rung comments: full, first line, hidden (cycles)"),
    Binding("b", ("b",), "breakpoint", "toggle a breakpoint on the selected rung"),
    Binding("Backspace", ("\x7f", "\x08"), "back", "one scan back in the history"),
    Binding("=", ("=",), "set", "set a value: ADDR = VALUE (N7:0 = 150, T4:0.PRE = 50, ST9:0 = \"text\")"),
    Binding("t, Ctrl-T", ("t", CTRL_T), "toggle", "toggle a bit (offers the selected rung's first bit)"),
    Binding("F", ("F",), "force", "force a bit: ADDR=1 or ADDR=0"),
    Binding("U", ("U",), "unforce", "remove the force on ADDR"),
    Binding("M", ("M",), "mode", "change mode: program, run or test"),
    Binding("C", ("C",), "clear_fault", "clear the major fault (to PROGRAM; then M run)"),
    Binding("/", ("/",), "find", "find an address or symbol: the rungs that read or write it"),
    Binding("x / X", ("x", "X"), "use", "the next / previous rung of the last find"),
    Binding("d", ("d",), "data_file", "show a data file as a grid (N7, or N7:20 from element 20)"),
    Binding("R", ("R",), "radix", "the grid's radix: decimal, hex, binary, ASCII (cycles)"),
    Binding("Esc", ("esc",), "close", "close the data-file grid, then the find list"),
    Binding("T", ("T",), "trend", "trend: add or remove ADDR (offers the rung's first operand); range LO HI | auto"),
    Binding("W", ("W",), "write_trend", "write the history's trend to FILE.csv or FILE.vcd"),
    Binding("E", ("E",), "edit_errors", "every error of the last rejected online program edit"),
    Binding("?", ("?",), "help", "show every key and what it does (pages: space; any other key closes it)"),
    Binding("q", ("q",), "quit", "quit (saves the retentive data table)"),
)
# (key label, help text) of every key: for ``softplc watch --help``.
KEYS: tuple[tuple[str, str], ...] = tuple((b.label, b.help) for b in BINDINGS)
_ACTIONS = {k: b.action for b in BINDINGS for k in b.keys}
# The prompts: kind -> the text before what is typed.
PROMPTS = {"g": "go to rung: ", "line": "go to line: ", "F": "force ADDR=1 or ADDR=0: ", "U": "remove the force on ADDR: ",
           "M": "mode (program, run, test): ", "=": "set ADDR = VALUE: ", "t": "toggle bit: ",
           "/": "find address or symbol: ", "d": "data file (N7, T4, ST9; N7:20): ",
           "tags": "tag (Tanks, Tanks[1]; Enter: every tag) or data file (F12): ",  # d in a Logix app
           "T": "trend: ADDR (add/remove), range LO HI | range auto: ", "W": "write trend to FILE.csv|.vcd: "}


class RawKeys:
    """Single key presses from a terminal's standard input."""

    def __init__(self, fd: int | None = None) -> None:
        self.fd = sys.stdin.fileno() if fd is None else fd
        self.saved = None
        self.pending = ""  # typed ahead (a paste, tmux send-keys): one key at a time

    def __enter__(self) -> "RawKeys":
        self.saved = termios.tcgetattr(self.fd)
        tty.setcbreak(self.fd)
        return self

    def __exit__(self, *exc) -> None:
        termios.tcsetattr(self.fd, termios.TCSADRAIN, self.saved)

    def read(self, timeout: float) -> str | None:
        if not self.pending:
            ready, _, _ = select.select([self.fd], [], [], timeout)
            if not ready:
                return None
            self.pending = os.read(self.fd, 256).decode("utf-8", "replace")
            if not self.pending:
                return None
        return self._next_key()

    def _next_key(self) -> str:
        data = self.pending
        if data.startswith("\x1b"):
            for seq, name in _ESCAPES.items():
                if data.startswith(seq):
                    self.pending = data[len(seq):]
                    return name
            self.pending = data[1:]
            return "esc"
        self.pending = data[1:]
        return data[0]


class Controller:
    """What each key does to the session (and the one-line prompts)."""

    def __init__(self, session: WatchSession) -> None:
        self.session = session
        self.prompt: str | None = None  # "go to rung: 12", "force ADDR=1|0: ..."
        self.prompt_kind = ""
        self.buffer = ""
        self.done = False
        self.help = False  # the help overlay is shown
        self.help_page = 0  # its page shown
        self.help_pages = 1  # its pages, as last drawn (ViewLoop tells)

    def key(self, k: str) -> None:
        if self.help:  # space/PgDn and PgUp page it; any other key (Esc too) closes it, and does nothing else
            if k in (" ", "pgdown") and self.help_page + 1 < self.help_pages:
                self.help_page += 1
            elif k == "pgup" and self.help_page > 0:
                self.help_page -= 1
            else:
                self.help, self.help_page = False, 0
            return
        if self.session.edit_report is not None:  # the same for the online edit's errors (E)
            self.session.edit_report = None
            return
        if self.prompt_kind:
            self._prompt_key(k)
            return
        action = _ACTIONS.get(k)
        if action is not None:
            getattr(self, f"_do_{action}")(k)

    # one method per action of BINDINGS (a test checks none is missing)
    def _do_step(self, k: str) -> None:
        self.session.scan()

    def _do_run(self, k: str) -> None:
        self.session.start()

    def _do_pause(self, k: str) -> None:
        self.session.pause()

    def _do_speed(self, k: str) -> None:
        self.session.faster() if k == "+" else self.session.slower()

    def _do_move(self, k: str) -> None:
        grid = self.session.grid
        if grid is not None and k in ("pgup", "pgdown"):  # the grid is shown: page it
            grid.page(1 if k == "pgdown" else -1)
            return
        self.session.move({"down": 1, "j": 1, "up": -1, "k": -1, "pgdown": 10, "pgup": -10}[k])

    def _do_ends(self, k: str) -> None:
        self.session.first_rung() if k == "home" else self.session.last_rung()

    def _do_goto(self, k: str) -> None:
        self._ask("line" if self.session.listing is not None else "g")  # a Structured Text routine: by line

    def _do_next_file(self, k: str) -> None:
        self.session.next_file()

    def _do_comments(self, k: str) -> None:
        self.session.cycle_comments()

    def _do_breakpoint(self, k: str) -> None:
        self.session.toggle_breakpoint()

    def _do_back(self, k: str) -> None:
        self.session.back()

    def _do_set(self, k: str) -> None:
        self._ask("=")

    def _do_toggle(self, k: str) -> None:
        self._ask("t", self.session.selected_bit())

    def _do_force(self, k: str) -> None:
        self._ask("F")

    def _do_unforce(self, k: str) -> None:
        self._ask("U")

    def _do_mode(self, k: str) -> None:
        self._ask("M")

    def _do_clear_fault(self, k: str) -> None:
        self.session.clear_fault()

    def _do_find(self, k: str) -> None:
        self._ask("/")

    def _do_use(self, k: str) -> None:
        self.session.next_use() if k == "x" else self.session.prev_use()

    def _do_data_file(self, k: str) -> None:
        self._ask("tags" if self.session.naming.is_logix else "d")

    def _do_radix(self, k: str) -> None:
        self.session.cycle_radix()

    def _do_close(self, k: str) -> None:
        self.session.close_panels()

    def _do_trend(self, k: str) -> None:
        self._ask("T", trendview.offered(self.session))

    def _do_write_trend(self, k: str) -> None:
        self._ask("W")

    def _do_edit_errors(self, k: str) -> None:
        self.session.show_edit_errors()

    def _do_help(self, k: str) -> None:
        self.help = True

    def _do_quit(self, k: str) -> None:
        self.done = True

    def _ask(self, kind: str, offered: str = "") -> None:
        self.prompt_kind, self.buffer = kind, offered
        self.prompt = PROMPTS[kind] + offered

    def _prompt_key(self, k: str) -> None:
        if k == "esc":
            self.prompt_kind, self.prompt = "", None
            return
        if k in ("\r", "\n"):
            kind, text = self.prompt_kind, self.buffer.strip()
            self.prompt_kind, self.prompt = "", None
            if text or kind == "tags":  # a Logix app's d: Enter alone lists every tag
                self._submit(kind, text)
            return
        if k in ("\x7f", "\x08"):
            self.buffer = self.buffer[:-1]
        elif len(k) == 1 and k.isprintable() and len(self.buffer) < PROMPT_MAX:
            self.buffer += k
        self.prompt = PROMPTS[self.prompt_kind] + self.buffer

    def _submit(self, kind: str, text: str) -> None:
        s = self.session
        try:
            if kind in ("g", "line"):
                s.goto_text(text)
            elif kind == "F":
                s.force(text)
            elif kind == "U":
                s.unforce(text)
            elif kind == "M":
                s.set_mode(text)
            elif kind == "=":
                s.set_value(text)
            elif kind == "t":
                s.toggle(text)
            elif kind == "/":
                s.find(text)
            elif kind in ("d", "tags"):
                s.show_file(text)
            elif kind == "T":
                s.trend_command(text)
            elif kind == "W":
                s.write_trend(text)
        except (ValueError, DataTableError) as e:
            s.message = f"{text}: {e}"


class ViewLoop:
    """The interactive loop without the terminal: a key (or None) in, then
    scan a slice if running, then redraw if due. ``draw`` puts the screen on
    the terminal (rich Live here; a benchmark passes its own)."""

    def __init__(self, session: WatchSession, screen: WatchScreen, draw) -> None:
        self.session = session
        self.screen = screen
        self.draw = draw
        self.control = Controller(session)
        self.redraws = 0
        self.last_draw = 0.0
        self.interval = 1 / REDRAW_HZ
        self.dirty = True

    def tick(self, k: str | None) -> None:
        session = self.session
        said = session.message
        session.poll_online()  # between scans, in the scanning thread: a saved program goes in here
        if session.message != said:
            self.dirty = True
        if k is not None:
            self.control.key(k)
            self.dirty = True
        if session.running:
            session.run_for(SLICE_S)
            self.dirty = True
        now = time.monotonic()
        if not session.running and self.screen.servers and now - self.last_draw >= PAUSED_SERVERS_S:
            self.dirty = True  # a server's clients and counts change while the scan is paused
        if k is not None or (self.dirty and now - self.last_draw >= self.interval):
            self.screen.prompt = self.control.prompt
            self.screen.help = KEYS if self.control.help else None
            self.screen.help_page = self.control.help_page
            self.draw(self.screen)
            self.control.help_pages = self.screen.help_pages
            drawn = time.monotonic()
            # Drawing takes at most DRAW_SHARE of the time while running: a
            # big screen redraws less often rather than slowing the scans.
            self.interval = max(1 / REDRAW_HZ, (drawn - now) / DRAW_SHARE)
            self.last_draw, self.dirty = drawn, False
            self.redraws += 1

    @property
    def done(self) -> bool:
        return self.control.done


def run_terminal(session: WatchSession, view_factory, console: Console | None = None) -> int:
    console = console or Console()
    screen = WatchScreen(session, view_factory)
    with RawKeys() as keys, Live(screen, console=console, auto_refresh=False, screen=True,
                                 redirect_stdout=False, redirect_stderr=False) as live:
        loop = ViewLoop(session, screen, lambda renderable: live.update(renderable, refresh=True))
        while not loop.done:
            loop.tick(keys.read(0 if session.running else 1 / REDRAW_HZ))
    session.redraws = loop.redraws
    return 0
