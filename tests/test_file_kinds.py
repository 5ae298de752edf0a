"""Files that are not what their name promises (docs/cli.md, "Input file
limits"): a name that is there but cannot be read is reported by name, in
words, never taken for no file nor left out, and never with the C library's
text ("No such file or directory", "Is a directory").

Each test runs the CLI on an app copied to tmp_path, from tmp_path, so
messages name files as ``app/...``: in this process (helpers.cli), but for
names that are not UTF-8 on the command line, which a process of its own
receives as bytes."""

from __future__ import annotations

import errno
import os
import re
import shutil
from pathlib import Path

import pytest

from softplc_lite.errors import describe_os_error, os_error_words

from helpers.cli import ROOT, softplc, softplc_here

# What the C library says (strerror) and Python's own "[Errno N]": never in a message.
RAW = re.compile(r"\[Errno \d+\]|No such file or directory|Is a directory|Not a directory|Too many levels of "
                 r"symbolic links|File too large|No space left on device|Permission denied|Traceback")


def copy_app(tmp_path: Path, name: str) -> Path:
    app = tmp_path / "app"
    shutil.copytree(ROOT / "programs" / name, app, ignore=shutil.ignore_patterns(".softplc"))
    return app


def make(path: Path, kind: str) -> None:
    """A dangling link, a link loop (NAME -> NAME.x -> NAME) or a directory at ``path``."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    elif os.path.lexists(path):
        path.unlink()
    if kind == "dangling":
        path.symlink_to("nowhere")
    elif kind == "loop":
        path.symlink_to(path.name + ".x")
        path.with_name(path.name + ".x").symlink_to(path.name)
    else:
        path.mkdir()
        (path / "x").write_text("x")


WORDS = {"dangling": "a symbolic link to nowhere, which does not exist",
         "loop": "too many symbolic links (a link loop)",
         "dir": "it is a directory"}


# -- softplc.toml and datatable.json: optional, but a link to nothing is not "no file" -------------------

@pytest.mark.parametrize("kind", ["dangling", "loop"])
@pytest.mark.parametrize("name, base", [("softplc.toml", "modbus_master"), ("datatable.json", "blinker")])
def test_an_optional_file_that_is_a_broken_link_is_reported_not_taken_for_no_file(tmp_path, name, base, kind):
    app = copy_app(tmp_path, base)
    make(app / name, kind)
    said = f"cannot read app/{name}: {WORDS[kind]}"
    check = softplc_here("check", "app", cwd=tmp_path)
    assert check.returncode == 1 and check.stderr.splitlines() == [said, "1 problem found"], check.stderr
    run = softplc_here("run", "app", "--scans", "2", "--fresh", "--state", "state", cwd=tmp_path)
    assert run.returncode == 1 and said in run.stderr.splitlines() and not RAW.search(run.stderr), run.stderr
    assert run.stdout == "" and not (tmp_path / "state").exists()  # refused before any scan


def test_an_optional_file_that_is_not_there_is_still_no_file(tmp_path):
    copy_app(tmp_path, "blinker")  # neither softplc.toml nor datatable.json
    assert not (tmp_path / "app" / "datatable.json").exists()
    result = softplc_here("check", "app", cwd=tmp_path)
    assert result.returncode == 0, result.stderr


# -- a directory named like a program file -----------------------------------------------------------------

def test_a_directory_named_like_the_only_program_file_is_named(tmp_path):
    app = copy_app(tmp_path, "blinker")
    make(app / "main.lad", "dir")
    for argv in (["check", "app"], ["run", "app", "--scans", "2", "--fresh", "--state", "state"]):
        result = softplc_here(*argv, cwd=tmp_path)
        assert result.returncode == 1, result.stderr
        assert "app/main.lad: a directory, not a program file" in result.stderr.splitlines(), result.stderr
        assert "no .lad program files" not in result.stderr and not RAW.search(result.stderr)


def test_a_directory_named_like_a_subroutine_file_is_named_with_the_jsr_it_breaks(tmp_path):
    app = copy_app(tmp_path, "modbus_slave")
    make(app / "sbr063_crc.lad", "dir")
    check = softplc_here("check", "app", cwd=tmp_path)
    lines = check.stderr.splitlines()
    assert check.returncode == 1 and "app/sbr063_crc.lad: a directory, not a program file" in lines, check.stderr
    fmt = softplc_here("fmt", "app", cwd=tmp_path)
    assert fmt.returncode == 1 and "app/sbr063_crc.lad: a directory, not a program file" in fmt.stderr.splitlines()
    assert not RAW.search(check.stderr + fmt.stderr)


# -- OS errors in words, wherever a message shows one -------------------------------------------------------

@pytest.mark.parametrize("kind", ["dangling", "loop", "dir"])
def test_a_replay_trace_that_cannot_be_read_is_said_in_words(tmp_path, kind):
    copy_app(tmp_path, "modbus_master")
    make(tmp_path / "t.trace", kind)
    result = softplc_here("run", "app", "--fresh", "--state", "state", "--replay", "t.trace", "--scans", "20",
                          cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    assert f"replay: t.trace: cannot read trace file: {WORDS[kind]} " in result.stderr, result.stderr
    assert not RAW.search(result.stderr), result.stderr


def test_a_directory_in_place_of_the_snapshot_is_said_in_words(tmp_path):
    app = copy_app(tmp_path, "blinker")
    first = softplc_here("run", "app", "--scans", "5", "--fresh", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    snap = app / ".softplc" / "datatable.snap"
    make(snap, "dir")
    result = softplc_here("run", "app", "--scans", "5", cwd=tmp_path)
    lines = result.stderr.splitlines()
    assert result.returncode == 1, result.stderr
    assert "warning: cannot read app/.softplc/datatable.snap: it is a directory" in lines[0], lines
    assert lines[-1] == ("error: cannot save the retentive snapshot app/.softplc/datatable.snap at the end of the "
                         "run: it is a directory"), lines
    assert not RAW.search(result.stderr), result.stderr


def test_a_record_trace_that_is_a_directory_is_said_in_words(tmp_path):
    copy_app(tmp_path, "loopback")
    (tmp_path / "out.trace").mkdir()
    result = softplc_here("run", "app", "--fresh", "--state", "state", "--scans", "5", "--record", "out.trace",
                          cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.strip() == "error: --record: cannot write out.trace: it is a directory", result.stderr


def test_every_os_error_is_said_in_words_never_in_the_c_library_s_nor_as_a_type_name(tmp_path):
    for number, words in [(errno.ENOENT, "no such file or directory"), (errno.EISDIR, "it is a directory"),
                          (errno.ELOOP, "too many symbolic links (a link loop)"),
                          (errno.ENOSPC, "no space left on the device (disk full)"),
                          (errno.EFBIG, "the file would be larger than the system allows (file too large)"),
                          (errno.EROFS, "the file system is read-only")]:
        assert os_error_words(OSError(number, os.strerror(number))) == words
    # An errno without words of its own: generic, with its number, not the C library's text.
    assert os_error_words(OSError(errno.ECHILD, os.strerror(errno.ECHILD))) == \
        f"the operating system refused it (error {errno.ECHILD})"
    assert os_error_words(ValueError("bad")) == "an unexpected error"  # not "ValueError: bad"
    # The file an error concerns is added when it is not the one the message names, or a rename onto it.
    snap, tmp = tmp_path / "datatable.snap", tmp_path / "datatable.snap.tmp"
    assert describe_os_error(OSError(errno.ENOTDIR, "Not a directory", str(tmp)), snap) == \
        f"a part of the path is not a directory ({tmp})"
    assert describe_os_error(OSError(errno.EISDIR, "Is a directory", str(tmp), None, str(snap)), snap) == \
        "it is a directory"


# -- fmt names a file the way every message does -----------------------------------------------------------

def test_fmt_names_a_non_utf8_file_name_with_escapes(tmp_path):
    app = tmp_path / "app"
    app.mkdir()
    name = os.fsdecode(b"\xff.lad")
    (app / name).write_text("XIC   B3/0    OTE O:0/0\n")
    checked = softplc_here("fmt", "--check", "app", cwd=tmp_path)
    assert checked.returncode == 1 and checked.stderr == "would reformat app/\\xff.lad\n", checked.stderr
    written = softplc_here("fmt", "--write", "app", cwd=tmp_path)
    assert written.returncode == 0 and written.stderr == "reformatted app/\\xff.lad\n", written.stderr
    assert (app / name).read_text() == "XIC B3/0 OTE O:0/0\n"


def test_the_snapshot_and_record_messages_name_a_non_utf8_path_with_escapes(tmp_path):
    # Processes: the names reach the command as bytes that are not UTF-8, as a shell passes them.
    app = tmp_path / os.fsdecode(b"\xff")
    shutil.copytree(ROOT / "programs" / "blinker", app, ignore=shutil.ignore_patterns(".softplc"))
    (app / ".softplc" / "datatable.snap").mkdir(parents=True)
    result = softplc("run", os.fsdecode(b"\xff"), "--scans", "5", "--fresh", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.splitlines()[-1] == ("error: cannot save the retentive snapshot \\xff/.softplc/datatable.snap "
                                              "at the end of the run: it is a directory"), result.stderr
    copy_app(tmp_path, "loopback")
    (tmp_path / os.fsdecode(b"\xfe.trace")).mkdir()
    result = softplc("run", "app", "--fresh", "--state", "state", "--scans", "5",
                     "--record", os.fsdecode(b"\xfe.trace"), cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.strip() == "error: --record: cannot write \\xfe.trace: it is a directory", result.stderr
