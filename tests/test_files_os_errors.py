"""OS errors on a user's files are said in words: "cannot read
APP/softplc.toml: it is a directory", never "[Errno 21] Is a directory:
'...'"; and a retentive snapshot that does not fit the program says that
it is the retentive snapshot in APP/.softplc/ and suggests --fresh.

Tests run as root in CI, where permission bits do not stop a read: these
use a directory where a file is expected and a missing parent directory,
which fail for root too; the permission test skips as root."""

from __future__ import annotations

import os
import shutil

import pytest

from softplc_lite.app import load_app
from softplc_lite.datatable import DataTable, snapshot
from softplc_lite.datatable.errors import SnapshotError
from softplc_lite.errors import FileAccessError, file_error
from softplc_lite.retentive import restore_snapshot
from softplc_lite.textfile import read_text

from helpers.cli import ROOT, softplc_here


def test_the_helper_says_the_error_in_words(tmp_path):
    with pytest.raises(OSError) as e:
        read_text(tmp_path)
    assert isinstance(e.value, FileAccessError)
    assert str(e.value) == f"cannot read {tmp_path}: it is a directory"
    with pytest.raises(OSError) as e:
        read_text(tmp_path / "no-dir" / "x.json")
    assert str(e.value) == f"cannot read {tmp_path / 'no-dir' / 'x.json'}: no such file or directory"
    try:
        open(tmp_path / "no-dir" / "out.json", "w")
    except OSError as error:
        assert file_error(error, action="write").report() == \
            f"cannot write {tmp_path / 'no-dir' / 'out.json'}: no such file or directory"


def test_app_config_files_that_cannot_be_read_are_said_in_words(tmp_path):
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "loopback", app)
    (app / "softplc.toml").mkdir()
    (app / "datatable.json").mkdir()
    result = softplc_here("check", str(app))
    assert result.returncode == 1
    assert result.stderr.splitlines() == [f"cannot read {app / 'softplc.toml'}: it is a directory",
                                          f"cannot read {app / 'datatable.json'}: it is a directory",
                                          "2 problems found"]
    assert "Errno" not in result.stderr


def test_load_and_snapshot_files_that_cannot_be_read_are_said_in_words(tmp_path):
    result = softplc_here("run", "programs/blinker", "--fresh", "--state", str(tmp_path / "state"), "--scans", "1",
                     "--load", str(tmp_path))
    assert result.returncode == 1 and result.stderr == f"error: cannot read {tmp_path}: it is a directory\n"
    result = softplc_here("datatable", str(tmp_path))
    assert result.returncode == 1 and result.stderr == f"error: cannot read {tmp_path}: it is a directory\n"


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file without read permission anyway (CI runs as root)")
def test_an_unreadable_settings_file_is_permission_denied_in_words(tmp_path):
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / "blinker", app)
    (app / "softplc.toml").write_text("[scan]\nscan_ms = 10\n")
    (app / "softplc.toml").chmod(0)
    try:
        result = softplc_here("check", str(app))
    finally:
        (app / "softplc.toml").chmod(0o644)
    assert result.returncode == 1
    assert f"cannot read {app / 'softplc.toml'}: permission denied" in result.stderr


def test_a_snapshot_that_does_not_fit_the_program_names_itself_and_suggests_fresh(tmp_path):
    app_dir = tmp_path / "app"
    app_dir.mkdir()
    (app_dir / "main.lad").write_text("MOV 1 N10:0\n")
    old = DataTable()
    old.create_file("F", 10, 1)  # what an earlier program kept: F10
    path = app_dir / ".softplc" / "datatable.snap"
    path.parent.mkdir()
    snapshot.save(old, path)
    app = load_app(app_dir, use_cache=False)
    table = DataTable()
    table.create_file("N", 10, 1)  # the program's table: N10
    with pytest.raises(SnapshotError) as e:
        restore_snapshot(table, app.snapshot_path)
    message = str(e.value)
    assert message.startswith(f"{path}: the retentive snapshot kept between runs in {path.parent}{os.sep} "
                              "does not fit the program (")
    assert "file number 10 is N10 in the program" in message and "run with --fresh" in message
    assert table.file(10).ftype.letter == "N"  # not changed
    ok = DataTable()
    ok.create_file("N", 10, 1)
    snapshot.save(ok, path)
    assert restore_snapshot(table, path).source == path


def test_a_snapshot_that_cannot_be_read_suggests_fresh(tmp_path):
    path = tmp_path / ".softplc" / "datatable.snap"
    path.parent.mkdir()
    path.write_bytes(b"not a snapshot")
    with pytest.raises(SnapshotError) as e:
        restore_snapshot(DataTable(), path)
    assert f"the retentive snapshot kept between runs in {path.parent}{os.sep} cannot be read" in str(e.value)
    assert "run with --fresh" in str(e.value)


def test_dump_into_a_directory_is_said_in_words_and_exits_1(tmp_path):
    """--dump to a path that is a directory: the run still ends cleanly, the
    error is a sentence, and the exit status says something failed."""
    out = softplc_here("run", "programs/motor", "--fresh", "--scans", "2", "--state", str(tmp_path / "state"),
                  "--dump", str(tmp_path))
    assert out.returncode == 1
    assert f"error: --dump: cannot write {tmp_path}: it is a directory" in out.stderr
    assert "Errno" not in out.stderr and "Traceback" not in out.stderr
