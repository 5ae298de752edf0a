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

from rich.console import Console
from rich.live import Live

from ..datatable import DataTableError
from .screen import WatchScreen
from .session import WatchSession

REDRAW_HZ = 10  # at most
DRAW_SHARE = 0.04  # of the wall time spent drawing while running, at most
SLICE_S = 0.02  # scanning time between two looks at the keyboard
PROMPT_MAX = 200  # characters a prompt (g, F, U, M) takes

_ESCAPES = {"\x1b[A": "up", "\x1b[B": "down", "\x1bOA": "up", "\x1bOB": "down",
            "\x1b[5~": "pgup", "\x1b[6~": "pgdown"}


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

    def key(self, k: str) -> None:
        s = self.session
        if self.prompt_kind:
            self._prompt_key(k)
            return
        if k in (" ", "n"):
            s.scan()
        elif k == "r":
            s.start()
        elif k == "p":
            s.pause()
        elif k == "+":
            s.faster()
        elif k == "-":
            s.slower()
        elif k in ("down", "j"):
            s.move(1)
        elif k in ("up", "k"):
            s.move(-1)
        elif k == "pgdown":
            s.move(10)
        elif k == "pgup":
            s.move(-10)
        elif k == "f":
            s.next_file()
        elif k == "b":
            s.toggle_breakpoint()
        elif k in ("\x7f", "\x08"):
            s.back()
        elif k == "g":
            self._ask("g", "go to rung: ")
        elif k == "F":
            self._ask("F", "force ADDR=1 or ADDR=0: ")
        elif k == "U":
            self._ask("U", "remove the force on ADDR: ")
        elif k == "M":
            self._ask("M", "mode (program, run, test): ")
        elif k == "q":
            self.done = True

    def _ask(self, kind: str, text: str) -> None:
        self.prompt_kind, self.buffer = kind, ""
        self.prompt = text

    def _prompt_key(self, k: str) -> None:
        label = {"g": "go to rung: ", "F": "force ADDR=1 or ADDR=0: ", "U": "remove the force on ADDR: ",
                 "M": "mode (program, run, test): "}
        if k == "esc":
            self.prompt_kind, self.prompt = "", None
            return
        if k in ("\r", "\n"):
            kind, text = self.prompt_kind, self.buffer.strip()
            self.prompt_kind, self.prompt = "", None
            if text:
                self._submit(kind, text)
            return
        if k in ("\x7f", "\x08"):
            self.buffer = self.buffer[:-1]
        elif len(k) == 1 and k.isprintable() and len(self.buffer) < PROMPT_MAX:
            self.buffer += k
        self.prompt = label[self.prompt_kind] + self.buffer

    def _submit(self, kind: str, text: str) -> None:
        s = self.session
        try:
            if kind == "g":
                s.goto(int(text))
            elif kind == "F":
                s.force(text)
            elif kind == "U":
                s.unforce(text)
            elif kind == "M":
                s.set_mode(text)
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
        if k is not None:
            self.control.key(k)
            self.dirty = True
        if session.running:
            session.run_for(SLICE_S)
            self.dirty = True
        now = time.monotonic()
        if k is not None or (self.dirty and now - self.last_draw >= self.interval):
            self.screen.prompt = self.control.prompt
            self.draw(self.screen)
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
