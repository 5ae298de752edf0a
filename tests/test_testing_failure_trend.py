"""A failure report draws the failing address over the scans before the
failure (testing/failure_trend.py): its values are the table's at each of
those scans, a bit as a band, and nothing is recorded unless asked (the
mutation runs never ask)."""

from __future__ import annotations

from softplc_lite.testing.failure_trend import TREND_SCANS
from softplc_lite.testing.plc import PLC
from softplc_lite.testing.runner import run_file

from helpers.cli import softplc_here
from helpers.shipped_apps import copy_app

FAILING = """scenario "the level stays low":
    run 3 s
    expect Level between 0 and 1500

scenario "the lamp is on early":
    run 2 s
    expect AtSetpoint == 1
"""


def tank_with_failures(tmp_path):
    app = copy_app("tank", tmp_path)
    (app / "tests" / "failing.plctest").write_text(FAILING, encoding="utf-8")
    return app


def test_the_trend_is_the_tables_values_up_to_the_failure(tmp_path):
    app = tank_with_failures(tmp_path)
    level, lamp = run_file(app, app / "tests" / "failing.plctest", trend=True)
    with PLC.load(app) as plc:
        seen = [plc["Level"]]
        for _ in range(300):
            plc.scan(1)
            seen.append(plc["Level"])
    chart = level.failure.trend
    (trace,) = chart.traces
    assert trace.values == seen[-TREND_SCANS:] and trace.values[-1] == level.failure.actual == 1878
    assert not trace.is_bit and (chart.x.first_scan, chart.x.last_scan) == (301 - TREND_SCANS, 300)
    assert chart.marker == len(trace.values) - 1
    (bit,) = lamp.failure.trend.traces
    assert bit.is_bit and set(bit.values) == {0} and len(bit.values) == TREND_SCANS  # scans 1..200
    text = level.failure.text(80)
    assert "Level from scan 101 to the failure:" in text and "1878┤" in text and "scan 300 3.000" in text


def test_without_asking_nothing_is_run_again(tmp_path):
    app = tank_with_failures(tmp_path)
    results = run_file(app, app / "tests" / "failing.plctest")
    assert [r.failure.trend for r in results] == [None, None]


def test_softplc_test_draws_it_under_the_rungs(tmp_path):
    app = tank_with_failures(tmp_path)
    r = softplc_here("test", str(app))
    assert r.returncode == 1
    out = r.stdout
    assert out.index("rungs that write Level") < out.index("Level from scan 101 to the failure:")
    assert "AtSetpoint from scan 1 to the failure:" in out and "AtSetpoint│" in out
