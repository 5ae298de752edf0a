"""Find and cross-reference and the data-file monitor in the real ``softplc
watch``, in tmux: ``/`` finds, ``x``/``X`` step through the uses, ``d``
shows a data file, ``R`` changes its radix, Esc closes it."""

from __future__ import annotations

import shutil
import sys
import time

import pytest
from helpers.tmux_helpers import Tmux


@pytest.fixture
def tmux(request):
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (apt-get install -y tmux)")
    t = Tmux("x" + request.node.name[:18].replace("[", "_").replace("]", "_"))
    yield t
    t.kill()


def quit_view(tmux: Tmux) -> None:
    tmux.keys("q")
    deadline = time.monotonic() + 10
    while tmux.alive() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not tmux.alive(), "q did not end softplc watch"


def test_find_a_symbol_and_jump_between_its_rungs(tmux, tmp_path):
    tmux.start(f"{sys.executable} -m softplc_lite watch programs/motor --fresh --state {tmp_path}",
               width=120, height=40)
    tmux.wait_for("PAUSED")
    tmux.keys("/", "Tripped", "Enter")
    screen = tmux.wait_for("find Tripped (B3/0): use 1 of 5, 2 writing")  # the side panel's short form
    assert "Tripped (B3/0) 1 of 5: file 2 rung 0  instruction 4 XIO  operand 1 B3/0  read" in screen
    assert "rung 0 of 7" in screen
    tmux.keys("x")
    screen = tmux.wait_for("2 of 5: file 2 rung 3")
    assert "instruction 2 OTL  operand 1 B3/0  write" in screen and "rung 3 of 7" in screen
    tmux.keys("x")
    tmux.wait_for("3 of 5: file 2 rung 4  instruction 3 OTU")
    tmux.keys("X", "X")
    tmux.wait_for("1 of 5: file 2 rung 0")
    tmux.keys("X")  # wraps to the last use
    tmux.wait_for("5 of 5: file 2 rung 6")
    tmux.keys("/", "C5:0", "Enter")  # the counter: its one writer, the CTU
    screen = tmux.wait_for("find C5:0: 1 use, 1 writing")
    assert "instruction 3 CTU  operand 1 C5:0  read/write" in screen
    tmux.keys("/", "Trippd", "Enter")  # a typo: said, nothing jumps
    screen = tmux.wait_for("find Trippd: Trippd is neither an address nor a program symbol")
    assert "Traceback" not in screen
    tmux.keys("Escape")  # closes the find list
    deadline = time.monotonic() + 10
    while "find C5:0" in tmux.screen() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert "find C5:0" not in tmux.screen()
    quit_view(tmux)


def test_data_file_grid_radix_and_escape(tmux, tmp_path):
    tmux.start(f"{sys.executable} -m softplc_lite watch programs/motor --fresh --state {tmp_path}",
               width=100, height=30)
    tmux.wait_for("PAUSED")
    tmux.keys("=", "N7:0 = 16706", "Enter")  # "AB" in ASCII
    tmux.wait_for("set N7:0 = 16706")
    tmux.keys("d", "N7", "Enter")
    screen = tmux.wait_for("radix decimal")
    assert "N7:0" in screen and "16706" in screen
    tmux.keys("R")
    screen = tmux.wait_for("radix hex")
    assert "4142" in screen
    tmux.keys("R")
    tmux.wait_for("radix binary")
    tmux.keys("R")
    screen = tmux.wait_for("radix ascii")
    assert "N7:0  AB" in screen
    tmux.keys("Escape")
    deadline = time.monotonic() + 10
    while "radix ascii" in tmux.screen() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert "program file 2" in tmux.screen()  # the rungs are back
    tmux.keys("d", "T4", "Enter")  # a timer file: one element a row
    screen = tmux.wait_for("T4:0  EN 0 TT 0 DN 0")
    assert "PRE  32767" in screen  # the RTO's preset
    tmux.keys("Escape", "d", "N99", "Enter")  # no such file: said on the message line
    screen = tmux.wait_for("there is no data file N99")
    assert "Traceback" not in screen
    quit_view(tmux)
