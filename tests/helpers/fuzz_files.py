"""Fuzz inputs: files that are not what their name promises.

Two kinds of :mod:`fuzz_inputs` cases live here:

``special_files``
    every file softplc reads (program files, ``softplc.toml``, ``MODULES.LST``,
    the module configs, ``datatable.json``, ``--load``, ``--replay``,
    ``softplc datatable FILE``, ``--watch-file``, and the app's own state:
    ``.softplc/datatable.snap``, its ``.prev`` and ``.softplc/codecache.bin``)
    replaced by a FIFO nobody writes to, a link to ``/dev/zero``, a dangling
    link, a link loop, a directory, a 20 GiB sparse file, or an empty file.
``state_damage``
    the real snapshot and code cache a first run wrote, with bytes flipped,
    the file truncated or padded.

Both are run by the ``files`` driver of ``tests/helpers/fuzz_oracle.py``: the case's
``prepare`` commands first (a run that writes the real state), then the
change to the target, then the case's commands. What the oracle requires is
the documented contract (docs/cli.md "Input file limits", docs/engine.md
"The code cache"): an input that cannot be read is refused promptly, exit 1,
naming the file; a state file that cannot be used is said in a warning and
the run goes on; a run with a damaged code cache computes what the same run
without any cache computes (a PLC never runs logic other than its program);
nothing is written through a link.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

SPECIALS = ["fifo", "devzero", "dangling", "loop", "dir", "sparse", "empty"]
SPARSE_SIZE = 20 * 2 ** 30  # sparse: costs no disk, far over every kind's limit (docs/cli.md)
DANGLING_SUFFIX = ".nowhere"  # a dangling link points at NAME.nowhere, beside it


def make_special(path: Path, spec: str) -> None:
    """Put ``spec`` at ``path`` in place of whatever is there."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.is_symlink() or path.is_file():
        path.unlink()
    elif path.is_dir():
        shutil.rmtree(path)
    if spec == "fifo":
        os.mkfifo(path)
    elif spec == "devzero":
        os.symlink("/dev/zero", path)
    elif spec == "dangling":
        os.symlink(path.name + DANGLING_SUFFIX, path)
    elif spec == "loop":  # NAME -> NAME.loop -> NAME
        other = path.with_name(path.name + ".loop")
        if other.is_symlink() or other.exists():
            other.unlink()
        os.symlink(other.name, path)
        os.symlink(path.name, other)
    elif spec == "dir":
        path.mkdir()
        (path / "x").write_bytes(b"x")
    elif spec == "sparse":
        with open(path, "wb") as f:
            f.truncate(SPARSE_SIZE)
    elif spec == "empty":
        path.write_bytes(b"")
    else:  # pragma: no cover - a generator bug
        raise ValueError(spec)


def damage(data: bytes, change: dict) -> bytes:
    """``data`` changed as ``change`` says: ``flips`` [[fraction, xor]...] (a
    position given as a fraction of the length, so the change means the same
    for a file of any size), ``truncate`` (a fraction), ``pad`` (bytes as
    latin-1 text)."""
    raw = bytearray(data)
    for where, xor in change.get("flips", []):
        if raw:
            i = min(int(where * len(raw)), len(raw) - 1)
            raw[i] ^= xor or 0xFF
    if "truncate" in change:
        del raw[int(change["truncate"] * len(raw)):]
    if "pad" in change:
        raw += change["pad"].encode("latin-1")
    return bytes(raw)


def apply_change(root: Path, target: str, change: dict) -> None:
    path = root / target
    if "special" in change:
        make_special(path, change["special"])
    elif path.is_file() and not path.is_symlink():
        path.write_bytes(damage(path.read_bytes(), change))


# -- the targets -------------------------------------------------------------------------------

RUN3 = ["run", "{d}/app", "--scans", "3", "--fresh", "--state", "{d}/state"]
CHECK = ["check", "{d}/app"]
# A first run in the app's own state directory: the real snapshot, .prev and code cache.
PREPARE = [["run", "{d}/app", "--scans", "20", "--fresh"]]
# The run that meets the state: no --fresh, its table dumped for the comparison.
STATE_RUN = ["run", "{d}/app", "--scans", "5", "--dump", "{d}/dump.json"]
CACHE_RUN = ["run", "{d}/app", "--scans", "30", "--fresh", "--dump", "{d}/dump.json"]

