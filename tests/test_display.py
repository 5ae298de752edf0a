"""softplc.toml [display]: the status line softplc run draws and the summary it prints."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from rich.console import Console

from helpers.cli import softplc_here
from helpers.apps import make_app
from softplc_lite.app import AppError, load_app
from softplc_lite.datatable import DataTable
from softplc_lite.run_output import StatusLine, parse_display


def app_dir(tmp_path: Path, display: str) -> Path:
    return make_app(tmp_path / "counting", "SYMBOL Count N7:0\nADD Count 1 Count\nXIC S:1/15 FLL 7 #N11:0 4\n",
                    softplc_toml="[scan]\nscan_ms = 5\n\n[display]\n" + display)


def test_summary_after_a_bounded_run(tmp_path):
    d = app_dir(tmp_path, 'status = { count = "Count", "first" = "N11:0" }\nsummary = { block = "#N11:0 3" }\n')
    out = softplc_here("run", str(d), "--fresh", "--scans", "40")
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == [
        "counting: 40 scans, 0.20 s simulated time",
        "count (N7:0) = 40",
        "first (N11:0) = 7",
        "block (#N11:0 3) = 7 7 7",
    ]
    assert out.stderr == ""  # no terminal: no status line drawn


def test_status_line_renders_scan_time_and_values():
    table = DataTable()
    table.reference("N7:1")
    table.write("N7:0", 12)
    display = parse_display({"status": {"polls": "N7:0", "regs": "#N7:0 2"}}, "softplc.toml")
    line = StatusLine("modbus_master", display.status)
    line.update(table, scans=3000, now_ms=3000, realtime=False)
    console = Console(width=100, record=True, color_system=None, file=open("/dev/null", "w"))
    console.print(line)
    assert console.export_text().rstrip() == "modbus_master  scan 3000  3.00 s simulated  polls 12  regs 12 0"


def test_status_line_counts_the_clients_of_an_app_with_a_server():
    line = StatusLine("hmi_server", [])
    line.update(DataTable(), scans=10, now_ms=100, realtime=True)
    console = Console(width=100, record=True, color_system=None, file=open("/dev/null", "w"))
    line.clients = 2
    console.print(line)
    line.clients = 1
    console.print(line)
    line.clients = None  # no network server: nothing said
    console.print(line)
    assert console.export_text().splitlines() == ["hmi_server  scan 10  0.10 s real  2 clients",
                                                  "hmi_server  scan 10  0.10 s real  1 client",
                                                  "hmi_server  scan 10  0.10 s real"]


@pytest.mark.parametrize("display,message", [
    ('status = { polls = 5 }\n', "[display] polls = 5; expected an address"),
    ('status = { polls = "N7:x" }\n', "[display] polls = 'N7:x': "),
    ('summary = { b = "#N11:0 0" }\n', "a block is #FILE:ELEMENT LEN with LEN 1..1000"),
    ('colour = { a = "N7:0" }\n', "[display] has colour = "),
])
def test_bad_display_settings_name_the_file(tmp_path, display, message):
    with pytest.raises(AppError) as info:
        load_app(app_dir(tmp_path, display))
    assert re.search(r"softplc.toml:\d+: ", str(info.value)) and message in str(info.value)
