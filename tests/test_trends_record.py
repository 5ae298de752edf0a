"""Trend recordings (softplc_lite/trends): the addresses chosen are resolved
with every problem said at once, and what a run records, read back by
independent readers (the csv module, vcdvcd), is value for value what the
data table held after each scan; a long recording takes constant memory."""

from __future__ import annotations

import csv
import struct
from pathlib import Path

import pytest
from vcdvcd import VCDVCD

from softplc_lite.app import load_app
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.trends.background import BackgroundRecorder
from softplc_lite.trends.record import Recorder, TrendFileError, format_of, open_writer, vcd_name
from softplc_lite.trends.series import TrendError, resolve_series

from helpers.apps import make_app
from helpers.cli import softplc_here
from helpers.shipped_apps import copy_app

TANK = ["Level", "Valve", "Loop[2]", "AtSetpoint", "LevelF"]


def recorder_of(how: str, runner: Runner, series, path: Path, on_change: bool = False):
    """The in-process Recorder (the watch view's), or the BackgroundRecorder
    (softplc run's: a writer process formats), attached after each scan."""
    if how.startswith("background"):
        recorder = BackgroundRecorder(runner.table, series, path, runner.app.name, "simulated", on_change,
                                      follow=how == "background, following")
    else:
        recorder = Recorder(runner.table, series, open_writer(path, series, runner.app.name, "simulated"), on_change)
    runner.after_scan.append(lambda e: recorder.record(e.scans, e.clock.now_ms))
    return recorder


HOW = pytest.mark.parametrize("how", ["in-process", "background", "background, following"])


def tank_runner(tmp_path: Path) -> Runner:
    return Runner(load_app(copy_app("tank", tmp_path)), RunOptions(fresh=True, save_state=False))


def table_history(runner: Runner, series, scans: int) -> list[tuple]:
    """Run ``scans`` scans; (scan, ms, values read by table.read) after each."""
    seen = []
    runner.after_scan.append(lambda e: seen.append(
        (e.scans, e.clock.now_ms, [e.table.read(s.address) for s in series])))
    runner.run(scans)
    return seen


def test_every_problem_is_said_at_once(tmp_path):
    runner = tank_runner(tmp_path)
    with pytest.raises(TrendError) as info:
        resolve_series(["Level", "Nope", "T4:0", "ST9:0", "#N7:1", "N99:0", "Level"], runner.table,
                       runner.app.program.symbols)
    problems = info.value.problems
    assert len(problems) == 5, problems
    assert "Nope is neither an address nor a program symbol" in problems[0]
    assert "T4:0.ACC, T4:0.PRE, T4:0/DN" in problems[1]
    assert "not a number a trend can draw" in problems[2]
    assert "direct address" in problems[3]
    assert "N99" in problems[4]
    runner.close()


def test_symbols_keep_their_names_and_repeats_count_once(tmp_path):
    runner = tank_runner(tmp_path)
    series = resolve_series(TANK + ["N11:0"], runner.table, runner.app.program.symbols)
    assert [(s.label, s.kind) for s in series] == [("Level", "word"), ("Valve", "word"), ("Loop[2]", "word"),
                                                   ("AtSetpoint", "bit"), ("LevelF", "float")]
    runner.close()


@HOW
def test_csv_rows_are_the_tables_values_after_each_scan(tmp_path, how):
    runner = tank_runner(tmp_path)
    series = resolve_series(TANK, runner.table, runner.app.program.symbols)
    path = tmp_path / "tank.csv"
    recorder = recorder_of(how, runner, series, path)
    expected = table_history(runner, series, 600)
    recorder.close()
    runner.close()
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["scan", "time_s (simulated)", *[s.label for s in series]]
    assert len(rows) == 601
    for row, (scan, ms, values) in zip(rows[1:], expected):
        assert int(row[0]) == scan and float(row[1]) == ms / 1000
        assert [int(x) for x in row[2:6]] == values[:4]
        assert struct.pack("<f", float(row[6])) == struct.pack("<f", values[4])  # the float32 exactly
    assert any(int(r[5]) for r in rows[1:]) and any(not int(r[5]) for r in rows[1:])  # the lamp changes


@HOW
def test_vcd_read_by_vcdvcd_has_every_change_at_its_time(tmp_path, how):
    runner = tank_runner(tmp_path)
    series = resolve_series(TANK, runner.table, runner.app.program.symbols)
    path = tmp_path / "tank.vcd"
    recorder = recorder_of(how, runner, series, path)
    expected = table_history(runner, series, 500)
    recorder.close()
    runner.close()
    vcd = VCDVCD(str(path))
    for k, s in enumerate(series):
        signal = vcd[f"tank.{vcd_name(s.label)}"]
        for _, ms, values in expected[::7]:
            raw = signal[ms]
            if s.kind == "float":
                assert struct.pack("<f", float(raw)) == struct.pack("<f", values[k]), (s.label, ms)
            else:
                value = int(raw, 2)
                if s.kind == "word" and value & 0x8000:
                    value -= 0x10000
                assert value == values[k], (s.label, ms)
    assert int(vcd["tank.AtSetpoint"].size) == 1
    assert int(vcd["tank.Level"].size) == 16