# target name -> (base app, path in the case, role, commands, prepare)
#   role "input": refused at once, exit 1, named; "snap": said, the run goes on from .prev or afresh;
#   "cache": the run computes what it computes without a cache.
TARGETS: dict[str, tuple[str, str, str, list[list[str]], list[list[str]]]] = {
    "main.lad": ("blinker", "app/main.lad", "input", [CHECK, RUN3, ["fmt", "{d}/app/main.lad"]], []),
    "subroutine.lad": ("modbus_slave", "app/sbr063_crc.lad", "input", [CHECK, RUN3], []),
    "softplc.toml": ("modbus_master", "app/softplc.toml", "input", [CHECK, RUN3], []),
    "MODULES.LST": ("strings", "app/MODULES.LST", "input", [CHECK, RUN3], []),
    "COMGENIUS.LST": ("strings", "app/COMGENIUS.LST", "input", [CHECK, RUN3], []),
    "MODBMAST.XML": ("modbus_scada", "app/MODBMAST.XML", "input", [CHECK, RUN3], []),
    "MODBTCPS.XML": ("hmi_server", "app/MODBTCPS.XML", "input", [CHECK, RUN3], []),
    "datatable.json": ("blinker", "app/datatable.json", "input", [CHECK, RUN3], []),
    "--load": ("blinker", "load.json", "input",
               [["run", "{d}/app", "--scans", "3", "--fresh", "--state", "{d}/state", "--load", "{d}/load.json"]], []),
    "--replay": ("modbus_master", "replay.trace", "input",
                 [["run", "{d}/app", "--fresh", "--state", "{d}/state", "--replay", "{d}/replay.trace", "--scans", "50"]], []),
    "datatable FILE.snap": ("blinker", "t.snap", "input", [["datatable", "{d}/t.snap", "--dump"]], []),
    "datatable FILE.json": ("blinker", "t.json", "input", [["datatable", "{d}/t.json", "--dump"]], []),
    "--watch-file": ("blinker", "watch.txt", "input",
                     [["watch", "{d}/app", "--snapshot", "{d}/view.txt", "--scans", "2", "--fresh", "--state",
                       "{d}/state", "--watch-file", "{d}/watch.txt"]], []),
    "datatable.snap": ("blinker", "app/.softplc/datatable.snap", "snap", [STATE_RUN], PREPARE),
    "datatable.snap.prev": ("blinker", "app/.softplc/datatable.snap.prev", "snap", [STATE_RUN], PREPARE),
    "codecache.bin": ("blinker", "app/.softplc/codecache.bin", "cache", [CACHE_RUN], PREPARE),
}
# Apps whose state is worth damaging: timers, counters, strings, subroutines, a module.
STATE_APPS = ["blinker", "motor", "strings", "subroutines", "tank"]
# What an input's place holds when it is not special (so that the run reaches it): the case's own content.
INPUT_CONTENT = {
    "load.json": b'{"N7": [1, 2, 3]}\n',
    "t.json": b'{"N7": [1, 2, 3]}\n',
    "app/datatable.json": b'{"N7": [0, 0]}\n',
    "watch.txt": b"C5:0.ACC\n",
}


# Target and special pairs of a feature (fuzz_inputs.FEATURES) still open: drawn only when the profile
# allows it. None is open: every target is drawn as every special.
OPEN_PAIRS: dict[str, set[tuple[str, str]]] = {}


def case_special_files(draw, rnd, profile):
    while True:
        name, spec = rnd.choice(sorted(TARGETS)), rnd.choice(SPECIALS)
        if all(profile.allows(f) or (name, spec) not in pairs for f, pairs in OPEN_PAIRS.items()):
            return special_case(name, spec, rnd, profile)


def special_case(name: str, spec: str, rnd, profile):
    """The target ``name`` (of TARGETS) replaced by ``spec`` (of SPECIALS)."""
    from helpers.fuzz_inputs import Case, program_files, snapshot_bytes

    base, target, role, commands, prepare = TARGETS[name]
    files = program_files(base)
    if target == "replay.trace":
        files["replay.trace"] = files.pop("app/pymodbus-session.trace")
    elif target == "t.snap":
        files["t.snap"] = snapshot_bytes(rnd, profile)
    elif target in INPUT_CONTENT:
        files[target] = INPUT_CONTENT[target]
    params = {"target": target, "role": role, "change": {"special": spec}, "prepare": prepare}
    if name == "datatable.snap.prev":  # .prev is read only when the snapshot is damaged: damage it too
        params["also"] = {"target": "app/.softplc/datatable.snap", "change": {"truncate": 0.5}}
    if name == "codecache.bin" or role == "snap":
        files = program_files(rnd.choice(STATE_APPS))
    return Case("special_files", files, [list(c) for c in commands], target=target, located="name",
                note=f"{name} as {spec}", driver="files", params=params)


