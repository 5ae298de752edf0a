"""Files that are not regular files or not of a sane size: every reader of
a user's file or of the app's state refuses a FIFO, a device, a socket or a
file over its kind's limit promptly and says where (textfile.read_bytes;
docs/cli.md, "Input file limits"); a damaged or unreadable retentive
snapshot, a dangling or looping link among them, is said and the previous
one used; a failed save leaves no temp file."""

from __future__ import annotations

import os
import resource
import socket
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from softplc_lite import textfile
from softplc_lite.app import AppError, load_app
from softplc_lite.datatable import DataTable, DataTableError, jsonio, snapshot
from softplc_lite.datatable.errors import SnapshotError
from softplc_lite.ports.trace import TraceError, read_trace
from softplc_lite.runner import RunOptions, Runner
from softplc_lite.textfile import FileRefused, Limit, read_bytes, read_text, size_text
from softplc_lite.watch.watchlist import read_watch_file

from helpers.cli import softplc
from helpers.shipped_apps import copy_app

GiB = 1 << 30
PROMPT_S = 30  # a refusal comes at once; a command that waits on a FIFO never ends, and is stopped after this


def sparse(path: Path, size: int) -> Path:
    """A file of ``size`` bytes that takes no room on disk (a hole)."""
    with open(path, "wb") as f:
        f.truncate(size)
    return path


def fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def zero_link(path: Path) -> Path:
    path.symlink_to("/dev/zero")
    return path


