"""The watch view's trend panel (softplc_lite/watch/trendview.py): the
series a session trends, the T and W keys, what the panel draws while
running, stepping back and stopped at a breakpoint, what a redraw reads
and that a scan reads nothing for it, and the history written to CSV and
VCD read back."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from rich.cells import cell_len

from softplc_lite.trends.series import TrendError
from softplc_lite.watch.snapshot import render
from softplc_lite.watch.terminal import Controller
from softplc_lite.watch.trendview import MAX_TRENDS, TrendPanel, panel_height

from helpers.watch_sessions import sessions

ROOT = Path(__file__).resolve().parent.parent
RAMP = """
SYMBOL Count N7:0
SYMBOL Ratio F8:0
SYMBOL Tick B3/0
// count scans, a float beside, and a bit on every fourth scan
ADD N7:0 1 N7:0
CPT F8:0 "N7:0 / 4.0"
CMP "N7:0 MOD 4 = 0" OTE B3/0
"""


@pytest.fixture
def session(tmp_path):
    yield from sessions(tmp_path, RAMP)


def _text(s, width=100, height=30) -> str:
    return render(s, width, height).export_text()


def _keys(c: Controller, text: str) -> None:
    for k in text:
        c.key(k)


def test_trends_from_the_options_are_resolved_before_scan_0(session):
    s = session(trend=("Count", "Tick", "F8:0"), online=False)
    assert [x.label for x in s.trend] == ["Count", "Tick", "F8:0"]
    assert [x.kind for x in s.trend] == ["word", "bit", "float"]
    assert s.engine.scans == 0 and s.message == ""


def test_bad_trends_from_the_options_raise_every_problem(session):
    with pytest.raises(TrendError) as e:
        session(trend=("Nope", "T4:0", "N7:0"), online=False)
    assert len(e.value.problems) == 2
    assert "--trend 'Nope'" in e.value.problems[0] and "T4:0.ACC" in e.value.problems[1]
    with pytest.raises(TrendError, match="at most 6"):
        session(trend=tuple(f"B3/{k}" for k in range(MAX_TRENDS + 1)), online=False)


def test_the_prompt_adds_removes_and_sets_the_range_and_says_errors_on_the_message_line(session):
    s = session(online=False)
    s.trend_command("Count")
    assert [x.label for x in s.trend] == ["Count"] and s.message == "trend: Count added"
    s.trend_command("N7:0")  # the same word by its address: removed
    assert s.trend == [] and "removed" in s.message and "closes" in s.message
    s.trend_command("Count")
    s.trend_command("range 0 100")
    assert s.trend_range == (0, 100) and s.message == "trend: y range 0 to 100"
    s.trend_command("range auto")
    assert s.trend_range is None
    for bad, said in (("range 5 1", "LO must be below HI"), ("range x", "expected two numbers"),
                      ("T4:0", "a whole timer"), ("Nope", "neither an address nor a program symbol")):
        s.trend_command(bad)
        assert said in s.message, (bad, s.message)
    assert [x.label for x in s.trend] == ["Count"]
    for k in range(MAX_TRENDS - 1):
        s.trend_command(f"B3/{k + 1}")
    s.trend_command("B3/9")
    assert len(s.trend) == MAX_TRENDS and "at most 6" in s.message


def test_add_and_remove_by_method(session):
    s = session(online=False)
    s.add_trend("Count", "B3/0")
    assert [x.label for x in s.trend] == ["Count", "B3/0"] and s.message == "trend: Count, B3/0 added"
    s.add_trend("N7:0")
    assert len(s.trend) == 2 and "already shown" in s.message
    s.remove_trend("Count")
    assert [x.label for x in s.trend] == ["B3/0"]
    s.remove_trend("Count")
    assert s.message == "trend: Count is not trended" and len(s.trend) == 1


def test_the_T_key_offers_the_selected_rungs_first_operand_by_its_symbol(session):
    s = session(online=False)
    c = Controller(s)
    c.key("T")
    assert c.prompt == "trend: ADDR (add/remove), range LO HI | range auto: Count"
    c.key("\r")
    assert [x.label for x in s.trend] == ["Count"]
    s.move(2)  # CMP ... OTE B3/0: the expression is no operand, the bit is
    c.key("T")
    assert c.prompt.endswith(": Tick")
    _keys(c, "\x7f" * 4 + "range 0 50\r")
    assert s.trend_range == (0, 50)


def test_the_panel_shows_the_last_scans_with_a_legend_and_the_axis_in_scans_and_seconds(session):
    s = session(trend=("Count", "Ratio", "Tick"), online=False)
    assert "trend: no scan recorded yet" in _text(s)
    for _ in range(300):
        s.scan()
    screen = _text(s, 120, 40)
    lines = screen.splitlines()
    assert all(cell_len(line) == 120 for line in lines) and len(lines) == 40
    legend = next(line for line in lines if line.startswith(" Count 300"))
    assert "Ratio 75.0  Tick 1  y auto" in legend
    axis = next(line for line in lines if "└scan" in line)
    first = int(axis.split("└scan ")[1].split()[0])
    assert axis.rstrip().endswith("scan 300 3.000 s")
    assert f"{first * 10 / 1000:.3f} s" in axis
    assert 300 - first + 1 == 2 * (120 - len("Count") - 1)  # the gutter is the longest label: a scan a dot column


def test_stepping_back_marks_the_shown_scan_and_keeps_it_in_the_window(session):
    s = session(trend=("Count", "Tick"), online=False)
    for _ in range(600):
        s.scan()
    for _ in range(3):
        s.back()
    screen = _text(s)
    assert "scan 597 of 600 (history)" in screen
    assert " Count 597  Tick 0" in screen  # the legend says the values of the scan shown
    axis = next(line for line in screen.splitlines() if "└" in line)
    assert "▲" in axis and "scan 600" in axis
    for _ in range(400):  # older than the newest window: the window moves with it
        s.back()
    screen = _text(s)
    axis = next(line for line in screen.splitlines() if "└" in line)
    assert "scan 197 of 600 (history)" in screen and "▲" in axis and "scan 600" not in axis
    s.scan()  # n: one forward in history, drawn with it
    assert " Count 198" in _text(s)


def test_a_breakpoint_stops_the_run_and_the_panel_ends_at_its_scan(session):
    s = session(trend=("Count",), break_when=("N7:0 >= 42",), online=False)
    s.start()
    s.run_for(2)
    assert not s.running and s.engine.scans == 42
    axis = next(line for line in _text(s).splitlines() if "└" in line)
    assert axis.rstrip().endswith("scan 42 0.420 s")


def test_a_scan_reads_nothing_for_the_panel_and_a_redraw_reads_only_the_new_scans(session):
    s = session(trend=("Count", "Ratio", "Tick"), online=False)
    cache = s.trend_cache
    for _ in range(500):
        s.scan()
    assert cache.reads == 0  # the scans recorded the history, as without a trend; nothing else
    _text(s, 100, 30)
    window = cache.reads
    assert 0 < window <= 2 * 100
    for _ in range(10):
        s.scan()
    assert cache.reads == window
    _text(s, 100, 30)
    assert cache.reads == window + 10  # the ten new scans, the rest kept
    _text(s, 100, 30)
    assert cache.reads == window + 10


def test_at_80x24_the_panel_is_smaller_and_says_what_it_leaves_out(session):
    s = session(trend=("Count", "Ratio", "B3/0", "B3/1", "B3/2", "B3/3"), online=False)
    assert panel_height(s, 80, 24) == 7 and panel_height(s, 120, 40) == 14
    for _ in range(50):
        s.scan()
    screen = _text(s, 80, 24)
    assert "+1 more" in screen  # two lines, three of the four bits
    assert "B3/2│" in screen and "B3/3│" not in screen
    assert "+1 more" not in _text(s, 120, 40)


def test_the_panel_without_room_says_so(session):
    s = session(trend=("Count",), online=False)
    s.scan()
    assert "no room" in render_panel(s, 1)


def render_panel(s, height: int) -> str:
    from rich.console import Console
    import io

    console = Console(width=60, file=io.StringIO(), record=True, color_system=None, legacy_windows=False)
    console.print(TrendPanel(s, height))
    return console.export_text()


def test_W_writes_the_history_as_csv_read_back_value_for_value(session, tmp_path):
    s = session(trend=("Count", "Ratio", "Tick"), online=False)
    for _ in range(30):
        s.scan()
    c = Controller(s)
    path = tmp_path / "trend.csv"
    c.key("W")
    _keys(c, f"{path}\r")
    assert s.message == f"trend of 30 scans (1 to 30) written to {path}"
    rows = list(csv.reader(path.open(encoding="utf-8")))
    assert rows[0] == ["scan", "time_s (simulated)", "Count", "Ratio", "Tick"]
    assert len(rows) == 31
    for k, row in enumerate(rows[1:], start=1):
        assert row == [str(k), f"{k * 10 / 1000:.3f}", str(k), repr(k / 4), str(int(k % 4 == 0))]


def test_W_writes_a_vcd_an_independent_reader_reads(session, tmp_path):
    vcdvcd = pytest.importorskip("vcdvcd")
    s = session(trend=("Count", "Tick"), online=False)
    for _ in range(12):
        s.scan()
    path = tmp_path / "trend.vcd"
    s.write_trend(str(path))
    assert "written to" in s.message
    vcd = vcdvcd.VCDVCD(str(path))
    count = next(v for k, v in vcd.data.items() if v.references[0].endswith(".Count"))
    tick = next(v for k, v in vcd.data.items() if v.references[0].endswith(".Tick"))
    assert [(t, int(v, 2)) for t, v in count.tv if v != "x"] == [(k * 10, k) for k in range(1, 13)]
    assert [(t, int(v, 2)) for t, v in tick.tv if v != "x"] == [(10, 0), (40, 1), (50, 0), (80, 1), (90, 0),
                                                                (120, 1)]


def test_W_errors_are_said_on_the_message_line(session, tmp_path):
    s = session(online=False)
    s.write_trend(str(tmp_path / "x.csv"))
    assert s.message == "write trend: no trend (T adds an address)"
    s.trend_command("Count")
    s.write_trend(str(tmp_path / "x.csv"))
    assert s.message == "write trend: no scan recorded yet"
    s.scan()
    s.write_trend(str(tmp_path / "x.txt"))
    assert s.message.startswith("write trend ") and "expected a .csv or .vcd" in s.message
    s.write_trend(str(tmp_path / "missing" / "x.csv"))
    assert "cannot write it" in s.message
    assert not (tmp_path / "x.csv").exists()


def test_cli_trend_snapshot_is_the_golden_view(tmp_path):
    from helpers.cli import softplc_here

    out = tmp_path / "view.txt"
    proc = softplc_here("watch", "programs/tank", "--fresh", "--state", str(tmp_path / "state"), "--scans", "520",
                        "--trend", "Level", "--trend", "Valve", "--trend", "AtSetpoint", "--snapshot", str(out),
                        "--width", "80", "--height", "24")
    assert proc.returncode == 0, proc.stderr
    golden = ROOT / "tests" / "data" / "watch" / "tank-trend-80x24.txt"
    assert "".join(line.rstrip() + "\n" for line in out.read_text(encoding="utf-8").splitlines()) == \
        golden.read_text(encoding="utf-8")


def _doc_block(after: str) -> str:
    doc = (ROOT / "docs" / "trends.md").read_text(encoding="utf-8")
    return doc.split(after, 1)[1].split("```text\n", 1)[1].split("```", 1)[0]


def test_the_doc_shows_the_golden_panel():
    """docs/trends.md shows the text of its --snapshot example: the tank-trend golden."""
    assert _doc_block("`/tmp/softplc-trend-tank.txt` then holds") == \
        (ROOT / "tests" / "data" / "watch" / "tank-trend-80x24.txt").read_text(encoding="utf-8")


def test_cli_bad_trends_are_every_one_said_before_scan_0(tmp_path):
    from helpers.cli import softplc_here

    out = tmp_path / "view.txt"
    proc = softplc_here("watch", "programs/tank", "--fresh", "--state", str(tmp_path / "state"), "--scans", "5",
                        "--trend", "T4:0", "--trend", "Nope", "--trend", "Level", "--snapshot", str(out))
    assert proc.returncode == 1
    assert proc.stderr == _doc_block("and says on standard error:")  # what docs/trends.md shows
    assert len(proc.stderr.splitlines()) == 2
    assert "Traceback" not in proc.stderr and not out.exists()
    assert not (tmp_path / "state" / "datatable.snap").exists()  # nothing ran, nothing saved


@pytest.mark.parametrize("width,height", [(40, 12), (80, 12), (80, 16), (120, 12), (200, 60)])
def test_the_panel_fits_any_size_and_says_when_it_has_no_room(session, width, height):
    s = session(trend=("Count", "Ratio", "Tick", "B3/1", "B3/2", "B3/3"), online=False)
    for _ in range(30):
        s.scan()
    lines = _text(s, width, height).splitlines()
    assert len(lines) == height and all(cell_len(line) == width for line in lines)
    text = "\n".join(lines)
    if width < 120 and height == 12:  # the rungs keep their 8 lines: one left for the panel
        assert "trend: no room" in text
    else:
        assert "└scan 1 0.010 s" in text