def case_state_damage(draw, rnd, profile):
    from helpers.fuzz_inputs import Case, program_files

    which = rnd.choice(["datatable.snap", "datatable.snap", "codecache.bin", "codecache.bin", "datatable.snap.prev"])
    _base, target, role, commands, prepare = TARGETS[which]
    change: dict = {}
    k = rnd.randrange(6)
    if k <= 2:  # one bit, a byte, a few bytes
        change["flips"] = [[rnd.random(), rnd.choice([1 << rnd.randrange(8), 0xFF, rnd.randrange(1, 256)])]
                           for _ in range(rnd.choice([1, 1, 1, 2, 5]))]
    elif k == 3:
        change["flips"] = [[rnd.choice([0.0, 0.01, 0.02, 0.03, 0.05, 0.99, 0.999]), 1 << rnd.randrange(8)]]  # the header, the trailer
    elif k == 4:
        change["truncate"] = rnd.choice([0.0, 0.1, 0.5, 0.9, 0.99, rnd.random()])
    else:
        change["pad"] = "".join(chr(rnd.randrange(256)) for _ in range(rnd.choice([1, 7, 100])))
    params = {"target": target, "role": role, "change": change, "prepare": prepare}
    if which == "datatable.snap.prev":
        params["also"] = {"target": "app/.softplc/datatable.snap", "change": {"truncate": 0.5}}
    app = rnd.choice(STATE_APPS)
    return Case("state_damage", program_files(app), [list(c) for c in commands], target=target, located="name",
                note=f"{which} of {app}: {sorted(change)}", driver="files", params=params)


# -- the driver ----------------------------------------------------------------------------------

# The C library's error texts (strerror) that a message must not show raw (docs: "what went wrong" in our words).
RAW_ERRNO = re.compile(r"\[Errno \d+\]|Is a directory|No such file or directory|Not a directory|Permission denied|"
                       r"Too many levels of symbolic links|No such device or address|Resource temporarily unavailable")
PROMPT_S = 5.0  # a refusal looks at the file, never reads it whole: well under this on a busy machine
STATE_NAMES = {"app/.softplc/datatable.snap": "datatable.snap", "app/.softplc/datatable.snap.prev": "datatable.snap.prev",
               "app/.softplc/codecache.bin": "codecache.bin"}


class memory_guard:
    """A 20 GiB file or /dev/zero read whole by a regression must be a
    MemoryError in this process, not the machine's trouble: the address
    space is capped at what it is now and 3 GiB more while the case runs."""

    def __enter__(self):
        import resource

        self.old = resource.getrlimit(resource.RLIMIT_AS)
        try:
            with open("/proc/self/status") as f:
                vm = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
        except (OSError, StopIteration):
            return self
        cap = vm + 3 * 2 ** 30
        if self.old[0] == resource.RLIM_INFINITY or self.old[0] > cap:
            resource.setrlimit(resource.RLIMIT_AS, (cap, self.old[1]))
        return self

    def __exit__(self, *exc):
        import resource

        resource.setrlimit(resource.RLIMIT_AS, self.old)


def _table(root: Path) -> object:
    """The dumped table without the status file (its scan-time words are the machine's)."""
    import json

    try:
        table = json.loads((root / "dump.json").read_text(encoding="utf-8"))
        (root / "dump.json").unlink()
    except (OSError, ValueError):
        return None
    return {k: v for k, v in table.items() if not k.startswith("S")}


def _put_state(state: Path, saved: dict[str, bytes]) -> None:
    """The state directory as ``saved`` (each file unlinked first: .prev is a hard link to the snapshot)."""
    if state.is_dir():
        for p in state.iterdir():
            if p.is_symlink() or p.is_file():
                p.unlink()
            elif p.is_dir():
                shutil.rmtree(p)
    state.mkdir(parents=True, exist_ok=True)
    for name, data in saved.items():
        (state / name).write_bytes(data)


def apply_change_unlinked(root: Path, target: str, change: dict) -> None:
    path = root / target
    if "special" not in change and path.is_file() and not path.is_symlink():
        data = damage(path.read_bytes(), change)
        path.unlink()  # not through the hard link .prev shares with the snapshot
        path.write_bytes(data)
    else:
        apply_change(root, target, change)