@contextmanager
def unblocked(path: Path, after: float = 2.0):
    """If the code under test blocks opening the FIFO ``path`` (no writer), a
    writer comes and goes after ``after`` seconds, so the test fails instead of
    hanging."""
    stop = threading.Event()

    def release() -> None:
        while not stop.wait(after):
            try:
                os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
            except OSError:  # nobody is waiting on it
                pass

    thread = threading.Thread(target=release, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (3 * GiB // 2, resource.RLIM_INFINITY))


def softplc_capped(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """The real CLI in a process of its own, never in-process: limited to
    1.5 GiB of address space (a reader that reads /dev/zero or 20 GiB whole
    fails at once instead of taking the machine's memory) and to PROMPT_S
    seconds (one that waits on a FIFO is stopped)."""
    return softplc(*args, cwd=cwd, timeout=PROMPT_S, preexec_fn=limit_memory)


# -- the reader itself --------------------------------------------------------------------------------------


def test_a_regular_file_within_its_limit_is_read_whole(tmp_path):
    exact = tmp_path / "exact"
    exact.write_bytes(b"x" * 100)
    assert read_bytes(exact, Limit("a test file", 100)) == b"x" * 100
    assert read_text(exact, limit=Limit("a test file", 100)) == "x" * 100
    with pytest.raises(FileRefused) as info:
        read_bytes(exact, Limit("a test file", 99))
    assert str(info.value) == f"cannot read {exact}: 100 bytes, over the 99 bytes limit for a test file"
    assert info.value.too_large


def test_a_fifo_is_refused_at_once_without_a_writer_and_with_one(tmp_path):
    path = fifo(tmp_path / "prog.lad")
    started = time.monotonic()
    with unblocked(path), pytest.raises(FileRefused) as info:
        read_bytes(path, textfile.PROGRAM)
    assert time.monotonic() - started < 1
    assert str(info.value) == f"cannot read {path}: not a regular file (a FIFO)"
    assert not info.value.too_large and isinstance(info.value, OSError)
    # A writer that keeps it open and never writes: still refused, never waited on.
    writer = os.open(path, os.O_RDWR)
    try:
        with pytest.raises(FileRefused, match="not a regular file"):
            read_bytes(path, textfile.PROGRAM)
    finally:
        os.close(writer)


def test_devices_sockets_directories_and_links_are_refused_in_words(tmp_path):
    with pytest.raises(FileRefused, match=r"zero: not a regular file \(a character device\)$"):
        read_bytes(zero_link(tmp_path / "zero"), textfile.SNAPSHOT)
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.bind(str(tmp_path / "sock"))
        with pytest.raises(FileRefused, match=r"sock: not a regular file \(a socket\)$"):
            read_bytes(tmp_path / "sock")
    finally:
        sock.close()
    (tmp_path / "dir").mkdir()
    with pytest.raises(OSError, match=r"^cannot read .*dir: it is a directory$"):
        read_bytes(tmp_path / "dir")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    with pytest.raises(OSError, match=r"^cannot read .*dangling: a symbolic link to .*nowhere, which does not exist$"):
        read_bytes(tmp_path / "dangling")
    (tmp_path / "loop1").symlink_to(tmp_path / "loop2")
    (tmp_path / "loop2").symlink_to(tmp_path / "loop1")
    with pytest.raises(OSError, match=r"^cannot read .*loop1: too many symbolic links \(a link loop\)$"):
        read_bytes(tmp_path / "loop1")


def test_a_huge_sparse_file_is_refused_by_its_size_before_any_of_it_is_read(tmp_path):
    big = sparse(tmp_path / "big.lad", 20 * GiB)
    started = time.monotonic()
    with pytest.raises(FileRefused) as info:
        read_bytes(big, textfile.PROGRAM)
    assert time.monotonic() - started < 1
    assert str(info.value) == f"cannot read {big}: 20 GiB, over the 16 MiB limit for a program file"


def test_a_file_that_says_it_is_empty_but_is_not_is_read_only_to_its_limit():
    """/proc files say size 0 and have content: the reader stops at limit + 1
    bytes (as for a file that grows while it is read) and refuses it."""
    status = Path("/proc/self/status")
    assert status.stat().st_size == 0 and len(read_bytes(status)) > 200
    with pytest.raises(FileRefused) as info:
        read_bytes(status, Limit("a test file", 200))
    assert str(info.value) == ("cannot read /proc/self/status: more than 200 bytes (it grew while being read), "
                               "over the limit for a test file")


def test_sizes_are_said_the_way_a_person_reads_them():
    assert [size_text(n) for n in (0, 1, 1023, 1024, 1536, 16 << 20, 20 * GiB, (3 << 30) // 2)] == [
        "0 bytes", "1 byte", "1023 bytes", "1 KiB", "1.5 KiB", "16 MiB", "20 GiB", "1.5 GiB"]


# -- every reader, in process: a file over its kind's limit (sparse) --------------------------------------------


def over(limit: Limit, path: Path) -> Path:
    return sparse(path, limit.size + 1)


def test_every_kind_of_file_has_its_limit_and_says_it(tmp_path):
    def refusal(limit: Limit) -> str:
        return f"{limit.size + 1:,} bytes, over the {size_text(limit.size)} limit for {limit.what}"

    # A program file, given alone or in an app directory: located at the file.
    lad = over(textfile.PROGRAM, tmp_path / "big.lad")
    with pytest.raises(AppError) as info:
        load_app(lad)
    assert f"big.lad:1:1: cannot read the file: {refusal(textfile.PROGRAM)}" in str(info.value)
    # softplc.toml, MODULES.LST, a module's config file, datatable.json.
    for name, limit in (("softplc.toml", textfile.CONFIG), ("MODULES.LST", textfile.CONFIG),
                        ("COMGENIUS.LST", textfile.CONFIG), ("datatable.json", textfile.DATA_JSON)):
        app = copy_app("loopback", tmp_path / name)
        (app / name).unlink(missing_ok=True)
        over(limit, app / name)
        with pytest.raises(AppError) as info:
            load_app(app, tmp_path / name / "state")
        assert f"cannot read {app / name}: {refusal(limit)}" in str(info.value), name
    # --load and `softplc datatable FILE.json`; a snapshot; a --replay trace; a --watch-file.
    with pytest.raises(DataTableError, match=f"cannot read .*: {refusal(textfile.DATA_JSON)}$"):
        jsonio.load_file(DataTable(), str(over(textfile.DATA_JSON, tmp_path / "big.json")))
    with pytest.raises(SnapshotError, match=f"cannot read .*: {refusal(textfile.SNAPSHOT)}$"):
        snapshot.load(over(textfile.SNAPSHOT, tmp_path / "big.snap"))
    with pytest.raises(TraceError, match=f"big.trace: cannot read trace file: {refusal(textfile.TRACE)}$"):
        read_trace(over(textfile.TRACE, tmp_path / "big.trace"))
    with pytest.raises(Exception, match="larger than 1024 KiB: a watch file lists at most"):
        read_watch_file(over(textfile.WATCH_FILE, tmp_path / "big.watch"))


def test_a_special_file_in_an_app_directory_is_reported_not_left_out(tmp_path):
    """A FIFO named like a program file, or a dangling link, is a program file
    that cannot be read: the app does not run without it."""
    app = copy_app("blinker", tmp_path)
    fifo(app / "extra.lad")
    (app / "gone.lad").symlink_to(tmp_path / "nowhere.lad")
    with unblocked(app / "extra.lad"), pytest.raises(AppError) as info:
        load_app(app)
    text = str(info.value)
    assert "extra.lad:1:1: cannot read the file: not a regular file (a FIFO)" in text
    assert (f"gone.lad:1:1: cannot read the file: a symbolic link to {tmp_path / 'nowhere.lad'}, which does not "
            "exist") in text


def test_a_special_modules_lst_is_refused_not_ignored(tmp_path):
    app = copy_app("loopback", tmp_path)
    (app / "MODULES.LST").unlink()
    zero_link(app / "MODULES.LST")
    with pytest.raises(AppError, match=r"MODULES.LST: not a regular file \(a character device\)"):
        load_app(app)


# -- the real CLI: a FIFO, /dev/zero or 20 GiB as each input, promptly refused ----------------------------------

# (what, how to make the bad file in the app copy, the command's arguments) -> the refusal's text
CLI_CASES = [
    ("program FIFO", "blinker", "main.lad", fifo, ("run", "blinker", "--fresh", "--scans", "5"),
     "blinker/main.lad:1:1: cannot read the file: not a regular file (a FIFO)"),
    ("program /dev/zero", "blinker", "zero.lad", zero_link, ("run", "blinker/zero.lad", "--scans", "5"),
     "blinker/zero.lad:1:1: cannot read the file: not a regular file (a character device)"),
    ("softplc.toml FIFO", "motor", "softplc.toml", fifo, ("run", "motor", "--fresh", "--scans", "5"),
     "cannot read motor/softplc.toml: not a regular file (a FIFO)"),
    ("MODULES.LST FIFO", "loopback", "MODULES.LST", fifo, ("run", "loopback", "--fresh", "--scans", "5"),
     "cannot read loopback/MODULES.LST: not a regular file (a FIFO)"),
    ("module config FIFO", "loopback", "COMGENIUS.LST", fifo, ("check", "loopback"),
     "cannot read loopback/COMGENIUS.LST: not a regular file (a FIFO)"),
    ("datatable.json FIFO", "blinker", "datatable.json", fifo, ("run", "blinker", "--fresh", "--scans", "5"),
     "cannot read blinker/datatable.json: not a regular file (a FIFO)"),
    ("--load FIFO", "blinker", "in.json", fifo,
     ("run", "blinker", "--fresh", "--scans", "5", "--load", "blinker/in.json"),
     "cannot read blinker/in.json: not a regular file (a FIFO)"),
    ("--replay FIFO", "modbus_master", "in.trace", fifo,
     ("run", "modbus_master", "--fresh", "--replay", "modbus_master/in.trace"),
     "modbus_master/in.trace: cannot read trace file: not a regular file (a FIFO)"),
    ("datatable FILE.json FIFO", "blinker", "in.json", fifo, ("datatable", "blinker/in.json", "--print", "N7:0"),
     "cannot read blinker/in.json: not a regular file (a FIFO)"),
    ("datatable SNAPSHOT /dev/zero", "blinker", "in.snap", zero_link,
     ("datatable", "blinker/in.snap", "--print", "N7:0"),
     "cannot read blinker/in.snap: not a regular file (a character device)"),
    ("datatable SNAPSHOT 20 GiB", "blinker", "in.snap", lambda p: sparse(p, 20 * GiB),
     ("datatable", "blinker/in.snap", "--print", "N7:0"),
     "cannot read blinker/in.snap: 20 GiB, over the 256 MiB limit for a snapshot"),
    ("--watch-file FIFO", "blinker", "list.watch", fifo,
     ("watch", "blinker", "--fresh", "--watch-file", "blinker/list.watch", "--snapshot", "view.txt"),
     "cannot read blinker/list.watch: not a regular file (a FIFO)"),
]


@pytest.mark.parametrize("what, app_name, name, make, args, said", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_the_cli_refuses_a_special_or_huge_input_promptly_and_says_where(tmp_path, what, app_name, name, make,
                                                                         args, said):
    app = copy_app(app_name, tmp_path)
    (app / name).unlink(missing_ok=True)
    make(app / name)
    p = softplc_capped(*args, cwd=tmp_path)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert said in p.stderr, p.stderr
    assert "Traceback" not in p.stderr and "internal error" not in p.stderr


# -- the app's state: the retentive snapshot and the code cache ---------------------------------------------------


def run_in_process(app: Path, scans: int = 100, fresh: bool = False) -> tuple[dict, list[str], object]:
    """``softplc run APP --scans N`` in this process: the values the blinker
    shows, what was logged (the app's warnings first) and the loaded app."""
    loaded = load_app(app)
    logged = [f"warning: {w}" for w in loaded.warnings]
    runner = Runner(loaded, RunOptions(fresh=fresh), log=logged.append)
    runner.run(scans)
    runner.engine.close()
    assert runner.finish() == []
    return {a: runner.table.read(a) for a in ("C5:0.ACC", "T4:0.ACC")}, logged, loaded


def run_blinker(tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return softplc_capped("run", "blinker", "--scans", "100", "--print", "C5:0.ACC", "--print", "T4:0.ACC", *extra,
                          cwd=tmp_path)


ONE_BLINK = {"C5:0.ACC": 1, "T4:0.ACC": 50}  # the blinker after 100 scans from its start
TWO_BLINKS = {"C5:0.ACC": 2, "T4:0.ACC": 50}  # after 100 more


def damage_snapshot(tmp_path: Path, make) -> tuple[Path, Path]:
    """The blinker run once (its snapshot and, durable at the end, .prev),
    then its snapshot replaced by ``make(path)``."""
    app = copy_app("blinker", tmp_path)
    assert run_in_process(app, fresh=True)[0] == ONE_BLINK
    snap = app / ".softplc" / "datatable.snap"
    snap.unlink()
    make(snap)
    return app, snap


SNAPSHOT_DAMAGE = {
    "FIFO": (fifo, "cannot read {snap}: not a regular file (a FIFO)"),
    "over its limit": (lambda p: over(textfile.SNAPSHOT, p),
                       "cannot read {snap}: 268,435,457 bytes, over the 256 MiB limit for a snapshot"),
    "dangling link": (lambda p: p.symlink_to(p.parent / "nowhere.snap"),
                      "{snap}: a symbolic link to {snap.parent}/nowhere.snap, which does not exist"),
    "looping link": (lambda p: p.symlink_to(p.name), "cannot read {snap}: too many symbolic links (a link loop)"),
}


@pytest.mark.parametrize("damage", list(SNAPSHOT_DAMAGE))
def test_a_snapshot_that_is_not_a_usable_file_is_said_and_the_previous_one_used(tmp_path, damage):
    make, said = SNAPSHOT_DAMAGE[damage]
    app, snap = damage_snapshot(tmp_path, make)
    with unblocked(snap):
        values, logged, _ = run_in_process(app)
    assert values == TWO_BLINKS  # restored from .prev, the first run's end
    assert logged == [f"warning: {said.format(snap=snap)}"], logged
    assert snap.is_file() and not snap.is_symlink()  # the saves replaced it with a real snapshot
    assert snapshot.load(snap).read("C5:0.ACC") == 2


def test_a_snapshot_linked_to_dev_zero_is_said_and_the_previous_one_used_by_the_cli(tmp_path):
    app, snap = damage_snapshot(tmp_path, zero_link)
    p = run_blinker(tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout == "C5:0.ACC = 2\nT4:0.ACC = 50\n"
    assert p.stderr == ("warning: cannot read blinker/.softplc/datatable.snap: not a regular file "
                        "(a character device)\n")
    assert snap.is_file() and not snap.is_symlink()


def test_a_snapshot_that_is_a_fifo_without_a_previous_one_stops_the_start_and_suggests_fresh(tmp_path):
    app = copy_app("blinker", tmp_path)
    (app / ".softplc").mkdir()
    fifo(app / ".softplc" / "datatable.snap")
    p = run_blinker(tmp_path)
    assert p.returncode == 1
    assert "cannot read blinker/.softplc/datatable.snap: not a regular file (a FIFO)" in p.stderr
    assert "--fresh" in p.stderr and "Traceback" not in p.stderr


@pytest.mark.parametrize("damage", ["FIFO", "over its limit"])
def test_a_code_cache_that_is_not_a_usable_file_is_said_and_rebuilt(tmp_path, damage):
    app = copy_app("blinker", tmp_path)
    assert run_in_process(app, fresh=True)[0] == ONE_BLINK
    cache = app / ".softplc" / "codecache.bin"
    kept = cache.read_bytes()
    cache.unlink()
    why = {"FIFO": "not a regular file (a FIFO)", "over its limit": "268,435,457 bytes, over the 256 MiB limit for a code cache"}
    (fifo if damage == "FIFO" else lambda p: over(textfile.CODE_CACHE, p))(cache)
    with unblocked(cache):
        values, logged, loaded = run_in_process(app, fresh=True)
    assert values == ONE_BLINK and loaded.code is None  # compiled from the text
    assert logged == [f"warning: {cache}: {why[damage]}; ignored, the program is compiled from its text and the "
                      "cache rewritten"]
    assert cache.is_file() and cache.read_bytes() == kept


def test_a_code_cache_linked_to_dev_zero_is_said_and_rebuilt_by_the_cli(tmp_path, monkeypatch):
    app = copy_app("blinker", tmp_path)
    assert run_in_process(app, fresh=True)[0] == ONE_BLINK
    cache = app / ".softplc" / "codecache.bin"
    kept = cache.read_bytes()  # made in this process: positions name the files by their absolute paths
    cache.unlink()
    zero_link(cache)
    p = run_blinker(tmp_path, "--fresh")
    assert p.returncode == 0 and p.stdout == "C5:0.ACC = 1\nT4:0.ACC = 50\n", p.stderr
    assert p.stderr == ("warning: blinker/.softplc/codecache.bin: not a regular file (a character device); ignored, "
                        "the program is compiled from its text and the cache rewritten\n")
    assert cache.is_file() and not cache.is_symlink() and cache.read_bytes() != kept  # cwd-relative positions
    monkeypatch.chdir(tmp_path)  # as the CLI ran: the same key, and the rewritten cache is used
    assert load_app("blinker").code is not None


# -- writing: nothing partial left behind, nothing written through ------------------------------------------------


def test_a_failed_write_removes_its_temp_file(tmp_path):
    """A real write limit (RLIMIT_FSIZE, in a child process: Python ignores
    SIGXFSZ, so the write fails with EFBIG as one on a full disk fails with
    ENOSPC): the snapshot and the code cache are left as they were, with no
    temp file beside them."""
    child = r"""
import resource, sys
from pathlib import Path
from softplc_lite.datatable import DataTable, snapshot
state = Path(sys.argv[1])
small = DataTable()
snapshot.save(small, state / "datatable.snap")
big = DataTable()
big.create_file("N", 10, 5000)
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))
for durable in (False, True):
    try:
        snapshot.write(snapshot.encode(big), state / "datatable.snap", durable)
    except OSError as e:
        print(e.errno)
try:
    snapshot.save(big, state / "datatable.snap")
except OSError as e:
    print(e.errno)
"""
    state = tmp_path / "state"
    state.mkdir()
    p = subprocess.run([sys.executable, "-c", child, str(state)], capture_output=True, text=True, timeout=30,
                       cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["27", "27", "27"]  # EFBIG, each time
    assert sorted(f.name for f in state.iterdir()) == ["datatable.snap"]
    assert 10 not in [f.number for f in snapshot.load(state / "datatable.snap").files()]  # the small one


def test_a_special_file_in_place_of_a_temp_file_is_replaced_not_written_through(tmp_path):
    """A FIFO nobody reads would hang the save; a link would write through to
    its target: both are removed and a new temp file made."""
    state = tmp_path / "state"
    state.mkdir()
    target = tmp_path / "someone-elses-file"
    target.write_text("keep me")
    fifo(state / "datatable.snap.tmp")
    with unblocked(state / "datatable.snap.tmp"):
        snapshot.write(snapshot.encode(DataTable()), state / "datatable.snap", False)
    (state / "datatable.snap.tmp").symlink_to(target)
    snapshot.write(snapshot.encode(DataTable()), state / "datatable.snap", True)
    assert target.read_text() == "keep me"
    assert sorted(f.name for f in state.iterdir()) == ["datatable.snap", "datatable.snap.prev"]
    snapshot.load(state / "datatable.snap")
