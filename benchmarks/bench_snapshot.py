"""Retentive snapshot save + load of a large data table.

Builds the standard table (100 N x 1000 words, 20 ST x 1000 82-character
strings, 10 F x 1000 floats), then times ``snapshot.save(table, path)`` and
``snapshot.load(path)`` in a temporary directory. ``save`` is the real atomic
save: write NAME.tmp, fsync, hard-link the old snapshot to NAME.prev, rename,
fsync the directory. One untimed warm-up save makes every timed save the
steady-state case (a previous snapshot exists). The in-memory
``snapshot.encode`` / ``decode`` are timed too, to separate CPU from I/O.

Same-run baselines, in the same directory:

* pickle: ``pickle.dumps`` of the same values as plain lists + write + fsync,
  then read + ``pickle.loads``;
* raw I/O: write the snapshot's number of bytes + fsync, then read them back.

Target: save + load <= 500 ms (median). A miss is reported, never turned into
a non-zero exit status.

    python benchmarks/bench_snapshot.py
"""

from __future__ import annotations

import os
import pickle
import tempfile
import time
from pathlib import Path

import _common as C

from softplc_lite.datatable import snapshot

NAME = "bench_snapshot"
REPEATS = 5
TARGET_MS = 500.0


def _write_fsync(path: Path, data: bytes) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
        os.fsync(fd)
    finally:
        os.close(fd)


def _timed(fn) -> tuple[int, object]:
    t0 = time.perf_counter_ns()
    result = fn()
    return time.perf_counter_ns() - t0, result


def _fs_type(path: str) -> str:
    best = ("", "?")
    try:
        with open("/proc/mounts", encoding="utf-8") as fh:
            for line in fh:
                parts = line.split()
                mount, fstype = parts[1], parts[2]
                if path.startswith(mount) and len(mount) > len(best[0]):
                    best = (mount, fstype)
    except OSError:
        pass
    return best[1]


def main() -> None:
    t_start = time.perf_counter()
    print(f"{NAME}: {C.describe_data()}")
    t0 = time.perf_counter_ns()
    table = C.build_table()
    plain = C.build_plain()
    print(f"built table and plain-list twin in {C.ms(time.perf_counter_ns() - t0):.0f} ms")

    samples: dict[str, list[int]] = {
        k: [] for k in ("save", "load", "total", "encode", "decode",
                        "pickle_save", "pickle_load", "pickle_total",
                        "raw_write", "raw_read", "raw_total")
    }
    with tempfile.TemporaryDirectory(prefix="softplc-bench-") as tmp:
        tmpdir = Path(tmp)
        snap = tmpdir / "retentive.snap"
        pick = tmpdir / "plain.pickle"
        raw_path = tmpdir / "raw.bin"
        fs_type = _fs_type(str(tmpdir.resolve()))

        snapshot.save(table, snap)  # warm-up: later saves keep a .prev
        size = snap.stat().st_size
        loaded = snapshot.load(snap)
        if loaded != table:
            raise SystemExit("snapshot round trip changed the table")
        payload = bytes(size)
        pickled_size = len(pickle.dumps(plain, protocol=pickle.HIGHEST_PROTOCOL))

        for _ in range(REPEATS):
            # Interleave the cases so machine noise hits them alike.
            ns_save, _ = _timed(lambda: snapshot.save(table, snap))
            ns_load, _ = _timed(lambda: snapshot.load(snap))
            samples["save"].append(ns_save)
            samples["load"].append(ns_load)
            samples["total"].append(ns_save + ns_load)

            ns_enc, blob = _timed(lambda: snapshot.encode(table))
            ns_dec, _ = _timed(lambda: snapshot.decode(blob))
            samples["encode"].append(ns_enc)
            samples["decode"].append(ns_dec)

            ns_ps, _ = _timed(lambda: _write_fsync(
                pick, pickle.dumps(plain, protocol=pickle.HIGHEST_PROTOCOL)))
            ns_pl, _ = _timed(lambda: pickle.loads(pick.read_bytes()))
            samples["pickle_save"].append(ns_ps)
            samples["pickle_load"].append(ns_pl)
            samples["pickle_total"].append(ns_ps + ns_pl)

            ns_rw, _ = _timed(lambda: _write_fsync(raw_path, payload))
            ns_rr, _ = _timed(raw_path.read_bytes)
            samples["raw_write"].append(ns_rw)
            samples["raw_read"].append(ns_rr)
            samples["raw_total"].append(ns_rw + ns_rr)

    stats = {k: C.summarize_ns(v) for k, v in samples.items()}

    def med(k: str) -> float:
        return C.ms(stats[k]["median_ns"])

    def best(k: str) -> float:
        return C.ms(stats[k]["best_ns"])

    print(f"snapshot size: {size} bytes ({size / 1e6:.2f} MB); pickle of plain lists: "
          f"{pickled_size} bytes; temp dir on {fs_type}")
    print(f"{REPEATS} repeats, interleaved; ms (median / best)")
    for label, key in (
        ("snapshot.save (atomic, 2 fsyncs)", "save"),
        ("snapshot.load", "load"),
        ("snapshot save + load", "total"),
        ("  encode (in memory)", "encode"),
        ("  decode (in memory)", "decode"),
        ("baseline pickle dumps+write+fsync", "pickle_save"),
        ("baseline pickle read+loads", "pickle_load"),
        ("baseline pickle total", "pickle_total"),
        ("baseline raw write+fsync (same bytes)", "raw_write"),
        ("baseline raw read", "raw_read"),
        ("baseline raw total", "raw_total"),
    ):
        print(f"  {label:40} {med(key):8.1f} / {best(key):8.1f}")
    ratio_pickle = med("total") / med("pickle_total")
    ratio_raw = med("total") / med("raw_total")
    print(f"ratio snapshot/pickle (total, median): {ratio_pickle:.2f}x")
    print(f"ratio snapshot/raw I/O (total, median): {ratio_raw:.2f}x")
    verdict = "PASS" if med("total") <= TARGET_MS else "MISS"
    print(f"\n{verdict}: save + load {med('total'):.1f} ms (median); target <= {TARGET_MS:.0f} ms")

    figures = {
        "data": C.describe_data(),
        "repeats": REPEATS,
        "target_ms": TARGET_MS,
        "verdict": verdict,
        "snapshot_bytes": size,
        "pickle_bytes": pickled_size,
        "temp_fs_type": fs_type,
        "ms_median": {k: med(k) for k in samples},
        "ms_best": {k: best(k) for k in samples},
        "ratio_total_snapshot_over_pickle": ratio_pickle,
        "ratio_total_snapshot_over_raw_io": ratio_raw,
        "raw_ns": stats,
        "wall_s": time.perf_counter() - t_start,
    }
    path = C.write_results(NAME, figures)
    print(f"results: {path.relative_to(C.REPO)} ({figures['wall_s']:.1f} s)")


if __name__ == "__main__":
    main()
