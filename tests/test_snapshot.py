"""Retentive snapshots: exact round trip, corruption detected, atomic saves
that survive a real SIGKILL."""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from hypothesis import given, settings

from conftest import random_tables
from softplc_lite.datatable import DataTable, DataTableError, SnapshotError
from softplc_lite.datatable import snapshot


def sample_table() -> DataTable:
    t = DataTable()
    t.reference("ST9:2")
    t.reference("N7:9")
    t.write("N7:9", -7)
    t.write("F8:0", 3.14)
    t.write("ST9:1", "héllo")
    t.write("T4:0", {"PRE": 10, "DN": 1})
    return t


@settings(max_examples=40, deadline=None)
@given(random_tables())
def test_encode_decode_exact(table: DataTable):
    assert snapshot.decode(snapshot.encode(table)) == table


def test_save_and_load(tmp_path):
    t = sample_table()
    path = tmp_path / "state" / "datatable.snap"
    snapshot.save(t, path)
    assert snapshot.load(path) == t
    assert not (tmp_path / "state" / "datatable.snap.tmp").exists()


def test_save_keeps_the_previous_good_snapshot(tmp_path):
    path = tmp_path / "datatable.snap"
    old = sample_table()
    snapshot.save(old, path)
    new = sample_table()
    new.write("N7:0", 99)
    snapshot.save(new, path)
    assert snapshot.load(path) == new
    assert snapshot.load(tmp_path / "datatable.snap.prev") == old


