"""One rendering of the watch view, to a string or a file: what
``softplc watch --snapshot`` writes, and what a test or a script reads
(docs/watch.md). No terminal is needed.

The sizes a snapshot may have are here, light to import: the argument
parser checks them with every command's start, which must not load rich."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

    from .session import WatchSession

# A real terminal's size at the low end; the top keeps a snapshot's memory
# and time bounded (1000x1000 takes about 1.3 s).
SNAPSHOT_WIDTH = range(40, 1001)
SNAPSHOT_HEIGHT = range(12, 1001)


def size_problem(width: int, height: int) -> str | None:
    """What is wrong with a snapshot size, None when it is in range."""
    for name, value, valid in (("--width", width, SNAPSHOT_WIDTH), ("--height", height, SNAPSHOT_HEIGHT)):
        if value not in valid:
            return f"{name}: expected an integer from {valid.start} to {valid.stop - 1}, not {value}"
    return None


def render(session: WatchSession, width: int, height: int, measured: bool = False) -> Console:
    """The view of ``session`` at ``width`` x ``height``, recorded (export it
    with ``export_text()`` or ``save_svg()``). The status bar shows the
    status file's scan times (S:8, S:9) unless ``measured``: on simulated
    time a snapshot is then the same on every machine. The size must be in
    SNAPSHOT_WIDTH x SNAPSHOT_HEIGHT (ValueError otherwise)."""
    from rich.console import Console

    from .screen import WatchScreen, rung_view

    problem = size_problem(width, height)
    if problem:
        raise ValueError(problem)
    console = Console(width=width, height=height, record=True, color_system="truecolor", force_terminal=True,
                      file=io.StringIO(), legacy_windows=False)
    console.print(WatchScreen(session, rung_view, measured=measured))
    return console


def write_snapshot(session: WatchSession, path: str, width: int, height: int) -> None:
    console = render(session, width, height)
    if path.lower().endswith(".svg"):
        console.save_svg(path, title=f"softplc watch {session.app.name}")
    else:
        console.save_text(path)
