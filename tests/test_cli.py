"""The softplc command as a user runs it: exit codes, messages, and no
Python traceback on bad input. Run by cli.main in the test's process: what
is checked is what the command prints and returns, and an exception
escaping main() fails the test as a traceback would show in a process."""

from __future__ import annotations

import json

from helpers.cli import softplc_here


def test_help_and_version():
    proc = softplc_here("--help")
    assert proc.returncode == 0 and "address" in proc.stdout and "datatable" in proc.stdout
    proc = softplc_here("--version")
    assert proc.returncode == 0 and proc.stdout.startswith("softplc_lite ")


def test_bad_address_exit_1_with_caret_and_no_traceback():
    proc = softplc_here("address", "N7:0", "T4:0.FOO")
    assert proc.returncode == 1
    assert proc.stdout == "address\tcanonical\tkind\taccess\nN7:0\tN7:0\tword\tdirect\n"  # a header names the columns
    assert "bad address 'T4:0.FOO': 'FOO' is not a member" in proc.stderr
    assert "  T4:0.FOO\n       ^" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_usage_error_exit_2():
    assert softplc_here("address").returncode == 2
    assert softplc_here("nonsense").returncode == 2


def test_datatable_dump_save_and_reload(tmp_path):
    snap = tmp_path / "t.snap"
    proc = softplc_here("datatable", "docs/examples/datatable.json", "--dump", "--save", str(snap))
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["N7"] == [100, -5, 0, 32767] and doc["ST9"] == ["HELLO WORLD", "café"]
    proc = softplc_here("datatable", str(snap), "--print", "N7:3", "--print", "C5:0/DN")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "N7:3 = 32767\nC5:0/DN = 1\n"


def test_datatable_errors_are_reported(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"N7": [1,\n 99999]}')
    proc = softplc_here("datatable", str(bad))
    assert proc.returncode == 1
    assert f"{bad}: N7[1]: 99999 does not fit N7:1" in proc.stderr
    assert "Traceback" not in proc.stderr
    corrupt = tmp_path / "c.snap"
    corrupt.write_bytes(b"SPLCSNAP" + b"\0" * 40)
    proc = softplc_here("datatable", str(corrupt))
    assert proc.returncode == 1 and "not a usable snapshot" in proc.stderr
    proc = softplc_here("datatable", "--print", "N7:50")
    assert proc.returncode == 1 and "past the end of N7" in proc.stderr
