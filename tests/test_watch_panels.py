"""The watch view's panels at the sizes a user meets (80x24, 100x40,
120x40): the ports panel's frames on one line each, the find list's read or
write column in the side panel, every key's whole text in the ``?`` list;
a step in PROGRAM mode, and ``softplc watch`` of an app that is not there."""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import pytest
from rich.console import Console

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions
from softplc_lite.watch.snapshot import render
from softplc_lite.watch.portsview import ports_of
from softplc_lite.watch.screen import WatchScreen, rung_view
from softplc_lite.watch.session import WatchOptions, WatchSession
from softplc_lite.watch.terminal import KEYS, Controller

from helpers.cli import softplc_here

ROOT = Path(__file__).resolve().parent.parent
SIZES = [(120, 40), (100, 40), (80, 24)]


@pytest.fixture
def open_app(tmp_path):
    made = []

    def make(name: str, scans: int = 0, **kw) -> WatchSession:
        app_dir = tmp_path / name
        if not app_dir.exists():
            shutil.copytree(ROOT / "programs" / name, app_dir, ignore=shutil.ignore_patterns(".softplc"))
        session = WatchSession(load_app(app_dir, state_dir=tmp_path / f"state{len(made)}"),
                               WatchOptions(run=RunOptions(fresh=True), online=False, **kw))
        made.append(session)
        for _ in range(scans):
            session.scan()
        return session
    yield make
    for session in made:
        session.quit()


@pytest.mark.parametrize("width, height", SIZES)
@pytest.mark.parametrize("name, scans", [("modbus_master", 400), ("modbus_scada", 100), ("loopback", 100)])
def test_each_frame_of_the_ports_panel_is_one_readable_line(open_app, name, scans, width, height):
    session = open_app(name, scans)
    lines = render(session, width, height).export_text().splitlines()
    frames = [f for port in ports_of(session.engine) for f in list(port.history)[-4:]]
    assert frames, "the app exchanged no frames"
    for _, direction, data in frames:
        start = f"{direction} {data[:8].hex(' ').upper()}"  # at least 8 bytes of a frame side by side
        assert any(start in line for line in lines), (start, "\n".join(lines))
    assert not any(line.rstrip().endswith(("│ RX", "│ TX")) for line in lines)


def test_the_find_list_in_the_side_panel_keeps_read_or_write_on_every_line(open_app):
    session = open_app("motor", 1)
    session.find("Tripped")
    lines = render(session, 120, 40).export_text().splitlines()
    at, column = next((k, line.index("find Tripped")) for k, line in enumerate(lines) if "find Tripped" in line)
    assert column == 120 - 45  # the side panel, beside the rungs
    side = [line[column:].rstrip() for line in lines]
    uses = side[at + 1:at + 6]
    assert [use.split()[1 if use.startswith("▶") else 0] for use in uses] == ["read", "write", "write", "read",
                                                                               "read"]
    assert all("file 2 rung" in use and "…" not in use for use in uses)
    assert side[at] == "find Tripped (B3/0): use 1 of 5, 2 writing"
    # where the whole line fits, it is the full description, read or write at its end
    wide = render(session, 100, 40).export_text()
    assert "▶ file 2 rung 0  instruction 4 XIO  operand 1 B3/0  read" in wide


def _draw(screen: WatchScreen, width: int, height: int) -> str:
    console = Console(width=width, height=height, color_system=None, file=io.StringIO(), legacy_windows=False)
    with console.capture() as cap:
        console.print(screen)
    return cap.get()


def test_the_key_list_at_80x24_shows_every_text_whole_in_pages(open_app):
    session = open_app("motor")
    control = Controller(session)
    screen = WatchScreen(session, rung_view, measured=False)
    control.key("?")
    shown = []
    for _ in range(len(KEYS)):
        screen.help, screen.help_page = KEYS if control.help else None, control.help_page
        if not control.help:
            break
        page = _draw(screen, 80, 24)
        control.help_pages = screen.help_pages
        assert "…" not in page
        shown.append(page)
        control.key(" ")  # the next page; on the last, it closes the list
    assert len(shown) == 2 and not control.help and session.engine.scans == 0
    assert "keys, page 1 of 2" in shown[0] and "keys, page 2 of 2" in shown[1]
    words = " ".join(" ".join(shown).split())
    for label, text in KEYS:
        assert " ".join(text.split()) in words.replace(" ".join([" " * 18]), " "), text
    # PgUp goes back a page; any other key closes the list and does nothing else
    control.key("?")
    control.help_pages = 2
    control.key("pgdown")
    control.key("pgup")
    assert control.help and control.help_page == 0
    control.key("n")
    assert not control.help and session.engine.scans == 0


def test_the_key_list_at_120x40_is_one_page(open_app):
    session = open_app("motor")
    screen = WatchScreen(session, rung_view, measured=False)
    screen.help = KEYS
    page = _draw(screen, 120, 40)
    assert "keys (any key closes this)" in page and screen.help_pages == 1
    for label, text in KEYS:
        assert text in page


def test_a_step_in_program_mode_records_no_scan_and_history_stays_scans(open_app):
    session = open_app("motor", 2)
    session.set_mode("program")
    for _ in range(3):
        session.scan()
    assert session.engine.scans == 2 and [f.scan for f in session.history.frames] == [1, 2]
    assert session.history.live and session.message.startswith("PROGRAM mode: the ladder does not run")
    assert " scan 2 " in render(session, 100, 30).export_text().splitlines()[0]
    session.back()
    assert " scan 1 of 2 (history)" in render(session, 100, 30).export_text().splitlines()[0]
    session.scan()  # forward: live again at once, no "2 of 2"
    assert session.history.live and session.message == "live"


def test_watch_of_a_missing_app_says_so_before_asking_for_a_terminal(tmp_path):
    p = softplc_here("watch", "nosuch", cwd=tmp_path)  # its standard input and output are not a terminal
    run = softplc_here("run", "nosuch", cwd=tmp_path)
    missing = (1, "nosuch: no such app directory or .lad file\n")
    assert (p.returncode, p.stderr) == (run.returncode, run.stderr) == missing
    assert p.stdout == ""


def test_the_view_loop_pages_the_key_list_at_the_size_it_draws(open_app):
    from softplc_lite.watch.terminal import ViewLoop

    session = open_app("motor")
    console = Console(width=80, height=24, color_system=None, file=io.StringIO(), legacy_windows=False)
    drawn = []

    def draw(screen):
        with console.capture() as cap:
            console.print(screen)
        drawn.append(cap.get())

    loop = ViewLoop(session, WatchScreen(session, rung_view, measured=False), draw)
    loop.tick("?")
    assert "keys, page 1 of 2" in drawn[-1]
    loop.tick(" ")
    assert "keys, page 2 of 2" in drawn[-1] and "quit (saves the retentive data table)" in drawn[-1]
    loop.tick(" ")  # past the last page: closed, and nothing else done
    assert "keys," not in drawn[-1] and "Rung 0" in drawn[-1] and session.engine.scans == 0