def run_files_case(case, root: Path, timeout: float, runner):
    """The ``files`` driver: prepare, a reference run where the role needs one,
    the change, the case's commands, and the role's oracle."""
    from helpers.fuzz_oracle import CaseRun, Finding, _first_error

    d = str(root)
    p = case.params
    target, role, change = p["target"], p["role"], p["change"]
    spec = change.get("special", "bytes")
    name = Path(target).name
    run = CaseRun(case, d, timeout, runner)
    findings, results, do = run.findings, run.results, run.do

    def add(cls: str, sig: str, r, detail: str) -> None:
        findings.append(Finding(cls, f"{cls}:{r.argv[0] if r.argv else '?'}:{sig}", r.argv, detail, case.kind, r))

    for argv in p.get("prepare", []):
        do(argv)
    reference = None
    state = root / "app" / ".softplc"
    if role in ("snap", "cache"):
        saved = {f.name: f.read_bytes() for f in state.iterdir() if f.is_file()} if state.is_dir() else {}
        if role == "cache":
            (state / "codecache.bin").unlink(missing_ok=True)  # the reference: no cache at all
        ref = do(case.commands[0])
        reference = (ref.code, _table(root))
        _put_state(state, saved)
    with memory_guard():
        if "also" in p:
            apply_change_unlinked(root, p["also"]["target"], p["also"]["change"])
        apply_change_unlinked(root, target, change)
        for argv in case.commands:
            r = do(argv)
            if r.hung or r.exception:
                continue
            errno = RAW_ERRNO.search(r.err)
            if errno:
                add("raw-errno", f"{name}:{spec}:{errno.group(0)}", r,
                    f"{name} as {spec}: a message shows the system's error text: {_first_error(r.err)[:200]}")
            if role == "input" and spec != "empty":
                if r.code != 1:
                    add("not-refused", f"{name}:{spec}:{r.code}", r,
                        f"{name} as {spec}: exit {r.code}, not 1 (a file that cannot be read is an error)")
                elif name not in r.err:
                    add("unnamed", f"{name}:{spec}", r, f"{name} as {spec}: the error does not name it: "
                                                        f"{_first_error(r.err)[:200]}")
                if r.seconds > PROMPT_S:
                    add("slow-refusal", f"{name}:{spec}", r, f"{name} as {spec}: {r.seconds:.1f} s to answer")
            elif role == "snap":
                table = _table(root)
                # Both the snapshot and .prev unusable: an error naming each (docs/datatable.md, Restore).
                both = "also" in p and r.code == 1 and "datatable.snap:" in r.err and "datatable.snap.prev:" in r.err
                # A directory in place of the snapshot: the final save cannot replace it (docs/engine.md: exit 1).
                unsaved = spec == "dir" and r.code == 1 and "cannot save" in r.err and name in r.err
                if r.code != 0 and not both and not unsaved:
                    add("state-run-failed", f"{name}:{spec}:{r.code}", r, f"{name} as {spec}: exit {r.code}: "
                                                                         f"{_first_error(r.err)[:200]}")
                elif table != reference[1] and name not in r.err:
                    add("silent-state", f"{name}:{spec}", r,
                        f"{name} as {spec}: the run restored another table and said nothing about {name}")
            elif role == "cache":
                table = _table(root)
                if (r.code, table) != reference:
                    add("cache-other-logic", f"{spec}:{r.code}", r,
                        f"codecache.bin as {spec}: exit {r.code} and {'the same' if table == reference[1] else 'another'}"
                        f" table, where the run without a cache exits {reference[0]}: a PLC never runs logic other "
                        f"than its program")
                elif spec == "bytes":  # the damaged cache was rewritten: the next run loads it quietly
                    again = do(argv)
                    if (again.code, _table(root)) != reference or "codecache" in again.err:
                        add("cache-not-rewritten", f"{again.code}", again,
                            f"the run after a damaged cache: exit {again.code}: {_first_error(again.err)[:200]}")
    if spec == "dangling":
        for t in [target] + ([p["also"]["target"]] if "also" in p else []):
            pointed = (root / t).with_name(Path(t).name + DANGLING_SUFFIX)
            if pointed.exists():
                findings.append(Finding("written-through", f"written-through:{name}", results[-1].argv,
                                        f"{t} was a dangling link and a command wrote {pointed.name} through it",
                                        case.kind, results[-1]))
    return findings, results