def test_truncated_snapshot_is_reported(tmp_path):
    path = tmp_path / "datatable.snap"
    snapshot.save(sample_table(), path)
    raw = path.read_bytes()
    for cut in (0, 10, len(raw) // 2, len(raw) - 1):
        path.write_bytes(raw[:cut])
        with pytest.raises(SnapshotError, match="truncated"):
            snapshot.load(path)


def test_corrupted_snapshot_is_reported(tmp_path):
    path = tmp_path / "datatable.snap"
    snapshot.save(sample_table(), path)
    raw = bytearray(path.read_bytes())
    raw[len(raw) // 2] ^= 0x40
    path.write_bytes(bytes(raw))
    with pytest.raises(SnapshotError, match="checksum mismatch .*corrupted"):
        snapshot.load(path)
    path.write_bytes(b"NOTASNAP" + bytes(raw[8:]))
    with pytest.raises(SnapshotError, match="wrong magic"):
        snapshot.load(path)
    with pytest.raises(SnapshotError, match="no snapshot"):
        snapshot.load(tmp_path / "missing.snap")


def test_restore_falls_back_to_previous_and_says_so(tmp_path):
    path = tmp_path / "datatable.snap"
    old = sample_table()
    snapshot.save(old, path)
    snapshot.save(sample_table(), path)
    path.write_bytes(path.read_bytes()[:-3])
    restored = snapshot.restore(path)
    assert restored.table == old
    assert restored.source == tmp_path / "datatable.snap.prev"
    assert len(restored.problems) == 1 and "truncated" in restored.problems[0]


def test_restore_refuses_when_nothing_is_usable(tmp_path):
    path = tmp_path / "datatable.snap"
    path.write_bytes(b"garbage")
    with pytest.raises(SnapshotError, match="no usable snapshot"):
        snapshot.restore(path)


def test_restore_with_no_snapshot_at_all(tmp_path):
    restored = snapshot.restore(tmp_path / "datatable.snap")
    assert restored.table is None and restored.problems == []


SAVER = textwrap.dedent("""
    import sys
    from softplc_lite.datatable import DataTable, snapshot
    path = sys.argv[1]
    t = DataTable()
    t.reference("N10:9999")
    t.reference("ST11:999")   # ~166 kB of strings: a save takes a while
    data = t.file("N10").data
    generation = 0
    while True:
        generation += 1
        t.write("N7:0", generation)
        for i in range(0, len(data), 97):
            data[i] = generation
        t.write("ST11:999", "generation %d" % generation)
        snapshot.save(t, path)
        print(generation, flush=True)
""")


def test_kill_during_save_leaves_old_or_new(tmp_path):
    """SIGKILL a process that saves in a loop, at random moments, and check
    the snapshot is always complete and consistent: the generation the
    process last reported, or the one it was writing."""
    path = tmp_path / "datatable.snap"
    rng = random.Random(1234)
    killed_mid_save = 0
    for attempt in range(12):
        proc = subprocess.Popen(
            [sys.executable, "-c", SAVER, str(path)],
            stdout=subprocess.PIPE, text=True,
        )
        try:
            first = proc.stdout.readline()
            assert first.strip().isdigit(), first
            time.sleep(rng.uniform(0.0, 0.05))
            proc.send_signal(signal.SIGKILL)
            rest = proc.stdout.read()
        finally:
            proc.kill()
            proc.wait(timeout=10)
            proc.stdout.close()
        reported = [int(x) for x in (first + rest).split()]
        last_reported = reported[-1]
        if (tmp_path / "datatable.snap.tmp").exists():
            killed_mid_save += 1
        restored = snapshot.restore(path)
        assert restored.problems == [] and restored.source == path
        t = restored.table
        generation = t.read("N7:0")
        # The last generation reported, or the next one if the kill came
        # after its rename but before its print.
        assert generation in (last_reported, last_reported + 1)
        data = t.file("N10").data
        assert all(data[i] == generation for i in range(0, len(data), 97))
        assert t.read("ST11:999") == f"generation {generation}"
        # Each attempt starts from a clean slate (every process starts at
        # generation 1), so "last reported" above holds.
        for leftover in tmp_path.iterdir():
            leftover.unlink()
    assert killed_mid_save >= 1, "no kill landed during a save; the test did not test anything"


def _forged(entries: list[tuple[bytes, int, int, bytes]]) -> bytes:
    """A snapshot with a valid checksum around hand-made file entries."""
    import struct
    import zlib

    body = b"".join(struct.pack("<2sHI", l, n, e) + d for l, n, e, d in entries)
    header = struct.pack("<8sHHIQ", b"SPLCSNAP", 1, 0, len(entries), len(body))
    crc = zlib.crc32(body, zlib.crc32(header))
    return header + body + struct.pack("<I8s", crc, b"SPLCEND!")


def test_forged_entries_are_refused_even_with_a_good_checksum():
    with pytest.raises(SnapshotError, match="claims 20000 elements"):
        snapshot.decode(_forged([(b"N ", 7, 20000, bytes(40000))]))
    with pytest.raises(SnapshotError, match="file number 7 appears twice"):
        snapshot.decode(_forged([(b"N ", 7, 1, bytes(2)), (b"N ", 7, 1, bytes(2))]))
    with pytest.raises(SnapshotError, match="unknown file type"):
        snapshot.decode(_forged([(b"X ", 7, 1, bytes(2))]))
    with pytest.raises(SnapshotError, match="runs past the end"):
        snapshot.decode(_forged([(b"N ", 7, 5, bytes(2))]))


def test_load_into_keeps_the_arrays_compiled_code_holds(tmp_path):
    path = tmp_path / "datatable.snap"
    saved = sample_table()
    snapshot.save(saved, path)
    live = DataTable()
    live.reference("N7:20")  # the program references more than was saved
    live.write("N7:20", 5)
    live.reference("N30:0")  # a file the snapshot does not have
    live.write("N30:0", 6)
    data, i = live.word_ref("N7:9")
    snapshot.load_into(live, path)
    assert live.file("N7").data is data and data[i] == -7
    assert live.file("N7").size == 21 and live.read("N7:20") == 0
    assert live.read("N30:0") == 0
    assert live.read("ST9:1") == "héllo" and live.read("T4:0/DN") == 1


def test_load_into_refuses_a_type_clash_and_changes_nothing(tmp_path):
    path = tmp_path / "datatable.snap"
    snapshot.save(sample_table(), path)  # has ST9
    live = DataTable()
    live.reference("N9:0")
    live.write("N9:0", 3)
    with pytest.raises(DataTableError, match="cannot load ST9: file number 9 is N9 here"):
        snapshot.load_into(live, path)
    assert live.read("N9:0") == 3