@HOW
def test_on_change_writes_only_the_scans_that_changed(tmp_path, how):
    app = make_app(tmp_path / "app", "XIC S:4/6 OTE B3/0\nADD N7:0 1 N7:0\n")  # S:4/6: the free-running clock bit
    runner = Runner(load_app(app), RunOptions(fresh=True, save_state=False))
    series = resolve_series(["B3/0"], runner.table, {})
    path = tmp_path / "b.csv"
    recorder = recorder_of(how, runner, series, path, on_change=True)
    expected = table_history(runner, series, 1000)
    recorder.close()
    runner.close()
    rows = list(csv.reader(open(path, newline="", encoding="utf-8")))[1:]
    changes = [(scan, v[0]) for k, (scan, _, v) in enumerate(expected) if k == 0 or v != expected[k - 1][2]]
    assert [(int(r[0]), int(r[2])) for r in rows] == changes and 2 < len(changes) < 1000


def test_softplc_run_records_and_refuses_bad_options(tmp_path):
    app = copy_app("tank", tmp_path)
    out = tmp_path / "level.csv"
    r = softplc_here("run", str(app), "--fresh", "--scans", "50", "--trend", "Level", "--trend", "AtSetpoint",
                     "--trend-file", str(out))
    assert r.returncode == 0, r.stderr
    assert len(out.read_text().splitlines()) == 51
    bad = softplc_here("run", str(app), "--fresh", "--scans", "5", "--trend", "Lvl", "--trend-file",
                       str(tmp_path / "x.txt"))
    assert bad.returncode == 1 and "Traceback" not in bad.stderr
    assert "--trend 'Lvl'" in bad.stderr or "Lvl" in bad.stderr
    assert "expected a .csv or .vcd file name" in bad.stderr
    alone = softplc_here("run", str(app), "--fresh", "--scans", "5", "--trend", "Level")
    assert alone.returncode == 1 and "--trend-file FILE.csv" in alone.stderr
    unwritable = softplc_here("run", str(app), "--fresh", "--scans", "5", "--trend", "Level", "--trend-file",
                              str(tmp_path / "no" / "such" / "dir.vcd"))
    assert unwritable.returncode == 1 and "cannot write it" in unwritable.stderr


def test_a_writer_that_died_is_said_when_the_recording_closes(tmp_path):
    runner = tank_runner(tmp_path)
    series = resolve_series(["Level"], runner.table, runner.app.program.symbols)
    recorder = recorder_of("background", runner, series, tmp_path / "t.csv")
    runner.run(10)
    recorder.proc.kill()
    recorder.proc.wait()
    runner.run(2000)  # its pipe is gone: the scans go on
    with pytest.raises(TrendFileError) as info:
        recorder.close()
    assert "status" in str(info.value)
    runner.close()


def test_the_format_comes_from_the_suffix():
    assert format_of("a.CSV") == "csv" and format_of("x/y.vcd") == "vcd"


def _rss_kib() -> int:
    """This process's resident memory now (Linux's /proc), in KiB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads Linux's /proc")
def test_a_long_recording_of_20_addresses_takes_constant_memory(tmp_path):
    """100,000 scans recording 20 addresses: the resident memory after
    25,000 rows and after 100,000 is the same within 2 MiB (a row kept would
    be 75,000 rows of 20 values: over 10 MiB), and the file has every row."""
    app = make_app(tmp_path / "app", "".join(f"ADD N7:{k} {k + 1} N7:{k}\n" for k in range(19))
                   + "XIC S:4/0 OTE B3/0\n")
    runner = Runner(load_app(app), RunOptions(fresh=True, save_state=False))
    series = resolve_series([f"N7:{k}" for k in range(19)] + ["B3/0"], runner.table, {})
    out = tmp_path / "long.csv"
    recorder = recorder_of("background", runner, series, out)
    runner.run(25_000)
    at_25k = _rss_kib()
    runner.run(75_000)
    at_100k = _rss_kib()
    recorder.close()
    runner.close()
    assert recorder.rows == 100_000
    assert at_100k - at_25k < 2048, (at_25k, at_100k)
    assert sum(1 for _ in open(out, encoding="utf-8")) == 100_001
